"""Stages 1–2 of the joint identification: where the joints' modes are, and which informs what.

* :func:`locate` — a coarse grid of the joint stiffnesses matched on the resonance-peak
  frequencies (model vs measurement), then an effect analysis (:mod:`rcsa.analysis.sensitivity`) that
  gives each joint parameter its most sensitive measured mode.
* :class:`Problem` — the model of every measured configuration at given joint values.
* :class:`Use` — one (measurement, mode) pair that informs one parameter.

See :mod:`rcsa.analysis.joint_identification.identify` for the whole procedure.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from rcsa.analysis.joint_identification.measured_peaks import (
    PEAK_PROMINENCE,
    MeasuredPeak,
    peaks_ln_hz,
)
from rcsa.analysis.joint_identification.request import IdentificationRequest
from rcsa.analysis.mode_features import mode_windows
from rcsa.analysis.sensitivity import effect_analysis
from rcsa.model.assembly import build_model
from rcsa.model.contract import AssemblySpec
from rcsa.model.parameters import get_parameter, set_parameter
from rcsa.model.prediction import SubassemblyCache
from rcsa.physics.algebra2x2 import inv2
from rcsa.physics.chain import Chain
from rcsa.physics.elimination import march

__all__ = ["NotIdentifiable", "Problem", "Use", "locate", "where_modes"]

_TWO_PI = 2.0 * np.pi
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


@dataclass(frozen=True)
class Use:
    """One (measurement, mode) pair that informs one parameter.

    Attributes
    ----------
    measurement : int
        Index of the measurement.
    parameter : str
        E.g. ``"holder_tool.stiffness_n_m"``.
    model_frequency_hz, model_peak_hz : float
        The mode's undamped natural frequency and damped tool-point peak in the model at
        the located values, Hz.
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
    model_frequency_hz: float
    model_peak_hz: float
    peak: MeasuredPeak
    window_rel: tuple[float, float]
    sensitivity: float


class NotIdentifiable(Exception):
    """Raised inside the procedure; becomes ``status: not_identifiable`` with this detail."""


class Problem:
    """Model evaluations of every measured configuration at given joint parameters.

    Parameters
    ----------
    req : IdentificationRequest
    """

    def __init__(self, req: IdentificationRequest) -> None:
        self.req = req
        self.names = req.parameters
        self.start = {n: float(get_parameter(req.base, n) or 0.0) for n in self.names}

    def spec(self, m: int, values: Mapping[str, float]) -> AssemblySpec:
        """Measurement ``m``'s assembly with the named parameters set (SI)."""
        spec = self.req.measurements[m].spec
        for name, value in values.items():
            spec = set_parameter(spec, name, value)
        return spec

    def chain(self, m: int, values: Mapping[str, float]) -> Chain:
        """Its whole chain, spindle rear → tool tip."""
        return build_model(self.spec(m, values)).chain()

    def h(self, m: int, values: Mapping[str, float], frequency_hz: np.ndarray) -> np.ndarray:
        """Its tool-point h (m/N) at the given frequencies, shape (nfreq,)."""
        g = inv2(march(self.chain(m, values), _TWO_PI * frequency_hz)[0])
        return g[:, 0, 0]


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


def _coarse_match(problem: Problem, values: dict[str, float], measured_ln: list[tuple[np.ndarray, np.ndarray]],
                  k_names: list[str]) -> tuple[dict[str, float], float, dict[str, str]]:
    """Stage 1: grid search of the joint stiffnesses on the peak-frequency match.

    Returns the best values, their peak mismatch, and for each stiffness whose best grid
    point lies on the edge of its range, the reason (raised later if it is informed). A
    stiffness that does not move the peaks at all is held at its start.
    """
    grids = []
    for m in problem.req.measurements:
        f = np.geomspace(m.frequency_hz[0], m.frequency_hz[-1], min(_GRID_LINES, m.frequency_hz.size))
        grids.append((f, SubassemblyCache(_TWO_PI * f)))

    def mismatch(k_values: dict[str, float]) -> float:
        total = 0.0
        for i, (f, cache) in enumerate(grids):
            model = build_model(problem.spec(i, {**values, **k_values}))
            tail = model.tool_side()
            h = inv2(march(tail, cache.omega_rad_s, cache.condensed(model.to_holder_tip()))[0])[:, 0, 0]
            total += _peak_mismatch(peaks_ln_hz(f, h), measured_ln[i])
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


