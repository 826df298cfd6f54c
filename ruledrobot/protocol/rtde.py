"""RTDE wire protocol (port 30004): packet framing, setup payloads and recipes.

Every packet is ``uint16 size`` (including the 3-byte header), ``uint8 type``
(an ASCII letter), then the payload; everything is big-endian.  This module
is pure: no sockets, no threads.  :class:`PacketFramer` cuts a byte stream
into packets (TCP delivers arbitrary fragments), :class:`OutputRecipe` packs
controller state into data packages, :class:`InputRecipe` unpacks the
client's data packages.  Anything malformed raises :class:`ProtocolError`.
"""

from __future__ import annotations

import math
import struct
from collections.abc import Iterator, Mapping
from dataclasses import dataclass, field

from .rtde_types import TYPE_FORMATS, input_type, output_type

__all__ = [
    "CONTROL_PACKAGE_PAUSE",
    "CONTROL_PACKAGE_SETUP_INPUTS",
    "CONTROL_PACKAGE_SETUP_OUTPUTS",
    "CONTROL_PACKAGE_START",
    "DATA_PACKAGE",
    "GET_URCONTROL_VERSION",
    "HEADER_SIZE",
    "MAX_PACKET_SIZE",
    "REQUEST_PROTOCOL_VERSION",
    "TEXT_MESSAGE",
    "InputRecipe",
    "OutputRecipe",
    "PacketFramer",
    "ProtocolError",
    "pack_packet",
    "parse_names",
    "parse_output_setup",
    "text_message",
]

REQUEST_PROTOCOL_VERSION = ord("V")
GET_URCONTROL_VERSION = ord("v")
TEXT_MESSAGE = ord("M")
DATA_PACKAGE = ord("U")
CONTROL_PACKAGE_SETUP_OUTPUTS = ord("O")
CONTROL_PACKAGE_SETUP_INPUTS = ord("I")
CONTROL_PACKAGE_START = ord("S")
CONTROL_PACKAGE_PAUSE = ord("P")

KNOWN_TYPES = frozenset(
    (
        REQUEST_PROTOCOL_VERSION,
        GET_URCONTROL_VERSION,
        TEXT_MESSAGE,
        DATA_PACKAGE,
        CONTROL_PACKAGE_SETUP_OUTPUTS,
        CONTROL_PACKAGE_SETUP_INPUTS,
        CONTROL_PACKAGE_START,
        CONTROL_PACKAGE_PAUSE,
    )
)

HEADER_SIZE = 3
#: the size field is a uint16
MAX_PACKET_SIZE = 0xFFFF
_HEADER = struct.Struct(">HB")


class ProtocolError(ValueError):
    """A peer sent something the RTDE protocol does not allow; the connection must close."""


def pack_packet(kind: int, payload: bytes = b"") -> bytes:
    """One packet: header (size including the header, type) + payload."""
    size = HEADER_SIZE + len(payload)
    if size > MAX_PACKET_SIZE:
        raise ProtocolError(f"packet of type {kind!r}: payload of {len(payload)} bytes is too long")
    return _HEADER.pack(size, kind) + payload


def text_message(message: str, source: str = "ruledrobot", level: int = 3) -> bytes:
    """A protocol v2 text message packet (level 0 exception, 1 error, 2 warning, 3 info)."""
    m = message.encode("utf-8", "replace")[:255]
    s = source.encode("utf-8", "replace")[:255]
    payload = bytes([len(m)]) + m + bytes([len(s)]) + s + bytes([level & 0xFF])
    return pack_packet(TEXT_MESSAGE, payload)


