"""URScript programs arriving on the script port (30003): splitting and parsing.

Two kinds of program matter:

* ``def rtde_control():`` — ur_rtde's control script.  It is not interpreted:
  the emulator re-implements its register handshake (``commands.py``).  Only
  two things are read from its text: the register offset ur_rtde injects
  after ``# float register offset`` (0, or 24 for the upper register range)
  and the path moves it injects after ``# inject move path`` for
  ``moveL(path)`` / ``moveJ(path)`` / ``movePath``, one
  ``\\tmovel(p[x,y,z,rx,ry,rz],a=A,v=V,r=R)`` (or ``movej([...])``,
  ``movep(p[...])``) line per waypoint.
* any other program — e.g. the standalone programs
  :mod:`ruledrobot.export.urscript` writes — is parsed into its top-level
  statements, which :class:`~.controller.Controller` runs with a small
  interpreter (motion, servoj, sleep, textmsg, set_tcp, register writes).
  Control flow (``if``/``while``/``thread``) is not supported: such lines are
  listed in ``Program.skipped``.
"""

from __future__ import annotations

import re
from collections.abc import Iterator
from dataclasses import dataclass, field

__all__ = [
    "PathWaypoint",
    "Pose",
    "Program",
    "ProgramSplitter",
    "ScriptSyntaxError",
    "Statement",
    "parse_call",
    "parse_program",
]


class ScriptSyntaxError(ValueError):
    """A statement the emulator cannot parse."""


@dataclass(frozen=True)
class Pose:
    """A URScript pose literal ``p[x, y, z, rx, ry, rz]``."""

    values: tuple[float, ...]


@dataclass
class Statement:
    """A top-level call ``name(args..., key=value...)`` and its 1-based line number."""

    name: str
    args: list
    kwargs: dict
    line: int


@dataclass(frozen=True)
class PathWaypoint:
    """An injected path move: ``kind`` movej/movel/movep to ``target`` (joints or pose)."""

    kind: str
    target: tuple[float, ...]
    pose: bool
    a: float
    v: float
    r: float


@dataclass
class Program:
    """A parsed program; ``kind`` is ``"rtde_control"`` or ``"script"``."""

    name: str
    text: str
    kind: str
    register_offset: int = 0
    path: list[PathWaypoint] = field(default_factory=list)
    statements: list[Statement] = field(default_factory=list)
    skipped: list[str] = field(default_factory=list)


# ------------------------------------------------------------------ tokenizer / parser

_TOKEN = re.compile(
    r"""\s*(?:
        (?P<num>[-+]?(?:\d+\.\d*|\.\d+|\d+)(?:[eE][-+]?\d+)?)
      | (?P<str>"(?:[^"\\]|\\.)*"|'(?:[^'\\]|\\.)*')
      | (?P<name>[A-Za-z_][A-Za-z_0-9]*)
      | (?P<op>[\[\](),=])
    )""",
    re.VERBOSE,
)


def _tokens(text: str) -> list[tuple[str, str]]:
    out = []
    pos = 0
    n = len(text)
    while pos < n:
        if text[pos:].strip() == "":
            break
        m = _TOKEN.match(text, pos)
        if m is None or m.end() == pos:
            raise ScriptSyntaxError(f"unexpected text {text[pos : pos + 20]!r}")
        kind = m.lastgroup or ""
        out.append((kind, m.group(kind)))
        pos = m.end()
    return out


class _Parser:
    def __init__(self, tokens: list[tuple[str, str]]) -> None:
        self.t = tokens
        self.i = 0

    def peek(self) -> tuple[str, str]:
        return self.t[self.i] if self.i < len(self.t) else ("end", "")

    def take(self, value: str | None = None) -> tuple[str, str]:
        tok = self.peek()
        if value is not None and tok[1] != value:
            raise ScriptSyntaxError(f"expected {value!r}, got {tok[1]!r}")
        self.i += 1
        return tok

    def value(self) -> object:
        kind, text = self.peek()
        if kind == "num":
            self.take()
            return float(text)
        if kind == "str":
            self.take()
            return text[1:-1]
        if kind == "op" and text == "[":
            return self.list_()
        if kind == "name":
            if text == "p" and self.i + 1 < len(self.t) and self.t[self.i + 1][1] == "[":
                self.take()
                return Pose(tuple(self.list_()))
            self.take()
            if text in ("True", "true"):
                return True
            if text in ("False", "false"):
                return False
            raise ScriptSyntaxError(f"variables are not supported ({text!r})")
        raise ScriptSyntaxError(f"unexpected {text!r}")

    def list_(self) -> list:
        self.take("[")
        items: list = []
        while self.peek()[1] != "]":
            v = self.value()
            if not isinstance(v, float):
                raise ScriptSyntaxError("list items must be numbers")
            items.append(v)
            if self.peek()[1] == ",":
                self.take()
            elif self.peek()[1] != "]":
                raise ScriptSyntaxError(f"expected ',' or ']', got {self.peek()[1]!r}")
        self.take("]")
        return items


