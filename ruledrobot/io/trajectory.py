"""Trajectory files: a plain CSV and its JSON sidecar (``docs/trajectory.md``).

``trajectory.csv`` — header ``t,q1,q2,q3,q4,q5,q6,x,y,z,rx,ry,rz`` on the first
line, then one row per controller period, and nothing else (``csv.reader`` and
``pandas.read_csv`` read it as it is).  Time from the start (s), joint positions
(rad), the TCP pose in the robot base frame as a UR pose vector (m, rad).  A
trajectory with a heat schedule (docs/kerf.md) has a 14th column ``heat_power``: the
wire power set-point per sample (W/m, already led by the heat's ``lag``); a file
without it reads as before.

``trajectory.json`` — the sidecar, same stem, required by every reader::

    {"format": "ruledrobot.trajectory-meta/1",
     "robot": "ur5e", "control_period_s": 0.002,
     "tcp_offset": [x, y, z, rx, ry, rz],           # TCP in the flange frame
     "payload": {"mass_kg": 1.0, "cog_m": [cx, cy, cz]},
     "kinematics": {"source": "nominal", "checksum": "sha256:...",
                    "dh": {"theta_offset": [...], "a": [...], "d": [...], "alpha": [...]}},
     "base": [...],                                   # robot base in the job's world
     "phases": [{"name": "approach", "start": 0, "stop": 812}, ...],
     "in_stock": [[1200, 9800]],
     "max_acceleration_rad_s2": [2.5, 2.5, 2.5, 2.5, 2.5, 2.5],   # or null: the default
     "heat": {"output": "standard:0", "value": 1.0, "preheat_s": 2.0,
              "windows": [[1100, 9900]], "mode": "on_off",
              "full_scale_w_m": null, "lag_s": 0.0},     # or null
     "cut": {"stock": {"centre": [...], "size": [...], "rotvec": [...]},   # or null
             "wire_length_m": 0.4,
             "feeds": [{"name": "cut", "start": 1858, "stop": 13406, "speed_m_s": 0.01,
                        "tolerance": 0.05, "held": [[2200, 12500]],
                        "wire_tolerance_m": 0.0005}]},
     "job": {"path": "job.toml", "sha256": "..."}, "source": "ruledrobot plan",
     "csv": "trajectory.csv", "csv_sha256": "...", "samples": 12925}

Required: ``format``, ``robot``, ``tcp_offset``, ``payload``; the rest defaults
(period and kinematics: the catalogue model's).  The reader checks the CSV's
checksum when the sidecar has one (a CSV from another plan next to this sidecar
is refused), the period, and that the TCP column is FK(q) · tcp_offset — the
column and the metadata describe the same TCP.
"""

from __future__ import annotations

import hashlib
import io
import json
import os
from pathlib import Path
from typing import Any

import numpy as np

from ..geometry.box import Box
from ..geometry.se3 import pose_from_rotvec, rotvec_from_matrix
from ..robot.motion.trajectory import (
    Heat,
    KinematicsRef,
    Payload,
    Phase,
    Trajectory,
    TrajectoryMeta,
)
from ..robot.wire.cut import WIRE_TOLERANCE, FeedWindow, WireCut
from ..robot.wire.face import FaceTarget
from ..robot.wire.kerf import Material
from .atomic import atomic_write_bytes, atomic_write_json, atomic_write_text
from .text import read_user_text

__all__ = [
    "HEADER",
    "HEAT_POWER",
    "META_FORMAT",
    "TCP_TOLERANCE",
    "TRAJECTORY_FORMAT",
    "meta_from_dict",
    "meta_to_dict",
    "read_trajectory",
    "sidecar_path",
    "write_trajectory",
    "write_trajectory_json",
    "write_trajectory_npz",
]

HEADER = ["t", "q1", "q2", "q3", "q4", "q5", "q6", "x", "y", "z", "rx", "ry", "rz"]
#: the optional last column: the wire power set-point per sample [W/m]
HEAT_POWER = "heat_power"
META_FORMAT = "ruledrobot.trajectory-meta/1"
#: Format of a whole trajectory in one JSON file (``ruledrobot export --format json``).
TRAJECTORY_FORMAT = "ruledrobot.trajectory/1"
#: Largest mismatch (m, rad) between the TCP column and FK(q) · tcp_offset that a
#: reader accepts (the CSV holds 10 significant digits).
TCP_TOLERANCE = 1e-6

