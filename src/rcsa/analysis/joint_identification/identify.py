"""Identification of the joints' translational stiffness and damping from tool-point FRFs.

Given a base assembly (its joints are the starting guess) and one or more measured
tool-point FRFs (the base assembly with ``tool`` fields overridden, e.g. several
stickouts), the translational stiffness ``k_t`` and damping ``c_t`` of the spindle–holder
and holder–tool joints are estimated from the modes they control — never by fitting every
parameter to the whole band. Rotational values are held at the given values, as the seed
paper does (Ertürk, Özgüven & Budak, IJMTM 47 (2007) 23–32), and flagged.

Procedure (θ = ln of the parameters, so every step is scale-free):

1. **Coarse match of the stiffnesses.** The peaks of the model FRF are matched to the
   measured ones (symmetric mean nearest distance in ln f; a side's prominent peaks, ≥ 3 %
   of max |h|, look for any listed peak, ≥ 1 %, on the other) on a geometric grid of the
   joint stiffnesses, ±1 decade around the start (9 points each, a weak pull toward the
   start deciding along valleys), then ±1/8 decade (5 points each). A stiffness the peaks
   do not see is held at its start; a best point at the edge of the range means the start
   is too far off.
2. **Which mode informs which parameter.** At that point, ``d ln f / d ln k`` and
   ``d ln|h|_peak / d ln c`` of every model peak matched to a measured one (central
   differences of the mode read on its measured lines, below); each parameter takes its
   most sensitive mode (greedily, one mode per parameter, stiffnesses and dampings
   separately). A parameter whose best ``|S|`` is below 0.05 (stiffness) or 0.1 (damping)
   is not informed by the data: it is returned unchanged and flagged, and the grid is
   searched again without it. Stages 1–2 live in :mod:`rcsa.analysis.joint_identification.locate`.
3. **Stiffness from the frequencies.** Levenberg–Marquardt (``scipy.optimize.least_squares``,
   trust-region reflective within the bounds) on ``ln f_model − ln f_measured`` of the
   stiffness modes, each read alike from model and measurement: one pole with residual
   terms fitted on the measured lines of the mode's window
   (:func:`rcsa.analysis.joint_identification.locate.band_features`).
4. **Damping from the peaks.** The same on ``ln |h|_peak,model − ln |h|_peak,measured`` of
   the damping modes (the fitted peak heights), stiffnesses held.
5. **Polish and uncertainty.** All informed parameters together on the complex log residual
   ``r = w·ln(h_model/h_measured)`` (real part: log magnitude, imaginary part: phase) on the
   lines within ``±max(2ζ, 0.5 %)`` of each used peak, ``w`` from the coherence when given.
   The covariance of θ is ``s² (JᵀJ)⁻¹`` with ``s² = ‖r‖²/(m − p)`` (m real residuals, p
   parameters, J the Jacobian of r at the optimum), and a parameter's standard uncertainty
   is ``p·σ_θ`` (delta method). It covers the noise only, not model-form error.

Speed: the model of each measurement is a
:class:`~rcsa.analysis.tool_point_model.ToolPointModel` — the spindle condensed and the beam
terms kept once per grid, so a new joint value costs a few 2×2 operations per line — and
every Jacobian is one stacked evaluation of all its finite-difference points.

**Measured spindles** (``"spindle": {"measurement_id": ...}``, ``docs/physics.md`` §4): the same
procedure on the hybrid model. At ``spindle_nose`` both joints are identifiable; at
``holder_tip`` the spindle–holder joint is inside the measurement and is reported under
``not_applicable``. The measured base's own uncertainty enters twice. Its noise (an
artifact identification amplifies the tap test's, by its condition number) makes the model
FRF noisy: its relative noise, from third differences of the model on the measured lines,
is added to the measurement's in the noise the residual is judged against, and it is in the
residual that gives the covariance. A ``direct_frf`` spindle's estimated rotations are
bounded by the equivalent-cantilever lengths L/2 and 2L: stage 5 is repeated on both bounds
and the half-range, as a uniform distribution (``range/(2√3)``), is added in quadrature to
each uncertainty (``uncertainty_components`` gives both parts).

Honesty checks, each giving ``status: "not_identifiable"`` with a ``detail``: no peak in the
band, no parameter informed, a best coarse match at the edge of the search range or at a
bound, a fitted parameter ending at a bound, a peak the model cannot follow, and an RMS fit
residual more than ``max_residual_to_noise`` (default 4) times the noise, which is
estimated from the measurement itself (:func:`rcsa.analysis.joint_identification.measured_peaks.relative_noise`).
Then the joints are returned as given (never invented) and the uncertainties are null.

On RA-1 with 1 % complex noise and a start 3× off (``tests/analysis/test_joint_identification.py``) the errors
are ~1e-4 (stiffness) and ~1e-3 (damping), consistent with the stated uncertainties, in
about 0.2 s for 4951 lines (``benchmarks/bench_jointid.py``; 1.2 s before the evaluator).

Examples
--------
>>> from rcsa.app.predictions import predict
>>> from rcsa.model.wire import complex_to_wire
>>> from rcsa.reference import ra1
>>> p = predict(ra1({"start_hz": 300.0, "stop_hz": 4500.0, "step_hz": 2.0}))
>>> measurement = {"frequency_hz": p.frequency_hz.tolist(), "h": complex_to_wire(p.tool_point.h)}
>>> start = ra1()
>>> start["joints"]["holder_tool"].update(stiffness_n_m=3.0e7, damping_ns_m=90.0)
>>> out = identify({"assembly": start, "measurements": [measurement]})
>>> out["status"], round(out["joints"]["holder_tool"]["stiffness_n_m"] / 1.14e7, 4)
('identified', 1.0)
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from scipy.optimize import least_squares

from rcsa.analysis.joint_identification.locate import (
    NotIdentifiable,
    Problem,
    Use,
    band_features,
    locate,
    where_modes,
)
from rcsa.analysis.joint_identification.measured_peaks import (
    PEAK_PROMINENCE,
    coherence_weights,
    measured_peaks,
    relative_noise,
)
from rcsa.analysis.joint_identification.request import (
    IdentificationRequest,
    parse_identification_request,
)
from rcsa.analysis.progress import Progress, report
from rcsa.model.contract import AssemblySpec, ClampingSpec, JointSpec
from rcsa.model.spindle_side import BaseResolver

__all__ = ["Identification", "identify", "identify_joints"]

#: Steps reported to a progress callback: peaks located, stiffness fit, damping fit, FRF fit, uncertainty.
_STEPS = 5
#: Correlation of two fitted parameters above which both are reported as confounded.
_MAX_CORRELATION = 0.98
#: Half-width of the polishing window around a peak: 2 ζ, at least 0.5 %.
_WINDOW_ZETAS = 2.0
_MIN_WINDOW = 0.005
#: A fitted ln-parameter this close to a bound counts as "at the bound".
_AT_BOUND = 1e-3
#: Finite-difference step of the Jacobian in θ = ln(p/p₀), and the scale of θ's steps (a
#: factor e^0.3 ≈ 1.35 at most in the first trust region).
_DIFF_STEP = 1e-4
_X_SCALE = 0.3

#: Residuals of several parameter sets at once: ``fun(sets) -> array (nsets, nresiduals)``.
SetResidual = Callable[[Sequence[Mapping[str, float]]], np.ndarray]


@dataclass
class Identification:
    """Result of a joint identification (see :meth:`to_dict` for the contract's JSON).

    Attributes
    ----------
    status : {"identified", "not_identifiable"}
    values : dict of str to float
        Every joint parameter (identified, or unchanged from the start), SI.
    uncertainty : dict of str to float
        Standard uncertainty of each identified parameter, SI.
    uncertainty_components : dict of str to dict
        Its parts: ``noise`` (the fit's covariance) and, on a ``direct_frf`` spindle,
        ``spindle_estimate`` (the spread over the rotations' bounds), SI.
    detail : str or None
        Why the data do not identify the joints (when ``status`` says so).
    not_applicable : dict of str to str
        Joint parameters that cannot exist on this spindle, and why.
    spindle_measurement : dict or None
        What the measured spindle is (kind, plane, method, conditioning), when hybrid.
    notes : list of str
    """

    status: str
    values: dict[str, float]
    start: dict[str, float]
    uncertainty: dict[str, float] = field(default_factory=dict)
    uncertainty_components: dict[str, dict[str, float]] = field(default_factory=dict)
    detail: str | None = None
    uses: list[Use] = field(default_factory=list)
    flags: list[dict[str, str]] = field(default_factory=list)
    residual_db: float | None = None
    residual_rel: float | None = None
    noise_rel: float | None = None
    band_hz: tuple[float, float] = (math.nan, math.nan)
    windows_hz: list[list[list[float]]] = field(default_factory=list)
    correlation: dict[str, Any] | None = None
    runtime_s: float = 0.0
    not_applicable: dict[str, str] = field(default_factory=dict)
    spindle_measurement: dict[str, Any] | None = None
    notes: list[str] = field(default_factory=list)
    clamping_model: str | None = None

    def to_dict(self) -> dict[str, Any]:
        """The contract's identification response (plus diagnostic fields)."""
        joints: dict[str, Any] = {}
        for joint in ("spindle_holder", "holder_tool"):
            keys = [k for k in self.values if k.startswith(joint + ".")]
            if not keys:
                continue
            entry: dict[str, Any] = {k.split(".", 1)[1]: self.values[k] for k in keys}
            clamping = "interface_stiffness_scale" in entry
            if clamping:  # the identified clamping as a holder_tool joint of the contract
                entry = {"model": self.clamping_model, **entry}
            entry["uncertainty"] = {f: self.uncertainty.get(f"{joint}.{f}")
                                    for f in (("interface_stiffness_scale",) if clamping else
                                              ("stiffness_n_m", "damping_ns_m"))}
            if any(k in self.not_applicable for k in keys):
                entry["status"] = "not_applicable"
                entry["reason"] = next(self.not_applicable[k] for k in keys if k in self.not_applicable)
            joints[joint] = entry
        out: dict[str, Any] = {
            "joints": joints,
            "status": self.status,
            "modes_used": [{"frequency_hz": u.peak.frequency_hz, "controls": u.parameter,
                            "measurement": u.measurement, "sensitivity": u.sensitivity} for u in self.uses],
            "residual_db": self.residual_db,
            "residual_rel": self.residual_rel,
            "noise_rel": self.noise_rel,
            "flags": self.flags,
            "start": self.start,
            "band_hz": list(self.band_hz),
            "windows_hz": self.windows_hz,
            "runtime_s": self.runtime_s,
        }
        if self.uncertainty_components:
            out["uncertainty_components"] = self.uncertainty_components
        if self.not_applicable:
            out["not_applicable"] = [{"parameter": k, "reason": v} for k, v in self.not_applicable.items()]
        if self.spindle_measurement is not None:
            out["spindle_measurement"] = self.spindle_measurement
        if self.notes:
            out["notes"] = self.notes
        if self.correlation is not None:
            out["correlation"] = self.correlation
        if self.detail is not None:
            out["detail"] = self.detail
        return out


# ---------------------------------------------------------------------------- stages 3–5


def _fit(fun: SetResidual, names: list[str], values: dict[str, float], problem: Problem
         ) -> tuple[dict[str, float], Any]:
    """Least squares in θ = ln(p/p₀) within the bounds (p₀: the values on entry).

    The Jacobian is a forward difference of step :data:`_DIFF_STEP` in θ, all its points
    in one call of ``fun``. Returns the new values and scipy's result (``fun``, ``jac`` at
    the optimum).
    """
    ref = np.array([values[n] for n in names])
    lo = np.log([problem.req.bounds[n][0] for n in names]) - np.log(ref)
    hi = np.log([problem.req.bounds[n][1] for n in names]) - np.log(ref)
    x0 = np.clip(np.zeros(len(names)), lo + 1e-9, hi - 1e-9)

    def at(x: np.ndarray) -> dict[str, float]:
        return {**values, **{n: float(r * math.exp(v)) for n, r, v in zip(names, ref, x, strict=True)}}

    def residual(x: np.ndarray) -> np.ndarray:
        out: np.ndarray = fun([at(x)])[0]
        return out

    def jacobian(x: np.ndarray) -> np.ndarray:
        steps = np.where(x + _DIFF_STEP <= hi, _DIFF_STEP, -_DIFF_STEP)
        points = [x] + [x + steps[j] * np.eye(len(names))[j] for j in range(len(names))]
        r = fun([at(p) for p in points])
        out: np.ndarray = ((r[1:] - r[0]) / steps[:, None]).T
        return out

    res = least_squares(residual, x0, jac=jacobian, bounds=(lo, hi), method="trf", x_scale=_X_SCALE,
                        max_nfev=100 * len(names))
    for n, x, a, b in zip(names, res.x, lo, hi, strict=True):
        if x - a < _AT_BOUND or b - x < _AT_BOUND:
            raise NotIdentifiable(
                f"{n}: the fit ended at a bound of its search range [{problem.req.bounds[n][0]:.4g}, "
                f"{problem.req.bounds[n][1]:.4g}]; the data do not support a value inside it (bad start or "
                "bounds, or a model that cannot follow the data)")
    return at(res.x), res


def _peak_lines(problem: Problem, uses: list[Use]) -> list[np.ndarray]:
    """The measured lines of each used mode's window: its model and measured peaks inside."""
    out = []
    for u in uses:
        f = problem.req.measurements[u.measurement].frequency_hz
        lo = min(u.peak.frequency_hz, u.model_peak_hz) * (1 - u.window_rel[0])
        hi = max(u.peak.frequency_hz, u.model_peak_hz) * (1 + u.window_rel[1])
        out.append(np.flatnonzero((f >= lo) & (f <= hi)))
    return out


def _peak_residual(problem: Problem, uses: list[Use], magnitude: bool) -> tuple[SetResidual, Callable[
        [dict[str, float]], None]]:
    """ln(model/measured) of the frequency (or peak height) of each used mode, both read by
    :func:`~rcsa.analysis.joint_identification.locate.band_features` on the mode's lines."""
    lines = _peak_lines(problem, uses)
    reqs = problem.req.measurements
    measured = [band_features(reqs[u.measurement].frequency_hz[idx], reqs[u.measurement].h[idx],
                              u.peak.frequency_hz) for u, idx in zip(uses, lines, strict=True)]
    for u, (fm, mm) in zip(uses, measured, strict=True):
        if not (math.isfinite(fm) and math.isfinite(mm)):
            raise NotIdentifiable(f"the measured peak near {u.peak.frequency_hz:.1f} Hz (measurement "
                                  f"{u.measurement}) cannot be read as a mode (no stable pole fits it)")
    per_m = {m: [k for k, u in enumerate(uses) if u.measurement == m] for m in {u.measurement for u in uses}}
    union = {m: np.unique(np.concatenate([lines[k] for k in ks])) for m, ks in per_m.items()}

    def features(sets: Sequence[Mapping[str, float]]) -> np.ndarray:
        out = np.empty((len(sets), len(uses), 2))
        for m, ks in per_m.items():
            f = reqs[m].frequency_hz
            h = problem.h_sets(m, sets, f[union[m]])
            pos = {int(line): i for i, line in enumerate(union[m])}
            for k in ks:
                cols = [pos[int(line)] for line in lines[k]]
                for s in range(len(sets)):
                    out[s, k] = band_features(f[lines[k]], h[s, cols], uses[k].peak.frequency_hz)
        return out

    ref = np.array([[math.log(fm), math.log(mm)] for fm, mm in measured])
    column = 1 if magnitude else 0

    def fun(sets: Sequence[Mapping[str, float]]) -> np.ndarray:
        feats = features(sets)[:, :, column]
        with np.errstate(invalid="ignore", divide="ignore"):
            r = np.log(feats) - ref[None, :, column]
        return np.where(np.isfinite(r), r, 1.0)  # a lost mode: a bounded, large residual

    def check(values: dict[str, float]) -> None:
        feats = features([values])[0]
        for k, (fm, mm) in enumerate(feats):
            if not (math.isfinite(fm) and math.isfinite(mm)):
                u = uses[k]
                raise NotIdentifiable(f"the model has no mode near {u.peak.frequency_hz:.1f} Hz (measurement "
                                      f"{u.measurement}) after fitting {u.parameter}: the data do not follow "
                                      "the model there")

    return fun, check


def _window_lines(problem: Problem, uses: list[Use]) -> list[np.ndarray]:
    """Indices of the measured lines near each used peak, per measurement."""
    out = []
    for m, meas in enumerate(problem.req.measurements):
        mask = np.zeros(meas.frequency_hz.size, dtype=bool)
        for u in (u for u in uses if u.measurement == m):
            zeta = u.peak.damping_ratio if math.isfinite(u.peak.damping_ratio) else 0.01
            half = max(_WINDOW_ZETAS * zeta, _MIN_WINDOW)
            half = min(half, 0.9 * min(u.window_rel))
            f = u.peak.frequency_hz
            mask |= (meas.frequency_hz >= f * (1 - half)) & (meas.frequency_hz <= f * (1 + half))
        out.append(np.flatnonzero(mask))
    return out


def _frf_residual(problem: Problem, lines: list[np.ndarray], weighted: bool = True) -> SetResidual:
    """Complex log residual ``w·ln(h_model/h_measured)`` on the window lines, as reals."""
    data = [(m, problem.req.measurements[m], idx) for m, idx in enumerate(lines) if idx.size]
    weights = [coherence_weights(None if meas.coherence is None else meas.coherence[idx], idx.size)
               if weighted else np.ones(idx.size) for _, meas, idx in data]

    def fun(sets: Sequence[Mapping[str, float]]) -> np.ndarray:
        parts = []
        for (m, meas, idx), w in zip(data, weights, strict=True):
            r = np.log(problem.h_sets(m, sets, meas.frequency_hz[idx]) / meas.h[idx][None, :])
            r = r.real + 1j * np.angle(np.exp(1j * r.imag))
            parts.extend([w * r.real, w * r.imag])
        return np.concatenate(parts, axis=1)

    return fun


def _windows_hz(problem: Problem, lines: list[np.ndarray]) -> list[list[list[float]]]:
    out = []
    for meas, idx in zip(problem.req.measurements, lines, strict=True):
        runs = np.split(idx, np.flatnonzero(np.diff(idx) > 1) + 1) if idx.size else []
        out.append([[float(meas.frequency_hz[r[0]]), float(meas.frequency_hz[r[-1]])] for r in runs])
    return out


# ---------------------------------------------------------------------------- driver


def _all_joint_values(spec: AssemblySpec) -> dict[str, float]:
    out = {}
    for joint in ("spindle_holder", "holder_tool"):
        spec_joint = getattr(spec, joint)
        if isinstance(spec_joint, ClampingSpec):  # a clamping along the insertion: its interface stiffness
            out[f"{joint}.interface_stiffness_scale"] = float(spec_joint.interface_stiffness_scale)
            continue
        if not isinstance(spec_joint, JointSpec):  # rigid
            continue
        for f in ("stiffness_n_m", "damping_ns_m", "rotational_stiffness_nm_rad", "rotational_damping_nms_rad"):
            v = getattr(spec_joint, f)
            if v is not None:
                out[f"{joint}.{f}"] = float(v)
    return out


def _model_noise(problem: Problem, m: int, values: dict[str, float], lines: np.ndarray) -> float:
    """RMS relative noise of model ``m``'s FRF on the window ``lines`` (a measured spindle's noise,
    spikes included: the residual sees them all)."""
    f = problem.req.measurements[m].frequency_hz
    if lines.size < 12:
        return float(np.median(problem.model_noise(m, f)))
    h = np.ones(f.size, dtype=complex)
    h[lines] = problem.h(m, values, f[lines])
    return relative_noise(h, lines, robust=False)


def _spindle_estimate(req: IdentificationRequest, values: dict[str, float], names: list[str],
                      lines: list[np.ndarray]) -> dict[str, float]:
    """Standard uncertainty from a ``direct_frf`` spindle's estimated rotations (stage 5 on each bound)."""
    spindle = req.spindle
    if spindle is None or len(spindle.alternatives) != 2:
        return {}
    ends = []
    for k in (0, 1):
        problem = Problem(req, spindle_index=k)
        try:
            ends.append(_fit(_frf_residual(problem, lines), names, values, problem)[0])
        except NotIdentifiable:
            ends.append(dict.fromkeys(names, math.nan))
    return {n: abs(ends[0][n] - ends[1][n]) / (2.0 * math.sqrt(3.0)) for n in names}


def _hybrid_notes(req: IdentificationRequest) -> list[str]:
    spindle = req.spindle
    if spindle is None:
        return []
    notes = list(spindle.notes)
    kind = spindle.kind
    if kind == "direct_frf":
        notes.append("the spindle's rotations are estimated (equivalent cantilever): stage 5 is repeated with "
                     "their bounds, and the spread enters each uncertainty (uncertainty_components."
                     "spindle_estimate)")
    elif kind == "artifact_frfs":
        cond = spindle.report.get("condition_number_max")
        notes.append("the spindle was identified from artifact FRFs"
                     + (f" (condition number up to {cond:.3g})" if isinstance(cond, int | float) else "")
                     + ": its noise makes the model noisy; that noise is estimated from the model itself and "
                     "added to the measurement's (noise_rel), and it is in the residual behind the uncertainties")
    if spindle.plane == "holder_tip" and spindle.report.get("kind") == "artifact_frfs":
        notes.append("holder_tip artifact measurement: the artifact's clamping is inside it, so an identified "
                     "holder_tool joint is this tool's clamping relative to the artifact's")
    return notes


def identify_joints(req: IdentificationRequest, progress: Progress | None = None) -> Identification:
    """Identify the joints' translational stiffness and damping (see the module docstring).

    Parameters
    ----------
    req : IdentificationRequest
        From :func:`rcsa.analysis.joint_identification.request.parse_identification_request`.
    progress : callable, optional
        ``progress(done, total)`` after the peaks are located, after each fit and at the
        end (:mod:`rcsa.analysis.progress`).

    Returns
    -------
    Identification
    """
    t0 = time.perf_counter()
    problem = Problem(req)
    start = _all_joint_values(req.base)
    band = (min(float(m.frequency_hz[0]) for m in req.measurements),
            max(float(m.frequency_hz[-1]) for m in req.measurements))
    result = Identification("not_identifiable", dict(start), dict(start), band_hz=band,
                            not_applicable=dict(req.not_applicable),
                            spindle_measurement=None if req.spindle is None else dict(req.spindle.report),
                            notes=_hybrid_notes(req),
                            clamping_model=req.base.holder_tool.model if isinstance(req.base.holder_tool, ClampingSpec)
                            else None)
    flags: list[dict[str, str]] = []
    noise = [relative_noise(m.h) for m in req.measurements]
    try:
        peaks = [measured_peaks(m.frequency_hz, m.h, s) for m, s in zip(req.measurements, noise, strict=True)]
        if not any(p.prominence >= PEAK_PROMINENCE for pk in peaks for p in pk):
            raise NotIdentifiable(f"no resonance peak stands out of the noise in the measured band "
                                   f"{band[0]:g}–{band[1]:g} Hz, so no mode controlled by a joint is seen")
        values, uses, flags = locate(problem, peaks)
        report(progress, 1, _STEPS)
        if not uses:
            raise NotIdentifiable(
                f"the measured band {band[0]:g}–{band[1]:g} Hz holds no peak of a mode controlled by a joint "
                f"parameter; measure across the joints' controlling modes ({where_modes(problem, values)})")
        k_uses = [u for u in uses if "stiffness" in u.parameter]
        c_uses = [u for u in uses if "damping" in u.parameter]
        k_names = list(dict.fromkeys(u.parameter for u in k_uses))
        c_names = list(dict.fromkeys(u.parameter for u in c_uses))
        for names_, uses_, magnitude in ((k_names, k_uses, False), (c_names, c_uses, True)):
            if names_:
                fun, check = _peak_residual(problem, uses_, magnitude)
                values, _ = _fit(fun, names_, values, problem)
                check(values)
            report(progress, 3 if magnitude else 2, _STEPS)
        lines = _window_lines(problem, uses)
        names = k_names + c_names
        values, res = _fit(_frf_residual(problem, lines), names, values, problem)
        report(progress, 4, _STEPS)
        raw = _frf_residual(problem, lines, weighted=False)([values])[0]
        m_res, p = res.fun.size, len(names)
        s2 = float(res.fun @ res.fun) / max(m_res - p, 1)
        cov = s2 * np.linalg.pinv(res.jac.T @ res.jac)
        sigma = np.sqrt(np.clip(np.diag(cov), 0.0, None))
        rms = math.sqrt(2.0 * float(raw @ raw) / raw.size)  # per complex line
        # the noise where the fit is judged (the windows), else over the whole measurement; plus the
        # model's own (a measured spindle's noise), estimated alike
        local = [relative_noise(m.h, idx) for m, idx in zip(req.measurements, lines, strict=True)]
        noise_lines = [a if math.isfinite(a) and idx.size >= 12 else b
                       for a, b, idx in zip(local, noise, lines, strict=True)]
        model_noise = [_model_noise(problem, k, values, idx) for k, idx in enumerate(lines)]
        total = [math.hypot(a, b if math.isfinite(b) else 0.0) for a, b in zip(noise_lines, model_noise,
                                                                              strict=True)]
        noise_rel = float(np.sqrt(np.nanmean(np.square(total))))
        result.residual_rel, result.noise_rel = rms, noise_rel
        result.residual_db = _db(raw, lines)
        result.windows_hz = _windows_hz(problem, lines)
        result.uses = uses
        if np.all(sigma > 0):
            corr = cov / np.outer(sigma, sigma)
            result.correlation = {"parameters": names, "matrix": corr.tolist()}
            for i, j in zip(*np.triu_indices(len(names), 1), strict=True):
                if abs(corr[i, j]) > _MAX_CORRELATION:
                    flags.append({"parameter": names[i], "reason": (
                        f"strongly correlated with {names[j]} (rho = {corr[i, j]:.3f}): the data constrain "
                        "their combination better than each alone")})
        if rms > req.max_residual_to_noise * noise_rel:
            raise NotIdentifiable(
                f"the fitted model leaves an RMS residual of {100 * rms:.2g} % around the used peaks, "
                f"{rms / noise_rel:.1f}× the measurement noise ({100 * noise_rel:.2g} %): the model cannot "
                "reproduce the measurement there (bad start, or a model-form error the joints cannot absorb)")
        u_noise = {n: float(values[n] * s) for n, s in zip(names, sigma, strict=True)}
        u_spindle = _spindle_estimate(req, values, names, lines)
        result.status = "identified"
        result.values = {**start, **{n: values[n] for n in names}}
        result.uncertainty = {n: math.hypot(u_noise[n], u_spindle.get(n, 0.0)) for n in names}
        if u_spindle:
            result.uncertainty_components = {n: {"noise": u_noise[n], "spindle_estimate": u_spindle[n]}
                                             for n in names}
            if any(not math.isfinite(v) for v in u_spindle.values()):
                raise NotIdentifiable("the fit cannot be repeated within the bounds of the spindle's estimated "
                                      "rotations (direct_frf, L/2 and 2L): the joints are not determined by "
                                      "this measurement; measure the spindle's rotations (artifact_frfs)")
    except NotIdentifiable as exc:
        result.status, result.detail = "not_identifiable", str(exc)
        if req.spindle is not None and req.spindle.kind == "direct_frf":
            result.detail += ("; note that the measured spindle is a direct_frf whose rotations are only estimated "
                              "(equivalent cantilever), a likely model-form error: measure them (artifact_frfs) or "
                              "adjust spindle.effective_length_m")
        result.values, result.uncertainty, result.uncertainty_components = dict(start), {}, {}
    result.flags = flags
    result.runtime_s = time.perf_counter() - t0
    report(progress, _STEPS, _STEPS)
    return result


def _db(raw: np.ndarray, lines: list[np.ndarray]) -> float:
    """RMS of 20 log10|h_model/h_measured| over all window lines, dB."""
    real_parts, k = [], 0
    for idx in lines:
        if idx.size:
            real_parts.append(raw[k:k + idx.size])
            k += 2 * idx.size
    db = 20.0 / math.log(10.0) * np.concatenate(real_parts)
    return float(np.sqrt(np.mean(db**2)))


def identify(request: Mapping[str, Any], resolve_base: BaseResolver | None = None,
             progress: Progress | None = None) -> dict[str, Any]:
    """Joint identification as JSON (the CLI's and the REST route's entry point).

    Parameters
    ----------
    request : dict
        ``{"assembly": {...}, "measurements": [{"tool": {...}, "frequency_hz": [...],
        "h": {"real": [...], "imag": [...]}, "coherence": [...]}], "bounds": {...},
        "max_residual_to_noise": 4.0}`` (``docs/contract.md`` "Joint identification";
        ``bounds`` and ``max_residual_to_noise`` optional). The assembly's spindle may be
        ``{"measurement_id": ...}`` when ``resolve_base`` is given.
    resolve_base : BaseResolver, optional
        Looks a measured spindle up (the application layer passes the store's).
    progress : callable, optional
        ``progress(done, total)`` at each step (:func:`identify_joints`).

    Returns
    -------
    dict
        ``{"joints": {...}, "status", "detail" (when not identifiable), "modes_used",
        "residual_db", "flags", "band_hz", "windows_hz", "runtime_s", ...}``; on a measured
        spindle also ``spindle_measurement``, ``notes``, ``not_applicable`` and
        ``uncertainty_components``.

    Raises
    ------
    InputError
        For a malformed request.
    """
    return identify_joints(parse_identification_request(request, resolve_base), progress).to_dict()
