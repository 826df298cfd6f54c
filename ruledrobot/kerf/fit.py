"""Fitting the kerf model to a measured ladder: constants, uncertainties, residuals, verdict.

The model (:mod:`ruledrobot.robot.wire.kerf`, docs/kerf.md) above the threshold is linear
in three coefficients (research: hotwire-physics.md, "Calibration")::

    w = kerf_base + (b1 p + b0) / v,   kerf_gain = b1,   power_threshold = -b0 / b1

fitted by ordinary least squares on the design ``[1, p/v, 1/v]``.  Standard errors come
from the covariance ``s^2 (X^T X)^-1`` with ``s^2 = RSS / (n - 3)``; the threshold's by the
delta method (gradient ``(b0/b1^2, -1/b1)`` of ``-b0/b1``).  Rows at or below the fitted
threshold melt nothing by the model (``w = kerf_base``) and do not follow the line: they
are left out and the fit repeated until the rows used stop changing.  The held-out check
is leave-one-out, in closed form: the prediction error of row i from the fit without it
is ``e_i / (1 - h_ii)`` (``h`` the hat matrix's diagonal).

Good enough (docs/kerf.md, "Calibration"): every constant determined by the design; the
RMS residual <= :data:`RMS_LIMIT`; every row predicted from the others within
:data:`HELD_OUT_LIMIT`; each constant's standard error <= :data:`RELATIVE_LIMIT` of its
value (the threshold's: of the mean heat above it in the rows fitted, ``mean(p) - p0``,
the relative error it puts into the melt term ``k (p - p0) / v``; a threshold near zero
is no worse known for being small); the constants physical.

``max_speed`` is bracketed, not fitted: a cut that went through bounds it from below by its
``v / (p - p0)``, a failed one from above; the largest ratio that cut is written, and only
when some cut failed (else the ladder never found the limit).  Units: SI (m, s, W/m).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..robot.verdict import Check, Verdict
from ..robot.wire.kerf import Material
from .measured import Measured

__all__ = ["HELD_OUT_LIMIT", "RELATIVE_LIMIT", "RMS_LIMIT", "Constant", "KerfFit",
           "fit_kerf"]  # fmt: skip

#: the first words of every table kerf fit writes (it writes over no other file)
FIT_HEADER = "# ruledrobot kerf fit"

#: largest RMS residual [m] of a good fit: twice a caliper's reading scatter on foam
RMS_LIMIT = 0.05e-3
#: largest leave-one-out prediction error [m]: the default face tolerance (docs/kerf.md)
HELD_OUT_LIMIT = 0.1e-3
#: largest standard error of a constant, as a fraction of its scale (module doc)
RELATIVE_LIMIT = 0.10
#: most refits while rows drop below the threshold
MAX_ROUNDS = 20


@dataclass(frozen=True)
class Constant:
    """One fitted constant with its standard error.

    ``name`` (the ``[material]`` field), ``value`` and ``sigma``
    (its standard error) in ``unit`` (SI), ``scale`` what ``sigma`` is judged against, and
    ``why`` when the data cannot determine it (``value`` NaN then)."""

    name: str
    value: float
    sigma: float
    unit: str
    scale: float = float("nan")
    why: str = ""

    @property
    def relative(self) -> float:
        """``sigma / scale`` (inf when the scale is not positive)."""
        return self.sigma / self.scale if self.scale > 0.0 else float("inf")


@dataclass(frozen=True)
class KerfFit:
    """The fit of a measured ladder (module doc).

    ``constants``: kerf_base [m], kerf_gain [m^2/s per W/m], power_threshold [W/m];
    ``material``: them as a :class:`Material` (with ``max_speed`` when a cut failed), None
    when the data cannot determine them or they are not physical; per row (N,):
    ``used`` (in the least squares), ``predicted`` [m] (NaN when no material),
    ``residual`` [m] (measured - predicted; NaN on failed rows), ``held_out`` [m] (the
    leave-one-out error of used rows, NaN elsewhere); ``rms`` [m] and ``r2`` over the used
    rows; ``max_speed_bounds`` ((m/s) per W/m: the largest ratio that cut, the smallest that
    failed; None if none); ``warnings`` (the data cannot determine something, or
    disagrees with itself), ``notes`` (what was decided); ``verdict``.
    """

    measured: Measured
    constants: tuple[Constant, ...]
    material: Material | None
    used: np.ndarray
    predicted: np.ndarray
    residual: np.ndarray
    held_out: np.ndarray
    rms: float
    r2: float
    max_speed_bounds: tuple[float | None, float | None]
    verdict: Verdict
    warnings: tuple[str, ...] = field(default_factory=tuple)
    notes: tuple[str, ...] = field(default_factory=tuple)

    def __getitem__(self, name: str) -> Constant:
        for c in self.constants:
            if c.name == name:
                return c
        raise KeyError(name)


def _ols(x: np.ndarray, w: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Least squares of ``w`` (n,) on ``x`` (n, q): coefficients (q,), their covariance
    (q, q) (``s^2 (X^T X)^-1``, s^2 = RSS/(n-q); NaN when n = q) and the leverages (n,).
    Columns are scaled to unit norm first (``p/v`` is ~1e4 times the intercept)."""
    scale = np.linalg.norm(x, axis=0)
    xs = x / scale
    inv = np.linalg.inv(xs.T @ xs)
    beta_s = inv @ (xs.T @ w)
    resid = w - xs @ beta_s
    n, q = x.shape
    s2 = float(resid @ resid) / (n - q) if n > q else float("nan")
    lev = np.einsum("ij,jk,ik->i", xs, inv, xs)
    return beta_s / scale, s2 * inv / np.outer(scale, scale), lev


