"""Where an emulator listens: its loopback address, or the next free one.

An emulator binds UR's fixed ports (RTDE 30004, dashboard 29999, script 30003,
primary 30001, secondary 30002; ur_rtde cannot change them), so two emulators
on one machine need two addresses: a whole free address, not free ports.  All
of 127.0.0.0/8 is loopback on Linux.  :func:`start_on_free_host` starts an
emulator on its address or, when that is taken (``EADDRINUSE``), on the next
loopback addresses in turn (:func:`loopback_hosts`).  The bind itself decides,
so two processes starting at the same moment end on two addresses.
"""

from __future__ import annotations

import errno
import ipaddress
from collections.abc import Callable
from typing import TypeVar

__all__ = ["FREE_HOST_TRIES", "address_in_use", "loopback_hosts", "start_on_free_host"]

#: how many loopback addresses :func:`start_on_free_host` tries, the first included
FREE_HOST_TRIES = 32

_LOOPBACK = ipaddress.ip_network("127.0.0.0/8")

T = TypeVar("T")


def address_in_use(exc: BaseException) -> bool:
    """True when ``exc`` says an address (a port of it) is taken: ``EADDRINUSE``."""
    return isinstance(exc, OSError) and exc.errno == errno.EADDRINUSE


def loopback_hosts(first: str, count: int = FREE_HOST_TRIES) -> list[str]:
    """``first``, then the loopback addresses after it: ``count`` addresses in all.

    The addresses follow ``first`` in 127.0.0.0/8 (wrapping round to 127.0.0.1),
    skipping those ending in .0 or .255.  A ``first`` outside 127.0.0.0/8 (a
    network interface, or a name) has no neighbours to move to: ``[first]``.
    """
    try:
        start = ipaddress.IPv4Address(first)
    except ValueError:
        return [first]
    if start not in _LOOPBACK:
        return [first]
    hosts = [first]
    lo, size = int(_LOOPBACK.network_address), _LOOPBACK.num_addresses
    k = int(start) - lo
    while len(hosts) < count:
        k = (k + 1) % size
        addr = ipaddress.IPv4Address(lo + k)
        if addr.packed[3] in (0, 255) or str(addr) == first:
            continue
        hosts.append(str(addr))
    return hosts


def start_on_free_host(
    first: str,
    start: Callable[[str], T],
    *,
    find_free_host: bool = True,
    count: int = FREE_HOST_TRIES,
) -> T:
    """``start(host)`` on ``first`` or, when it is taken, on the next free loopback address.

    Parameters
    ----------
    first : the address to try first.
    start : binds everything on the address it is given and returns what runs there;
        raises an ``OSError`` with ``errno.EADDRINUSE`` when a port is taken, having
        released whatever it bound.
    find_free_host : False: ``first`` only (an address the user chose: a taken one is an
        error, never silently replaced).
    count : how many addresses to try (:func:`loopback_hosts`).

    Returns
    -------
    What ``start`` returned for the first address it could bind.

    Raises
    ------
    OSError
        Any error of ``start`` but a taken address at once; ``EADDRINUSE`` (its
        ``errno``) when every address tried was taken, naming them.
    """
    hosts = loopback_hosts(first, count) if find_free_host else [first]
    last: OSError | None = None
    for host in hosts:
        try:
            return start(host)
        except OSError as exc:
            if not address_in_use(exc) or len(hosts) == 1:
                raise
            last = exc
    exc = OSError(
        f"no free loopback address: {hosts[0]} and the {len(hosts) - 1} addresses after it "
        f"(to {hosts[-1]}) are taken (last: {last}); does something listen on these ports "
        "on every address (0.0.0.0)?"
    )
    exc.errno = errno.EADDRINUSE
    raise exc

