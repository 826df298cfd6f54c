"""What every command shares: the typer app, the consoles, bad-input exits, the verdict table."""

from __future__ import annotations

import typer
from rich.console import Console

app = typer.Typer(
    name="ruledrobot",
    help="Robot motion planning on ruled surfaces: refine line sequences, plan, simulate, export.",
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
)
#: columns when the output is not a terminal (a log, a pipe, CI) and COLUMNS is not set:
#: rich's default of 80 folded a check table's rows into 4-5 lines each (issue 34)
PLAIN_WIDTH = 100


def _width(stream: object) -> int | None:
    import os

    isatty = getattr(stream, "isatty", None)
    if "COLUMNS" in os.environ or (isatty is not None and isatty()):
        return None  # rich's own: the terminal's width, or COLUMNS
    return PLAIN_WIDTH


console = Console(stderr=False, soft_wrap=True, width=_width(__import__("sys").stdout))
err = Console(stderr=True, soft_wrap=True, width=_width(__import__("sys").stderr))


def literal(text: str) -> str:
    """Return help text shown as written, its square brackets escaped.

    Typer renders help as rich markup, where ``[part]``, ``[m]`` or ``[default: ...]`` is a
    style tag and vanishes ("... and the , , , of a job"); square brackets that would read
    as tags are escaped.
    """
    from rich.markup import escape

    return escape(text)


def reflow_help(typer_app: typer.Typer) -> None:
    """Give every command of ``typer_app`` (and of its groups) its docstring as help, reflowed.

    Typer (0.29) prints the lines after a command's first paragraph as written, so a
    docstring wrapped at 95 columns broke mid-sentence in an 80-column terminal ("...
    setup's program" / "(cut.script), ..."). The lines of each paragraph are joined
    unless a line starts a list item (``-``, ``*``) or is indented (an example); rich
    wraps the rest to the terminal.
    """
    import inspect
    import re

    for info in typer_app.registered_commands:
        if info.help is None and info.callback is not None and info.callback.__doc__:
            doc = inspect.cleandoc(info.callback.__doc__)
            info.help = re.sub(r"(?<=\S)\n(?![-*\s])", " ", doc)
    for group in typer_app.registered_groups:
        if group.typer_instance is not None:
            reflow_help(group.typer_instance)


def numbers(text: str | None, option: str, n: int | None = None) -> list[float] | None:
    """Parse a comma-separated list of numbers.

    ``"a,b,c"`` -> floats (exactly ``n`` when given), or None for None; a ValueError
    names the option."""
    if text is None:
        return None
    try:
        values = [float(v) for v in text.replace(" ", "").split(",")]
    except ValueError:
        values = []
    if not values or (n is not None and len(values) != n):
        count = f"{n} " if n is not None else ""
        raise ValueError(f"{option}: expected {count}comma-separated numbers, got {text!r}")
    return values


def fail(message: str) -> typer.Exit:
    """Print a bad-input error literally (no markup: ``[cut]`` stays) and exit 2."""
    from rich.text import Text

    err.print(Text("error: ", style="bold red") + Text(str(message)), highlight=False)
    return typer.Exit(code=2)


def print_verdict(verdict, title: str) -> None:
    """The table of checks (value, limit, ok) and the verdict line, printed literally."""
    from rich.table import Table
    from rich.text import Text

    table = Table(title=title, title_justify="left", show_edge=False, pad_edge=False)
    # the label and long values fold when the screen is narrow (rich's own wrapping)
    table.add_column("check", justify="left", overflow="fold")
    for col in ("value", "limit"):
        table.add_column(col, justify="right", overflow="fold")
    table.add_column("ok", justify="left", no_wrap=True)
    for c in verdict.checks:
        mark = (Text("ok", style="green") if c.ok else Text("FAIL", style="bold red")) \
            if c.gating else Text("info", style="dim")
        table.add_row(Text(c.label), Text(c.value_text), Text(c.limit_text), mark)
    console.print(table)
    for c in verdict.failed:
        for line in c.detail.splitlines():
            err.print(Text(f"  {c.name}: ", style="bold red") + Text(line), highlight=False)
    style = "bold green" if verdict.ok else "bold red"
    word = "PASS" if verdict.ok else "FAIL"
    console.print(Text(f"verdict: {word} — {verdict.summary()}", style=style), highlight=False)


