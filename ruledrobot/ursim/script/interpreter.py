"""The URScript interpreter: a program's threads stepped once per control period.

A program is parsed (:mod:`.syntax`, lark), checked and turned into Python generator
functions (:mod:`.transpile`) when it arrives — a program that does not compile is refused
whole, as the controller refuses it.  :class:`Interpreter` runs it: every control period
(:meth:`Interpreter.step`, called by the controller's tick) each live thread runs until it
waits (``sync()``, a move, ``sleep``, ``servoj``, a socket read, ``join``), the main
program first, then the threads in the order they were started.  A thread that loops
:data:`MAX_SPIN` times in one period without waiting is a runtime error ("infinite loop"),
as the controller's "runtime too much behind"; so is any error of the program (an index out
of range, a bad argument, a pose out of reach): the program stops and the error, with its
URScript line, goes to the log.  When the main program ends, its threads end with it.
"""

from __future__ import annotations

import gc
import math
import operator
import sys
import types
from collections.abc import Callable, Generator
from dataclasses import dataclass
from typing import Any

from ...robot.motion.ur_motion import MotionError
from .host import ProgramHost
from .library import Library, PoseValue
from .program import CompileError, Program, ScriptRuntimeError, Statement, parse_program
from .syntax import parse_tree
from .transpile import Transpiled, transpile

__all__ = ["MAX_SPIN", "CompiledScript", "Interpreter", "compile_script", "load_program"]

#: loop iterations one thread may run in one control period without waiting
MAX_SPIN = 100_000

_FILENAME = "<urscript>"


@dataclass
class CompiledScript:
    """A program compiled to Python: its code object and line map (:class:`Transpiled`)."""

    code: types.CodeType
    transpiled: Transpiled

    def us_line(self, py_line: int) -> int:
        """The URScript line of line ``py_line`` of the generated Python."""
        lines = self.transpiled.lines
        return lines[py_line - 1] if 1 <= py_line <= len(lines) else 0


def compile_script(text: str, *, max_payload: float | None = None) -> CompiledScript:
    """Parse, check and compile ``text``; CompileError naming the line when it cannot run.

    The cyclic garbage collector is off meanwhile: a large program's parse tree is millions
    of objects, and a full collection among them holds the GIL for most of a second (the
    emulator's clock thread would miss its periods); the tree makes no cycles."""
    enabled = gc.isenabled()
    gc.disable()
    try:
        tr = transpile(parse_tree(text), text, max_payload=max_payload)
    finally:
        if enabled:
            gc.enable()
    try:
        code = compile(tr.source, _FILENAME, "exec")
    except SyntaxError as exc:  # a construct the transpiler let through that Python refuses
        line = tr.lines[(exc.lineno or 1) - 1] if exc.lineno else 1
        src = text.splitlines()[line - 1] if 0 < line <= len(text.splitlines()) else ""
        raise CompileError(line, src, f"cannot be compiled: {exc.msg}") from None
    return CompiledScript(code, tr)


def load_program(text: str, *, max_payload: float | None = None) -> Program:
    """A program as the controller receives it.

    Ur_rtde's control script classified (:func:`~.program.parse_program`), any other compiled
    (``Program.compiled``)."""
    prog = parse_program(text)
    if prog.kind != "rtde_control":
        prog.compiled = compile_script(text, max_payload=max_payload)
    return prog


class _Halt(Exception):
    """``halt``: the program ends."""


# ---------------------------------------------------------------------- value helpers
def _num(v: object, op: str) -> Any:
    if isinstance(v, bool) or not isinstance(v, (int, float)):
        raise ScriptRuntimeError(f"'{op}' takes numbers, got {v!r}")
    return v


def _arith(op: str, fn: Callable[[Any, Any], Any]) -> Callable[[Any, Any], Any]:
    def run(a: object, b: object) -> Any:
        return fn(_num(a, op), _num(b, op))

    return run


def _div(a: object, b: object) -> float:
    a, b = _num(a, "/"), _num(b, "/")
    if b == 0:
        raise ScriptRuntimeError("division by zero")
    return a / b


