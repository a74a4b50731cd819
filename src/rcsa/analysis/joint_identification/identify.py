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
2. **Which mode informs which parameter.** An effect analysis (:mod:`rcsa.analysis.sensitivity`) at
   that point gives ``d ln f / d ln k`` and ``d ln|h|_peak / d ln c`` for every mode in the
   measured band; each parameter takes its most sensitive mode among those seen as peaks
   in the measurement (greedily, one mode per parameter, stiffnesses and dampings
   separately). A parameter whose best ``|S|`` is below 0.05 (stiffness) or 0.1 (damping)
   is not informed by the data: it is returned unchanged and flagged, and the grid is
   searched again without it. Stages 1–2 live in :mod:`rcsa.analysis.joint_identification.locate`.
3. **Stiffness from the frequencies.** Levenberg–Marquardt (``scipy.optimize.least_squares``,
   trust-region reflective within the bounds) on ``ln f_peak,model − ln f_peak,measured`` of
   the stiffness modes.
4. **Damping from the peaks.** The same on ``ln |h|_peak,model − ln |h|_peak,measured`` of
   the damping modes, stiffnesses held.
5. **Polish and uncertainty.** All informed parameters together on the complex log residual
   ``r = w·ln(h_model/h_measured)`` (real part: log magnitude, imaginary part: phase) on the
   lines within ``±max(2ζ, 0.5 %)`` of each used peak, ``w`` from the coherence when given.
   The covariance of θ is ``s² (JᵀJ)⁻¹`` with ``s² = ‖r‖²/(m − p)`` (m real residuals, p
   parameters, J the Jacobian of r at the optimum), and a parameter's standard uncertainty
   is ``p·σ_θ`` (delta method). It covers the noise only, not model-form error.

Honesty checks, each giving ``status: "not_identifiable"`` with a ``detail``: no peak in the
band, no parameter informed, a best coarse match at the edge of the search range or at a
bound, a fitted parameter ending at a bound, a peak the model cannot follow, and an RMS fit
residual more than ``max_residual_to_noise`` (default 4) times the noise, which is
estimated from the measurement itself (:func:`rcsa.analysis.joint_identification.measured_peaks.relative_noise`).
Then the joints are returned as given (never invented) and the uncertainties are null.

On RA-1 with 1 % complex noise and a start 3× off (``tests/analysis/test_joint_identification.py``) the errors
are ~1e-4 (stiffness) and ~1e-3 (damping), consistent with the stated uncertainties, in
about 1 s for 4951 lines (``benchmarks/bench_jointid.py``).

Examples
--------
>>> from rcsa.app.predictions import predict
>>> from rcsa.reference import ra1
>>> p = predict(ra1({"start_hz": 300.0, "stop_hz": 4500.0, "step_hz": 2.0}))
>>> measurement = {"frequency_hz": p.frequency_hz.tolist(),
...                "h": {"real": p.tool_point.h.real.tolist(), "imag": p.tool_point.h.imag.tolist()}}
>>> start = ra1()
>>> start["joints"]["holder_tool"].update(stiffness_n_m=3.0e7, damping_ns_m=90.0)
>>> out = identify({"assembly": start, "measurements": [measurement]})
>>> out["status"], round(out["joints"]["holder_tool"]["stiffness_n_m"] / 1.14e7, 4)
('identified', 1.0)
"""

from __future__ import annotations

import math
import time
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from scipy.optimize import least_squares

from rcsa.analysis.joint_identification.locate import (
    NotIdentifiable,
    Problem,
    Use,
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
from rcsa.analysis.mode_features import window_peaks
from rcsa.model.contract import AssemblySpec

__all__ = ["Identification", "identify", "identify_joints"]

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
    detail : str or None
        Why the data do not identify the joints (when ``status`` says so).
    """

    status: str
    values: dict[str, float]
    start: dict[str, float]
    uncertainty: dict[str, float] = field(default_factory=dict)
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

    def to_dict(self) -> dict[str, Any]:
        """The contract's identification response (plus diagnostic fields)."""
        joints: dict[str, Any] = {}
        for joint in ("spindle_holder", "holder_tool"):
            keys = [k for k in self.values if k.startswith(joint + ".")]
            if not keys:
                continue
            entry: dict[str, Any] = {k.split(".", 1)[1]: self.values[k] for k in keys}
            entry["uncertainty"] = {f: self.uncertainty.get(f"{joint}.{f}")
                                    for f in ("stiffness_n_m", "damping_ns_m")}
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
        if self.correlation is not None:
            out["correlation"] = self.correlation
        if self.detail is not None:
            out["detail"] = self.detail
        return out


