"""From a part to robot programs in one command (``ruledrobot make``, docs/make.md).

``make(cell, out)`` carves the cell's part (:mod:`ruledrobot.carve`), plans every setup
carve wrote (:mod:`ruledrobot.wirecut`, verified in MuJoCo), exports each setup's program
(:mod:`ruledrobot.export`), writes each setup's viewer file (:mod:`ruledrobot.view`) and
says what to do by hand between setups, into one folder swapped in whole::

    from ruledrobot.make import make
    result = make("cell.toml", "out/part")
    result.ok, [o.verdict.summary() for o in result.setups], result.hand

An application package beside carve, batch and view: it imports carve, the planner's
top-level names, export, view, io and robot; only the command line imports it.  Modules,
one job each: :mod:`.run` (the run), :mod:`.setups` (carve's setups, the operator's
steps), :mod:`.program` (cut.script), :mod:`.viewer` (view/setupN.html), :mod:`.restage`
(a setup's folder listed again, or stripped of what could run), :mod:`.summary`
(make.json), :mod:`.steps` and :mod:`.progress` (progress reports and their bars),
:mod:`.demo` (the demo's cell).
"""

from .run import MakeResult, make
from .steps import Step
from .summary import SetupOutcome

__all__ = ["MakeResult", "SetupOutcome", "Step", "make"]
