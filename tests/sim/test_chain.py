"""The serial chain of a line sequence: at q = 0 its joint axes are the input lines."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from ruledrobot.geometry.lines import Lines
from ruledrobot.geometry.ruled import RuledSurface
from ruledrobot.geometry.surfaces import helical_motion, sample_surface
from ruledrobot.io.lines import save_lines
from ruledrobot.sim import chain_mjcf, write_chain


def _axes(xml: str) -> tuple[mujoco.MjModel, mujoco.MjData]:
    m = mujoco.MjModel.from_xml_string(xml)
    d = mujoco.MjData(m)
    mujoco.mj_kinematics(m, d)
    return m, d


def _assert_axes_are_lines(d: mujoco.MjData, lines: Lines) -> None:
    n = len(lines)
    # direction (oriented) and a point on the line: the anchor's moment is the line's
    np.testing.assert_allclose(d.xaxis[:n], lines.direction, atol=1e-9)
    np.testing.assert_allclose(np.cross(d.xanchor[:n], lines.direction), lines.moment, atol=1e-9)


@pytest.mark.parametrize("seed", range(5))
def test_random_lines(seed):
    rng = np.random.default_rng(seed)
    n = int(rng.integers(2, 12))
    lines = Lines.from_point_direction(rng.normal(size=(n, 3)), rng.normal(size=(n, 3)))
    m, d = _axes(chain_mjcf(lines))
    assert m.njnt == n and m.nu == n
    _assert_axes_are_lines(d, lines)


def test_closed_helical_chain_returns_to_its_start():
    """Rulings of a closed helical surface (a skew line turned about z: the hyperboloid),
    and the chain's end site, placed by the closing DH row, is frame 0 again."""
    phi = 2 * np.pi * np.arange(10) / 10
    line = Lines.from_point_direction([[0.6, 0.0, 0.0]], [[0.0, 0.6, 0.8]]).plucker[0]
    from ruledrobot.geometry.lines import plucker_transform

    lines = Lines(plucker_transform(helical_motion(phi, 0.0), line))
    surf = RuledSurface(lines, closed=True)
    m, d = _axes(chain_mjcf(surf))
    _assert_axes_are_lines(d, lines)
    s = m.site("end").id
    np.testing.assert_allclose(d.site_xpos[s], surf.dh_frames()[0, :3, 3], atol=1e-9)
    np.testing.assert_allclose(d.site_xmat[s].reshape(3, 3), surf.dh_frames()[0, :3, :3], atol=1e-9)
    # every link has the same DH row: a helical chain
    rows = surf.dh_parameters()
    np.testing.assert_allclose(rows, np.broadcast_to(rows[0], rows.shape), atol=1e-9)


@pytest.mark.parametrize("name", ["helicoid", "helical_surface", "mobius_band", "cylindroid"])
def test_builtin_surfaces(name):
    s = sample_surface(name, n=16)
    surf = RuledSurface(s.lines, closed=s.closed)
    m, d = _axes(chain_mjcf(surf))
    _assert_axes_are_lines(d, s.lines)
    if surf.closed:
        # a Möbius band closes with a flip: the end frame is frame 0 turned by pi about x
        F = surf.dh_frames()[0] @ np.diag([1.0, -1.0, -1.0, 1.0] if surf.flip else [1.0] * 4)
        sid = m.site("end").id
        np.testing.assert_allclose(d.site_xmat[sid].reshape(3, 3), F[:3, :3], atol=1e-9)
        np.testing.assert_allclose(d.site_xpos[sid], F[:3, 3], atol=1e-9)


def test_chain_moves_about_its_lines():
    """Turning joint 0 by a quarter turn moves every later axis about line 0."""
    from ruledrobot.geometry.lines import plucker_transform
    from ruledrobot.geometry.se3 import pose_from_rotvec

    rng = np.random.default_rng(7)
    lines = Lines.from_point_direction(rng.normal(size=(5, 3)), rng.normal(size=(5, 3)))
    m = mujoco.MjModel.from_xml_string(chain_mjcf(lines))
    d = mujoco.MjData(m)
    d.qpos[0] = np.pi / 2
    mujoco.mj_kinematics(m, d)
    l0, p0 = lines.direction[0], lines.point[0]
    R = pose_from_rotvec(l0 * np.pi / 2)
    T = np.eye(4)
    T[:3, :3] = R[:3, :3]
    T[:3, 3] = p0 - R[:3, :3] @ p0
    moved = Lines(plucker_transform(T, lines.plucker))
    _assert_axes_are_lines(d, moved)


def test_write_chain(tmp_path):
    s = sample_surface("hyperboloid", n=8)
    src = save_lines(tmp_path / "hyp.json", s.lines, closed=True)
    out = write_chain(src, tmp_path / "out" / "chain.xml")
    assert out.exists()
    m, d = _axes(out.read_text())
    _assert_axes_are_lines(d, s.lines)
    assert m.site("end") is not None
    with pytest.raises(ValueError, match=r"missing\.json"):
        write_chain(tmp_path / "missing.json", tmp_path / "x.xml")
    assert not (tmp_path / "x.xml").exists()


def test_bad_input():
    with pytest.raises(ValueError, match="at least 2"):
        chain_mjcf(Lines.from_point_direction([[0, 0, 0]], [[0, 0, 1]]))
    with pytest.raises(ValueError, match="radius"):
        chain_mjcf(
            Lines.from_point_direction([[0, 0, 0], [1, 0, 0]], [[0, 0, 1], [0, 1, 0]]), radius=-1.0
        )