_DH_COLUMNS = ("theta_offset", "a", "d", "alpha")


def sidecar_path(path: str | os.PathLike[str]) -> Path:
    """``cut.csv`` -> ``cut.json`` beside it."""
    return Path(path).with_suffix(".json")


def _ur(T: np.ndarray) -> list[float]:
    from ..geometry.se3 import ur_vector_from_pose

    return [float(x) for x in ur_vector_from_pose(T)]


def meta_to_dict(meta: TrajectoryMeta) -> dict[str, Any]:
    """The sidecar fields of ``meta`` (JSON-ready)."""
    dh = meta.kinematics.dh
    return {
        "format": META_FORMAT,
        "robot": meta.robot,
        "control_period_s": meta.control_period,
        "tcp_offset": _ur(meta.tcp_offset),
        "payload": {"mass_kg": meta.payload.mass, "cog_m": meta.payload.cog.tolist()},
        "kinematics": {
            "source": meta.kinematics.source,
            "checksum": meta.kinematics.checksum,
            "controller_checksum": None if meta.kinematics.controller_checksum is None
            else list(meta.kinematics.controller_checksum),
            "dh": {c: dh[:, i].tolist() for i, c in enumerate(_DH_COLUMNS)},
        },
        "base": _ur(meta.base),
        "phases": [{"name": p.name, "start": p.start, "stop": p.stop} for p in meta.phases],
        "in_stock": [list(r) for r in meta.in_stock],
        "heat": None if meta.heat is None else {
            "output": meta.heat.output, "value": meta.heat.value,
            "preheat_s": meta.heat.preheat, "windows": [list(w) for w in meta.heat.windows],
            "mode": meta.heat.mode, "full_scale_w_m": meta.heat.full_scale,
            "lag_s": meta.heat.lag,
        },
        "max_acceleration_rad_s2": None if meta.max_acceleration is None
        else meta.max_acceleration.tolist(),
        "cut": None if meta.cut is None else _cut_to_dict(meta.cut),
        "job": meta.job,
        "source": meta.source,
    }


def _cut_to_dict(cut: WireCut) -> dict[str, Any]:
    st = cut.stock
    return {
        "stock": {"centre": st.centre.tolist(), "size": st.size.tolist(),
                  "rotvec": rotvec_from_matrix(st.rotation).tolist()},
        "wire_length_m": cut.wire_length,
        "feeds": [{"name": w.name, "start": w.start, "stop": w.stop, "speed_m_s": w.speed,
                   "tolerance": w.tolerance, "held": [list(r) for r in w.held],
                   "wire_tolerance_m": w.wire_tolerance}
                  for w in cut.feeds],
        "faces": [{"name": f.name, **{k: getattr(f, k).tolist() for k in _FACE_ARRAYS},
                   "ranges": [list(r) for r in f.ranges], "kerf_m": f.kerf,
                   "tolerance_m": f.tolerance} for f in cut.faces],
        "material": None if cut.material is None else {
            "kerf_base_m": cut.material.kerf_base, "kerf_gain": cut.material.kerf_gain,
            "power_threshold_w_m": cut.material.power_threshold,
            "max_speed": cut.material.max_speed},
    }  # fmt: skip


#: a face target's arrays in the sidecar (:class:`FaceTarget`'s fields; m)
_FACE_ARRAYS = ("origins", "directions", "normal_a", "normal_b", "chord")


def _faces(d: _Doc, c: dict) -> tuple[FaceTarget, ...]:
    """The sidecar's ``cut.faces`` (absent in older files: none)."""
    faces = []
    for i, f in enumerate(c.get("faces") or []):
        try:
            arrays = {k: np.asarray(f[k], dtype=np.float64) for k in _FACE_ARRAYS}
            faces.append(FaceTarget(str(f["name"]), **arrays,
                                    ranges=tuple(tuple(r) for r in f.get("ranges", [])),
                                    kerf=float(f["kerf_m"]),
                                    tolerance=float(f["tolerance_m"])))  # fmt: skip
        except (KeyError, TypeError, ValueError, AttributeError) as exc:
            raise d.fail(f"cut.faces[{i}]", "expected {name, " + ", ".join(_FACE_ARRAYS)
                         + f", ranges, kerf_m, tolerance_m}}: {exc}") from None  # fmt: skip
    return tuple(faces)