def _mod(a: object, b: object) -> Any:
    a, b = _num(a, "%"), _num(b, "%")
    if b == 0:
        raise ScriptRuntimeError("modulo by zero")
    return math.fmod(a, b) if isinstance(a, float) or isinstance(b, float) else a % b


def _neg(a: object) -> Any:
    return -_num(a, "-")


def _cond(v: object) -> bool:
    if isinstance(v, bool):
        return v
    if isinstance(v, (int, float)):
        return v != 0
    raise ScriptRuntimeError(f"a condition must be a boolean, got {v!r}")


def _index(i: object, n: int) -> int:
    if isinstance(i, bool) or not isinstance(i, (int, float)) or int(i) != i:
        raise ScriptRuntimeError(f"a list index must be an integer, got {i!r}")
    k = int(i)
    if not 0 <= k < n:
        raise ScriptRuntimeError(f"list index {k} out of range (length {n})")
    return k


def _idx(a: object, i: object) -> Any:
    if not isinstance(a, (list, str)):
        raise ScriptRuntimeError(f"only a list, a pose or a string can be indexed, got {a!r}")
    return a[_index(i, len(a))]


def _setidx(a: object, i: object, v: object) -> None:
    if not isinstance(a, list):
        raise ScriptRuntimeError(f"only a list or a pose element can be assigned, got {a!r}")
    a[_index(i, len(a))] = v


class _Thread:
    def __init__(self, handle: int, name: str, gen: Generator[None, None, Any]) -> None:
        self.handle, self.name, self.gen = handle, name, gen
        self.done = False


