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
console = Console(stderr=False, soft_wrap=True)
err = Console(stderr=True, soft_wrap=True)


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
    for col in ("check", "value", "limit", "ok"):
        table.add_column(col, justify="right" if col in ("value", "limit") else "left")
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