# ---------------------------------------------------------------------------- stages 3–5


def _fit(fun: Any, names: list[str], values: dict[str, float], problem: Problem
         ) -> tuple[dict[str, float], Any]:
    """Least squares in θ = ln(p/p₀) within the bounds (p₀: the values on entry).

    Returns the new values and scipy's result (``fun``, ``jac`` at the optimum).
    """
    ref = np.array([values[n] for n in names])
    lo = np.log([problem.req.bounds[n][0] for n in names]) - np.log(ref)
    hi = np.log([problem.req.bounds[n][1] for n in names]) - np.log(ref)
    x0 = np.clip(np.zeros(len(names)), lo + 1e-9, hi - 1e-9)

    def at(x: np.ndarray) -> dict[str, float]:
        return {**values, **{n: float(r * math.exp(v)) for n, r, v in zip(names, ref, x, strict=True)}}

    res = least_squares(lambda x: fun(at(x)), x0, bounds=(lo, hi), method="trf", diff_step=_DIFF_STEP,
                        x_scale=_X_SCALE, max_nfev=100 * len(names))
    for n, x, a, b in zip(names, res.x, lo, hi, strict=True):
        if x - a < _AT_BOUND or b - x < _AT_BOUND:
            raise NotIdentifiable(
                f"{n}: the fit ended at a bound of its search range [{problem.req.bounds[n][0]:.4g}, "
                f"{problem.req.bounds[n][1]:.4g}]; the data do not support a value inside it (bad start or "
                "bounds, or a model that cannot follow the data)")
    return at(res.x), res


def _peak_residual(problem: Problem, uses: list[Use], magnitude: bool) -> Any:
    """ln(model/measured) of the peak frequency (or height) of each used mode."""
    windows = []
    for u in uses:  # the model's peak at the location stage and the measured one: both inside
        lo = min(u.peak.frequency_hz, u.model_peak_hz) * (1 - u.window_rel[0])
        hi = max(u.peak.frequency_hz, u.model_peak_hz) * (1 + u.window_rel[1])
        windows.append((lo, hi))

    def fun(values: dict[str, float]) -> np.ndarray:
        out = np.empty(len(uses))
        for m in {u.measurement for u in uses}:
            idx = [k for k, u in enumerate(uses) if u.measurement == m]
            _, f_pk, mag = window_peaks(problem.chain(m, values), np.array([windows[k][0] for k in idx]),
                                        np.array([windows[k][1] for k in idx]), points=81)
            for k, fp, mg in zip(idx, f_pk, mag, strict=True):
                out[k] = math.log(mg / uses[k].peak.magnitude_m_n) if magnitude \
                    else math.log(fp / uses[k].peak.frequency_hz)
        return out

    def check(values: dict[str, float]) -> None:
        for m in {u.measurement for u in uses}:
            idx = [k for k, u in enumerate(uses) if u.measurement == m]
            found, _, _ = window_peaks(problem.chain(m, values), np.array([windows[k][0] for k in idx]),
                                       np.array([windows[k][1] for k in idx]), points=81)
            if not found.all():
                k = idx[int(np.flatnonzero(~found)[0])]
                raise NotIdentifiable(f"the model has no peak near {uses[k].peak.frequency_hz:.1f} Hz "
                                       f"(measurement {m}) after fitting {uses[k].parameter}: the data do not "
                                       "follow the model there")

    fun.check = check  # type: ignore[attr-defined]
    return fun


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