class PacketFramer:
    """Cuts a TCP byte stream into ``(type, payload)`` packets.

    ``feed`` accepts any fragment; complete packets come out of ``packets``.
    A header whose size is below the header size, or whose type is not an
    RTDE command, raises :class:`ProtocolError` (the stream cannot be
    resynchronised after that).  ``max_buffer`` bounds the memory a peer can
    make us hold.
    """

    def __init__(self, max_buffer: int = 1 << 20) -> None:
        self._buf = bytearray()
        self._max = int(max_buffer)

    def feed(self, data: bytes) -> None:
        """Append received bytes."""
        self._buf += data
        if len(self._buf) > self._max:
            raise ProtocolError(f"more than {self._max} bytes buffered without a complete packet")

    def packets(self) -> Iterator[tuple[int, bytes]]:
        """Yield the complete packets received so far, in order."""
        buf = self._buf
        while len(buf) >= HEADER_SIZE:
            size, kind = _HEADER.unpack_from(buf, 0)
            if size < HEADER_SIZE:
                raise ProtocolError(f"packet header with size {size} < {HEADER_SIZE}")
            if kind not in KNOWN_TYPES:
                raise ProtocolError(f"unknown packet type {kind} (size {size})")
            if len(buf) < size:
                return
            payload = bytes(buf[HEADER_SIZE:size])
            del buf[:size]
            yield kind, payload

    @property
    def pending(self) -> int:
        """Bytes buffered that do not form a complete packet yet."""
        return len(self._buf)


def parse_names(payload: bytes, what: str) -> list[str]:
    """Comma-separated variable names (ur_rtde adds a trailing comma: empty names dropped)."""
    try:
        text = payload.decode("ascii")
    except UnicodeDecodeError:
        raise ProtocolError(f"{what}: variable names are not ASCII") from None
    names = [n.strip() for n in text.split(",")]
    names = [n for n in names if n]
    if not names:
        raise ProtocolError(f"{what}: no variable names")
    for n in names:
        if not n.isprintable() or len(n) > 64:
            raise ProtocolError(f"{what}: bad variable name {n[:40]!r}")
    return names


def parse_output_setup(payload: bytes, protocol_version: int) -> tuple[float | None, list[str]]:
    """``O`` payload -> (frequency or None for protocol v1, names)."""
    if protocol_version >= 2:
        if len(payload) < 8:
            raise ProtocolError("output setup: payload shorter than the frequency field")
        (freq,) = struct.unpack_from(">d", payload, 0)
        if not math.isfinite(freq) or freq <= 0.0 or freq > 1000.0:
            raise ProtocolError(f"output setup: frequency {freq!r} outside (0, 1000] Hz")
        return freq, parse_names(payload[8:], "output setup")
    return None, parse_names(payload, "output setup")


def _counts(types: list[str]) -> list[int]:
    """Number of scalars in each type (1 for scalars, 3 or 6 for vectors)."""
    return [int(TYPE_FORMATS[t][0]) if TYPE_FORMATS[t][0].isdigit() else 1 for t in types]


class RecipeKey:
    """Recipe id and names, hashed once.

    Equal recipes share one packed package per period (a tuple of 59 names would be hashed
    again at every lookup)."""

    __slots__ = ("_hash", "items")

    def __init__(self, items: tuple[str, ...]) -> None:
        self.items = items
        self._hash = hash(items)

    def __hash__(self) -> int:
        return self._hash

    def __eq__(self, other: object) -> bool:
        return isinstance(other, RecipeKey) and other.items == self.items


@dataclass
class _Recipe:
    """What both recipes share: their id and names, their types checked and compiled, the
    reply to their setup and the size of their struct (``__post_init__`` sets the types)."""

    recipe_id: int
    names: list[str]
    types: list[str] = field(init=False)
    ok: bool = field(init=False)
    too_large: bool = field(init=False, default=False)
    _struct: struct.Struct | None = field(init=False, repr=False, default=None)
    _counts: list[int] = field(init=False, repr=False, default_factory=list)

    def _compile(self, head: str, around: int) -> None:
        """``ok`` (every name known, the package fits in :data:`MAX_PACKET_SIZE` with
        ``around`` bytes beside the struct), ``too_large``, and when ok the struct ``head`` +
        the fields and the scalars per field."""
        self.ok = "NOT_FOUND" not in self.types
        if not self.ok:
            return
        fmt = head + "".join(TYPE_FORMATS[t] for t in self.types)
        if around + struct.calcsize(fmt) > MAX_PACKET_SIZE:
            self.ok = False
            self.too_large = True
            return
        self._struct = struct.Struct(fmt)
        self._counts = _counts(self.types)

    def _size(self) -> int:
        return self._struct.size if self._struct is not None else 0

    def reply(self) -> bytes:
        """The ``O`` / ``I`` reply payload: recipe id (0 = invalid), comma-separated types."""
        return bytes([self.recipe_id if self.ok else 0]) + ",".join(self.types).encode("ascii")