def _material(d: _Doc, c: dict) -> Material | None:
    """The sidecar's ``cut.material`` (absent or null: none)."""
    m = c.get("material")
    if m is None:
        return None
    try:
        top = m.get("max_speed")
        return Material(float(m["kerf_base_m"]), float(m["kerf_gain"]),
                        float(m.get("power_threshold_w_m", 0.0)),
                        None if top is None else float(top))  # fmt: skip
    except (KeyError, TypeError, ValueError, AttributeError) as exc:
        raise d.fail("cut.material", "expected {kerf_base_m, kerf_gain, power_threshold_w_m, "
                     f"max_speed}}: {exc}") from None  # fmt: skip


class _Doc:
    """Field access with errors naming the file and the field."""

    def __init__(self, doc: Any, where: str) -> None:
        if not isinstance(doc, dict):
            raise ValueError(f"{where}: expected a JSON object")
        self.doc, self.where = doc, where

    def fail(self, key: str, msg: str) -> ValueError:
        return ValueError(f"{self.where}: field {key!r}: {msg}")

    def get(self, key: str, required: bool = False, default: Any = None) -> Any:
        if key not in self.doc:
            if required:
                raise self.fail(key, "missing (required)")
            return default
        return self.doc[key]

    def numbers(self, key: str, value: Any, n: int | None) -> np.ndarray:
        try:
            arr = np.asarray(value, dtype=np.float64)
        except (TypeError, ValueError):
            raise self.fail(key, f"expected numbers, got {value!r}") from None
        if arr.ndim != 1 or (n is not None and arr.size != n) or not np.isfinite(arr).all():
            want = f"{n} finite numbers" if n else "a list of finite numbers"
            raise self.fail(key, f"expected {want}, got {value!r}")
        return arr


def _heat(d: _Doc) -> Heat | None:
    h = d.get("heat")
    if h is None:
        return None
    if not isinstance(h, dict) or not isinstance(h.get("output"), str) or ":" not in h["output"]:
        raise d.fail("heat", 'expected {"output": "KIND:N", "value": f, "windows": [[a, b]]} '
                     f"or null, got {h!r}")  # fmt: skip
    kind, _, index = h["output"].partition(":")
    wins = h.get("windows", [])
    if not isinstance(wins, list) or not all(
        isinstance(w, list) and len(w) == 2 and all(isinstance(x, int) for x in w) for w in wins
    ):
        raise d.fail("heat.windows", f"expected [[start, stop], ...] sample indices, got {wins!r}")
    if not index.isdigit():
        raise d.fail("heat.output", f"expected KIND:N, got {h['output']!r}")
    full_scale = h.get("full_scale_w_m")
    try:
        return Heat(kind, int(index), float(h.get("value", 1.0)), tuple(map(tuple, wins)),
                    float(h.get("preheat_s", 0.0)), str(h.get("mode", "on_off")),
                    None if full_scale is None else float(full_scale),
                    float(h.get("lag_s", 0.0)))  # fmt: skip
    except (TypeError, ValueError) as exc:
        raise d.fail("heat", str(exc)) from None


