"""The house rules on the import graph: no circles, every layer imports only downward,
and ``import ruledrobot`` stays light.  ``docs/architecture.md`` draws the same picture."""

from __future__ import annotations

import subprocess
import sys

from .imports import ROOT, cycles, graph

#: Each sub-package and the packages it may import (besides itself).  Lower layers
#: first; a package never names one above it.  Keep in step with docs/architecture.md.
ALLOWED: dict[str, set[str]] = {
    "geometry": set(),
    "protocol": set(),
    "subdivision": {"geometry"},
    "algorithms": {"geometry", "subdivision"},
    "robot": {"geometry", "protocol"},
    "io": {"geometry", "robot"},
    "sim": {"geometry", "io", "robot"},
    "export": {"geometry", "io", "protocol", "robot"},
    "ursim": {"geometry", "io", "protocol", "robot", "sim"},
    "gallery": {"algorithms", "geometry", "io", "subdivision"},
    "wirecut": {"algorithms", "geometry", "io", "robot", "sim", "subdivision"},
    "view": {"geometry", "io", "robot", "sim", "wirecut"},
    # where to put the block: an application of the planner (search, setups, moved jobs)
    "place": {"geometry", "io", "robot", "sim", "wirecut"},
    "batch": {"geometry", "io", "place", "robot", "wirecut"},
    # from a part to its cuts: the planner's top-level names only (tests/carve/test_layer.py)
    "carve": {"geometry", "io", "robot", "subdivision", "wirecut"},
    # calibrating the kerf model: the ladder's jobs (the planner's top-level names only,
    # tests/kerf/test_ladder.py) and the fit of what was measured
    "kerf": {"geometry", "io", "robot", "wirecut"},
    # from a part to programs: carve, plan (the planner's top-level names), export, view
    "make": {"carve", "export", "io", "robot", "view", "wirecut"},
    "cli": {
        "algorithms", "batch", "carve", "export", "gallery", "geometry", "io", "kerf", "make",
        "place", "protocol", "robot", "sim", "subdivision", "ursim", "view", "wirecut",
    },
    # the package root re-exports the light lower layers only (``rr.Lines``, ``rr.refine``)
    "": {"algorithms", "geometry", "io", "subdivision"},
}

#: Modules that may use nothing but numpy/scipy and the standard library.
PURE = ("geometry", "subdivision")


def _package(module: str) -> str:
    parts = module.split(".")
    return parts[1] if len(parts) > 1 else ""


def test_there_is_no_import_circle():
    circles = cycles(graph())
    assert not circles, "import circles: " + "; ".join(" <-> ".join(c) for c in circles)


def test_every_package_has_a_place_in_the_layers():
    packages = {_package(m) for m in graph()}
    assert packages <= set(ALLOWED), f"not in ALLOWED: {sorted(packages - set(ALLOWED))}"


def test_every_layer_imports_only_downward():
    bad = []
    for module, targets in sorted(graph().items()):
        src = _package(module)
        for target in sorted(targets):
            dst = _package(target)
            if dst != src and dst not in ALLOWED[src]:
                bad.append(f"{module} imports {target} ({src} may use {sorted(ALLOWED[src])})")
    assert not bad, "\n".join(bad)


def test_the_allowed_table_itself_has_no_circle():
    edges = {p: {q for q in deps if q} for p, deps in ALLOWED.items() if p}
    assert not cycles(edges)


def test_the_math_layers_import_only_numpy_and_scipy():
    import ast

    # numba: compiled kernels of the same math, loaded only when first used
    allowed_roots = {"numpy", "scipy", "numba", "ruledrobot", "__future__"} | set(
        sys.stdlib_module_names)
    bad = []
    for pkg in PURE:
        for path in sorted((ROOT / pkg).rglob("*.py")):
            tree = ast.parse(path.read_text(encoding="utf-8"))
            for node in ast.walk(tree):
                if isinstance(node, ast.Import):
                    names = [a.name for a in node.names]
                elif isinstance(node, ast.ImportFrom) and not node.level:
                    names = [node.module or ""]
                else:
                    continue
                bad += [f"{path.name}: {n}" for n in names if n.split(".")[0] not in allowed_roots]
    assert not bad, bad


def test_import_ruledrobot_loads_no_heavy_library():
    code = (
        "import sys, ruledrobot, ruledrobot.robot, ruledrobot.io, ruledrobot.sim, "
        "ruledrobot.export, ruledrobot.wirecut\n"
        "heavy = [m for m in ('mujoco', 'matplotlib', 'toppra', 'rtde_control', 'rtde_receive',"
        " 'typer', 'rich', 'ezdxf', 'rhino3dm', 'viser', 'distributed', 'dask') "
        "if m in sys.modules]\n"
        "print(','.join(heavy))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "", f"imported on `import ruledrobot...`: {out.stdout.strip()}"
