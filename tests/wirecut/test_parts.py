"""Parts, not one cut: jobs with several cuts, closed surfaces, kerf compensation, cut order,
the part's mesh.  Every measurement here is made independently of the planner: from the
sampled joints through forward kinematics, against the analytic surfaces."""

from __future__ import annotations

import json

import numpy as np
import pytest
from typer.testing import CliRunner

from ruledrobot.cli import app
from ruledrobot.geometry.surfaces import hyperbolic_paraboloid_residual
from ruledrobot.io.mesh import read_stl
from ruledrobot.robot.tool import BowTool
from ruledrobot.wirecut.job.demo import DEMO_JOB, PART_JOB
from ruledrobot.wirecut.job.load import load_job, parse_job
from ruledrobot.wirecut.planner import plan
from ruledrobot.wirecut.report.part_mesh import signed_volume

runner = CliRunner()


def _wire_segments(traj, tool) -> np.ndarray:
    """(M, 2, 3) the wire's ends in the base frame at every sample (FK of the samples)."""
    from ruledrobot.robot import model_for

    model = model_for(traj.meta).with_tool(np.eye(4))
    bow = BowTool.from_spec(tool)
    P = model.fk(traj.q)
    ends = np.stack([bow.wire_start, bow.wire_end])
    return np.einsum("mij,kj->mki", P[:, :3, :3], ends) + P[:, None, :3, 3]


@pytest.fixture(scope="module")
def part(tmp_path_factory):
    """The built-in part demo, planned and verified in MuJoCo by the CLI (about 15 s):
    the job, the trajectory read back from its files, the output folder."""
    from ruledrobot.io.trajectory import read_trajectory

    folder = tmp_path_factory.mktemp("part")
    job_path = folder / "part.toml"
    job_path.write_text(PART_JOB)
    res = runner.invoke(app, ["plan", str(job_path), "--out", str(folder / "out")])
    assert res.exit_code == 0, res.output
    assert "verdict: PASS" in res.output
    return load_job(job_path), read_trajectory(folder / "out" / "trajectory.csv"), folder / "out"


def _labels(traj) -> np.ndarray:
    labels = np.full(traj.n, "", dtype=object)
    for p in traj.meta.phases:
        labels[p.start : p.stop] = p.name
    return labels.astype(str)


def test_the_part_demo_plans_and_verifies_with_a_section_per_cut(part):
    _, traj, out = part
    report = json.loads((out / "report.json").read_text())
    assert [c["name"] for c in report["cuts"]] == ["top", "side", "plug"]
    plug = report["cuts"][2]
    assert plug["closed"] and plug["passes"] == 1 and plug["kerf_compensated"]
    assert all(c["kerf_compensated"] for c in report["cuts"])
    names = {c["name"] for c in report["verdict"]["checks"]}
    assert {"feed_min:plug", "wire_deviation:top", "kept_surface:side"} <= names
    assert report["collisions"] == []
    phases = [p.name for p in traj.meta.phases]
    assert phases.count("preheat") == 3 and "transit" in phases
    assert traj.meta.heat is not None and len(traj.meta.heat.windows) == 3


def test_transits_never_enter_the_stock(part):
    """The wire and the bow's rods, from the sampled joints, outside the stock wherever no
    pass is cutting (independently of the planner's clearance model)."""
    job, traj, _ = part
    moving = np.isin(_labels(traj), ("approach", "transit", "retract", "preheat"))
    wire = _wire_segments(traj, job.tool)
    assert not job.stock.segment_hits(wire[moving, 0], wire[moving, 1]).any()
    from ruledrobot.robot import model_for

    rods = BowTool.from_spec(job.tool).segments()  # (3, 2, 3) flange frame
    P = model_for(traj.meta).with_tool(np.eye(4)).fk(traj.q[moving])
    w = np.einsum("mij,kej->mkei", P[:, :3, :3], rods) + P[:, None, None, :3, 3]
    assert not job.stock.segment_hits(w[..., 0, :], w[..., 1, :]).any()


def test_the_kept_surface_lies_within_0_1_mm_of_the_target(part):
    """The 'top' cut: the sampled wire inside the stock lies kerf/2 from the analytic
    saddle z = x y / c (first-order distance), on the waste side (above it): the kerf it
    melts leaves the part's surface on the saddle."""
    job, traj, _ = part
    cut = job.cuts[0]
    first = next(p for p in traj.meta.phases if p.name == "cut")  # the 'top' cut's surface
    rows = np.arange(first.start, first.stop)
    wire = _wire_segments(traj, job.tool)[rows]
    t = np.linspace(0.0, 1.0, 41)
    pts = wire[:, None, 0] + t[None, :, None] * (wire[:, None, 1] - wire[:, None, 0])
    inside = job.stock.contains(pts.reshape(-1, 3)).reshape(pts.shape[:2])
    local = pts[inside] - np.array([0.5, 0.0, 0.335])  # the surface frame (identity rotation)
    d = -hyperbolic_paraboloid_residual(local, c=0.4)  # the residual is x y / c - z
    assert d.min() > 0.0  # the wire is above the saddle: in the waste (the part is below)
    error = np.abs(d - 0.5 * cut.kerf)
    assert error.max() < 1e-4, f"kept surface off by {error.max() * 1e3:.3f} mm"


