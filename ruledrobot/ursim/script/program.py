"""URScript programs arriving on the script port (30003): splitting and classifying.

Two kinds of program matter:

* ``def rtde_control():`` — ur_rtde's control script.  The emulator re-implements its
  register handshake (:mod:`.handshake`, the documented fallback until the interpreter runs
  the script itself).  Only two things are read from its text: the register offset
  ur_rtde injects after ``# float register offset`` (0, or 24 for the upper register
  range) and the path moves it injects after ``# inject move path`` for ``moveL(path)`` /
  ``moveJ(path)`` / ``movePath``, one ``\\tmovel(p[x,y,z,rx,ry,rz],a=A,v=V,r=R)`` (or
  ``movej([...])``, ``movep(p[...])``) line per waypoint.
* any other program — ``def name(): ... end``, ``sec name(): ... end`` (a secondary
  program: it runs beside the primary one, no motion, no waiting) or bare lines — is
  parsed by lark and run by the interpreter (:mod:`.interpreter`: variables, lists and
  poses, ``if``/``while``, functions, threads, sockets, the motion and IO functions).
  :func:`~.interpreter.load_program` classifies with :func:`parse_program` and compiles.

A program that does not compile is refused whole: :class:`CompileError` names the line,
its text and the reason, and nothing of the program runs — as a controller refuses it.
"""

from __future__ import annotations

import math
import re
from collections.abc import Iterator
from dataclasses import dataclass, field

from ...robot.motion.ur_motion import MotionError

__all__ = [
    "MAX_LINE_BYTES",
    "MAX_PROGRAM_BYTES",
    "CompileError",
    "PathWaypoint",
    "Pose",
    "Program",
    "ProgramSplitter",
    "ScriptRuntimeError",
    "ScriptSyntaxError",
    "Statement",
    "parse_call",
    "parse_program",
]


class ScriptSyntaxError(ValueError):
    """A statement the emulator cannot parse."""


class CompileError(ScriptSyntaxError):
    """A program line the emulator cannot run: the whole program is refused.

    ``line`` is 1-based in the program text, ``text`` the line (stripped,
    shortened to 80 characters), ``reason`` what is wrong with it.
    """

    def __init__(self, line: int, text: str, reason: str) -> None:
        self.line = int(line)
        self.text = text.strip()[:80]
        self.reason = reason
        super().__init__(f"line {self.line}: {self.text!r}: {reason}")


class ScriptRuntimeError(MotionError):
    """A runtime error of a running program: the program stops.

    An index out of range, a bad argument, a pose out of reach; the interpreter adds the
    line.
    """


@dataclass(frozen=True)
class Pose:
    """A URScript pose literal ``p[x, y, z, rx, ry, rz]``."""

    values: tuple[float, ...]


@dataclass
class Statement:
    """A top-level call ``name(args..., key=value...)``, its 1-based line number and text.

    ``params``: the checked arguments by name (filled by
    :func:`~.functions.bind`).
    """

    name: str
    args: list
    kwargs: dict
    line: int
    text: str = ""
    params: dict = field(default_factory=dict)


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
    """A program; ``kind`` is ``"rtde_control"``, ``"script"``, ``"sec"`` or ``"idle"``."""

    name: str
    text: str
    kind: str
    register_offset: int = 0
    path: list[PathWaypoint] = field(default_factory=list)
    #: the program compiled by :func:`~.interpreter.compile_script` (None for rtde_control)
    compiled: object = None


# ------------------------------------------------------------------ tokenizer / parser

_TOKEN = re.compile(
    r"""(?:
        (?P<num>[-+]?(?:\d+\.\d*|\.\d+|\d+)(?:[eE][-+]?\d+)?)
      | (?P<str>"(?:[^"\\]|\\.)*"|'(?:[^'\\]|\\.)*')
      | (?P<name>[A-Za-z_][A-Za-z_0-9]*)
      | (?P<op>[\[\](),=])
      | (?P<comment>\#.*)
    )""",
    re.VERBOSE,
)
_SPACE = re.compile(r"\s*")


