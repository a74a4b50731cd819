"""Stages 1–2 of the joint identification: where the joints' modes are, and which informs what.

* :func:`locate` — a coarse grid of the joint stiffnesses matched on the resonance-peak
  frequencies (model vs measurement), then the sensitivities of the matched modes that give
  each joint parameter its most informative measured mode.
* :class:`Problem` — the model of every measured configuration at given joint values
  (:class:`~rcsa.analysis.tool_point_model.ToolPointModel`: analytical or measured spindle).
* :class:`Use` — one (measurement, mode) pair that informs one parameter.
* :func:`band_features` — a mode's frequency and peak height read from ``h`` on the
  measured lines around it, alike for the model and the measurement.

See :mod:`rcsa.analysis.joint_identification.identify` for the whole procedure.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from rcsa.analysis.effects.mode_features import mode_windows
from rcsa.analysis.effects.sensitivities import effect_analysis
from rcsa.analysis.joint_identification.measured_peaks import (
    PEAK_PROMINENCE,
    MeasuredPeak,
    peaks_ln_hz,
)
from rcsa.analysis.joint_identification.request import IdentificationRequest
from rcsa.analysis.tool_point_model import ToolPointModel
from rcsa.model.contract import AssemblySpec
from rcsa.model.modal_fit import local_relative_noise, rational_fit
from rcsa.model.parameters import get_parameter
from rcsa.physics.arrays import ComplexArray, FloatArray

__all__ = ["NotIdentifiable", "Problem", "Use", "band_features", "locate", "where_modes"]

_GRID_DECADES = 1.0
_GRID_POINTS = 9
_FINE_POINTS = 5
_GRID_LINES = 1200
#: Largest acceptable mean ln-frequency mismatch of the coarse peak match (≈ 5 %).
_MAX_PEAK_MISMATCH = 0.05
#: A stiffness whose grid line changes the mismatch by less than this (0.1 %) is not seen.
_FLAT_MISMATCH = 1e-3
#: Weight of the pull toward the start in the grid search, per decade² (0.2 % mismatch).
_PRIOR = 2e-3
#: Smallest |d ln f/d ln k| (stiffness) and |d ln|h|_peak/d ln c| (damping) that informs.
_MIN_S_STIFFNESS = 0.05
_MIN_S_DAMPING = 0.1
#: Relative step of the sensitivities of stage 2 (central differences in ln p).
_SENSITIVITY_STEP = 1e-3


@dataclass(frozen=True)
class Use:
    """One (measurement, mode) pair that informs one parameter.

    Attributes
    ----------
    measurement : int
        Index of the measurement.
    parameter : str
        E.g. ``"holder_tool.stiffness_n_m"``.
    model_peak_hz : float
        The mode's peak in the model at the located values, Hz.
    peak : MeasuredPeak
        The measured peak it was matched to.
    window_rel : (float, float)
        Relative search half-widths below/above the peak (45 % of the log gap to the
        neighbouring visible peaks, at most 10 %).
    sensitivity : float
        ``d ln f / d ln k`` (stiffness) or ``d ln|h|_peak / d ln c`` (damping) of the mode.
    """

    measurement: int
    parameter: str
    model_peak_hz: float
    peak: MeasuredPeak
    window_rel: tuple[float, float]
    sensitivity: float


class NotIdentifiable(Exception):
    """Raised inside the procedure; becomes ``status: not_identifiable`` with this detail."""


def band_features(frequency_hz: FloatArray, h: ComplexArray, near_hz: float) -> tuple[float, float]:
    """A mode's natural frequency and peak height read from ``h`` on a band of lines.

    One pole with residual terms (:func:`rcsa.model.modal_fit.rational_fit`) on the band:
    the pole nearest ``near_hz`` and the fitted ``|h|`` maximum next to it. The model and
    the measurement are read alike on the same lines, so what the form misses cancels, and
    a noisy ``h`` (a measured spindle's noise) gives smooth features.

    Returns
    -------
    (float, float)
        Hz and m/N; NaN when the band holds no stable pole or no maximum.
    """
    fit = rational_fit(frequency_hz, h)
    if fit is None:
        return math.nan, math.nan
    poles = fit.modes()["frequency_hz"]
    if poles.size == 0:
        return math.nan, math.nan
    fn = float(poles[np.argmin(np.abs(poles - near_hz))])
    return fn, fit.peak(fn)[1]


class Problem:
    """Model evaluations of every measured configuration at given joint parameters.

    Parameters
    ----------
    req : IdentificationRequest
    spindle_index : int, optional
        Evaluate on one of the measured spindle's alternative receptances (the bounds of an
        estimate, e.g. ``direct_frf`` rotations at L/2 and 2L) instead of its nominal one.
    """

    def __init__(self, req: IdentificationRequest, spindle_index: int | None = None) -> None:
        self.req = req
        self.names = req.parameters
        self.start = {n: float(get_parameter(req.base, n) or 0.0) for n in self.names}
        spindle = req.spindle
        if spindle is not None and spindle_index is not None:
            spindle = spindle.alternative(spindle_index)
        self.models = [ToolPointModel(m.spec, spindle) for m in req.measurements]
        self._model_noise: list[FloatArray] | None = None

    def spec(self, m: int, values: Mapping[str, float]) -> AssemblySpec:
        """Measurement ``m``'s assembly with the named parameters set (SI)."""
        return self.models[m].spec_at(values)

    def h(self, m: int, values: Mapping[str, float], frequency_hz: FloatArray) -> ComplexArray:
        """Its tool-point h (m/N) at the given frequencies, shape (nfreq,)."""
        return self.models[m].h(frequency_hz, values)

    def h_sets(self, m: int, sets: Sequence[Mapping[str, float]], frequency_hz: FloatArray) -> ComplexArray:
        """The same for several parameter sets in one pass, shape (nsets, nfreq)."""
        return self.models[m].h_sets(frequency_hz, sets)

    def noise_of(self, h: ComplexArray) -> FloatArray | float:
        """Local relative noise of a model FRF: a measured spindle's noise, which the joints
        amplify differently at every value (zero for an analytical spindle)."""
        if self.req.spindle is None:
            return 0.0
        return np.nan_to_num(local_relative_noise(h))

    def model_noise(self, m: int, frequency_hz: FloatArray) -> FloatArray:
        """Local relative noise of model ``m``'s FRF at the start, read at ``frequency_hz``.

        Zero in effect for an analytical spindle; a measured spindle's own noise (the
        artifact identification's, or the tap test's) for a hybrid one, where it is
        (:func:`rcsa.model.modal_fit.local_relative_noise` on the measured lines).
        """
        if self._model_noise is None:
            self._model_noise = [np.nan_to_num(local_relative_noise(self.h(k, self.start, meas.frequency_hz)))
                                 for k, meas in enumerate(self.req.measurements)]
        out: FloatArray = np.interp(frequency_hz, self.req.measurements[m].frequency_hz, self._model_noise[m])
        return out