def _cut(d: _Doc) -> WireCut | None:
    c = d.get("cut")
    if c is None:
        return None
    if not isinstance(c, dict) or not isinstance(c.get("stock"), dict):
        raise d.fail("cut", 'expected {"stock": {...}, "wire_length_m": L, "feeds": [...]} or '
                     f"null, got {c!r}")  # fmt: skip
    st = c["stock"]
    try:
        stock = Box(d.numbers("cut.stock.centre", st.get("centre"), 3),
                    d.numbers("cut.stock.size", st.get("size"), 3),
                    pose_from_rotvec(d.numbers("cut.stock.rotvec", st.get("rotvec", [0, 0, 0]),
                                               3))[:3, :3])  # fmt: skip
    except ValueError as exc:
        raise d.fail("cut.stock", str(exc)) from None
    length = c.get("wire_length_m")
    if not isinstance(length, (int, float)) or isinstance(length, bool):
        raise d.fail("cut.wire_length_m", f"expected a length in metres, got {length!r}")
    feeds = []
    for i, w in enumerate(c.get("feeds") or []):
        try:
            feeds.append(FeedWindow(str(w["name"]), int(w["start"]), int(w["stop"]),
                                    float(w["speed_m_s"]), float(w["tolerance"]),
                                    tuple(tuple(r) for r in w.get("held", [])),
                                    float(w.get("wire_tolerance_m", WIRE_TOLERANCE))))  # fmt: skip
        except (KeyError, TypeError, ValueError, AttributeError) as exc:
            raise d.fail(f"cut.feeds[{i}]", "expected {name, start, stop, speed_m_s, tolerance, "
                         f"held}}: {exc}") from None  # fmt: skip
    try:
        return WireCut(stock, float(length), tuple(feeds), _faces(d, c), _material(d, c))
    except ValueError as exc:
        raise d.fail("cut", str(exc)) from None


def meta_from_dict(doc: Any, where: str = "trajectory metadata") -> TrajectoryMeta:
    """Parse sidecar fields; ValueError names ``where`` and the field."""
    from ..robot import MODEL_NAMES, load

    d = _Doc(doc, where)
    fmt = d.get("format", required=True)
    if fmt != META_FORMAT:
        raise d.fail("format", f"expected {META_FORMAT!r}, got {fmt!r}")
    robot = d.get("robot", required=True)
    if not isinstance(robot, str) or robot.lower() not in MODEL_NAMES:
        raise d.fail("robot", f"expected one of {', '.join(MODEL_NAMES)}, got {robot!r}")
    model = load(robot)
    tcp = d.numbers("tcp_offset", d.get("tcp_offset", required=True), 6)
    pay = d.get("payload", required=True)
    if not isinstance(pay, dict) or "mass_kg" not in pay:
        raise d.fail("payload", 'expected {"mass_kg": m, "cog_m": [x, y, z]}')
    try:
        mass = float(pay["mass_kg"])
    except (TypeError, ValueError):
        raise d.fail("payload.mass_kg", f"expected a number, got {pay['mass_kg']!r}") from None
    cog = d.numbers("payload.cog_m", pay.get("cog_m", [0.0, 0.0, 0.0]), 3)
    period = d.get("control_period_s", default=model.control_period)
    if not isinstance(period, (int, float)) or isinstance(period, bool):
        raise d.fail("control_period_s", f"expected a number of seconds, got {period!r}")
    if abs(period - model.control_period) > 1e-12:
        raise d.fail("control_period_s", f"{period} s, but a {model.name} runs at "
                     f"{model.control_period} s")  # fmt: skip
    kin = d.get("kinematics")
    if kin is None:
        kinematics = KinematicsRef.of(model)
    else:
        if not isinstance(kin, dict) or not isinstance(kin.get("dh"), dict):
            raise d.fail("kinematics", 'expected {"source": ..., "checksum": ..., "dh": {...}}')
        cols = [d.numbers(f"kinematics.dh.{c}", kin["dh"].get(c), model.n_joints)
                for c in _DH_COLUMNS]  # fmt: skip
        cc = kin.get("controller_checksum")
        if cc is not None and not (isinstance(cc, list) and len(cc) == 6 and all(
                isinstance(c, int) and 0 <= c < 2**32 for c in cc)):  # fmt: skip
            raise d.fail("kinematics.controller_checksum", f"expected 6 uint32 or null, got {cc!r}")
        try:
            kinematics = KinematicsRef(np.stack(cols, axis=1), str(kin.get("source", "?")),
                                       str(kin.get("checksum", "")),
                                       None if cc is None else tuple(cc))  # fmt: skip
        except ValueError as exc:
            raise ValueError(f"{where}: {exc}") from None
    phases = []
    for i, p in enumerate(d.get("phases", default=[]) or []):
        try:
            phases.append(Phase(str(p["name"]), int(p["start"]), int(p["stop"])))
        except (KeyError, TypeError, ValueError) as exc:
            raise d.fail(f"phases[{i}]", f"expected {{name, start, stop}}: {exc}") from None
    stock = []
    for i, r in enumerate(d.get("in_stock", default=[]) or []):
        if not (isinstance(r, list) and len(r) == 2 and all(isinstance(x, int) for x in r)):
            raise d.fail(f"in_stock[{i}]", f"expected [start, stop] sample indices, got {r!r}")
        stock.append((r[0], r[1]))
    base = d.numbers("base", d.get("base", default=[0.0] * 6), 6)
    heat = _heat(d)
    acc = d.get("max_acceleration_rad_s2")
    max_acc = None if acc is None else d.numbers("max_acceleration_rad_s2", acc, model.n_joints)
    job = d.get("job")
    if job is not None and not isinstance(job, dict):
        raise d.fail("job", f"expected an object or null, got {job!r}")
    cut = _cut(d)  # its errors name the file and field already
    try:
        return TrajectoryMeta(
            robot=model.name, control_period=float(period), tcp_offset=tcp,
            payload=Payload(mass, cog), kinematics=kinematics, base=base,
            phases=tuple(phases), in_stock=tuple(stock), job=job,
            source=str(d.get("source", default="")), heat=heat, max_acceleration=max_acc,
            cut=cut,
        )  # fmt: skip
    except ValueError as exc:
        raise ValueError(f"{where}: {exc}") from None


