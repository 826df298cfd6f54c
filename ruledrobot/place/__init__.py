"""Where to put the block: an application of the planner, beside ``batch`` and ``view``.

* :mod:`.regions` — search regions, turns of the block, placements, moved jobs;
* :mod:`.search` — the placement search (scored by the planner's margin model,
  :mod:`ruledrobot.wirecut.reach.evaluate`) and the verification of the best;
* :mod:`.setups` — when no single placement serves every cut: turns of the block;
* :mod:`.job_file` — a job file written with the block moved (and, for setups, some
  of its cuts);
* :mod:`.plot`, :mod:`.run` — ``margin.png`` and ``ruledrobot place`` with its files.
"""
