"""Forwarded execution: the plan's samples sent ahead of time to a URScript program that
plays them on the controller's clock (:mod:`.program`: the program, its settings and
messages; :mod:`.client`: the runner's side, in its child process).  docs/rtde.md,
"Forwarded execution"."""

from .program import ForwardSettings, State, forward_program

__all__ = ["ForwardSettings", "State", "forward_program"]