def _design_gaps(speed: np.ndarray, power: np.ndarray) -> list[str]:
    """Why rows at these (speed, power) cannot determine the three constants (empty: they
    can)."""
    gaps = []
    speeds, powers = np.unique(np.round(speed, 9)), np.unique(np.round(power, 6))
    if powers.size < 2:
        gaps.append(f"one power only ({powers[0]:g} W/m): kerf_gain and power_threshold "
                    "cannot be told apart (only kerf_gain*(p - power_threshold) can); cut at "
                    "a second power")  # fmt: skip
    if speeds.size < 2:
        gaps.append(f"one speed only ({speeds[0] * 1e3:g} mm/s): kerf_base and "
                    "power_threshold cannot be told apart; cut at a second speed")  # fmt: skip
    if not gaps and speed.size <= 3:
        gaps.append(f"{speed.size} rows for 3 constants: nothing is left to judge the fit by; "
                    "measure at least 4 cuts (the ladder has 8)")  # fmt: skip
    return gaps


def _undetermined(m: Measured, gaps: list[str], ok: np.ndarray) -> KerfFit:
    why = "; ".join(gaps)
    consts = tuple(Constant(n, float("nan"), float("nan"), u, why=why) for n, u in
                   (("kerf_base", "m"), ("kerf_gain", "m^2/s per W/m"),
                    ("power_threshold", "W/m")))  # fmt: skip
    nan = np.full(m.speed.shape, np.nan)
    verdict = Verdict((Check("determined", "the design determines every constant", "no",
                             "yes", "", "==", False, True, why),))  # fmt: skip
    return KerfFit(m, consts, None, ok, nan, nan, nan, float("nan"), float("nan"),
                   (None, None), verdict, tuple(gaps))  # fmt: skip