def _assign(problem: Problem, values: dict[str, float], peaks: list[list[MeasuredPeak]]
            ) -> tuple[list[Use], list[dict[str, str]]]:
    """Stage 2: each parameter's most informative measured mode(s), from an effect analysis."""
    rotational = [f"{j}.rotational_stiffness_nm_rad" for j in ("spindle_holder", "holder_tool")]
    uses: list[Use] = []
    best_rot: dict[str, float] = {}
    for m, meas in enumerate(problem.req.measurements):
        spec = problem.spec(m, values)
        extra = [r for r in rotational if (get_parameter(spec, r) or 0) > 0]
        report = effect_analysis(spec, parameters=[*problem.names, *extra],
                                 band_hz=(float(meas.frequency_hz[0]), float(meas.frequency_hz[-1])))
        modes = report.modes
        seen = np.flatnonzero(np.isfinite(modes.peak_frequency_hz))
        model_pk = modes.peak_frequency_hz[seen]
        # search windows between the model's *visible* peaks (hidden modes make no peak)
        windows = dict(zip(seen.tolist(), mode_windows(model_pk, model_pk), strict=True)) if seen.size else {}
        measured_hz = np.array([p.frequency_hz for p in peaks[m]])
        match = {}
        if seen.size and measured_hz.size:
            d = np.abs(np.log(measured_hz)[:, None] - np.log(model_pk)[None, :])
            for j, k in enumerate(np.argmin(d, axis=1)):  # mutual nearest, within the window
                if np.argmin(d[:, k]) == j and d[j, k] < math.log1p(0.5 * min(windows[int(seen[k])])) + 0.02:
                    match[j] = int(seen[k])
        candidates = {i: j for j, i in match.items()}
        for r in extra:
            s = max((abs(report.column(r)[i]) for i in candidates), default=0.0)
            best_rot[r] = max(best_rot.get(r, 0.0), s)
        for kind, feature, threshold in (("stiffness", "frequency_hz", _MIN_S_STIFFNESS),
                                         ("damping", "peak_magnitude_m_n", _MIN_S_DAMPING)):
            names = [n for n in problem.names if (kind == "damping") == ("damping" in n)]
            table = {n: {i: abs(float(report.column(n, feature)[i])) for i in candidates} for n in names}
            taken: set[int] = set()
            for n in sorted(names, key=lambda n: -max(table[n].values(), default=0.0)):
                options = [(s, i) for i, s in table[n].items() if i not in taken and s >= threshold]
                if not options:
                    continue
                s, i = max(options)
                taken.add(i)
                uses.append(Use(m, n, float(modes.frequency_hz[i]), float(modes.peak_frequency_hz[i]),
                                 peaks[m][candidates[i]], (float(windows[i][0]), float(windows[i][1])),
                                 float(report.column(n, feature)[i])))
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
    """Where the joint-controlled modes of the first configuration lie (for a detail message)."""
    spec = problem.spec(0, values)
    report = effect_analysis(spec, parameters=[n for n in problem.names if "stiffness" in n],
                             band_hz=(float(spec.frequency_hz[0]) / 3, float(spec.frequency_hz[-1]) * 3))
    parts = []
    for n in report.parameters:
        i = report.controlled_mode(n, min_participation=0.02)
        if i is not None:
            parts.append(f"{n}: {report.frequency_hz[i]:.0f} Hz")
    return "; ".join(parts) or "none found within a factor 3 of the band"