class Interpreter:
    """Runs a compiled program (``program.compiled``) on a controller, one period per step.

    The controller is seen through :class:`~ruledrobot.ursim.script.host.ProgramHost`;
    ``on_finish`` is called when the main program ends (a secondary program's runner
    passes its own, so that the primary program goes on).
    """

    def __init__(
        self,
        host: ProgramHost,
        program: Program,
        on_finish: Callable[[], None] | None = None,
    ) -> None:
        compiled = program.compiled
        if not isinstance(compiled, CompiledScript):
            raise TypeError("Interpreter: the program was not compiled (compile_script)")
        self.c = host
        self.program = program
        self.compiled = compiled
        #: called when the main program ends (default: the host's ``program_finished``)
        self.on_finish = on_finish if on_finish is not None else host.program_finished
        self.lib = Library(host, self)
        self._spin_count = 0
        self._next_handle = 1
        ns: dict[str, Any] = {
            "__name__": "urscript", "__builtins__": {}, "_rt": self, "_Pose": PoseValue,
            "_Halt": _Halt, "_cond": _cond, "_idx": _idx, "_setidx": _setidx, "_neg": _neg,
            "_add": _arith("+", operator.add), "_sub": _arith("-", operator.sub),
            "_mul": _arith("*", operator.mul), "_div": _div, "_mod": _mod, "_spin": self._spin,
        }  # fmt: skip
        ns.update(self.lib.namespace())
        ns.update(compiled.transpiled.tables)
        exec(compiled.code, ns)  # defines __main__ and the program's functions
        self.ns = ns
        self.main = _Thread(0, "main", self._body(ns["__main__"]()))
        self.threads: list[_Thread] = []
        self.finished = False

    # ------------------------------------------------------------ the program's threads
    def _body(self, gen: Generator[None, None, Any]) -> Generator[None, None, Any]:
        result = yield from gen
        yield from self.lib.flush()  # moves still pending when the thread ends run
        return result

    def run(self, fn: Callable[[], Generator[None, None, Any]], name: str) -> int:
        """``run name()``: start a thread; its handle."""
        h = self._next_handle
        self._next_handle += 1
        self.threads.append(_Thread(h, name, self._body(fn())))
        return h

    def _find(self, handle: object) -> _Thread | None:
        return next((t for t in self.threads if t.handle == handle), None)

    def join(self, handle: object) -> Generator[None, None, None]:
        """``join``: wait (in periods) until the thread ended."""
        t = self._find(handle)
        while t is not None and not t.done:
            yield

    def kill(self, handle: object) -> None:
        """``kill``: end the thread (its pending moves are dropped)."""
        t = self._find(handle)
        if t is not None and not t.done:
            t.done = True
            t.gen.close()

    def calls(self, table: list[Statement]) -> Generator[None, None, None]:
        """Run a table of bound literal calls (see :mod:`.transpile`), in order."""
        run = self.lib.run_bound
        for st in table:
            line = st.line  # read by :attr:`line` while the call waits
            try:
                yield from run(st)
            except (ScriptRuntimeError, MotionError) as exc:
                exc.us_line = line  # type: ignore[attr-defined]
                raise

    def _spin(self) -> None:
        self._spin_count += 1
        if self._spin_count > MAX_SPIN:
            raise ScriptRuntimeError(f"infinite loop detected: {MAX_SPIN} iterations in "
                                     "one control period without sync(), sleep() or a move")

    # ------------------------------------------------------------ stepping
    @property
    def line(self) -> int:
        """The URScript line the main program waits at (0 when done)."""
        if self.finished:
            return 0
        frame, table_line = _innermost(self.main.gen, Interpreter.calls.__code__)
        if table_line:
            return table_line
        return self.compiled.us_line(frame.f_lineno) if frame is not None else 0

    def step(self) -> None:
        """One control period: every live thread runs until it waits."""
        if self.finished:
            return
        self._spin_count = 0
        if not self._advance(self.main):
            self.finished = True
            self.close()
            self.on_finish()
            return
        for t in list(self.threads):
            if not t.done:
                self._spin_count = 0
                self._advance(t)
        self.threads = [t for t in self.threads if not t.done]

    def _advance(self, t: _Thread) -> bool:
        """Run thread ``t`` until it waits; False when it ended."""
        try:
            next(t.gen)
            return True
        except StopIteration:
            t.done = True
            return False
        except _Halt:
            t.done = True
            if t is not self.main:
                raise MotionError(f"line {self._error_line()}: halt") from None
            return False
        except CompileError as exc:  # a literal check at run time (cannot happen) - be clear
            raise MotionError(str(exc)) from None
        except (ScriptRuntimeError, MotionError) as exc:
            self.finished = True
            self.close()
            raise MotionError(f"line {self._error_line()}: {_message(exc)}") from None
        except (TypeError, ValueError, ArithmeticError, NameError, IndexError) as exc:
            self.finished = True
            self.close()
            raise MotionError(f"line {self._error_line()}: {_python_error(exc)}") from None

    def _error_line(self) -> int:
        exc = sys.exc_info()[1]
        if getattr(exc, "us_line", 0):
            return int(exc.us_line)  # type: ignore[union-attr]
        tb = sys.exc_info()[2]
        line = 0
        while tb is not None:
            if tb.tb_frame.f_code.co_filename == _FILENAME:
                line = self.compiled.us_line(tb.tb_lineno)
            tb = tb.tb_next
        return line

    def close(self) -> None:
        """End every thread and close the program's sockets."""
        for t in [self.main, *self.threads]:
            if not t.done:
                t.done = True
                t.gen.close()
        self.lib.close()


def _innermost(gen: Generator[Any, Any, Any], calls: types.CodeType
               ) -> tuple[types.FrameType | None, int]:  # fmt: skip
    """The innermost program frame a waiting thread is in, and the line of the table call
    it waits in (0 when none)."""
    frame = None
    g: Any = gen
    while g is not None:
        f = getattr(g, "gi_frame", None)
        if f is None:
            break
        if f.f_code.co_filename == _FILENAME:
            frame = f
        elif f.f_code is calls:
            return frame, int(f.f_locals.get("line", 0))
        g = getattr(g, "gi_yieldfrom", None)
    return frame, 0


def _message(exc: Exception) -> str:
    return str(exc)


def _python_error(exc: Exception) -> str:
    if isinstance(exc, NameError):
        name = str(exc).split("'")[1] if "'" in str(exc) else str(exc)
        name = name.removeprefix("u_")
        return (f"variable {name!r} is used before it is assigned (a function or thread "
                f"that assigns a program variable declares it: global {name})")
    if isinstance(exc, ZeroDivisionError):
        return "division by zero"
    return f"{type(exc).__name__}: {exc}"
