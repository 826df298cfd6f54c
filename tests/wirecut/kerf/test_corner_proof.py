"""Sharp corners of a compensated path, proved from closed forms on small plans (issue 33):
an open path turned by 90 and 120 degrees and a square loop, each with the part inside the
angle (convex corners) and outside it (concave), with the per-point model
(``constant_kerf``) and without ``[material]`` (the constant kerf).

Computed here from the trajectory's TCP columns, not by the planner's functions: the wire
is the TCP's z axis through its origin, its chord ends the points where it crosses the
block's faces ``y = -0.1`` and ``y = 0.1``; their speeds across the wire by central
differences in time; the kerf ``w = kerf_base + kerf_gain (p - p0) / v`` (``p`` the
``heat_power`` column), a wire melting nothing new (``p <= p0``) or standing (slower than
1 mm/s) keeping the channel it melted last (docs/kerf.md); without a material the cut's
``kerf``.  At every sample of the cut phase, at both ends: the face (the end moved half a
kerf towards the part) lies within the tolerance of the part's face beside it (the faces
as the test's own lines), the wire is never nearer the part than half a kerf less the
tolerance (no gouge), and at each corner the wire's ends reach the corner point of the
offset profile, ``C + h (a + b) / (1 + a . b)`` (``a``, ``b`` the faces' normals into
the waste, ``h`` half the kerf)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from ruledrobot.wirecut.cut.kerf_corners import MITRE_LIMIT
from ruledrobot.wirecut.job.load import load_job
from ruledrobot.wirecut.plan import make_plan

from .corners import ANALOG_CONSTANT_KERF, DIGITAL, Y0, Y1, Profile, corner, ell, square
from .panel import KERF, MATERIAL

KB, KG, P0 = MATERIAL["kerf_base"], MATERIAL["kerf_gain"], MATERIAL["power_threshold"]
TOL = 1e-4  # the cut's tolerance (the default)
BLOCK = ((0.47, 0.53), (0.25, 0.35))  # the block's x and z ranges


def _ends(traj):
    """(M, 2, 2) the chord ends' (x, z) at y = -0.1, 0.1 and (M, 2) their speeds across
    the wire."""
    p, z = traj.tcp[:, :3], Rotation.from_rotvec(np.array(traj.tcp[:, 3:])).as_matrix()[:, :, 2]
    ends = np.stack([p + ((y - p[:, 1]) / z[:, 1])[:, None] * z for y in (Y0, Y1)], axis=1)
    v = np.gradient(ends, traj.t, axis=0)
    v -= np.einsum("mki,mi->mk", v, z)[..., None] * z[:, None, :]
    return ends[..., [0, 2]], np.linalg.norm(v, axis=-1)


def _kerf(traj, v):
    """(M, 2) the kerf at the chord ends by the documented rule (module doc)."""
    if traj.heat_power is None:
        return np.full(v.shape, KERF)
    p = np.broadcast_to(np.asarray(traj.heat_power)[:, None], v.shape)
    melts = (p > P0 + 1e-9) & (v >= 1e-3)
    w = np.where(melts, KB + KG * (p - P0) / np.where(melts, v, 1.0), np.nan)
    last = np.maximum.accumulate(np.where(melts, np.arange(len(v))[:, None], -1), axis=0)
    return np.where(last >= 0, w[np.maximum(last, 0), [0, 1]], np.nan)


def _check(profile: Profile, traj, convex: bool) -> dict:
    q, v = _ends(traj)
    w = _kerf(traj, v)
    on = np.zeros(traj.n, dtype=bool)
    for ph in traj.meta.phases:
        on[ph.start:ph.stop] |= ph.name == "cut"
    (x0, x1), (z0, z1) = BLOCK
    on &= ((q[..., 0] > x0) & (q[..., 0] < x1) & (q[..., 1] > z0) & (q[..., 1] < z1)).all(axis=1)
    assert on.sum() > 200
    q, w = q[on], w[on]
    assert np.isfinite(w).all()
    a, b = profile.segments()
    n = profile.normals
    L = np.linalg.norm(b - a, axis=1)
    d = (b - a) / L[:, None]
    rel = q[:, :, None, :] - a  # (S, 2, F, 2)
    along = (rel * d).sum(-1)
    side = (rel * n).sum(-1)  # distance from each face's line, + into the waste
    beside = (along > -2.0 * w[..., None]) & (along < L + 2.0 * w[..., None])
    face = np.where(beside, np.abs(side - 0.5 * w[..., None]), np.inf).min(axis=2)
    foot = a + np.clip(along / L, 0.0, 1.0)[..., None] * (b - a)
    gap = np.linalg.norm(q[:, :, None, :] - foot, axis=-1).min(axis=2)
    if profile.closed:  # the part inside the loop: even-odd crossings of a ray in +x
        up = (a[:, 1] > q[..., None, 1]) != (b[:, 1] > q[..., None, 1])
        x = a[:, 0] + (q[..., None, 1] - a[:, 1]) * (b - a)[:, 0] / np.where(
            b[:, 1] == a[:, 1], 1.0, (b - a)[:, 1])  # fmt: skip
        in_part = (up & (x > q[..., None, 0])).sum(axis=2) % 2 == 1
    else:  # inside the angle (convex) or outside it (concave)
        in_part = (side < 0.0).all(axis=2) if convex else (side < 0.0).any(axis=2)
    # the offset profile's corner points, at the corners inside the block
    verts = profile.vertices
    reach = []
    for k in range(len(verts)) if profile.closed else range(1, len(verts) - 1):
        na, nb = n[k - 1], n[k % len(n)]
        X = verts[k] + 0.5 * KERF * (na + nb) / (1.0 + na @ nb)
        reach.append(np.linalg.norm(q - X, axis=-1).min(axis=0))
    return {"face": face.max(axis=0), "gouge": (0.5 * w - gap).max(axis=0),
            "in_part": in_part.any(), "reach": np.max(reach, axis=0)}


def _plan(profile: Profile):
    plan = make_plan(load_job(profile.job))
    assert plan.trajectory is not None, plan.reasons
    assert plan.motion.corner_stop.any()  # the wire stops at the corners in the block
    return plan.trajectory


def _assert_within(got: dict, traj) -> None:
    assert not got["in_part"]
    assert (got["face"] <= TOL).all(), got  # both ends
    assert (got["gouge"] <= TOL).all(), got
    assert (got["reach"] <= 2e-5).all(), got  # the wire at the corner point, both ends
    fe = traj.face_errors()["cut"]
    assert fe.ok, (fe.worst, fe.t)


@pytest.mark.parametrize("material", [True, False], ids=["constant_kerf", "no_material"])
@pytest.mark.parametrize("convex", [True, False], ids=["convex", "concave"])
@pytest.mark.parametrize("turn", [90.0, 120.0])
def test_a_corner_of_an_open_path_is_cut_to_the_offset_profiles_corner(
    tmp_path, turn, convex, material
):
    heat = ANALOG_CONSTANT_KERF if material else DIGITAL
    profile = corner(tmp_path, turn, convex, heat, material)
    traj = _plan(profile)
    _assert_within(_check(profile, traj, convex), traj)


@pytest.mark.parametrize("material", [True, False], ids=["constant_kerf", "no_material"])
@pytest.mark.parametrize("shape", ["square", "ell"])
def test_a_prism_loop_is_cut_to_its_offset_profile(tmp_path, shape, material):
    """A square prism (four convex corners) and an L-shaped one (five convex, one
    concave), the part inside."""
    heat = ANALOG_CONSTANT_KERF if material else DIGITAL
    profile = (square if shape == "square" else ell)(tmp_path, heat, material)
    traj = _plan(profile)
    _assert_within(_check(profile, traj, True), traj)


def test_on_off_heat_burns_at_a_corner_stop_and_says_what_to_do(tmp_path):
    """With [material] the wire's power while on stays while it stops at a corner: a burn
    (face_error inf), whose message names the fix."""
    from ruledrobot.wirecut.report.outcome import plan_outcome

    profile = corner(tmp_path, 90.0, True, DIGITAL, True)
    plan = make_plan(load_job(profile.job))
    _, verdict = plan_outcome(plan, None)
    check = verdict["face_error"]
    assert check.gating and not check.ok and check.value == float("inf")
    assert "at a corner stop" in check.detail
    assert 'mode = "constant_kerf" on an analog output' in check.detail


@pytest.mark.parametrize("turn", [170.0, 177.0])
def test_a_wedge_past_the_mitre_limit_is_cut_back_and_face_error_fails_it(tmp_path, turn):
    """A thin wedge (the part inside a turn of 170 or 177 degrees, no material): up to the
    mitre limit (a turn of ``2 arccos(1 / 25)``, 175.4 degrees) the wire reaches the corner
    point; past it the point is held to 25 half kerfs along the bisector, so the kerf cuts
    the tip back by ``h - 25 h sin(psi / 2)`` (``psi`` the wedge's angle; 0.138 mm at 3
    degrees, 0.4 mm half kerf), and ``face_error`` (the gating check) says so: not within
    the tolerance."""
    profile = corner(tmp_path, turn, True, DIGITAL, False)
    plan = make_plan(load_job(profile.job))
    fe = plan.measured.faces["cut"]
    h, psi = 0.5 * KERF, np.radians(180.0 - turn)
    if turn > np.degrees(2.0 * np.arccos(1.0 / MITRE_LIMIT)):
        assert fe.worst == pytest.approx(h - MITRE_LIMIT * h * np.sin(0.5 * psi), abs=2e-6)
        assert not fe.ok
    else:
        assert fe.worst <= 2e-6 and fe.ok