def fit_kerf(m: Measured) -> KerfFit:
    """Fit the kerf model to the measured rows ``m`` (module doc)."""
    ok = ~m.failed
    gaps = _design_gaps(m.speed[ok], m.power[ok])
    if gaps:
        return _undetermined(m, gaps, ok)
    used = ok.copy()
    warnings: list[str] = []
    notes: list[str] = []
    for _ in range(MAX_ROUNDS):
        v, p, w = m.speed[used], m.power[used], m.kerf[used]
        x = np.column_stack([np.ones_like(v), p / v, 1.0 / v])
        beta, cov, lev = _ols(x, w)
        p0 = -beta[2] / beta[1] if beta[1] > 0.0 else -np.inf
        again = ok & (m.power > p0)
        if np.array_equal(again, used):
            break
        gaps = _design_gaps(m.speed[again], m.power[again])
        if gaps:
            return _undetermined(m, [f"above the fitted threshold {p0:.3g} W/m: {g}"
                                     for g in gaps], again)  # fmt: skip
        used = again
    else:
        warnings.append(f"the rows above the threshold did not settle in {MAX_ROUNDS} refits")
    below = ok & ~used
    if below.any():
        notes.append(f"{int(below.sum())} row(s) at or below the fitted threshold "
                     f"{p0:.3g} W/m (lines {', '.join(map(str, m.lines[below]))}) left out: "
                     "the model melts nothing there")  # fmt: skip
    w0, k, b0 = (float(b) for b in beta)
    grad = np.array([0.0, b0 / k**2, -1.0 / k]) if k > 0.0 else np.full(3, np.nan)
    sig_p0 = float(np.sqrt(grad @ cov @ grad))
    resid = w - x @ beta
    rms = float(np.sqrt(np.mean(resid**2)))
    tss = float(np.sum((w - w.mean()) ** 2))
    r2 = 1.0 - float(resid @ resid) / tss if tss > 0.0 else float("nan")
    with np.errstate(divide="ignore"):
        loo = np.where(lev < 1.0 - 1e-9, resid / (1.0 - lev), np.inf)
    p_mean = float(np.mean(p)) - p0
    consts = (Constant("kerf_base", w0, float(np.sqrt(cov[0, 0])), "m", w0),
              Constant("kerf_gain", k, float(np.sqrt(cov[1, 1])), "m^2/s per W/m", k),
              Constant("power_threshold", p0, sig_p0, "W/m", p_mean))  # fmt: skip
    physical = k > 0.0 and w0 > 0.0 and p0 > -2.0 * sig_p0
    why_not = []
    if k <= 0.0:
        why_not.append(f"kerf_gain {k:.3g} <= 0: the kerf does not grow with the heat")
    if w0 <= 0.0:
        why_not.append(f"kerf_base {w0 * 1e3:.3g} mm <= 0: no wire is that thin")
    if p0 <= -2.0 * sig_p0:
        why_not.append(f"power_threshold {p0:.3g} +- {sig_p0:.2g} W/m is below zero")
    if physical and p0 < 0.0:
        notes.append(f"power_threshold {p0:.3g} +- {sig_p0:.2g} W/m is within two standard "
                     "errors of zero: written as 0")  # fmt: skip
    lo, hi, max_speed = _max_speed(m, ok, max(p0, 0.0), notes, warnings)
    material = None
    if physical:
        material = Material(w0, k, max(p0, 0.0), max_speed)
    n = m.speed.size
    predicted = material.kerf(m.speed, m.power) if material else np.full(n, np.nan)
    held = np.full(n, np.nan)
    held[used] = loo
    checks = [
        Check("determined", "the design determines every constant", "yes", "yes", "", "==",
              True, True),
        Check("physical", "the constants are physical (gain > 0, base > 0, threshold >= 0)",
              "yes" if physical else "no", "yes", "", "==", physical, True,
              "; ".join(why_not)),
        Check.at_most("rms", "RMS residual of the rows fitted", rms * 1e3, RMS_LIMIT * 1e3,
                      "mm", "the model does not follow the measurements: a misread row, a "
                      "cut that dragged (mark it failed), or heat that did not settle"),
        Check.at_most("held_out", "largest error predicting a row from the others",
                      float(np.max(np.abs(loo))) * 1e3, HELD_OUT_LIMIT * 1e3, "mm",
                      f"line {m.lines[used][int(np.argmax(np.abs(loo)))]}: the fit leans on "
                      "this cut; measure it again or add cuts near it"),
    ]  # fmt: skip
    for c in consts:
        checks.append(Check.at_most(
            f"{c.name}_uncertainty", f"standard error of {c.name}"
            + (" (of the mean heat above it)" if c.name == "power_threshold" else ""),
            100.0 * c.relative, 100.0 * RELATIVE_LIMIT, "%",
            f"{c.name} = {c.value:.4g} +- {c.sigma:.2g} {c.unit}: cut more speeds or powers "
            "farther apart, or measure each slot more times"))  # fmt: skip
    checks.append(Check.info("r2", "R^2 of the rows fitted", r2))
    checks.append(Check.info("rows", "rows fitted / measured", f"{int(used.sum())} / {n}"))
    resid_all = np.where(ok, m.kerf - predicted, np.nan)
    return KerfFit(m, consts, material, used, predicted, resid_all, held, rms, r2,
                   (lo, hi), Verdict(tuple(checks)), tuple(warnings), tuple(notes))  # fmt: skip


