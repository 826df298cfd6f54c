"""URScript parsed with lark: the grammar (``urscript.lark``), newlines inside brackets,
and syntax errors as :class:`~.program.CompileError` naming the line.

:func:`parse_tree` returns lark's tree of a program; :mod:`.transpile` turns it into
Python.  The grammar covers the language real programs use: ``def``/``sec``/``thread``
blocks closed by ``end``, ``if``/``elif``/``else``, ``while``, ``global``/``local``,
assignments to variables and list elements, ``return``, ``break``, ``continue``,
``halt``, ``run``/``join``/``kill``, ``enter_critical``/``exit_critical``, numbers,
strings, booleans, lists, poses ``p[...]``, calls with keyword arguments and the
operators ``or xor and not == != < <= > >= + - * / %``.  Comments (``#``) and
PolyScope's ``$ ...`` labels are skipped; a line may continue inside brackets.
"""

from __future__ import annotations

from collections.abc import Iterator
from functools import lru_cache
from importlib import resources

from lark import Lark, Token, Tree
from lark.exceptions import UnexpectedCharacters, UnexpectedEOF, UnexpectedInput, UnexpectedToken

from .program import CompileError

__all__ = ["parse_tree", "warm_up"]

_OPEN = frozenset({"LPAR", "LSQB", "POSE_OPEN"})
_CLOSE = frozenset({"RPAR", "RSQB"})


class _BracketNewlines:
    """Post-lexer: drops the newline tokens inside ``(...)`` and ``[...]`` (a call or a
    list written over several lines)."""

    always_accept = ("_NL",)

    def process(self, stream: Iterator[Token]) -> Iterator[Token]:
        depth = 0
        for tok in stream:
            if tok.type in _OPEN:
                depth += 1
            elif tok.type in _CLOSE:
                depth = max(0, depth - 1)
            elif tok.type == "_NL" and depth > 0:
                continue
            yield tok


@lru_cache(maxsize=1)
def _parser() -> Lark:
    grammar = resources.files(__package__).joinpath("urscript.lark").read_text("utf-8")
    # no propagate_positions (it doubles the time): statements keep a token with its line
    return Lark(grammar, parser="lalr", postlex=_BracketNewlines(), maybe_placeholders=True)


def warm_up() -> None:
    """Build the parser now (about 0.1 s, once per process).

    The emulator does it before its clock starts, so that the first program does not stall the
    clock."""
    _parser()


def _line_text(text: str, line: int) -> str:
    lines = text.splitlines()
    return lines[line - 1] if 1 <= line <= len(lines) else ""


def _expected(exc: UnexpectedInput) -> str:
    names = sorted(getattr(exc, "expected", None) or getattr(exc, "allowed", None) or [])
    words = {"_NL": "end of line", "RPAR": "')'", "RSQB": "']'", "LPAR": "'('", "COLON": "':'",
             "NAME": "a name", "END": "'end'", "EQUAL": "'='", "COMMA": "','"}  # fmt: skip
    shown = [words.get(n, n.lower() if n.isupper() else n) for n in names[:6]]
    return f"; expected {' or '.join(shown)}" if shown else ""


def parse_tree(text: str) -> Tree:
    """The parse tree of program ``text``; CompileError (line, text, reason) on a syntax error."""
    if not text.endswith("\n"):
        text += "\n"
    try:
        return _parser().parse(text)
    except UnexpectedEOF as exc:
        n = text.count("\n")
        raise CompileError(n, _line_text(text, n), "the program ends inside a block "
                           f"(a missing 'end'?){_expected(exc)}") from None  # fmt: skip
    except UnexpectedToken as exc:
        tok = exc.token
        if tok.type == "$END":
            n = text.count("\n")
            raise CompileError(n, _line_text(text, n), "the program ends inside a block "
                               "(a missing 'end'?)") from None  # fmt: skip
        line = int(tok.line or 1)
        shown = "end of line" if tok.type == "_NL" else repr(str(tok))
        raise CompileError(line, _line_text(text, line),
                           f"syntax error at {shown}{_expected(exc)}") from None  # fmt: skip
    except UnexpectedCharacters as exc:
        line = int(exc.line)
        raise CompileError(line, _line_text(text, line),
                           f"unexpected character {exc.char!r} (column {exc.column})") from None
    except UnexpectedInput as exc:  # pragma: no cover - the two above are lark's lexer/parser
        line = int(getattr(exc, "line", 1) or 1)
        raise CompileError(line, _line_text(text, line), f"syntax error: {exc}") from None
