"""URScript to Python: a parsed program (:mod:`.syntax`) becomes Python generator
functions that :class:`~.interpreter.Interpreter` steps once per control period.

Each URScript function and thread is a Python generator; a ``yield`` is the end of the
thread's share of one control period (``sync()``, a move, ``sleep``, ``servoj``, a socket
read that waits).  Calls of program functions are ``(yield from u_f(...))``, so a function
may block; the blocking built-ins are generators too (``b_name``), the others plain calls.
Names are prefixed (``u_x``) so that no URScript name meets a Python one.

Scopes follow URScript: the program's own variables (assigned at program level) are
globals of the generated module; in a function or thread a variable assigned without
``global`` is local.  A variable read where it is not defined anywhere, a call of an
unknown function, a pose literal without 6 values, a built-in called with literal
arguments it refuses (:func:`~.functions.bind`) and a secondary (``sec``) program that
moves are compile errors naming the line: nothing of such a program runs.

:func:`transpile` returns the Python source and the map from its lines to the URScript
lines (runtime errors and the current line are reported in URScript lines).
"""

from __future__ import annotations

import ast
from dataclasses import dataclass, field

from lark import Token, Tree

from .functions import FUNCTIONS, MOTION_FUNCTIONS, bind
from .library import BLOCKING, PURE
from .program import CompileError, Pose, Statement

__all__ = ["Transpiled", "transpile"]

_ARITH = {"+": "_add", "-": "_sub", "*": "_mul", "/": "_div", "%": "_mod"}
_NOT_LITERAL = object()


@dataclass
class Transpiled:
    """A program as Python.

    ``source``, the URScript line of each Python line (``lines[i]`` for line ``i + 1``), the
    main program's name and whether it is ``sec``."""

    source: str
    lines: list[int]
    name: str
    secondary: bool
    functions: list[str] = field(default_factory=list)
    threads: list[str] = field(default_factory=list)
    #: runs of literal calls, bound (``_T0``, ...: the runtime walks them)
    tables: dict[str, list[Statement]] = field(default_factory=dict)


class _Scope:
    """The names a function (or the program level) assigns, declares global, takes."""

    def __init__(self, params: list[str], level: bool) -> None:
        self.params = set(params)
        self.assigned: set[str] = set()
        self.globals: set[str] = set()
        self.level = level  # the program level: its assignments are globals


def _assigned_names(block: Tree, scope: _Scope) -> None:
    """Collect what a block assigns (not descending into nested defs and threads)."""
    for st in block.children:
        if not isinstance(st, Tree):
            continue
        d = st.data
        if d == "assign":
            tgt = st.children[0]
            if isinstance(tgt, Tree) and tgt.data == "var":
                scope.assigned.add(str(tgt.children[0]))
        elif d == "global_decl":
            scope.globals.add(str(st.children[0]))
            if st.children[1] is not None:
                scope.assigned.add(str(st.children[0]))
        elif d == "local_decl":
            scope.assigned.add(str(st.children[0]))
        elif d in ("if_stmt", "while_stmt"):
            for ch in st.children:
                if isinstance(ch, Tree):
                    if ch.data == "block":
                        _assigned_names(ch, scope)
                    elif ch.data in ("elif_part", "else_part"):
                        _assigned_names(ch.children[-1], scope)


class _Writer:
    def __init__(self, text: str) -> None:
        self.text_lines = text.splitlines()
        self.out: list[str] = []
        self.map: list[int] = []

    def emit(self, indent: int, code: str, line: int) -> None:
        self.out.append("    " * indent + code)
        self.map.append(line)

    def source_line(self, line: int) -> str:
        return self.text_lines[line - 1] if 1 <= line <= len(self.text_lines) else ""