#: rows formatted by one ``%`` operation (a fifth faster than a row at a time)
_CSV_BLOCK = 256


def _header(traj: Trajectory) -> list[str]:
    """The CSV columns of ``traj``: :data:`HEADER`, and ``heat_power`` when it has one."""
    return HEADER if traj.heat_power is None else [*HEADER, HEAT_POWER]


def csv_text(traj: Trajectory) -> str:
    """Return the CSV of ``traj``: the header line, then one row per sample.

    ``%.10g`` each, the text ``numpy.savetxt`` writes, formatted ``_CSV_BLOCK`` rows at a time."""
    cols = [traj.t[:, None], traj.q, traj.tcp]
    if traj.heat_power is not None:
        cols.append(traj.heat_power[:, None])
    data = np.concatenate(cols, axis=1)
    row = ",".join(["%.10g"] * data.shape[1]) + "\n"
    full = len(data) - len(data) % _CSV_BLOCK
    blocks = data[:full].reshape(-1, _CSV_BLOCK * data.shape[1]).tolist()
    text = [(row * _CSV_BLOCK) % tuple(b) for b in blocks]
    text.append((row * (len(data) - full)) % tuple(data[full:].ravel().tolist()))
    return ",".join(_header(traj)) + "\n" + "".join(text)


def write_trajectory(path: str | os.PathLike[str], traj: Trajectory) -> Path:
    """Write ``traj`` as ``path`` (CSV) and its sidecar (``.json``), each atomically.

    The sidecar, written last, holds the CSV's SHA-256.  Returns the CSV path."""
    p = Path(path)
    if p.suffix.lower() != ".csv":
        raise ValueError(f"{p}: a trajectory CSV needs the suffix .csv")
    text = csv_text(traj)
    doc = meta_to_dict(traj.meta)
    doc.update(
        csv=p.name,
        csv_sha256=hashlib.sha256(text.encode()).hexdigest(),
        samples=traj.n,
        duration_s=traj.duration,
    )
    atomic_write_text(p, text)
    atomic_write_json(sidecar_path(p), doc)
    return p


def write_trajectory_json(path: str | os.PathLike[str], traj: Trajectory) -> Path:
    """Write ``traj`` as one JSON document (atomically).

    ``{"format": "ruledrobot.trajectory/1", "units": {...}, "meta": {sidecar fields},
    "header": [...], "t": [...], "q": [[...]], "tcp": [[...]]}`` (and ``"heat_power": [...]``
    W/m when the trajectory has one).  Refuses a name whose ``.csv`` sibling exists (the JSON
    would take the place of that CSV's sidecar)."""
    p = Path(path)
    if p.with_suffix(".csv").exists():
        raise ValueError(f"{p}: would replace the metadata of {p.with_suffix('.csv').name} "
                         "beside it; choose another name")  # fmt: skip
    doc = {
        "format": TRAJECTORY_FORMAT,
        "units": {"t": "s", "q": "rad", "tcp": "m, rad (UR pose vector, robot base frame)",
                  HEAT_POWER: "W/m"},
        "meta": meta_to_dict(traj.meta),
        "header": _header(traj),
        "t": traj.t.tolist(),
        "q": traj.q.tolist(),
        "tcp": traj.tcp.tolist(),
    }
    if traj.heat_power is not None:
        doc[HEAT_POWER] = traj.heat_power.tolist()
    return atomic_write_json(p, doc, compact=True)


