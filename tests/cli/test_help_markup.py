"""Every command's ``--help`` shows its square brackets (issue 32): typer renders help
as rich markup, where ``[part]`` or ``[m]`` is a style tag and vanished ("... and the
, , , of a job"); help texts with such brackets go through ``cli._common.literal``."""

from __future__ import annotations

import itertools
import re

import typer
from typer.testing import CliRunner

from ruledrobot.cli import app


def _commands(command, path):
    yield path, command
    for name, sub in getattr(command, "commands", {}).items():
        yield from _commands(sub, [*path, name])


def test_every_bracket_of_every_help_text_is_shown():
    runner = CliRunner()
    eaten = {}
    commands = list(_commands(typer.main.get_command(app), []))
    assert len(commands) > 15
    for path, command in commands:
        texts = [command.help or "", command.epilog or ""]
        texts += [getattr(p, "help", None) or "" for p in command.params]
        out = runner.invoke(app, [*path, "--help"], env={"COLUMNS": "100"}).output
        flat = " ".join(re.sub("[│╭╮╰╯─]", " ", out).split())  # the panels' borders off
        lost = {m for t in texts for m in re.findall(r"\[[^\[\]]*\]", " ".join(t.split()))
                if m not in flat}  # fmt: skip
        if lost:
            eaten[" ".join(["ruledrobot", *path])] = sorted(lost)
    assert not eaten, eaten


def test_every_help_text_wraps_at_the_terminal_not_at_the_docstrings_lines():
    """At 80 columns no paragraph line of a command's description breaks short of the
    width before the paragraph ends (typer 0.29 printed a docstring's own line breaks:
    "... write each setup's program" / "(cut.script), ..." in an 80-column terminal)."""
    runner = CliRunner()
    short = {}
    for path, _ in _commands(typer.main.get_command(app), []):
        out = runner.invoke(app, [*path, "--help"], env={"COLUMNS": "80"}).output
        head = out.split("╭")[0].splitlines()[3:]  # the description, after the usage line
        for line, nxt in itertools.pairwise(head):
            text, follow = line.strip(), nxt.strip()
            if text and follow and not follow.startswith(("-", "*")) and len(text) < 55:
                short[" ".join(["ruledrobot", *path])] = text
    assert not short, short
