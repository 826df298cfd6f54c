"""The wire-pose search's memo: a search asked again with the same inputs is answered once.

``make`` asks the planner's own search twice for every cut: carve's robot check
(:func:`~.feasible.cut_reasons`) chooses the cuts with it, then the plan of each setup
runs it again on the same rulings, bow, cell and options (measured on the twisted column:
all 6 of the plan's searches repeated carve's, bit for bit).  The memo keys a search by a
digest of its inputs' *content* (:func:`value_digest`: every field of every dataclass,
recursively, and every array's dtype, shape and bytes), so any difference in any input,
a field added later included, is a different search; results are frozen values, shared.

In one process only, the last :data:`SIZE` searches.
"""

from __future__ import annotations

import dataclasses
import hashlib
import threading
from collections import OrderedDict
from collections.abc import Callable
from typing import Any, TypeVar

import numpy as np

__all__ = ["SIZE", "memoized", "value_digest"]

#: searches kept (a part's cuts and their passes, a few setups)
SIZE = 64

T = TypeVar("T")
_memo: OrderedDict[str, Any] = OrderedDict()
_lock = threading.Lock()


def _feed(h: Any, x: Any) -> None:
    if dataclasses.is_dataclass(x) and not isinstance(x, type):
        h.update(b"D" + type(x).__qualname__.encode())
        for f in dataclasses.fields(x):
            h.update(b"." + f.name.encode())
            _feed(h, getattr(x, f.name))
    elif isinstance(x, np.ndarray):
        a = np.ascontiguousarray(x)
        h.update(b"A" + f"{a.dtype.str}{a.shape}".encode())
        h.update(a.tobytes())
    elif isinstance(x, (list, tuple)):
        h.update(b"(" + str(len(x)).encode())
        for v in x:
            _feed(h, v)
    elif isinstance(x, dict):
        h.update(b"{" + str(len(x)).encode())
        for k in sorted(x, key=repr):
            h.update(repr(k).encode())
            _feed(h, x[k])
    elif x is None or isinstance(x, (bool, int, float, str, bytes, np.generic)):
        h.update(b"V" + type(x).__name__.encode() + repr(x).encode())
    else:  # nothing else has a content the digest can read: refuse, never guess
        raise TypeError(f"value_digest: cannot read a {type(x).__qualname__}")


def value_digest(*values: Any) -> str:
    """Return the SHA-256 (hex) of the content of ``values``.

    Dataclasses by their type and every field (recursively; cached properties are not
    fields and are left out), arrays by dtype, shape and bytes, sequences and mappings by
    their items, scalars and strings by type and ``repr`` (exact for floats).  TypeError
    for any other object."""
    h = hashlib.sha256()
    _feed(h, values)
    return h.hexdigest()


def _frozen(out: T) -> T:
    """``out`` with the arrays of its fields made read-only: a result shared by two callers
    must not be changed by one under the other (a write raises instead)."""
    if dataclasses.is_dataclass(out) and not isinstance(out, type):
        for f in dataclasses.fields(out):
            v = getattr(out, f.name)
            if isinstance(v, np.ndarray):
                v.flags.writeable = False
    return out


def memoized(compute: Callable[[], T], *inputs: Any) -> T:
    """``compute()``, or its result for the same ``inputs`` (by :func:`value_digest`).

    The result's arrays are made read-only (it is shared).  Inputs whose content the
    digest cannot read are not memoized (computed each time)."""
    try:
        key = value_digest(*inputs)
    except TypeError:
        return compute()
    with _lock:
        if key in _memo:
            _memo.move_to_end(key)
            return _memo[key]
    out = _frozen(compute())
    with _lock:
        _memo[key] = out
        while len(_memo) > SIZE:
            _memo.popitem(last=False)
    return out
