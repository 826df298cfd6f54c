"""``cut_reasons``: the plan's first stage alone, as carve asks it of every cut (issue 32)."""

from __future__ import annotations

from ruledrobot.wirecut import cut_reasons, load_job
from ruledrobot.wirecut.job.demo import DEMO_JOB
from ruledrobot.wirecut.plan import make_plan


def test_the_demo_cut_is_feasible_as_the_plan_finds_it(tmp_path):
    path = tmp_path / "job.toml"
    path.write_text(DEMO_JOB)
    job = load_job(path)
    assert cut_reasons(job) == {"cut": ""}
    plan = make_plan(job)
    assert all(p.feasible for p in plan.passes)  # the same model, the same answer


def test_the_demo_cut_1_m_on_is_out_of_reach_in_the_plans_words(tmp_path):
    path = tmp_path / "job.toml"
    path.write_text(DEMO_JOB.replace("[0.5, 0.0, 0.3", "[1.5, 0.0, 0.3"))
    job = load_job(path)
    (why,) = cut_reasons(job).values()
    plan = make_plan(job)
    assert "no continuous IK solution" in why
    assert why == "; ".join(plan.reasons)  # the plan says the same, word for word
