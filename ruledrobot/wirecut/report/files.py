"""Writing a planned job: the files of ``docs/verdict.md``, into a staging folder that
replaces the output folder as a whole (:class:`~ruledrobot.io.outdir.StagedFolder`).

A plan whose verdict fails leaves its report, its plots and the simulation's report
— and no trajectory: nothing of an earlier plan in that folder stays runnable.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ...geometry import se3
from ...geometry.lines import Lines
from ...geometry.mesh import Mesh, box_clipped_mesh
from ...io.atomic import atomic_write_bytes, atomic_write_json
from ...io.lines import save_lines
from ...io.mesh import write_stl
from ...io.outdir import StagedFolder
from ...io.trajectory import write_trajectory
from ...robot.verdict import Verdict
from ..cut.wire_geometry import chords
from ..plan import Plan, job_source_bytes
from ..verify import Verification
from .part_mesh import RESOLUTION, part_mesh, signed_volume
from .plots import plot_plan

__all__ = ["surface_mesh", "write_plan"]

#: grid step of the part drawn in the video [m] (a lighter mesh than part.stl)
VIDEO_RESOLUTION = 0.005


def _lines_of(frames: np.ndarray) -> Lines:
    z, o = frames[:, :3, 2], frames[:, :3, 3]
    return Lines(np.concatenate([z, np.cross(o, z)], axis=1))


#: sub-rulings per interval where the surface enters or leaves the block (surface.stl)
EDGE_SUBDIVISION = 32


def _with_edge_rulings(frames: np.ndarray, stock) -> np.ndarray:
    """``frames`` (M, 4, 4) with :data:`EDGE_SUBDIVISION` - 1 screw-geodesic frames added
    in every interval where one ruling crosses the block and the next does not, so that
    the meshed surface reaches the block's faces where the wire does (within 1/32 of a
    ruling interval) rather than stopping at the last ruling inside."""
    _, _, hit = chords(frames, stock)
    edge = np.flatnonzero(hit[:-1] != hit[1:])
    if not edge.size:
        return frames
    f = np.arange(1, EDGE_SUBDIVISION) / EDGE_SUBDIVISION
    sub = se3.geodesic(frames[edge, None], frames[edge + 1, None], f[None, :])  # (E, k, 4, 4)
    key = np.r_[np.arange(len(frames), dtype=float), (edge[:, None] + f[None, :]).ravel()]
    allf = np.concatenate([frames, sub.reshape(-1, 4, 4)])
    return allf[np.argsort(key, kind="stable")]


def surface_mesh(plan: Plan) -> Mesh | None:
    """Return the target surfaces of every pass inside the stock as one mesh, or None.

    In [m, base frame] (``surface.stl``, drawn in ``plots.png`` when no cut names its kept
    side); None when no pass crosses the block.
    """
    verts, faces, n = [], [], 0
    job = plan.job
    for cp in plan.passes:
        frames = _with_edge_rulings(cp.target_frames, job.stock)
        mesh = box_clipped_mesh(_lines_of(frames), job.stock.centre, job.stock.size,
                                job.stock.rotation)  # fmt: skip
        if len(mesh.faces):
            verts.append(mesh.vertices)
            faces.append(mesh.faces + n)
            n += len(mesh.vertices)
    return Mesh(np.concatenate(verts), np.concatenate(faces)) if verts else None


def _surfaces(folder: Path, plan: Plan, surface: Mesh | None) -> dict[str, Path]:
    """``refined.json`` (the wire's rulings and frames of every pass, one after the
    other) and ``surface.stl`` (``surface``: the target surfaces inside the stock)."""
    files: dict[str, Path] = {}
    F = np.concatenate([cp.frames for cp in plan.passes])
    files["refined"] = save_lines(folder / "refined.json", _lines_of(F), frames=F)
    if surface is not None:
        files["surface"] = write_stl(folder / "surface.stl", surface.vertices, surface.faces)
    return files


def write_plan(
    stage: StagedFolder,
    plan: Plan,
    ver: Verification | None,
    report: dict,
    verdict: Verdict,
    video: bool = False,
) -> dict[str, Path]:
    """Write the plan's files into ``stage`` (not yet committed); return them by name.

    ``report`` gains the write time and, when the video cannot be made, a note.
    """
    folder = stage.path
    files: dict[str, Path] = {}
    if plan.motion is not None:
        ok = verdict.ok
        if ok:
            files["trajectory"] = write_trajectory(folder / "trajectory.csv", plan.trajectory)
            files["trajectory_meta"] = folder / "trajectory.json"
        surface = surface_mesh(plan)
        files.update(_surfaces(folder, plan, surface))
        part = part_mesh(plan.job, plan.passes)
        if part is not None:
            files["part"] = write_stl(folder / "part.stl", part.vertices, part.faces,
                                      header="ruledrobot part (the stock after every cut), m")
            volume = signed_volume(part.vertices, part.faces)
            report["part"] = {
                "file": "part.stl", "volume_m3": volume,
                "removed_m3": float(np.prod(plan.job.stock.size)) - volume,
                "triangles": len(part.faces), "grid_step_m": RESOLUTION,
                "cuts_without_keep": [c.name for c in plan.job.cuts if c.keep is None],
            }  # fmt: skip
        files["plots"] = plot_plan(folder / "plots.png", plan, part, surface)
        if ver is not None:
            sim = ver.playback.write(folder / "simulation", trajectory=ok)
            files.update({f"simulation_{k}": v for k, v in sim.items()})
            if video and ok:
                from ...sim import RenderUnavailable, Scene, render_video

                try:
                    coarse = part_mesh(plan.job, plan.passes, VIDEO_RESOLUTION)
                    scene = Scene.from_job(plan.job, robot=plan.model, bow=plan.bow,
                                           part=coarse)
                    mo = plan.motion
                    files["video"] = render_video(scene, folder / "video.mp4", mo.timed.t,
                                                  ver.playback.q,
                                                  phases=plan.trajectory.meta.phases)  # fmt: skip
                except RenderUnavailable as exc:
                    report.setdefault("notes", []).append(f"no video: {exc}")
    if video and not verdict.ok:
        report.setdefault("notes", []).append(
            "no video: the plan fails (--video renders the cut of a plan that passes; "
            "plots.png and report.json show this one)")
    files["report"] = atomic_write_json(folder / "report.json", report)  # fmt: skip
    data = plan.source_bytes if plan.source_bytes is not None else job_source_bytes(plan.job)
    if data is not None:  # the bytes the plan read (and hashed) once
        files["job"] = atomic_write_bytes(folder / "job.toml", data)
    return files