# ---------------------------------------------------------------------------- stage 1


def _one_way(a: np.ndarray, b: np.ndarray) -> float:
    if a.size == 0:
        return 0.0
    if b.size == 0:
        return 1.0
    return float(np.abs(a[:, None] - b[None, :]).min(axis=1).mean())


def _peak_mismatch(model: tuple[np.ndarray, np.ndarray], measured: tuple[np.ndarray, np.ndarray]) -> float:
    """Symmetric mean nearest ln-frequency distance between model and measured peaks.

    Each side's prominent peaks (≥ 3 %) look for any listed peak (≥ 1 %) on the other side,
    so a borderline peak seen on one side only costs nothing.
    """
    (lm, pm), (ld, pd) = model, measured
    if not np.any(pm >= PEAK_PROMINENCE):
        return 1.0
    return _one_way(lm[pm >= PEAK_PROMINENCE], ld) + _one_way(ld[pd >= PEAK_PROMINENCE], lm)


def _coarse_grid(frequency_hz: FloatArray) -> FloatArray:
    """Geometric grid of the coarse match over a measurement's band (≤ 1200 lines)."""
    out: FloatArray = np.geomspace(frequency_hz[0], frequency_hz[-1], min(_GRID_LINES, frequency_hz.size))
    return out


def _coarse_match(problem: Problem, values: dict[str, float], measured_ln: list[tuple[np.ndarray, np.ndarray]],
                  k_names: list[str]) -> tuple[dict[str, float], float, dict[str, str]]:
    """Stage 1: grid search of the joint stiffnesses on the peak-frequency match.

    Returns the best values, their peak mismatch, and for each stiffness whose best grid
    point lies on the edge of its range, the reason (raised later if it is informed). A
    stiffness that does not move the peaks at all is held at its start.
    """
    grids = [_coarse_grid(m.frequency_hz) for m in problem.req.measurements]

    def mismatch(k_values: dict[str, float]) -> float:
        total = 0.0
        for i, f in enumerate(grids):
            h = problem.h(i, {**values, **k_values}, f)
            total += _peak_mismatch(peaks_ln_hz(f, h, problem.noise_of(h)), measured_ln[i])
        return total / len(grids)

    def search(axes: list[np.ndarray]) -> tuple[tuple[int, ...], np.ndarray, np.ndarray]:
        table, prior = np.empty([a.size for a in axes]), np.zeros([a.size for a in axes])
        for idx in itertools.product(*(range(a.size) for a in axes)):
            k_values = {n: float(a[i]) for n, a, i in zip(k_names, axes, idx, strict=True)}
            table[idx] = mismatch(k_values)
            # a weak pull toward the start decides along valleys (one mode, two stiffnesses)
            prior[idx] = _PRIOR * sum(math.log10(v / problem.start[n]) ** 2 for n, v in k_values.items())
        best = tuple(int(i) for i in np.unravel_index(int(np.argmin(table + prior)), table.shape))
        return best, table, prior

    axes = []
    for n in k_names:
        lo, hi = problem.req.bounds[n]
        s = problem.start[n]
        axes.append(np.geomspace(max(lo, s / 10**_GRID_DECADES), min(hi, s * 10**_GRID_DECADES), _GRID_POINTS))
    idx, table, _ = search(axes)
    half = _GRID_DECADES / (_GRID_POINTS - 1)
    fine, edges = [], {}
    for d, (n, a, i) in enumerate(zip(k_names, axes, idx, strict=True)):
        line = table[tuple(slice(None) if e == d else j for e, j in enumerate(idx))]
        if float(line.max() - line.min()) < _FLAT_MISMATCH:  # the peaks do not see this stiffness
            fine.append(np.array([problem.start[n]]))
            continue
        lo, hi = problem.req.bounds[n]
        if i in (0, a.size - 1):
            where = "a bound of the search range" if a[i] in (lo, hi) else "10× from the starting value"
            edges[n] = (f"{n}: the measured peaks are best matched at {a[i]:.4g} ({where}); the starting value "
                        f"{problem.start[n]:.4g} is too far from the data, or the model misses a resonance")
        fine.append(np.geomspace(max(lo, a[i] / 10**half), min(hi, a[i] * 10**half), _FINE_POINTS))
    idx, table, _ = search(fine)
    k_best = {n: float(a[i]) for n, a, i in zip(k_names, fine, idx, strict=True)}
    return {**values, **k_best}, float(table[idx]), edges