def test_the_part_mesh_is_closed_and_inside_the_stock(part):
    job, _, out = part
    v, f, _ = read_stl(out / "part.stl")
    volume = signed_volume(v, f)
    assert 0.0 < volume < np.prod(job.stock.size)
    assert job.stock.contains(v, margin=1e-6).all()
    # closed and consistently oriented: every edge shared by two faces, in both directions
    edges = np.concatenate([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]])
    keys = {tuple(e) for e in edges.tolist()}
    assert all((b, a) in keys for a, b in keys)
    report = json.loads((out / "report.json").read_text())
    assert report["part"]["volume_m3"] == pytest.approx(volume)


def test_a_closed_column_plans_in_one_pass_or_splits_with_reasons(tmp_path):
    """A vertical-axis hyperboloid column in a tall block: the bow cannot go round under
    the block (the table), so the planner either finds a single pass or says why not."""
    text = DEMO_JOB.replace(
        '''builtin = "hyperbolic_paraboloid"
params = { c = 0.4 }
u = [-0.12, 0.12]          # rulings at x = u (m) in the surface frame
rulings = 9                # input rulings, refined below''',
        '''builtin = "hyperboloid"
params = { a = 0.05, c = 0.25 }
rulings = 16
closed = true''',
    ).replace("kerf = 0.0008", 'kerf = 0.0008\nkeep = "inside"')
    path = tmp_path / "column.toml"
    path.write_text(text)
    result = plan(load_job(path), None, simulate=False)
    report = result.report
    cut = report.get("cuts", [{}])[0] if "cuts" in report else None
    if result.plan.motion is None:  # no motion at all: the reasons say why
        assert report["reasons"] and any("roll" in r or "reach" in r or "IK" in r
                                         for r in report["reasons"])  # fmt: skip
    else:
        assert cut["closed"]
        notes = " ".join(cut["notes"])
        assert ("one pass round the loop" in notes) or ("two passes" in notes and "no single "
                                                        "pass" in notes)  # fmt: skip


def test_a_cut_through_a_freed_part_is_refused_naming_both_cuts(tmp_path):
    """The plug (closed, keep inside) first frees the part: a trim after it would cut a
    loose piece.  The order is refused before any planning, naming both cuts."""
    doc = __import__("tomllib").loads(PART_JOB)
    doc["cut"] = [doc["cut"][2], doc["cut"][0], doc["cut"][1]]  # plug first
    with pytest.raises(ValueError, match=r"cut 'top' comes after cut 'plug'.*list 'top' before"):
        from ruledrobot.wirecut.cut.order import check_cut_order

        check_cut_order(parse_job(doc, "order.toml"))


def test_a_hole_is_refused(tmp_path):
    doc = __import__("tomllib").loads(PART_JOB)
    doc["cut"][2]["keep"] = "outside"
    from ruledrobot.wirecut.cut.order import check_cut_order

    with pytest.raises(ValueError, match=r"cut 'plug': keep = \"outside\" \(a hole\)"):
        check_cut_order(parse_job(doc, "hole.toml"))


@pytest.mark.parametrize(
    ("edit", "message"),
    [
        (lambda d: d.update(surface={"builtin": "helicoid"}),
         r"\[surface\] with \[\[cut\]\] tables"),
        (lambda d: d["cut"][1].update(name="top"), r"name 'top' is used by an earlier cut"),
        (lambda d: d["cut"][0].update(keep="inside"), r"\[cut 'top'\] keep: \"inside\" needs a "
                                                      r"closed surface"),
        (lambda d: d["cut"][0].update(keep=[1, 2]), r"\[cut 'top'\] keep: expected a list of 3"),
        (lambda d: d["cut"][2]["surface"].update(builtin="torus"),
         r"\[cut 'plug'.surface\] builtin: unknown surface 'torus'"),
        (lambda d: d["tool"].update(heat={"output": "standard:9"}),
         r"\[tool.heat\] output: standard outputs are numbered 0..7"),
        (lambda d: d["tool"].update(heat={"output": "relay:0"}),
         r"\[tool.heat\] output: unknown output kind 'relay'"),
        (lambda d: d["tool"].update(heat={"output": "standard:0", "value": 0.5}),
         r"\[tool.heat\] value: only for an analog output"),
        (lambda d: d.update(cut=[]), r"\[\[cut\]\] is empty"),
    ],
)
def test_bad_part_jobs_name_the_cut_and_the_field(edit, message):
    doc = __import__("tomllib").loads(PART_JOB)
    edit(doc)
    with pytest.raises(ValueError, match=message):
        parse_job(doc, "part.toml")