@dataclass
class OutputRecipe(_Recipe):
    """An output recipe: names, their types, and a precompiled packer.

    ``ok`` is False when some name is unknown (the reply lists ``NOT_FOUND``)
    or when its data package would exceed :data:`MAX_PACKET_SIZE` (the size
    field is 16 bits; ``too_large``): the reply's recipe id is 0 (failed) and
    such a recipe can never be started.
    """

    frequency: float
    key: RecipeKey = field(init=False, repr=False)

    def __post_init__(self) -> None:
        self.key = RecipeKey((str(self.recipe_id), *self.names))  # equal recipes, one package
        self.types = [output_type(n) or "NOT_FOUND" for n in self.names]
        self._compile(">HBB", 0)  # the header and the recipe id in the struct

    @property
    def size(self) -> int:
        """Data package size in bytes including the header."""
        return self._size()

    def pack(self, state: Mapping[str, object]) -> bytes:
        """A complete data package (header + recipe id + fields) from ``state``.

        ``state`` maps names to numbers (scalars) or sequences (vectors); a name
        missing from ``state`` is packed as zeros.
        """
        if self._struct is None:
            raise ProtocolError(f"output recipe {self.recipe_id} has unknown variables")
        values: list = [self._struct.size, DATA_PACKAGE, self.recipe_id]
        get = state.get
        for name, n in zip(self.names, self._counts, strict=True):
            v = get(name)
            if n == 1:
                values.append(0 if v is None else v)
            elif v is None:
                values.extend((0,) * n)
            else:
                values.extend(v)  # type: ignore[arg-type]
        return self._struct.pack(*values)


@dataclass
class InputRecipe(_Recipe):
    """An input recipe: names, types, and the decoder of the client's data packages.

    ``ok`` is False when some name is unknown (reply ``NOT_FOUND``, id 0) or
    when no data package of it could be sent (larger than
    :data:`MAX_PACKET_SIZE`; ``too_large``, id 0).
    """

    def __post_init__(self) -> None:
        self.types = [input_type(n) or "NOT_FOUND" for n in self.names]
        self._compile(">", HEADER_SIZE + 1)  # the fields only

    @property
    def payload_size(self) -> int:
        """Size of the fields (without the recipe id byte)."""
        return self._size()

    def unpack(self, fields: bytes) -> dict[str, object]:
        """Decode the fields (after the recipe id byte) into ``{name: value}``.

        Vectors come out as tuples.  Raises :class:`ProtocolError` on a size
        mismatch or a non-finite double.
        """
        if self._struct is None:
            raise ProtocolError(f"input recipe {self.recipe_id} is invalid (unknown names)")
        if len(fields) != self._struct.size:
            raise ProtocolError(
                f"data package for input recipe {self.recipe_id}: {len(fields)} bytes of fields, "
                f"the recipe needs {self._struct.size}"
            )
        flat = self._struct.unpack(fields)
        out: dict[str, object] = {}
        i = 0
        for name, typ, n in zip(self.names, self.types, self._counts, strict=True):
            if n == 1:
                v = flat[i]
                if typ == "DOUBLE" and not math.isfinite(v):
                    raise ProtocolError(f"data package: {name} is not finite")
                out[name] = v
            else:
                v = flat[i : i + n]
                if typ.endswith("D") and not all(math.isfinite(x) for x in v):
                    raise ProtocolError(f"data package: {name} is not finite")
                out[name] = v
            i += n
        return out