def locate(problem: Problem, peaks: list[list[MeasuredPeak]]
            ) -> tuple[dict[str, float], list[Use], list[dict[str, str]]]:
    """Stages 1–2: coarse stiffnesses, then which measured mode informs which parameter.

    A stiffness that no measured mode informs is reset to its start and the grid is searched
    again without it, so it cannot drag the others along a valley.

    Parameters
    ----------
    problem : Problem
    peaks : list of list of MeasuredPeak
        The measured peaks of each measurement.

    Returns
    -------
    values : dict of str to float
        Joint parameters after the coarse match (uninformed ones at their start), SI.
    uses : list of Use
        The modes that inform each parameter.
    flags : list of dict
        ``{"parameter", "reason"}`` for parameters held (uninformed or rotational).

    Raises
    ------
    NotIdentifiable
        Best match at the edge of the search range or a bound, or too large a mismatch.
    """
    measured_ln = [(np.log([p.frequency_hz for p in pk]), np.array([p.prominence for p in pk]))
                   if pk else (np.empty(0), np.empty(0)) for pk in peaks]
    k_all = [n for n in problem.names if "stiffness" in n]
    values, mismatch, edges = _coarse_match(problem, dict(problem.start), measured_ln, k_all)
    uses, flags = _assign(problem, values, peaks)
    informed = [n for n in k_all if any(u.parameter == n for u in uses)]
    if informed != k_all:
        values = {**values, **{n: problem.start[n] for n in k_all if n not in informed}}
        if informed:
            values, mismatch, edges = _coarse_match(problem, values, measured_ln, informed)
        uses, flags = _assign(problem, values, peaks)
    for n in informed:
        if n in edges:
            raise NotIdentifiable(edges[n])
    if informed and mismatch > _MAX_PEAK_MISMATCH:
        raise NotIdentifiable(
            f"the model's resonance peaks cannot be matched to the measured ones within the search range "
            f"(mean mismatch {100 * mismatch:.1f} % in frequency at best)")
    return values, uses, flags