def write_trajectory_npz(path: str | os.PathLike[str], traj: Trajectory) -> Path:
    """Write ``traj`` as a compressed NPZ (atomically).

    Arrays ``t``, ``q``, ``tcp``, ``heat_power`` (when the trajectory has one) and ``meta``
    (the sidecar fields as JSON text)."""
    buf = io.BytesIO()
    extra = {} if traj.heat_power is None else {HEAT_POWER: traj.heat_power}
    np.savez_compressed(buf, t=traj.t, q=traj.q, tcp=traj.tcp,
                        meta=np.array(json.dumps(meta_to_dict(traj.meta))), **extra)  # fmt: skip
    return atomic_write_bytes(path, buf.getvalue())


def _parse_csv(p: Path, text: str) -> np.ndarray:
    """The samples (M, 13), or (M, 14) with the ``heat_power`` column; ValueError names
    the file and line."""
    lines = text.splitlines()
    if not lines or not lines[0].strip():
        raise ValueError(f"{p}: line 1: expected the header {','.join(HEADER)}")
    head = [c.strip().lower() for c in lines[0].split(",")]
    if head not in (HEADER, [*HEADER, HEAT_POWER]):
        raise ValueError(f"{p}: line 1: expected the header {','.join(HEADER)} (and "
                         f"optionally {HEAT_POWER}), got {lines[0][:80]!r}")  # fmt: skip
    body = [s for s in lines[1:] if s.strip()]
    if not body:
        raise ValueError(f"{p}: no samples after the header")
    try:
        data = np.loadtxt(io.StringIO("\n".join(body)), delimiter=",", ndmin=2)
    except ValueError:
        data = None
    if data is None or data.shape[1] != len(head):
        # find the offending line for the message
        for lineno, s in enumerate(lines[1:], start=2):
            if not s.strip():
                continue
            cells = s.split(",")
            if len(cells) != len(head):
                raise ValueError(f"{p}: line {lineno}: expected {len(head)} values, "
                                 f"got {len(cells)}")  # fmt: skip
            try:
                [float(c) for c in cells]
            except ValueError:
                raise ValueError(f"{p}: line {lineno}: not a number in {s[:80]!r}") from None
        raise ValueError(f"{p}: could not read the samples")  # pragma: no cover
    lineno = np.flatnonzero([bool(s.strip()) for s in lines[1:]]) + 2
    bad = ~np.isfinite(data).all(axis=1)
    if bad.any():
        raise ValueError(f"{p}: line {lineno[np.argmax(bad)]}: contains NaN or infinity")
    dt = np.diff(data[:, 0])
    if np.any(dt <= 0):
        k = int(np.argmax(dt <= 0)) + 1
        raise ValueError(f"{p}: line {lineno[k]}: time {data[k, 0]} does not increase")
    return data


def _check_manifest(p: Path, data: bytes) -> None:
    """In an output folder (one with ``manifest.json``), a listed file must be the one
    the folder was completed with."""
    from .outdir import read_manifest

    man = read_manifest(p.parent)
    if man is None:
        return
    entry = man.get("files", {}).get(p.name)
    if entry is not None and entry.get("sha256") != hashlib.sha256(data).hexdigest():
        raise ValueError(f"{p}: differs from the file its folder's manifest.json lists (the "
                         "folder was changed after the plan wrote it); plan again")  # fmt: skip


def _check_tcp(traj: Trajectory, where: str, line_offset: int) -> None:
    dp, da, k = traj.tcp_error()
    if dp > TCP_TOLERANCE or da > TCP_TOLERANCE:
        raise ValueError(
            f"{where}: {'line' if line_offset else 'sample'} {k + line_offset}: the TCP columns "
            f"differ from FK(q) · tcp_offset by {dp * 1e3:.4g} mm / {np.degrees(da):.4g} deg: "
            "the TCP is not the TCP its metadata names (or the kinematics differ)"
        )


