"""The job: what to cut, from what, with which robot and tool.

* :mod:`.spec` — the value types (surface, stock, robot, tool, cuts, job);
* :mod:`.load` — a job file (TOML) read and checked; :mod:`.sections` its tables;
* :mod:`.demo` — the built-in demo jobs;
* :mod:`.scene` — the MuJoCo scene of the job a trajectory names.
"""