# ---------------------------------------------------------------------------- stage 2


def _sensitivities(problem: Problem, m: int, values: dict[str, float], names: list[str],
                   peaks_hz: FloatArray, windows: FloatArray) -> tuple[FloatArray, FloatArray]:
    """``d ln f / d ln p`` and ``d ln|h|_peak / d ln p`` of each model peak, shape (npeaks, nnames).

    Central differences (step :data:`_SENSITIVITY_STEP` in ln p) of :func:`band_features` on
    the measured lines of each peak's window, all parameter sets in one stacked evaluation.
    """
    f = problem.req.measurements[m].frequency_hz
    bands = [np.flatnonzero((f >= pk * (1 - w[0])) & (f <= pk * (1 + w[1]))) for pk, w in zip(peaks_hz, windows,
                                                                                               strict=True)]
    lines = np.unique(np.concatenate(bands)) if bands else np.empty(0, dtype=int)
    s_f = np.full((len(bands), len(names)), np.nan)
    s_h = np.full((len(bands), len(names)), np.nan)
    if lines.size == 0 or not names:
        return s_f, s_h
    spec = problem.spec(m, values)
    nominal = {n: float(values[n]) if n in values else float(get_parameter(spec, n) or 0.0) for n in names}
    sets = [{**values, n: nominal[n] * math.exp(sign * _SENSITIVITY_STEP)} for n in names for sign in (1.0, -1.0)]
    h = problem.h_sets(m, sets, f[lines])
    where = {int(line): k for k, line in enumerate(lines)}
    for i, (band, pk) in enumerate(zip(bands, peaks_hz, strict=True)):
        cols = [where[int(line)] for line in band]
        for j in range(len(names)):
            (f_hi, m_hi), (f_lo, m_lo) = (band_features(f[band], h[2 * j + k, cols], float(pk)) for k in (0, 1))
            s_f[i, j] = (math.log(f_hi) - math.log(f_lo)) / (2 * _SENSITIVITY_STEP)
            s_h[i, j] = (math.log(m_hi) - math.log(m_lo)) / (2 * _SENSITIVITY_STEP)
    return s_f, s_h


