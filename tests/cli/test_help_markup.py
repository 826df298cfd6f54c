"""Every command's ``--help`` shows its square brackets (issue 32): typer renders help
as rich markup, where ``[part]`` or ``[m]`` is a style tag and vanished ("... and the
, , , of a job"); help texts with such brackets go through ``cli._common.literal``."""

from __future__ import annotations

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