def parse_call(text: str, line: int = 0) -> Statement:
    """Parse one call statement ``name(arg, ..., key=value, ...)`` with literal arguments."""
    toks = _tokens(text)
    p = _Parser(toks)
    kind, name = p.take()
    if kind != "name":
        raise ScriptSyntaxError(f"line {line}: expected a function call, got {text.strip()[:40]!r}")
    p.take("(")
    args: list = []
    kwargs: dict = {}
    while p.peek()[1] != ")":
        if p.peek()[0] == "name" and p.i + 1 < len(toks) and toks[p.i + 1][1] == "=":
            key = p.take()[1]
            p.take("=")
            kwargs[key] = p.value()
        else:
            if kwargs:
                raise ScriptSyntaxError(f"line {line}: positional argument after keyword")
            args.append(p.value())
        if p.peek()[1] == ",":
            p.take()
        elif p.peek()[1] != ")":
            raise ScriptSyntaxError(f"line {line}: expected ',' or ')', got {p.peek()[1]!r}")
    p.take(")")
    if p.peek()[0] != "end":
        raise ScriptSyntaxError(f"line {line}: text after the call: {p.peek()[1]!r}")
    return Statement(name, args, kwargs, line)


# ------------------------------------------------------------------ programs

_DEF = re.compile(r"^(def|sec)\s+([A-Za-z_][A-Za-z_0-9]*)\s*\(\s*\)\s*:")
_OFFSET = re.compile(r"# float register offset\n\s*(\d+)")
_INJECT = "# inject move path\n"
_MOVES = ("movej", "movel", "movep")


def _waypoint(st: Statement) -> PathWaypoint:
    if st.name not in _MOVES or len(st.args) != 1:
        raise ScriptSyntaxError(f"line {st.line}: not a path move")
    target = st.args[0]
    pose = isinstance(target, Pose)
    values = target.values if isinstance(target, Pose) else tuple(target)
    if len(values) != 6:
        raise ScriptSyntaxError(f"line {st.line}: expected 6 values, got {len(values)}")

    def num(key: str, default: float) -> float:
        v = st.kwargs.get(key, default)
        if not isinstance(v, float):
            raise ScriptSyntaxError(f"line {st.line}: {key} must be a number")
        return v

    return PathWaypoint(st.name, tuple(values), pose, num("a", 1.2), num("v", 0.25), num("r", 0.0))


def parse_program(text: str) -> Program:
    """Classify and parse one complete program (``def name(): ... end`` or one statement)."""
    lines = text.splitlines()
    first = next((ln for ln in lines if ln.strip()), "")
    m = _DEF.match(first.strip())
    name = m.group(2) if m else ""
    if name == "rtde_control":
        prog = Program(name, text, "rtde_control")
        mo = _OFFSET.search(text)
        if mo:
            prog.register_offset = int(mo.group(1))
        k = text.find(_INJECT)
        if k >= 0:
            lineno = text.count("\n", 0, k + len(_INJECT)) + 1
            for raw in text[k + len(_INJECT) :].splitlines():
                s = raw.strip()
                if not s or s.startswith("signal_async_progress("):
                    lineno += 1
                    continue
                if not s.startswith(_MOVES):
                    break
                prog.path.append(_waypoint(parse_call(s, lineno)))
                lineno += 1
        return prog
    prog = Program(name, text, "script")
    body = lines
    if m:
        start = lines.index(first) + 1
        body = lines[start:]
        # drop the closing 'end' at column 0
        while body and not body[-1].strip():
            body.pop()
        if body and body[-1].rstrip() == "end":
            body.pop()
        offset = start
    else:
        offset = 0
    for i, raw in enumerate(body, start=offset + 1):
        s = raw.strip()
        if not s or s.startswith("#"):
            continue
        try:
            prog.statements.append(parse_call(s, i))
        except ScriptSyntaxError:
            prog.skipped.append(f"line {i}: {s[:80]}")
    return prog


class ProgramSplitter:
    """Splits the script-port byte stream into complete programs.

    A program starting with ``def name():`` / ``sec name():`` is complete at
    a line that is exactly ``end`` at column 0 (inner ``end`` s are indented);
    any other text is taken one line at a time.  ``max_bytes`` bounds what an
    unterminated program may buffer (ValueError beyond).
    """

    def __init__(self, max_bytes: int = 64 << 20) -> None:
        self._buf = ""
        self._max = max_bytes
        self._scan = 0  # where to resume looking for the closing 'end'

    def feed(self, text: str) -> Iterator[str]:
        """Add received text; yield each program completed by it."""
        self._buf += text
        if len(self._buf) > self._max:
            raise ValueError(f"script port: more than {self._max} bytes without a complete program")
        while True:
            buf = self._buf.lstrip()
            if len(buf) != len(self._buf):
                self._scan = max(0, self._scan - (len(self._buf) - len(buf)))
                self._buf = buf
            if not buf:
                return
            if _DEF.match(buf.split("\n", 1)[0].strip()):
                m = re.compile(r"^end[ \t\r]*$", re.M).search(buf, self._scan)
                if m is None:
                    self._scan = max(0, len(buf) - 8)
                    return
                end = m.end()
                if end < len(buf) and buf[end] == "\n":
                    end += 1
                elif end == len(buf):
                    # 'end' without its newline yet: wait for more text
                    self._scan = m.start()
                    return
                self._buf = buf[end:]
                self._scan = 0
                yield buf[:end]
            else:
                nl = buf.find("\n")
                if nl < 0:
                    return
                self._buf = buf[nl + 1 :]
                self._scan = 0
                yield buf[: nl + 1]