def _assign(problem: Problem, values: dict[str, float], peaks: list[list[MeasuredPeak]]
            ) -> tuple[list[Use], list[dict[str, str]]]:
    """Stage 2: each parameter's most informative measured mode(s), from the modes' sensitivities."""
    rotational = [f"{j}.rotational_stiffness_nm_rad" for j in ("spindle_holder", "holder_tool")]
    uses: list[Use] = []
    best_rot: dict[str, float] = {}
    for m, meas in enumerate(problem.req.measurements):
        spec = problem.spec(m, values)
        extra = [r for r in rotational if (get_parameter(spec, r) or 0) > 0
                 and r.split(".")[0] in {n.split(".")[0] for n in problem.names}]
        grid = _coarse_grid(meas.frequency_hz)
        h_grid = problem.h(m, values, grid)
        ln_pk, _ = peaks_ln_hz(grid, h_grid, problem.noise_of(h_grid))
        model_pk = np.exp(ln_pk)
        # search windows between the model's *visible* peaks (hidden modes make no peak)
        windows = mode_windows(model_pk, model_pk) if model_pk.size else np.empty((0, 2))
        measured_hz = np.array([p.frequency_hz for p in peaks[m]])
        match = {}
        if model_pk.size and measured_hz.size:
            d = np.abs(np.log(measured_hz)[:, None] - np.log(model_pk)[None, :])
            for j, k in enumerate(np.argmin(d, axis=1)):  # mutual nearest, within the window
                if np.argmin(d[:, k]) == j and d[j, k] < math.log1p(0.5 * min(windows[k])) + 0.02:
                    match[j] = int(k)
        candidates = {i: j for j, i in match.items()}
        order = sorted(candidates)
        all_names = [*problem.names, *extra]
        s_f, s_h = _sensitivities(problem, m, values, all_names, model_pk[order], windows[order])
        row = {i: r for r, i in enumerate(order)}
        for r in extra:
            col = all_names.index(r)
            s = max((abs(s_f[row[i], col]) for i in candidates if math.isfinite(s_f[row[i], col])), default=0.0)
            best_rot[r] = max(best_rot.get(r, 0.0), s)
        for kind, table_s, threshold in (("stiffness", s_f, _MIN_S_STIFFNESS), ("damping", s_h, _MIN_S_DAMPING)):
            names = [n for n in problem.names if (kind == "damping") == ("damping" in n)]
            table = {n: {i: abs(float(table_s[row[i], all_names.index(n)])) for i in candidates
                         if math.isfinite(table_s[row[i], all_names.index(n)])} for n in names}
            taken: set[int] = set()
            for n in sorted(names, key=lambda n: -max(table[n].values(), default=0.0)):
                options = [(s, i) for i, s in table[n].items() if i not in taken and s >= threshold]
                if not options:
                    continue
                s, i = max(options)
                taken.add(i)
                uses.append(Use(m, n, float(model_pk[i]), peaks[m][candidates[i]],
                                (float(windows[i][0]), float(windows[i][1])),
                                float(table_s[row[i], all_names.index(n)])))
    used = {u.parameter for u in uses}
    flags: list[dict[str, str]] = []
    for n in problem.names:
        if n not in used:
            what = "natural frequency" if "stiffness" in n else "peak height"
            flags.append({"parameter": n, "reason": (
                f"not informed by the data: no resonance peak in the measured band(s) has a {what} "
                f"sensitive to it (|d ln / d ln p| below "
                f"{_MIN_S_STIFFNESS if 'stiffness' in n else _MIN_S_DAMPING}); returned unchanged")})
    for r, s in best_rot.items():
        flags.append({"parameter": r, "reason": (
            f"held at the given value (as the seed paper does); its largest |d ln f / d ln k_r| on a measured "
            f"peak is {s:.3g}")})
    return uses, flags


def where_modes(problem: Problem, values: dict[str, float]) -> str:
    """Where the joint-controlled modes of the first configuration lie (for a detail message).

    Analytical spindles only: a measured one is known only in its measured band.
    """
    if problem.req.spindle is not None:
        return "the measured spindle is known only in its measured band"
    spec = problem.spec(0, values)
    report = effect_analysis(spec, parameters=[n for n in problem.names if "stiffness" in n],
                             band_hz=(float(spec.frequency_hz[0]) / 3, float(spec.frequency_hz[-1]) * 3))
    parts = []
    for n in report.parameters:
        i = report.controlled_mode(n, min_participation=0.02)
        if i is not None:
            parts.append(f"{n}: {report.frequency_hz[i]:.0f} Hz")
    return "; ".join(parts) or "none found within a factor 3 of the band"
