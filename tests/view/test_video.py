"""The video of a real plan: the cut surface grows as the wire passes, a caption, a close-up."""

from __future__ import annotations

import numpy as np
import pytest

from ruledrobot.io.trajectory import read_trajectory
from ruledrobot.sim import Renderer, RenderUnavailable, Scene
from ruledrobot.sim.annotate import CutAnnotator
from ruledrobot.sim.render import frame_times
from ruledrobot.wirecut.job.load import load_job


def test_annotated_frames_show_the_cut_growing(plan_folder, tmp_path):
    job = load_job(plan_folder / "job.toml")
    traj = read_trajectory(plan_folder / "trajectory.csv")
    scene = Scene.from_job(job, robot=job.robot_model())
    times = frame_times(traj.t, 5.0)
    try:
        renderer = Renderer(scene, 320, 240)
    except RenderUnavailable as exc:  # pragma: no cover - CI installs Mesa EGL
        pytest.skip(f"no headless OpenGL here: {exc}")
    with renderer as r, CutAnnotator(r, traj.t, traj.q, times, traj.meta.phases) as ann:
        cut = np.flatnonzero(ann.labels == "cut")
        assert cut.size > 10 and ann.close is not None
        h, w = ann.close.height, ann.close.width
        k0, k1 = cut[1], cut[-1]
        qs = np.array([traj.q[np.searchsorted(traj.t, times[k] - 1e-9)] for k in (0, k0, k1)])
        first, early, late = (ann.frame(k, q) for k, q in zip((0, k0, k1), qs, strict=True))
        plain_early, plain_late = r.frame(qs[1]), r.frame(qs[2])
    assert first.shape == (240, 320, 3) and first.dtype == np.uint8
    # the caption band on top, in words
    assert (first[:8].astype(int) > 230).all(axis=-1).mean() > 0.9
    assert "approach" in ann.caption(0) and "wire outside the stock" not in ann.caption(k0)
    words = ann.caption(k1).split()
    assert "cut" in words and abs(float(words[words.index("feed") + 1]) - 40.0) < 2.0
    # what the annotation adds to the picture (cut surface swept so far, the trail, the
    # wire) grows during the cut; caption band and inset left out
    main = np.ones((240, 320), bool)
    main[:20] = False
    main[240 - h - 12 :, 320 - w - 12 :] = False

    def added(img, plain):
        return int(((np.abs(img.astype(int) - plain).max(axis=-1) > 30) & main).sum())

    assert added(late, plain_late) > added(early, plain_early) + 100
    # the close-up inset in the lower right corner during the cut, framed in white
    frame_px = late[240 - h - 10, 320 - w - 10 + 5 : 320 - 10]
    assert (frame_px > 250).all()
    assert not (first[240 - h - 10, 320 - w - 10 + 5 : 320 - 10] > 250).all()
