"""The URScript functions of the controller's motion, IO and message table: their
signatures and argument checks.

:func:`bind` checks a call's arguments by kind and range — digital output pins 0-7, tool
pins 0-1, analog values 0-1, servoj lookahead 0.03-0.2 s and gain 100-2000, the payload
mass — and returns the call's parameters by name with defaults filled in.  The
interpreter (:mod:`.library`) binds every call of these functions when it runs (a bad
value is a runtime error naming the line); :mod:`.transpile` binds the calls whose
arguments are all literals when the program compiles, so that such a program is refused
whole before anything moves, as before variables existed.

Units: metres, radians, seconds, kilograms; analog outputs as a fraction
0..1 of their range (URScript ``set_standard_analog_out``).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

from .program import CompileError, Pose, Statement

__all__ = ["FUNCTIONS", "MOTION_FUNCTIONS", "Param", "bind"]

_REQUIRED = object()
_INT32 = (-(1 << 31), (1 << 31) - 1)


class _BadArgument(ValueError):
    """One argument is wrong (the message says which and why)."""


def _number(name: str, v: object) -> float:
    if isinstance(v, bool) or not isinstance(v, float):
        raise _BadArgument(f"{name} must be a number, got {_show(v)}")
    if not math.isfinite(v):
        raise _BadArgument(f"{name} must be a finite number, got {v}")
    return v


def _show(v: object) -> str:
    if isinstance(v, Pose):
        return f"p{list(v.values)}"
    return repr(v)


@dataclass(frozen=True)
class Param:
    """One parameter: ``kind`` says what it accepts, ``lo``/``hi`` bound numbers.

    Kinds: ``number``; ``int`` (an integral number, e.g. a pin); ``bool``
    (True/False); ``vector3`` / ``vector6`` (lists of finite numbers);
    ``pose`` (``p[...]`` or a list of 6); ``target`` (a joint list or a pose,
    as movej/movel take); ``text`` (a string or a number, as textmsg prints).
    """

    name: str
    kind: str
    default: object = _REQUIRED
    lo: float | None = None
    hi: float | None = None
    unit: str = ""

    def check(self, v: object) -> object:
        """The checked value (ints as int, vectors as tuples of float)."""
        k = self.kind
        if k == "bool":
            if not isinstance(v, bool):
                raise _BadArgument(f"{self.name} must be True or False, got {_show(v)}")
            return v
        if k == "text":
            if isinstance(v, (str, float, bool)):
                return v
            raise _BadArgument(f"{self.name} must be a string or a number, got {_show(v)}")
        if k in ("number", "int"):
            x = _number(self.name, v)
            if k == "int" and not x.is_integer():
                raise _BadArgument(f"{self.name} must be an integer, got {x:g}")
            self._range(x)
            return int(x) if k == "int" else x
        return self._vector(v)

    def _range(self, x: float) -> None:
        lo, hi = self.lo, self.hi
        if (lo is not None and x < lo) or (hi is not None and x > hi):
            if self.kind == "int":
                span = f"{lo:g}..{hi:g}" if hi != _INT32[1] else "int32"
            else:
                span = f"[{lo:g}, {hi:g}]" if hi is not None else f">= {lo:g}"
            unit = f" {self.unit}" if self.unit else ""
            raise _BadArgument(f"{self.name} must be in {span}{unit}, got {x:g}")

    def _vector(self, v: object) -> object:
        n = 3 if self.kind == "vector3" else 6
        is_pose = isinstance(v, Pose)
        if is_pose and self.kind in ("vector3", "vector6"):
            raise _BadArgument(f"{self.name} must be a list of {n} numbers, got a pose")
        vals = v.values if isinstance(v, Pose) else v
        if not isinstance(vals, (list, tuple)) or len(vals) != n:
            what = "a pose p[...] or a list" if self.kind in ("pose", "target") else "a list"
            raise _BadArgument(f"{self.name} must be {what} of {n} numbers, got {_show(v)}")
        out = tuple(_number(self.name, x) for x in vals)
        if self.kind == "pose":
            return Pose(out)
        if self.kind == "target":
            return Pose(out) if is_pose else out
        return out


@dataclass(frozen=True)
class Function:
    """A URScript function the emulator runs: its parameters in positional order."""

    name: str
    params: tuple[Param, ...]
    check: Callable[[dict[str, object]], None] | None = None


def _p(name: str, kind: str, default: object = _REQUIRED, lo: float | None = None,
       hi: float | None = None, unit: str = "") -> Param:  # fmt: skip
    return Param(name, kind, default, lo, hi, unit)


def _no_move_time(args: dict[str, object]) -> None:
    if args.get("t", 0.0) != 0.0:
        raise _BadArgument("t (a move given by its duration) is not emulated; give a and v")


def _payload_mass(max_mass: float | None) -> Callable[[dict[str, object]], None]:
    def check(args: dict[str, object]) -> None:
        m = args["m"]
        assert isinstance(m, float)
        if m < 0.0 or (max_mass is not None and m > max_mass):
            top = f"{max_mass:g} kg (the arm's rated payload)" if max_mass is not None else "inf"
            raise _BadArgument(f"mass must be in [0, {top}], got {m:g} kg")

    return check


def _functions(max_payload: float | None) -> dict[str, Function]:
    pin8 = (0, 7)
    payload = _payload_mass(max_payload)
    pos = {"lo": 0.0, "unit": "m/s^2"}
    fns = [
        Function("movej", (_p("q", "target"), _p("a", "number", 1.4, **pos),
                           _p("v", "number", 1.05, 0.0), _p("t", "number", 0.0, 0.0),
                           _p("r", "number", 0.0, 0.0, unit="m")), _no_move_time),
        Function("movel", (_p("pose", "target"), _p("a", "number", 1.2, **pos),
                           _p("v", "number", 0.25, 0.0), _p("t", "number", 0.0, 0.0),
                           _p("r", "number", 0.0, 0.0, unit="m")), _no_move_time),
        Function("movep", (_p("pose", "target"), _p("a", "number", 1.2, **pos),
                           _p("v", "number", 0.25, 0.0), _p("r", "number", 0.0, 0.0, unit="m"))),
        Function("servoj", (_p("q", "vector6"), _p("a", "number", 0.0), _p("v", "number", 0.0),
                            _p("t", "number", 0.002, 0.0, unit="s"),
                            _p("lookahead_time", "number", 0.1, 0.03, 0.2, "s"),
                            _p("gain", "number", 300.0, 100.0, 2000.0))),
        Function("speedj", (_p("qd", "vector6"), _p("a", "number", lo=0.0, unit="rad/s^2"),
                            _p("t", "number", 0.0, 0.0, unit="s"))),
        Function("stopj", (_p("a", "number", lo=0.0, unit="rad/s^2"),)),
        Function("stopl", (_p("a", "number", lo=0.0, unit="m/s^2"),
                           _p("aRot", "number", 0.0, 0.0))),
        Function("sleep", (_p("t", "number", lo=0.0, unit="s"),)),
        Function("sync", ()),
        Function("textmsg", (_p("s1", "text"), _p("s2", "text", ""))),
        Function("popup", (_p("s", "text"), _p("title", "text", "Popup"),
                           _p("warning", "bool", False), _p("error", "bool", False),
                           _p("blocking", "bool", False))),
        Function("set_tcp", (_p("pose", "pose"),)),
        Function("set_payload", (_p("m", "number", unit="kg"), _p("cog", "vector3", None)),
                 payload),
        Function("set_target_payload", (_p("m", "number", unit="kg"), _p("cog", "vector3"),
                                        _p("inertia", "vector6", (0.0,) * 6),
                                        _p("transition_time", "number", 0.0, 0.0, unit="s")),
                 payload),
        Function("set_payload_mass", (_p("m", "number", unit="kg"),), payload),
        Function("set_payload_cog", (_p("CoG", "vector3"),)),
        Function("write_output_integer_register",
                 (_p("address", "int", lo=0, hi=47), _p("value", "int", lo=_INT32[0],
                                                         hi=_INT32[1]))),
        Function("write_output_float_register",
                 (_p("address", "int", lo=0, hi=47), _p("value", "number"))),
        Function("write_output_boolean_register",
                 (_p("address", "int", lo=0, hi=127), _p("value", "bool"))),
        Function("set_standard_digital_out", (_p("n", "int", lo=pin8[0], hi=pin8[1]),
                                              _p("b", "bool"))),
        Function("set_configurable_digital_out", (_p("n", "int", lo=pin8[0], hi=pin8[1]),
                                                  _p("b", "bool"))),
        Function("set_tool_digital_out", (_p("n", "int", lo=0, hi=1), _p("b", "bool"))),
        # deprecated (CB3) name: 0-7 standard, 8-9 the tool outputs
        Function("set_digital_out", (_p("n", "int", lo=0, hi=9), _p("b", "bool"))),
        Function("set_standard_analog_out", (_p("n", "int", lo=0, hi=1),
                                             _p("f", "number", lo=0.0, hi=1.0))),
        Function("set_analog_out", (_p("n", "int", lo=0, hi=1),
                                    _p("f", "number", lo=0.0, hi=1.0))),
    ]  # fmt: skip
    return {f.name: f for f in fns}


#: the functions a standalone program may call (argument checks without a payload limit)
FUNCTIONS: dict[str, Function] = _functions(None)

#: the functions that move the arm or block the program (not allowed in ``sec`` programs)
MOTION_FUNCTIONS = frozenset(
    {"movej", "movel", "movep", "servoj", "speedj", "stopj", "stopl", "sleep", "sync"}
)


def bind(st: Statement, functions: dict[str, Function] = FUNCTIONS) -> dict[str, object]:
    """The checked parameters of call ``st`` by name; CompileError when it cannot run."""
    fn = functions.get(st.name)
    if fn is None:
        raise CompileError(st.line, st.text, f"{st.name}() is not emulated")
    names = [p.name for p in fn.params]
    if len(st.args) > len(names):
        raise CompileError(st.line, st.text, f"{st.name}() takes at most {len(names)} "
                           f"arguments, got {len(st.args)}")  # fmt: skip
    given: dict[str, object] = dict(zip(names, st.args, strict=False))
    for key, v in st.kwargs.items():
        if key not in names:
            raise CompileError(st.line, st.text, f"{st.name}() has no parameter {key!r}")
        if key in given:
            raise CompileError(st.line, st.text, f"{st.name}(): {key} given twice")
        given[key] = v
    out: dict[str, object] = {}
    try:
        for p in fn.params:
            if p.name in given:
                out[p.name] = p.check(given[p.name])
            elif p.default is _REQUIRED:
                raise _BadArgument(f"missing argument {p.name}")
            else:
                out[p.name] = p.default
        if fn.check is not None:
            fn.check(out)
    except _BadArgument as exc:
        raise CompileError(st.line, st.text, f"{st.name}(): {exc}") from None
    return out
