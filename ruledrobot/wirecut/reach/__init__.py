"""Reach: one margin model behind the plan's explanations, ``reach`` and ``place``.

* :mod:`.margins` — how far each configuration is from breaking a rule;
* :mod:`.grid` — the rulings x rolls x wire directions sampled;
* :mod:`.map` — the reachability map of a job;
* :mod:`.evaluate` — many placements scored at once (:mod:`.branch_bound`);
* :mod:`.explain` — why a plan found no path, in numbers;
* :mod:`.report` — ``reach.json``, ``reach.png`` and the text.
"""