def _frf_residual(problem: Problem, lines: list[np.ndarray], weighted: bool = True) -> Any:
    """Complex log residual ``w·ln(h_model/h_measured)`` on the window lines, as reals."""
    data = [(m, problem.req.measurements[m], idx) for m, idx in enumerate(lines) if idx.size]
    weights = [coherence_weights(None if meas.coherence is None else meas.coherence[idx], idx.size)
               if weighted else np.ones(idx.size) for _, meas, idx in data]

    def fun(values: dict[str, float]) -> np.ndarray:
        parts = []
        for (m, meas, idx), w in zip(data, weights, strict=True):
            r = np.log(problem.h(m, values, meas.frequency_hz[idx]) / meas.h[idx])
            r = r.real + 1j * np.angle(np.exp(1j * r.imag))
            parts.extend([w * r.real, w * r.imag])
        return np.concatenate(parts)

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
        if spec_joint is None:
            continue
        for f in ("stiffness_n_m", "damping_ns_m", "rotational_stiffness_nm_rad", "rotational_damping_nms_rad"):
            v = getattr(spec_joint, f)
            if v is not None:
                out[f"{joint}.{f}"] = float(v)
    return out


def identify_joints(req: IdentificationRequest) -> Identification:
    """Identify the joints' translational stiffness and damping (see the module docstring).

    Parameters
    ----------
    req : IdentificationRequest
        From :func:`rcsa.analysis.joint_identification.request.parse_identification_request`.

    Returns
    -------
    Identification
    """
    t0 = time.perf_counter()
    problem = Problem(req)
    start = _all_joint_values(req.base)
    band = (min(float(m.frequency_hz[0]) for m in req.measurements),
            max(float(m.frequency_hz[-1]) for m in req.measurements))
    result = Identification("not_identifiable", dict(start), dict(start), band_hz=band)
    flags: list[dict[str, str]] = []
    noise = [relative_noise(m.h) for m in req.measurements]
    try:
        peaks = [measured_peaks(m.frequency_hz, m.h, s) for m, s in zip(req.measurements, noise, strict=True)]
        if not any(p.prominence >= PEAK_PROMINENCE for pk in peaks for p in pk):
            raise NotIdentifiable(f"no resonance peak stands out of the noise in the measured band "
                                   f"{band[0]:g}–{band[1]:g} Hz, so no mode controlled by a joint is seen")
        values, uses, flags = locate(problem, peaks)
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
                fun = _peak_residual(problem, uses_, magnitude)
                values, _ = _fit(fun, names_, values, problem)
                fun.check(values)
        lines = _window_lines(problem, uses)
        names = k_names + c_names
        values, res = _fit(_frf_residual(problem, lines), names, values, problem)
        raw = _frf_residual(problem, lines, weighted=False)(values)
        m_res, p = res.fun.size, len(names)
        s2 = float(res.fun @ res.fun) / max(m_res - p, 1)
        cov = s2 * np.linalg.pinv(res.jac.T @ res.jac)
        sigma = np.sqrt(np.clip(np.diag(cov), 0.0, None))
        rms = math.sqrt(2.0 * float(raw @ raw) / raw.size)  # per complex line
        # the noise where the fit is judged (the windows), else over the whole measurement
        local = [relative_noise(m.h, idx) for m, idx in zip(req.measurements, lines, strict=True)]
        noise_lines = [a if math.isfinite(a) and idx.size >= 12 else b
                       for a, b, idx in zip(local, noise, lines, strict=True)]
        noise_rel = float(np.sqrt(np.nanmean(np.square(noise_lines))))
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
        result.status = "identified"
        result.values = {**start, **{n: values[n] for n in names}}
        result.uncertainty = {n: float(values[n] * s) for n, s in zip(names, sigma, strict=True)}
    except NotIdentifiable as exc:
        result.status, result.detail = "not_identifiable", str(exc)
        result.values, result.uncertainty = dict(start), {}
    result.flags = flags
    result.runtime_s = time.perf_counter() - t0
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


def identify(request: Mapping[str, Any]) -> dict[str, Any]:
    """Joint identification as JSON (the CLI's and the REST route's entry point).

    Parameters
    ----------
    request : dict
        ``{"assembly": {...}, "measurements": [{"tool": {...}, "frequency_hz": [...],
        "h": {"real": [...], "imag": [...]}, "coherence": [...]}], "bounds": {...},
        "max_residual_to_noise": 4.0}`` (``contract.md`` "Joint identification";
        ``bounds`` and ``max_residual_to_noise`` optional).

    Returns
    -------
    dict
        ``{"joints": {...}, "status", "detail" (when not identifiable), "modes_used",
        "residual_db", "flags", "band_hz", "windows_hz", "runtime_s", ...}``

    Raises
    ------
    InputError
        For a malformed request.
    """
    return identify_joints(parse_identification_request(request)).to_dict()