def _read_bundle(p: Path, check_tcp: bool) -> Trajectory:
    """A whole trajectory in one JSON or NPZ export."""
    if p.suffix.lower() == ".npz":
        try:
            with np.load(p, allow_pickle=False) as z:
                arrays = {k: z[k] for k in ("t", "q", "tcp", "meta")}
                power = z[HEAT_POWER] if HEAT_POWER in z.files else None
        except (OSError, ValueError, KeyError) as exc:
            raise ValueError(f"{p}: not a ruledrobot trajectory NPZ (t, q, tcp, meta): {exc}"
                             ) from None  # fmt: skip
        try:
            meta_doc = json.loads(str(arrays["meta"]))
        except ValueError:
            raise ValueError(f"{p}: array 'meta' is not JSON text") from None
        t, q, tcp = arrays["t"], arrays["q"], arrays["tcp"]
    else:
        _, text = read_user_text(p, "trajectory file")
        try:
            doc = json.loads(text)
        except json.JSONDecodeError as exc:
            raise ValueError(f"{p}: line {exc.lineno}: not valid JSON ({exc.msg})") from None
        if not isinstance(doc, dict) or doc.get("format") != TRAJECTORY_FORMAT:
            raise ValueError(f"{p}: expected format {TRAJECTORY_FORMAT!r} (a trajectory CSV "
                             "has a .csv name)")  # fmt: skip
        for key in ("meta", "t", "q", "tcp"):
            if key not in doc:
                raise ValueError(f"{p}: field {key!r} missing")
        meta_doc, t, q, tcp = doc["meta"], doc["t"], doc["q"], doc["tcp"]
        power = doc.get(HEAT_POWER)
    meta = meta_from_dict(meta_doc, f"{p}: meta")
    try:
        traj = Trajectory(np.asarray(t, float), np.asarray(q, float), np.asarray(tcp, float),
                          meta, None if power is None else np.asarray(power, float))  # fmt: skip
    except (ValueError, TypeError) as exc:
        raise ValueError(f"{p}: {exc}") from None
    if check_tcp:
        _check_tcp(traj, str(p), 0)
    return traj


def read_trajectory(path: str | os.PathLike[str], check_tcp: bool = True) -> Trajectory:
    """Read a trajectory: a CSV and its required sidecar, or a JSON / NPZ export.

    ValueError names the file and the line or field of any problem (see the module
    doc for what is checked)."""
    if Path(path).suffix.lower() in (".json", ".npz"):
        return _read_bundle(Path(path), check_tcp)
    p, text = read_user_text(path, "trajectory file")
    side = sidecar_path(p)
    if not side.is_file():
        raise ValueError(
            f"{p}: its metadata file {side.name} is missing beside it. Every trajectory CSV "
            "needs one: robot, TCP offset and payload at least, e.g. "
            '{"format": "ruledrobot.trajectory-meta/1", "robot": "ur5e", '
            '"tcp_offset": [0, 0, 0, 0, 0, 0], "payload": {"mass_kg": 0, "cog_m": [0, 0, 0]}} '
            "(docs/trajectory.md)"
        )
    sp, stext = read_user_text(side, "trajectory metadata file")
    try:
        doc = json.loads(stext)
    except json.JSONDecodeError as exc:
        raise ValueError(f"{sp}: line {exc.lineno}: not valid JSON ({exc.msg})") from None
    meta = meta_from_dict(doc, str(sp))
    want = doc.get("csv_sha256") if isinstance(doc, dict) else None
    if want is not None and hashlib.sha256(text.encode()).hexdigest() != want:
        raise ValueError(
            f"{p}: does not match its metadata {sp.name} (checksum differs): the CSV was "
            "changed or comes from another plan; plan again or fix the pair"
        )
    _check_manifest(p, text.encode())
    data = _parse_csv(p, text)
    try:
        power = data[:, 13] if data.shape[1] > 13 else None
        traj = Trajectory(data[:, 0], data[:, 1:7], data[:, 7:13], meta, power)
    except ValueError as exc:
        raise ValueError(f"{p} with {sp.name}: {exc}") from None
    if check_tcp:
        _check_tcp(traj, f"{p} with {sp.name}", 2)
    return traj