def _tokens(text: str) -> list[tuple[str, str]]:
    """The tokens of one line, in one pass (linear in its length)."""
    out = []
    pos = _SPACE.match(text).end()  # type: ignore[union-attr]
    n = len(text)
    while pos < n:
        m = _TOKEN.match(text, pos)
        if m is None or m.end() == pos:
            raise ScriptSyntaxError(f"unexpected text {text[pos : pos + 20]!r}")
        kind = m.lastgroup or ""
        if kind == "comment":
            break
        out.append((kind, m.group(kind)))
        pos = _SPACE.match(text, m.end()).end()  # type: ignore[union-attr]
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
            raise ScriptSyntaxError(f"variables are not emulated ({text!r})")
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
        raise ScriptSyntaxError(f"expected a function call, got {text.strip()[:40]!r}")
    if p.peek()[1] == "=":
        raise ScriptSyntaxError("assignments (variables) are not emulated")
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
                raise ScriptSyntaxError("positional argument after keyword")
            args.append(p.value())
        if p.peek()[1] == ",":
            p.take()
        elif p.peek()[1] != ")":
            raise ScriptSyntaxError(f"expected ',' or ')', got {p.peek()[1]!r}")
    p.take(")")
    if p.peek()[0] != "end":
        raise ScriptSyntaxError(f"text after the call: {p.peek()[1]!r}")
    return Statement(name, args, kwargs, line, text.strip())


# ------------------------------------------------------------------ programs

_DEF = re.compile(r"^(def|sec)\s+([A-Za-z_][A-Za-z_0-9]*)\s*\(\s*\)\s*:\s*(#.*)?$")
_OFFSET = re.compile(r"# float register offset\n\s*(\d+)")
_INJECT = "# inject move path\n"
_MOVES = ("movej", "movel", "movep")
#: words that start a control-flow or declaration line (not emulated)
_KEYWORDS = frozenset({"if", "elif", "else", "while", "for", "thread", "def", "sec", "end",
                       "return", "global", "local", "run", "join", "kill", "halt", "break",
                       "continue", "enter_critical", "exit_critical"})  # fmt: skip
_FIRST_WORD = re.compile(r"[A-Za-z_][A-Za-z_0-9]*")


def _waypoint(st: Statement) -> PathWaypoint:
    if st.name not in _MOVES or len(st.args) != 1:
        raise CompileError(st.line, st.text, "not a path move")
    target = st.args[0]
    pose = isinstance(target, Pose)
    values = target.values if isinstance(target, Pose) else tuple(target)
    if len(values) != 6:
        raise CompileError(st.line, st.text, f"expected 6 values, got {len(values)}")

    def num(key: str, default: float) -> float:
        v = st.kwargs.get(key, default)
        if not isinstance(v, float) or not math.isfinite(v):
            raise CompileError(st.line, st.text, f"{key} must be a finite number")
        return v

    return PathWaypoint(st.name, tuple(values), pose, num("a", 1.2), num("v", 0.25), num("r", 0.0))


def _call(line: str, lineno: int) -> Statement:
    """One statement line as a call; CompileError naming the line otherwise."""
    word = _FIRST_WORD.match(line)
    if word is not None and word.group(0) in _KEYWORDS:
        raise CompileError(lineno, line, f"{word.group(0)!r}: control flow and declarations "
                           "are not emulated")  # fmt: skip
    try:
        return parse_call(line, lineno)
    except CompileError:
        raise
    except ScriptSyntaxError as exc:
        raise CompileError(lineno, line, str(exc)) from None


def _rtde_control(text: str) -> Program:
    prog = Program("rtde_control", text, "rtde_control")
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
            prog.path.append(_waypoint(_call(s, lineno)))
            lineno += 1
    return prog


