"""What a plan says and writes.

* :mod:`.verdict` — every measurement as a check, and the verdict;
* :mod:`.outcome` — ``report.json``;
* :mod:`.files` — the plan's files, staged and replaced whole;
* :mod:`.plots` — ``plots.png``; :mod:`.part_mesh` — ``part.stl``.
"""