class _Transpiler:
    def __init__(self, text: str, functions: dict, secondary: bool) -> None:
        self.w = _Writer(text)
        self.fn_specs = functions
        self.secondary = secondary
        self.user_functions: dict[str, Tree] = {}
        self.threads: dict[str, Tree] = {}
        self.program_globals: set[str] = set()
        self.scope: _Scope | None = None
        self.tables: dict[str, list[Statement]] = {}

    # ------------------------------------------------------------------ errors
    def error(self, node: Tree | Token, reason: str) -> CompileError:
        line = _line(node)
        return CompileError(line, self.w.source_line(line), reason)

    # ------------------------------------------------------------------ program
    def program(self, tree: Tree) -> tuple[str, list[Tree]]:
        """The main program's name and body statements (the one top-level def, or the
        top-level lines)."""
        stmts = [c for c in tree.children if isinstance(c, Tree)]
        defs = [s for s in stmts if s.data == "funcdef"]
        if len(stmts) == 1 and len(defs) == 1:
            main = defs[0]
            kw, name, params, block = main.children
            if params is not None:
                raise self.error(main, "the program's def takes no parameters")
            self.secondary = str(kw) == "sec"
            return str(name), list(block.children)
        return "", stmts

    def collect(self, body: list[Tree]) -> list[Tree]:
        """Program-level defs and threads (hoisted); the rest is the main body."""
        rest = []
        for st in body:
            if not isinstance(st, Tree):
                continue
            if st.data in ("funcdef", "threaddef"):
                name = str(st.children[1] if st.data == "funcdef" else st.children[0])
                if name in self.user_functions or name in self.threads:
                    raise self.error(st, f"{name} is defined twice")
                if name in self.fn_specs or name in BLOCKING or name in PURE:
                    raise self.error(st, f"{name} is a built-in function")
                if st.data == "funcdef" and str(st.children[0]) == "sec":
                    raise self.error(st, "a sec program cannot be defined inside another")
                (self.user_functions if st.data == "funcdef" else self.threads)[name] = st
            else:
                rest.append(st)
        return rest

    def run(self, tree: Tree) -> Transpiled:
        name, body = self.program(tree)
        main_body = self.collect(body)
        level = _Scope([], True)
        _assigned_names(Tree("block", main_body), level)
        self.program_globals = level.assigned | level.globals
        for fn in [*self.user_functions.values(), *self.threads.values()]:
            s = _Scope([], False)
            _assigned_names(fn.children[-1], s)
            self.program_globals |= s.globals
        for fname, fn in self.user_functions.items():
            self.function(fname, fn)
        for tname, th in self.threads.items():
            self.thread(tname, th)
        self.scope = level
        line = _line(tree.children[0]) if tree.children else 1
        self.w.emit(0, "def __main__():", line)
        names = sorted(self.program_globals)
        if names:
            self.w.emit(1, "global " + ", ".join(f"u_{n}" for n in names), line)
        self.w.emit(1, "if False: yield", line)
        self.block(main_body, 1)
        return Transpiled("\n".join(self.w.out) + "\n", self.w.map, name, self.secondary,
                          sorted(self.user_functions), sorted(self.threads),
                          self.tables)  # fmt: skip

    def function(self, name: str, fn: Tree) -> None:
        _kw, _name, params, block = fn.children
        plist: list[str] = []
        defaults: list[str] = []
        self.scope = _Scope([], False)
        if params is not None:
            for p in params.children:
                pname, default = str(p.children[0]), p.children[1]
                plist.append(pname)
                defaults.append(f"u_{pname}" + ("" if default is None else
                                                f"={self.expr(default)}"))  # fmt: skip
        self.scope = _Scope(plist, False)
        _assigned_names(block, self.scope)
        self.w.emit(0, f"def u_{name}({', '.join(defaults)}):", _line(fn))
        self.body(block, fn)

    def thread(self, name: str, th: Tree) -> None:
        self.scope = _Scope([], False)
        _assigned_names(th.children[-1], self.scope)
        self.w.emit(0, f"def u_{name}():", _line(th))
        self.body(th.children[-1], th)

    def body(self, block: Tree, node: Tree) -> None:
        assert self.scope is not None
        if self.scope.globals:
            self.w.emit(1, "global " + ", ".join(f"u_{n}" for n in sorted(self.scope.globals)),
                        _line(node))  # fmt: skip
        self.w.emit(1, "if False: yield", _line(node))
        self.block(list(block.children), 1)

    # ------------------------------------------------------------------ statements
    def block(self, stmts: list, indent: int) -> None:
        n = len(self.w.out)
        run: list[Statement] = []
        for st in stmts:
            if not isinstance(st, Tree):
                continue
            bound = self.literal_call(st)
            if bound is not None:
                run.append(bound)
                continue
            self.table(run, indent)
            run = []
            self.statement(st, indent)
        self.table(run, indent)
        if len(self.w.out) == n:
            self.w.emit(indent, "pass", self.w.map[-1] if self.w.map else 1)

    def literal_call(self, st: Tree) -> Statement | None:
        """A statement that calls a function of the table with literal arguments, bound
        now (CompileError when it cannot run); None for any other statement."""
        if st.data != "expr_stmt" or not isinstance(st.children[0], Tree):
            return None
        e = st.children[0]
        if e.data != "call":
            return None
        name = str(e.children[0])
        if name in self.user_functions or name not in self.fn_specs:
            return None
        arg_nodes = e.children[1].children if e.children[1] is not None else []
        if any(isinstance(a, Tree) and a.data == "kwarg" for a in arg_nodes[:-1]) and not all(
            isinstance(a, Tree) and a.data == "kwarg"
            for a in arg_nodes[next(i for i, a in enumerate(arg_nodes)
                                    if isinstance(a, Tree) and a.data == "kwarg"):]
        ):  # fmt: skip
            return None  # a positional argument after a keyword: call() says so
        vals = [_literal(a) for a in arg_nodes if not (isinstance(a, Tree) and a.data == "kwarg")]
        kvals = {str(a.children[0]): _literal(a.children[1]) for a in arg_nodes
                 if isinstance(a, Tree) and a.data == "kwarg"}  # fmt: skip
        if any(v is _NOT_LITERAL for v in [*vals, *kvals.values()]):
            return None
        if self.secondary and name in MOTION_FUNCTIONS:
            raise self.error(e, f"{name}(): a secondary (sec) program cannot move the arm "
                             "or wait")  # fmt: skip
        line = _line(e)
        bound = Statement(name, vals, kvals, line, self.w.source_line(line))
        bound.params = bind(bound, self.fn_specs)
        if name == "popup" and bound.params.get("blocking"):
            raise CompileError(line, bound.text, "popup(): a blocking popup is not emulated")
        return bound

    def table(self, run: list[Statement], indent: int) -> None:
        """Consecutive literal calls as one table the runtime walks (no Python per line:
        a program of 20,000 servoj lines compiles in a fraction of the time)."""
        if not run:
            return
        key = f"_T{len(self.tables)}"
        self.tables[key] = run
        self.w.emit(indent, f"yield from _rt.calls({key})", run[0].line)

    def statement(self, st: Tree, indent: int) -> None:
        d, line, emit = st.data, _line(st), self.w.emit
        if d in ("funcdef", "threaddef"):
            raise self.error(st, "a def or thread inside a function or block is not emulated "
                             "(define it at the program's level)")  # fmt: skip
        if d == "expr_stmt":
            emit(indent, self.expr(st.children[0]), line)
        elif d == "assign":
            tgt, value = st.children
            if isinstance(tgt, Tree) and tgt.data == "var":
                emit(indent, f"u_{tgt.children[0]} = {self.expr(value)}", line)
            elif isinstance(tgt, Tree) and tgt.data == "index":
                cont, idx = tgt.children
                emit(indent, f"_setidx({self.expr(cont)}, {self.expr(idx)}, {self.expr(value)})",
                     line)  # fmt: skip
            else:
                raise self.error(st, "only a variable or a list element can be assigned")
        elif d == "global_decl":
            if st.children[1] is not None:
                emit(indent, f"u_{st.children[0]} = {self.expr(st.children[1])}", line)
        elif d == "local_decl":
            emit(indent, f"u_{st.children[0]} = {self.expr(st.children[1])}", line)
        elif d == "return_stmt":
            v = st.children[0]
            emit(indent, "return" if v is None else f"return {self.expr(v)}", line)
        elif d == "break_stmt":
            emit(indent, "break", line)
        elif d == "continue_stmt":
            emit(indent, "continue", line)
        elif d == "halt_stmt":
            emit(indent, "raise _Halt()", line)
        elif d in ("enter_critical", "exit_critical"):
            emit(indent, "pass  # " + d, line)  # threads switch only where they wait
        elif d == "join_stmt":
            emit(indent, f"yield from _rt.join({self.expr(st.children[0])})", line)
        elif d == "kill_stmt":
            emit(indent, f"_rt.kill({self.expr(st.children[0])})", line)
        elif d == "if_stmt":
            _kw, cond, block, *rest = st.children
            emit(indent, f"if _cond({self.expr(cond)}):", line)
            self.block(list(block.children), indent + 1)
            for part in rest:
                if part is None:
                    continue
                if part.data == "elif_part":
                    emit(indent, f"elif _cond({self.expr(part.children[1])}):", _line(part))
                else:
                    emit(indent, "else:", _line(part))
                self.block(list(part.children[-1].children), indent + 1)
        elif d == "while_stmt":
            _kw, cond, block = st.children
            emit(indent, f"while _cond({self.expr(cond)}):", line)
            emit(indent + 1, "_spin()", line)
            self.block(list(block.children), indent + 1)
        else:  # pragma: no cover - the grammar has no other statement
            raise self.error(st, f"{d} is not emulated")

    # ------------------------------------------------------------------ expressions
    def expr(self, e: Tree | Token) -> str:
        if isinstance(e, Token):  # pragma: no cover - every atom is aliased
            raise self.error(e, f"unexpected {e!s}")
        d = e.data
        if d == "number":
            return repr(_number(str(e.children[0])))
        if d == "string":
            return repr(_string(str(e.children[0])))
        if d == "true":
            return "True"
        if d == "false":
            return "False"
        if d == "var":
            return self.var(e)
        if d == "list":
            items = e.children[0].children if e.children[0] is not None else []
            return "[" + ", ".join(self.expr(x) for x in items) + "]"
        if d == "numlist":
            return repr(_numbers(str(e.children[0])))
        if d == "numpose":
            vals = _numbers(str(e.children[0])[1:])
            if len(vals) != 6:
                raise self.error(e, f"a pose p[...] has 6 values, got {len(vals)}")
            return f"_Pose({vals!r})"
        if d == "pose":
            items = e.children[1].children if e.children[1] is not None else []
            if len(items) != 6:
                raise self.error(e, f"a pose p[...] has 6 values, got {len(items)}")
            return "_Pose([" + ", ".join(self.expr(x) for x in items) + "])"
        if d == "index":
            return f"_idx({self.expr(e.children[0])}, {self.expr(e.children[1])})"
        if d == "neg":
            return f"_neg({self.expr(e.children[0])})"
        if d in ("sum", "product"):
            ch = e.children
            out = self.expr(ch[0])
            for i in range(1, len(ch), 2):
                out = f"{_ARITH[str(ch[i])]}({out}, {self.expr(ch[i + 1])})"
            return out
        if d == "comparison":
            a, op, b = e.children
            return f"({self.expr(a)} {op} {self.expr(b)})"
        if d == "and_expr":
            return "(" + " and ".join(f"_cond({self.expr(x)})" for x in e.children) + ")"
        if d == "or_expr":
            return "(" + " or ".join(f"_cond({self.expr(x)})" for x in e.children) + ")"
        if d == "xor_expr":
            out = f"_cond({self.expr(e.children[0])})"
            for x in e.children[1:]:
                out = f"({out} != _cond({self.expr(x)}))"
            return out
        if d == "not_op":
            return f"(not _cond({self.expr(e.children[0])}))"
        if d == "call":
            return self.call(e)
        if d == "run_thread":
            name = str(e.children[0])
            if name not in self.threads:
                raise self.error(e, f"run {name}(): no thread {name} is defined")
            return f"_rt.run(u_{name}, {name!r})"
        raise self.error(e, f"{d} is not emulated")  # pragma: no cover

    def var(self, e: Tree) -> str:
        name = str(e.children[0])
        s = self.scope
        known = name in self.program_globals or (s is not None and (name in s.params or
                                                                    name in s.assigned))
        if not known:
            if name in self.user_functions or name in self.threads:
                raise self.error(e, f"{name} is a function: call it as {name}(...)")
            raise self.error(e, f"unknown variable {name!r} (not assigned anywhere)")
        return f"u_{name}"

    def call(self, e: Tree) -> str:
        name = str(e.children[0])
        arg_nodes = e.children[1].children if e.children[1] is not None else []
        pos: list[Tree] = []
        kws: list[tuple[str, Tree]] = []
        for a in arg_nodes:
            if isinstance(a, Tree) and a.data == "kwarg":
                kws.append((str(a.children[0]), a.children[1]))
            else:
                if kws:
                    raise self.error(e, f"{name}(): a positional argument after a keyword")
                pos.append(a)
        if name in self.user_functions:
            args = [self.expr(a) for a in pos] + [f"u_{k}={self.expr(v)}" for k, v in kws]
            return f"(yield from u_{name}({', '.join(args)}))"
        if name in self.threads:
            raise self.error(e, f"{name} is a thread: start it with 'run {name}()'")
        if self.secondary and name in MOTION_FUNCTIONS:
            raise self.error(e, f"{name}(): a secondary (sec) program cannot move the arm "
                             "or wait")  # fmt: skip
        if name in self.fn_specs:
            self.check_literal_call(e, name, pos, kws)
        args = [self.expr(a) for a in pos] + [f"{k}={self.expr(v)}" for k, v in kws]
        if name in BLOCKING or name in self.fn_specs:
            return f"(yield from b_{name}({', '.join(args)}))"
        if name in PURE:
            return f"b_{name}({', '.join(args)})"
        raise self.error(e, f"{name}() is not emulated (no such built-in, no such def)")

    def check_literal_call(self, e: Tree, name: str, pos: list, kws: list) -> None:
        """A call whose arguments are all literals is checked now (as before it ran)."""
        vals = [_literal(a) for a in pos]
        kvals = {k: _literal(v) for k, v in kws}
        if any(v is _NOT_LITERAL for v in [*vals, *kvals.values()]):
            # still check the names and the count of the arguments
            spec = self.fn_specs[name]
            names = [p.name for p in spec.params]
            if len(pos) > len(names):
                raise self.error(e, f"{name}() takes at most {len(names)} arguments, "
                                 f"got {len(pos)}")  # fmt: skip
            for k, _ in kws:
                if k not in names:
                    raise self.error(e, f"{name}() has no parameter {k!r}")
            return
        line = _line(e)
        st = Statement(name, vals, kvals, line, self.w.source_line(line))
        params = bind(st, self.fn_specs)
        if name == "popup" and params.get("blocking"):
            raise CompileError(line, st.text, "popup(): a blocking popup is not emulated")