def _max_speed(m: Measured, ok: np.ndarray, p0: float, notes: list[str],
               warnings: list[str]) -> tuple[float | None, float | None, float | None]:  # fmt: skip
    """The drag limit's bracket from the rows (module doc): ``(lowest bound, highest bound,
    value written)`` in (m/s) per W/m."""
    hot = m.power > p0
    ratio = np.where(hot, m.speed / np.where(hot, m.power - p0, 1.0), np.nan)
    lo = float(np.nanmax(ratio[ok])) if np.any(ok & hot) else None
    hi = float(np.nanmin(ratio[~ok])) if np.any(~ok & hot) else None
    if not np.any(~ok):
        notes.append("no cut failed: the ladder did not find the drag limit; max_speed is "
                     "left out (cut faster at the lower power to find it)")  # fmt: skip
        return lo, hi, None
    if hi is None:
        notes.append("the failed rows are at or below the threshold (no melt): they bound "
                     "no speed; max_speed is left out")  # fmt: skip
        return lo, hi, None
    if lo is not None and lo >= hi:
        warnings.append(f"a cut went through at {lo * 1e3:.3g} mm/s per W/m above the "
                        f"threshold but one failed at {hi * 1e3:.3g}: the failures are not "
                        "the drag limit (a snapped wire, a loose block?); max_speed is left "
                        "out")  # fmt: skip
        return lo, hi, None
    notes.append(f"max_speed between {lo * 1e3:.3g} and {hi * 1e3:.3g} (mm/s) per W/m above "
                 "the threshold: the largest that cut is written" if lo is not None else
                 "no cut went through above the threshold: max_speed is left out")
    return lo, hi, lo


def material_text(fit: KerfFit) -> str:
    """The ``[material]`` table of a fit, to paste into a job.

    4 significant digits, its standard errors in the
    comments), headed by what it was fitted from and its verdict; ValueError when the fit
    gives no material."""
    from ..io.toml_text import toml_value

    mat = fit.material
    if mat is None:
        raise ValueError(f"{fit.measured.source}: no material: {fit.verdict.summary()}")
    word = "PASS" if fit.verdict.ok else "FAIL"
    out = [f"{FIT_HEADER} {fit.measured.source}: {int(fit.used.sum())} of "
           f"{fit.used.size} rows fitted, RMS {fit.rms * 1e3:.3f} mm; {word}: "
           f"{fit.verdict.summary()}", "# paste into a job file (docs/kerf.md)", "[material]"]
    for c in fit.constants:
        value = getattr(mat, c.name)
        out.append(f"{c.name} = {toml_value(float(f'{value:.4g}'))}  # {c.unit}, standard "
                   f"error {c.sigma:.2g} ({100 * c.relative:.1f} %)")  # fmt: skip
    if mat.max_speed is not None:
        hi = fit.max_speed_bounds[1]
        out.append(f"max_speed = {toml_value(float(f'{mat.max_speed:.4g}'))}  # (m/s) per "
                   f"W/m: the fastest that cut; one failed at {hi:.3g}")  # fmt: skip
    return "\n".join(out) + "\n"
