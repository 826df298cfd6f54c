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


def test_a_kerf_offset_that_cannot_hold_the_surface_is_named_as_the_verdict_would(tmp_path):
    """The demo's saddle with its part side named and a wire tolerance of 1 micrometre:
    the parallel kerf offset cannot follow the twist that closely; cut_reasons says so
    with the number the plan's kept_surface check measures (carve asks it of every cut:
    a loop whose offset cannot hold its face is not chosen)."""
    path = tmp_path / "job.toml"
    text = DEMO_JOB.replace("kerf = 0.0008", "kerf = 0.0008\nkeep = [0.5, 0.0, 0.2]\n"
                            "wire_tolerance = 0.000001")  # fmt: skip
    assert text != DEMO_JOB
    path.write_text(text)
    job = load_job(path)
    (why,) = cut_reasons(job).values()
    assert "the kept surface would lie" in why and "limit 0.001 mm" in why
    plan = make_plan(job)
    err = max(float(p.kerf_error.max()) for p in plan.passes if p.compensated)
    assert f"{err * 1e3:.3g} mm" in why  # the plan's own number
