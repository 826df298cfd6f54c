"""Commands on line sequences: refine, the paper's gallery, the chain of a surface."""

from __future__ import annotations

from enum import Enum
from pathlib import Path

import typer

from ._common import app, console, fail


class AlgorithmName(str, Enum):
    """Refinement algorithm of ``refine`` (``--algorithm``)."""
    projection = "projection"
    combined = "combined"
    dh = "dh"


class SchemeName(str, Enum):
    """Subdivision scheme of ``refine`` (``--scheme``)."""
    linear = "linear"
    chaikin = "chaikin"
    bspline3 = "bspline3"
    four_point = "four_point"
    six_point = "six_point"
    ternary_four_point = "ternary_four_point"


@app.command(
    epilog="Example:  ruledrobot refine lines.json --algorithm dh --scheme four_point "
    "--steps 4 --out refined.json --mesh refined.stl"
)
def refine(
    lines_file: Path = typer.Argument(..., help="Lines file (.json or .csv, ruledrobot.lines/1)."),
    out: Path = typer.Option(Path("refined.json"), "--out", "-o", help="Output .json or .csv."),
    algorithm: AlgorithmName = typer.Option(AlgorithmName.dh, help="Refinement algorithm."),
    scheme: SchemeName = typer.Option(SchemeName.four_point, help="Subdivision scheme."),
    steps: int = typer.Option(4, min=0, max=20, help="Number of subdivision steps."),
    closed: bool | None = typer.Option(
        None, "--closed/--open", help="Override the file's closed flag."
    ),
    w: float | None = typer.Option(None, help="four_point shape parameter (default 1/16)."),
    mu: float | None = typer.Option(None, help="ternary_four_point parameter (default 1/11)."),
    mesh: Path | None = typer.Option(
        None, help="Also write a triangle strip of the refined surface (.stl or .obj)."
    ),
    half_width: float = typer.Option(0.1, help="Half width (m) of the --mesh strip."),
) -> None:
    """Refine a discrete ruled surface (projection, combined or dh algorithm)."""
    import numpy as np

    from ..algorithms import refine as do_refine
    from ..geometry.ruled import RuledSurface
    from ..io.lines import read_lines_document, save_lines
    from ..io.paths import check_not_input

    params = {k: v for k, v in (("w", w), ("mu", mu)) if v is not None}
    try:
        for target in (out, mesh):
            if target is not None:
                check_not_input(target, lines_file)
        doc = read_lines_document(lines_file)
        is_closed = doc.closed if closed is None else closed
        surf = RuledSurface(doc.lines, closed=is_closed)
        res = do_refine(surf, algorithm.value, scheme.value, steps, **params)
        save_lines(
            out,
            res.lines,
            closed=res.closed,
            frames=res.frames if out.suffix.lower() == ".json" else None,
            striction=res.striction if out.suffix.lower() == ".json" else None,
        )
        if mesh is not None:
            from ..geometry.mesh import strip_mesh
            from ..io.mesh import write_obj, write_stl

            vertices, faces = strip_mesh(res.surface(), half_width=half_width)
            writer = {".stl": write_stl, ".obj": write_obj}.get(mesh.suffix.lower())
            if writer is None:
                raise ValueError(f"{mesh}: mesh must be .stl or .obj")
            writer(mesh, vertices, faces)
    except ValueError as exc:
        raise fail(str(exc)) from None
    kind = "closed with a flip" if res.flip else ("closed" if res.closed else "open")
    l = res.lines.plucker
    constraint = float(
        max(
            np.abs(np.linalg.norm(l[:, :3], axis=1) - 1).max(),
            np.abs((l[:, :3] * l[:, 3:]).sum(1)).max(),
        )
    )
    console.print(
        f"{len(doc.lines)} -> {len(res.lines)} rulings ({kind}), {algorithm.value}/{scheme.value}, "
        f"{steps} steps; line-manifold residual {constraint:.1e}"
    )
    console.print(f"wrote {out}")
    if mesh is not None:
        console.print(f"wrote {mesh}")


@app.command(epilog="Example:  ruledrobot gallery --out out/gallery")
def gallery(
    out: Path = typer.Option(Path("out/gallery"), "--out", "-o", help="Output folder."),
) -> None:
    """Run the paper's six examples, write PNGs and checks.json; exit 1 if a check fails."""
    from ..gallery import run_gallery

    with console.status("gallery") as status:
        result = run_gallery(out, progress=lambda msg: status.update(f"gallery: {msg}"))
    for ex in result["examples"]:
        ok = all(c["passed"] for c in ex["checks"])
        mark = "[green]ok[/]" if ok else "[bold red]FAILED[/]"
        console.print(f"{mark}  {ex['name']}  ({ex['algorithm']}/{ex['scheme']})")
        for c in ex["checks"]:
            console.print(
                f"      {c['name']}: {c['value']:.3g} (limit {c['limit']:.3g})", highlight=False
            )
    console.print(f"wrote {out}/checks.json and {len(result['examples'])} PNGs in {out}")
    if not result["passed"]:
        raise typer.Exit(code=1)


@app.command(epilog="Example:  ruledrobot chain lines.json --out chain.xml")
def chain(
    lines_file: Path = typer.Argument(..., help="Lines file (.json or .csv)."),
    out: Path = typer.Option(Path("chain.xml"), "--out", "-o", help="Output MJCF file."),
) -> None:
    """Write the serial chain whose joint axes are the given lines, as MuJoCo MJCF.

    At zero joint angles the joint axes coincide with the lines (the paper's view of
    a discrete ruled surface as the axes of a robot).
    """
    from ..io.paths import check_not_input
    from ..sim import write_chain

    try:
        check_not_input(out, lines_file)
        path = write_chain(lines_file, out)
    except ValueError as exc:
        raise fail(str(exc)) from None
    joints = path.read_text(encoding="utf-8").count("<joint name=")
    console.print(f"wrote {path}: a serial chain of {joints} hinge joints whose axes are the "
                  f"lines of {lines_file} (MuJoCo MJCF; load it with mujoco.MjModel.from_xml_path)",
                  highlight=False, markup=False)  # fmt: skip