# ---------------------------------------------------------------------- helpers


def _line(node: Tree | Token | None) -> int:
    """The line of a node: its first token's (every statement keeps one)."""
    if isinstance(node, Token):
        return int(node.line or 0)
    if isinstance(node, Tree):
        for ch in node.children:
            n = _line(ch)
            if n:
                return n
    return 0


def _number(text: str) -> int | float:
    if any(c in text for c in ".eE"):
        return float(text)
    return int(text)


def _numbers(text: str) -> list[int | float]:
    """The numbers of a list token ``[1, -2.5, 3e-3]``."""
    inner = text.strip()[1:-1]
    return [_number(x.strip()) for x in inner.split(",")] if inner.strip() else []


def _string(text: str) -> str:
    try:
        return str(ast.literal_eval(text))
    except (ValueError, SyntaxError):
        return text[1:-1]


def _literal(e: object) -> object:
    """The value of a literal argument as the argument checks take it (numbers as
    float), or ``_NOT_LITERAL``."""
    if not isinstance(e, Tree):
        return _NOT_LITERAL
    d = e.data
    if d == "number":
        return float(_number(str(e.children[0])))
    if d == "string":
        return _string(str(e.children[0]))
    if d in ("true", "false"):
        return d == "true"
    if d == "neg":
        v = _literal(e.children[0])
        return -v if isinstance(v, float) else _NOT_LITERAL
    if d == "numlist":
        return [float(x) for x in _numbers(str(e.children[0]))]
    if d == "numpose":
        return Pose(tuple(float(x) for x in _numbers(str(e.children[0])[1:])))
    if d in ("list", "pose"):
        holder = e.children[0] if d == "list" else e.children[1]
        items = [_literal(x) for x in (holder.children if holder is not None else [])]
        if any(not isinstance(x, float) for x in items):
            return _NOT_LITERAL
        return Pose(tuple(items)) if d == "pose" else items  # type: ignore[arg-type]
    return _NOT_LITERAL


def transpile(tree: Tree, text: str, *, max_payload: float | None = None) -> Transpiled:
    """Python for the parsed program ``tree`` of ``text``; CompileError when it cannot run.

    ``max_payload``: the arm's rated payload [kg] (bounds literal ``set_payload`` masses).
    """
    from .functions import _functions  # the table with this arm's payload bound

    specs = FUNCTIONS if max_payload is None else _functions(max_payload)
    return _Transpiler(text, specs, False).run(tree)
