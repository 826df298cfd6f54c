"""Hot-wire cutting: job files, the cut path, the time law, the planner.

Usage::

    from ruledrobot.wirecut import load_job, plan
    result = plan(load_job("job.toml"), "out/cut")
"""

from .cut.feasible import cut_reasons
from .job.load import Job, load_job, parse_job
from .job.spec import CutSpec
from .planner import PlanResult, plan
from .report.part_mesh import part_mesh, part_sdf, signed_volume, stock_mesh

__all__ = ["CutSpec", "Job", "PlanResult", "cut_reasons", "load_job", "parse_job", "part_mesh",
           "part_sdf", "plan", "signed_volume", "stock_mesh"]