def parse_program(text: str) -> Program:
    """Classify one complete program (``def name(): ... end``, ``sec``, or lines).

    ur_rtde's control script is read here (register offset, injected path); any other
    program is returned with its name and kind, for :func:`~.interpreter.compile_script`.
    Raises :class:`CompileError` (line, text, reason) for an empty program, a ``def`` not
    at column 0 or a program without its closing ``end``.
    """
    lines = text.splitlines()
    first_i = next((i for i, ln in enumerate(lines) if ln.strip()), None)
    if first_i is None:
        raise CompileError(1, "", "empty program")
    first = lines[first_i]
    m = _DEF.match(first.rstrip()) if not first[:1].isspace() else None
    if m is None and first.lstrip().startswith(("def ", "sec ")):
        raise CompileError(first_i + 1, first, "expected 'def name():' at column 0")
    name = m.group(2) if m else ""
    if name == "rtde_control":
        return _rtde_control(text)
    if m:
        close = next((i for i in range(len(lines) - 1, first_i, -1)
                      if lines[i].strip()), None)  # fmt: skip
        if close is None or lines[close].rstrip() != "end":
            raise CompileError(len(lines), lines[-1] if lines else "",
                               "the program has no closing 'end' at column 0")  # fmt: skip
    return Program(name, text, "sec" if m and m.group(1) == "sec" else "script")


#: the largest program the script port takes [bytes]: 4 times what
#: :func:`ruledrobot.export.urscript.urscript_program` writes without ``allow_long``;
#: a field report tells of an 18 MB program crashing a controller
MAX_PROGRAM_BYTES = 8 << 20
#: the longest line [bytes]; ur_rtde's and ruledrobot's lines are about 100
MAX_LINE_BYTES = 64 << 10


class ProgramSplitter:
    """Splits the script-port text stream into complete programs, line by line.

    A program starting with ``def name():`` / ``sec name():`` is complete at
    a line that is exactly ``end`` at column 0 (inner ``end`` s are indented);
    any other text is taken one line at a time; blank lines between programs
    are dropped.  Each byte is looked at once (the time is linear in the
    text).  A program longer than ``max_bytes`` or a line longer than
    ``max_line`` raises ValueError as soon as it is: the stream cannot be
    resynchronised, the connection must close.
    """

    def __init__(self, max_bytes: int = MAX_PROGRAM_BYTES, max_line: int = MAX_LINE_BYTES) -> None:
        self._max = int(max_bytes)
        self._max_line = int(max_line)
        self._partial: list[str] = []  # the current line, not complete yet
        self._partial_len = 0
        self._program: list[str] | None = None  # lines of the def/sec program being read
        self._program_len = 0

    def feed(self, text: str) -> Iterator[str]:
        """Add received text; yield each program completed by it."""
        start = 0
        n = len(text)
        while start < n:
            nl = text.find("\n", start)
            if nl < 0:
                self._partial.append(text[start:])
                self._partial_len += n - start
                self._check(self._partial_len)
                return
            piece = text[start : nl + 1]
            start = nl + 1
            if self._partial:
                self._partial.append(piece)
                piece = "".join(self._partial)
                self._partial.clear()
                self._partial_len = 0
            self._check(len(piece))
            done = self._line(piece)
            if done is not None:
                yield done

    def _check(self, line_len: int) -> None:
        if line_len > self._max_line:
            raise ValueError(f"script port: a line longer than {self._max_line} bytes")
        if self._program_len + line_len > self._max:
            raise ValueError(f"script port: a program larger than {self._max / 2**20:g} MiB")

    def _line(self, line: str) -> str | None:
        """One complete line (with its newline); the program it completes, if any."""
        if self._program is None:
            stripped = line.strip()
            if not stripped:
                return None
            if _DEF.match(stripped):
                self._program = [line]
                self._program_len = len(line)
                return None
            return line
        self._program.append(line)
        self._program_len += len(line)
        if line.startswith("end") and line.rstrip(" \t\r\n") == "end":
            text = "".join(self._program)
            self._program = None
            self._program_len = 0
            return text
        return None
