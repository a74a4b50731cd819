"""Effect analysis: which bearing, joint or tool parameter moves which mode, and how.

For an analytical assembly, every mode inside a band is described by four features of the
exact model:

* ``frequency_hz`` — the undamped natural frequency (Wittrick–Williams, exact);
* ``peak_magnitude_m_n`` — the local maximum of the damped tool-point ``|h|`` next to it;
* ``peak_frequency_hz`` — where that maximum sits;
* ``damping_ratio`` — from a single-mode (Levy) fit of the damped ``h`` around the peak.

Their normalised (logarithmic) sensitivities ``S = d ln(feature) / d ln(parameter)`` to each
bearing's k and c, each joint's k_t, c_t, k_r, c_r, the stickout and the fluted diameter
ratio are central finite differences of the exact model::

    S ≈ [ln q(p·e^{+δ}) − ln q(p·e^{−δ})] / (2δ),      δ = relative_step (default 1e-3)

Step: the truncation error is ``δ²/6 · d³ln q/d(ln p)³``. The most curved entry on RA-1,
the stickout's effect on the 1384 Hz peak height (next to its veering with the 1445 Hz
mode), has ``S(δ) − S(0) ≈ −390 δ²`` (measured: −0.304 at δ = 0.01 against −0.265), so
δ = 1e-3 keeps it within 0.04 % of S = −0.27; the features themselves are computed to
~1e-10 relative (natural frequencies bracketed to 1e-11, peaks refined to sub-ppm, fits
linear), so the rounding part ``1e-10/δ`` stays near 1e-7. A 0.1 % change moves every
mode by far less than the gap to its neighbours (RA-1's closest pair, 1384/1445 Hz, is
4 % apart), so modes are tracked between the ± runs by proximity of their exact natural
frequencies. Halving the step changes the sensitivities by less than 0.2 % (tested).

This is the quantitative form of the "effect analysis" of Ertürk, Özgüven & Budak,
IJMTM 47 (2007) 23–32 (``diagnosis.md`` §3.3): bearings act on the lowest spindle modes,
the interfaces on the higher holder/tool modes; stiffness moves frequencies, damping moves
peaks.

Examples
--------
>>> from rcsa.reference import ra1
>>> doc = ra1({"start_hz": 300.0, "stop_hz": 1500.0, "step_hz": 1.0})
>>> report = effect_analysis(doc, parameters=["holder_tool.stiffness_n_m"])
>>> [round(float(f), 1) for f in report.frequency_hz]
[599.9, 921.7, 1115.5, 1383.6, 1444.7]
>>> round(report.controls("holder_tool.stiffness_n_m"), 1)
1383.6
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from .assembly import build_model
from .chain import Chain, undamped
from .dsm import march
from .errors import InputError
from .linalg2 import inv2
from .modes import natural_frequencies_hz
from .spec import AssemblySpec, SpindleSpec, parse_assembly

__all__ = [
    "FEATURES",
    "DEFAULT_RELATIVE_STEP",
    "EffectReport",
    "ModeFeatures",
    "effect_analysis",
    "effects",
    "effects_figure",
    "effects_report",
    "get_parameter",
    "mode_features",
    "nominal_features",
    "parameter_names",
    "set_parameter",
    "single_mode_fit",
    "tip_residues_1_kg",
    "window_peaks",
]

_TWO_PI = 2.0 * np.pi

#: Relative (logarithmic) finite-difference step δ; see the module docstring.
DEFAULT_RELATIVE_STEP = 0.001

#: Mode features whose sensitivities are reported, in table order.
FEATURES = ("frequency_hz", "peak_magnitude_m_n", "damping_ratio", "peak_frequency_hz")

_JOINT_FIELDS = ("stiffness_n_m", "damping_ns_m", "rotational_stiffness_nm_rad", "rotational_damping_nms_rad")
_BEARING_FIELDS = ("stiffness_n_m", "damping_ns_m")
_TOOL_FIELDS = ("stickout_m", "fluted_diameter_ratio")

# Dense local grid per mode used to find the damped peak, and its refinement passes.
_PEAK_GRID_POINTS = 161
_PEAK_REFINE_PASSES = 5
# A mode's search window reaches at most this fraction of the (log) gap to each neighbour,
# and never further than _MAX_WINDOW (relative) from its natural frequency.
_WINDOW_GAP_FRACTION = 0.45
_MAX_WINDOW = 0.10
# Points of the single-mode fit, and its half-width in units of the damping ratio.
_FIT_POINTS = 41
_FIT_HALF_WIDTH_ZETAS = 3.0
_FIT_MIN_HALF_WIDTH = 0.003
# Relative offset used for the undamped tip residue (1/h is linear in ω² near a pole).
_RESIDUE_OFFSET = 1e-6


# ---------------------------------------------------------------------------- parameters


def parameter_names(spec: AssemblySpec) -> tuple[str, ...]:
    """Names of the parameters an effect analysis varies, in report order.

    Each bearing's ``stiffness_n_m`` and ``damping_ns_m``, each elastic joint's four
    values, then ``tool.stickout_m`` and ``tool.fluted_diameter_ratio``. Parameters that are
    zero or rigid (``None``) are left out: their normalised sensitivity is not defined.

    Parameters
    ----------
    spec : AssemblySpec
        An assembly with an analytical spindle.

    Returns
    -------
    tuple of str
        E.g. ``("bearings[0].stiffness_n_m", ..., "holder_tool.rotational_damping_nms_rad",
        "tool.stickout_m", "tool.fluted_diameter_ratio")``.
    """
    names: list[str] = []
    if isinstance(spec.spindle, SpindleSpec):
        for i, _ in enumerate(spec.spindle.bearings):
            names.extend(f"bearings[{i}].{k}" for k in _BEARING_FIELDS)
    for joint in ("spindle_holder", "holder_tool"):
        names.extend(f"{joint}.{k}" for k in _JOINT_FIELDS)
    names.extend(f"tool.{k}" for k in _TOOL_FIELDS)
    return tuple(n for n in names if (v := get_parameter(spec, n)) is not None and v > 0)


def _split(name: str) -> tuple[str, int | None, str]:
    head, _, field = name.partition(".")
    if head.startswith("bearings[") and head.endswith("]"):
        index = head[len("bearings["):-1]
        if not index.isdigit():
            raise InputError("parameters", f"bad bearing index in {name!r}")
        return "bearings", int(index), field
    return head, None, field


def get_parameter(spec: AssemblySpec, name: str) -> float | None:
    """Value of a named parameter in SI units (``None`` when rigid or absent).

    Raises
    ------
    InputError
        For an unknown name.
    """
    group, index, field = _split(name)
    if group == "bearings":
        if field not in _BEARING_FIELDS or not isinstance(spec.spindle, SpindleSpec) \
                or index is None or index >= len(spec.spindle.bearings):
            raise InputError("parameters", f"unknown parameter {name!r}")
        return float(getattr(spec.spindle.bearings[index], field))
    if group in ("spindle_holder", "holder_tool") and field in _JOINT_FIELDS:
        joint = getattr(spec, group)
        value = None if joint is None else getattr(joint, field)
        return None if value is None else float(value)
    if group == "tool" and field in _TOOL_FIELDS:
        return float(getattr(spec.tool, field))
    raise InputError("parameters", f"unknown parameter {name!r}")


def set_parameter(spec: AssemblySpec, name: str, value: float) -> AssemblySpec:
    """A copy of ``spec`` with one named parameter replaced (no re-validation).

    The value is set as given, so a derivative may be taken at a bound (e.g. a fluted
    diameter ratio of exactly 1). A stickout change keeps the overall length: the inserted
    length changes with it (``contract.md`` "Assembly").

    Parameters
    ----------
    spec : AssemblySpec
    name : str
        As in :func:`parameter_names`.
    value : float
        New value, SI units.
    """
    group, index, field = _split(name)
    if group == "bearings":
        get_parameter(spec, name)  # validates
        spindle = spec.spindle
        assert isinstance(spindle, SpindleSpec) and index is not None
        bearings = list(spindle.bearings)
        bearings[index] = replace(bearings[index], **{field: float(value)})
        return replace(spec, spindle=replace(spindle, bearings=tuple(bearings)))
    if group in ("spindle_holder", "holder_tool") and field in _JOINT_FIELDS:
        joint = getattr(spec, group)
        if joint is None:
            raise InputError("parameters", f"{name!r}: the joint {group} is rigid in this assembly")
        return replace(spec, **{group: replace(joint, **{field: float(value)})})
    if group == "tool" and field in _TOOL_FIELDS:
        return replace(spec, tool=replace(spec.tool, **{field: float(value)}))
    raise InputError("parameters", f"unknown parameter {name!r}")


def _is_damping(name: str) -> bool:
    return name.endswith(("damping_ns_m", "damping_nms_rad"))


# ---------------------------------------------------------------------------- mode features


@dataclass(frozen=True)
class ModeFeatures:
    """Features of the modes of one model, arrays of shape (nmodes,).

    Attributes
    ----------
    frequency_hz : numpy.ndarray
        Undamped natural frequencies, Hz (exact).
    tip_residue_1_kg : numpy.ndarray
        ``φ_tip²`` of the mass-normalised undamped mode, 1/kg: the residue of the undamped
        tool-point h, ``h ≈ φ²/(ω_n² − ω²)`` (large = dominant at the tool point).
    peak_frequency_hz, peak_magnitude_m_n : numpy.ndarray
        The damped ``|h|`` maximum next to the mode; NaN when ``|h|`` has none in the
        mode's window (a mode hidden at the tool point).
    damping_ratio : numpy.ndarray
        Single-mode fit of the damped h around the peak; NaN without a peak.
    window_rel : numpy.ndarray, shape (nmodes, 2)
        Relative half-widths (below, above) of each mode's search window.
    """

    frequency_hz: np.ndarray
    tip_residue_1_kg: np.ndarray
    peak_frequency_hz: np.ndarray
    peak_magnitude_m_n: np.ndarray
    damping_ratio: np.ndarray
    window_rel: np.ndarray

    def feature(self, name: str) -> np.ndarray:
        """One of :data:`FEATURES` as an array, shape (nmodes,)."""
        return np.asarray(getattr(self, name), dtype=float)


def _windows(frequency_hz: np.ndarray, neighbours_hz: np.ndarray) -> np.ndarray:
    """Relative search half-widths (below, above) of each mode, shape (nmodes, 2)."""
    ln_f = np.log(frequency_hz)
    ln_all = np.log(np.sort(neighbours_hz))
    out = np.full((frequency_hz.size, 2), _MAX_WINDOW)
    for i, x in enumerate(ln_f):
        below = ln_all[ln_all < x * (1 - 1e-12)]
        above = ln_all[ln_all > x * (1 + 1e-12)]
        if below.size:
            out[i, 0] = min(out[i, 0], -math.expm1(-_WINDOW_GAP_FRACTION * (x - below[-1])))
        if above.size:
            out[i, 1] = min(out[i, 1], math.expm1(_WINDOW_GAP_FRACTION * (above[0] - x)))
    return out


def _tip_h(chain: Chain, frequency_hz: np.ndarray, start: np.ndarray | None = None) -> np.ndarray:
    """Tool-point h for any array of frequencies (same shape), m/N."""
    f = np.asarray(frequency_hz, dtype=float)
    g = inv2(march(chain, _TWO_PI * f.ravel(), start)[0])
    return g[:, 0, 0].reshape(f.shape)


def tip_residues_1_kg(chain: Chain, frequency_hz: np.ndarray) -> np.ndarray:
    """Residue ``φ_tip²`` (1/kg) of the undamped tool-point h at each natural frequency.

    ``1/h ≈ (ω_n² − ω²)/φ²`` next to a pole, so ``φ² = −Δ(ω²)/Δ(1/h)`` across
    ``ω_n(1 ± 1e-6)``.

    Parameters
    ----------
    chain : Chain
        The whole assembly (damping is removed).
    frequency_hz : numpy.ndarray, shape (nmodes,)
        Exact undamped natural frequencies.
    """
    f = np.asarray(frequency_hz, dtype=float)
    if f.size == 0:
        return np.empty(0)
    pair = np.stack([f * (1 - _RESIDUE_OFFSET), f * (1 + _RESIDUE_OFFSET)], axis=1)
    inv_h = 1.0 / _tip_h(undamped(chain), pair).real
    w2 = (_TWO_PI * pair) ** 2
    return -(w2[:, 1] - w2[:, 0]) / (inv_h[:, 1] - inv_h[:, 0])


def _refine_peaks(chain: Chain, f_hz: np.ndarray, step_rel: np.ndarray, lo: np.ndarray,
                  hi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Successive parabolic refinement of ``|h|`` maxima, all modes at once."""
    f = f_hz.copy()
    d = step_rel * f
    for _ in range(_PEAK_REFINE_PASSES):
        pts = np.stack([f - d, f, f + d], axis=1)
        m = np.abs(_tip_h(chain, pts))
        curv = m[:, 0] - 2 * m[:, 1] + m[:, 2]
        shift = np.where(curv < 0, 0.5 * d * (m[:, 0] - m[:, 2]) / np.where(curv < 0, curv, -1.0), 0.0)
        f = np.clip(f + np.clip(shift, -d, d), lo, hi)
        d = d / 6.0
    return f, np.abs(_tip_h(chain, f))


def single_mode_fit(frequency_hz: np.ndarray, h: np.ndarray) -> tuple[np.ndarray, float] | None:
    """One mode with residual terms fitted by Levy's linearised least squares.

    ``h ≈ (c₀ + c₁s + c₂s²)/(s² + a₁s + a₀)`` with the scaled ``s = iω/scale``.

    Parameters
    ----------
    frequency_hz : numpy.ndarray, shape (n,)
    h : numpy.ndarray, shape (n,), complex

    Returns
    -------
    (numpy.ndarray, float) or None
        ``([a0, a1, c0, c1, c2], scale)`` with scale in rad/s (natural frequency
        ``√a0·scale``, damping ratio ``a1/(2√a0)``), or None when the fitted pole is not a
        stable oscillator.
    """
    s = 2j * np.pi * np.asarray(frequency_hz, dtype=float)
    scale = float(np.abs(s).max())
    sn = s / scale
    cols = np.stack([h, h * sn, -np.ones_like(sn), -sn, -(sn**2)], axis=1)
    rhs = -h * sn**2
    a = np.concatenate([cols.real, cols.imag])
    b = np.concatenate([rhs.real, rhs.imag])
    col_scale = np.linalg.norm(a, axis=0)
    x = np.linalg.lstsq(a / col_scale, b, rcond=None)[0] / col_scale
    if x[0] <= 0 or x[1] <= 0:
        return None
    return x, scale


def _levy_fit(frequency_hz: np.ndarray, h: np.ndarray) -> tuple[float, float]:
    """``(f_n_hz, ζ)`` of :func:`single_mode_fit` (NaN when not a stable oscillator)."""
    fit = single_mode_fit(frequency_hz, h)
    if fit is None:
        return math.nan, math.nan
    x, scale = fit
    return math.sqrt(x[0]) * scale / _TWO_PI, x[1] / (2 * math.sqrt(x[0]))


def _fit_damping(chain: Chain, peak_hz: float, window: tuple[float, float]) -> float:
    """Damping ratio of the mode peaking at ``peak_hz``: a wide fit, then one on ±3ζ."""
    lo, hi = 1 - min(window[0], 0.05), 1 + min(window[1], 0.05)
    f = peak_hz * np.geomspace(lo, hi, _FIT_POINTS)
    zeta = _levy_fit(f, _tip_h(chain, f))[1]
    if not math.isfinite(zeta):
        return math.nan
    half = max(_FIT_HALF_WIDTH_ZETAS * zeta, _FIT_MIN_HALF_WIDTH)
    f = peak_hz * np.geomspace(1 - min(half, window[0]), 1 + min(half, window[1]), _FIT_POINTS)
    return _levy_fit(f, _tip_h(chain, f))[1]


def window_peaks(chain: Chain, lo_hz: np.ndarray, hi_hz: np.ndarray, points: int = _PEAK_GRID_POINTS
                 ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The largest interior maximum of the damped tool-point ``|h|`` in each window.

    A dense geometric grid per window locates the maximum, then successive parabolic
    passes refine it (all windows at once) to well below 1e-6 relative.

    Parameters
    ----------
    chain : Chain
        Whole assembly (damped).
    lo_hz, hi_hz : numpy.ndarray, shape (nwin,)
        Window edges, Hz.
    points : int
        Points of the dense grid per window.

    Returns
    -------
    found : numpy.ndarray of bool, shape (nwin,)
        False where ``|h|`` has no interior maximum in the window.
    frequency_hz, magnitude_m_n : numpy.ndarray, shape (nwin,)
        The refined maximum; where none is found, the largest ``|h|`` on the window's grid
        (at one of its edges), so that a fit sees a bounded, continuous residual.
    """
    lo_hz, hi_hz = np.atleast_1d(np.asarray(lo_hz, dtype=float)), np.atleast_1d(np.asarray(hi_hz, dtype=float))
    nw = lo_hz.size
    found = np.zeros(nw, dtype=bool)
    if nw == 0:
        return found, np.empty(0), np.empty(0)
    grid = np.geomspace(lo_hz, hi_hz, points, axis=1)
    mag = np.abs(_tip_h(chain, grid))
    interior = (mag[:, 1:-1] > mag[:, :-2]) & (mag[:, 1:-1] >= mag[:, 2:])
    top = np.argmax(mag, axis=1)
    peak_f, peak_m = grid[np.arange(nw), top], mag[np.arange(nw), top]
    start = np.empty(nw)
    for i in range(nw):  # one window at a time: pick its largest interior maximum
        idx = np.flatnonzero(interior[i]) + 1
        if idx.size:
            found[i] = True
            start[i] = grid[i, idx[np.argmax(mag[i, idx])]]
    if np.any(found):
        step = np.log(hi_hz / lo_hz)[found] / (points - 1)
        peak_f[found], peak_m[found] = _refine_peaks(chain, start[found], step, grid[found, 0], grid[found, -1])
    return found, peak_f, peak_m


def mode_features(chain: Chain, frequency_hz: np.ndarray, window_rel: np.ndarray | None = None,
                  neighbours_hz: np.ndarray | None = None) -> ModeFeatures:
    """Tip residue, damped peak and damping ratio of given modes of a chain.

    Parameters
    ----------
    chain : Chain
        Whole assembly, spindle rear → tool tip (damped).
    frequency_hz : numpy.ndarray, shape (nmodes,)
        Its exact undamped natural frequencies (from :func:`rcsa.modes.natural_frequencies_hz`).
    window_rel : numpy.ndarray, shape (nmodes, 2), optional
        Relative search half-widths below/above each frequency. By default 45 % of the log
        gap to the neighbouring mode, at most 10 %; pass the base run's windows when
        differencing perturbed runs, so every run looks at the same relative band.
    neighbours_hz : numpy.ndarray, optional
        All natural frequencies (also just outside the band) used for the default windows.

    Returns
    -------
    ModeFeatures
    """
    fn = np.asarray(frequency_hz, dtype=float)
    nm = fn.size
    if window_rel is None:
        window_rel = _windows(fn, fn if neighbours_hz is None else np.asarray(neighbours_hz, dtype=float))
    residue = tip_residues_1_kg(chain, fn)
    zeta = np.full(nm, np.nan)
    lo_hz, hi_hz = fn * (1 - window_rel[:, 0]), fn * (1 + window_rel[:, 1])
    found, peak_f, peak_m = window_peaks(chain, lo_hz, hi_hz)
    peak_f, peak_m = np.where(found, peak_f, np.nan), np.where(found, peak_m, np.nan)
    for i in np.flatnonzero(found):  # the window, seen from the peak
        below, above = 1 - lo_hz[i] / peak_f[i], hi_hz[i] / peak_f[i] - 1
        zeta[i] = _fit_damping(chain, float(peak_f[i]), (max(below, 1e-4), max(above, 1e-4)))
    return ModeFeatures(fn, residue, peak_f, peak_m, zeta, np.asarray(window_rel, dtype=float))


# ---------------------------------------------------------------------------- effect analysis


@dataclass(frozen=True)
class EffectReport:
    """Normalised sensitivities of the modes of an assembly to its parameters.

    Attributes
    ----------
    band_hz : tuple of float
        Band whose modes are analysed, Hz.
    relative_step : float
        Finite-difference step δ in ln(parameter).
    modes : ModeFeatures
        Features of the nominal model, arrays (nmodes,).
    parameters : tuple of str
        Parameter names, in column order.
    values : numpy.ndarray, shape (nparams,)
        Their nominal values, SI.
    sensitivity : dict of str to numpy.ndarray, shape (nmodes, nparams)
        ``d ln(feature)/d ln(parameter)`` per feature of :data:`FEATURES`; NaN where the
        feature is undefined (no peak) or the mode could not be tracked.
    notes : tuple of str
    """

    band_hz: tuple[float, float]
    relative_step: float
    modes: ModeFeatures
    parameters: tuple[str, ...]
    values: np.ndarray
    sensitivity: Mapping[str, np.ndarray]
    notes: tuple[str, ...] = ()

    @property
    def frequency_hz(self) -> np.ndarray:
        """Natural frequencies of the analysed modes, Hz, shape (nmodes,)."""
        return self.modes.frequency_hz

    @property
    def tip_participation(self) -> np.ndarray:
        """Tip residue relative to the largest in the band, shape (nmodes,), in [0, 1]."""
        r = np.abs(self.modes.tip_residue_1_kg)
        return r / r.max() if r.size and r.max() > 0 else r

    def column(self, parameter: str, feature: str = "frequency_hz") -> np.ndarray:
        """Sensitivities of all modes to one parameter, shape (nmodes,)."""
        return self.sensitivity[feature][:, self.parameters.index(parameter)]

    def controls(self, parameter: str, feature: str | None = None) -> float | None:
        """Natural frequency (Hz) of the mode a parameter moves most.

        By default a stiffness or geometry parameter is judged on ``frequency_hz`` and a
        damping on ``peak_magnitude_m_n`` (stiffness moves frequencies, damping peaks).
        Returns ``None`` when no mode responds.
        """
        i = self.controlled_mode(parameter, feature)
        return None if i is None else float(self.frequency_hz[i])

    def controlled_mode(self, parameter: str, feature: str | None = None,
                        min_participation: float = 0.0) -> int | None:
        """Index of the mode with the largest ``|S|`` for ``parameter`` (see :meth:`controls`).

        Parameters
        ----------
        min_participation : float
            Consider only modes whose :attr:`tip_participation` reaches this.
        """
        feature = feature or ("peak_magnitude_m_n" if _is_damping(parameter) else "frequency_hz")
        s = np.abs(self.column(parameter, feature))
        s = np.where(self.tip_participation >= min_participation, s, np.nan)
        if not np.any(np.isfinite(s)) or np.nanmax(s) == 0:
            return None
        return int(np.nanargmax(s))

    def controlled_by(self, mode: int, feature: str = "frequency_hz",
                      among: Sequence[str] | None = None) -> str | None:
        """The parameter with the largest ``|S|`` for one mode (``among`` a subset of names)."""
        names = list(among) if among is not None else list(self.parameters)
        cols = [self.parameters.index(n) for n in names if n in self.parameters]
        s = np.abs(self.sensitivity[feature][mode, cols])
        if not np.any(np.isfinite(s)) or np.nanmax(s) == 0:
            return None
        return self.parameters[cols[int(np.nanargmax(s))]]

    def to_dict(self) -> dict[str, Any]:
        """JSON form: modes, parameters and the sensitivity table (NaN → null)."""
        interface = [p for p in self.parameters if not p.startswith("tool.")]
        part = self.tip_participation
        modes = []
        for i in range(self.frequency_hz.size):
            modes.append({
                "index": i,
                "frequency_hz": float(self.frequency_hz[i]),
                "tip_residue_1_kg": _num(self.modes.tip_residue_1_kg[i]),
                "tip_participation": _num(part[i]),
                "peak_frequency_hz": _num(self.modes.peak_frequency_hz[i]),
                "peak_magnitude_m_n": _num(self.modes.peak_magnitude_m_n[i]),
                "damping_ratio": _num(self.modes.damping_ratio[i]),
                "controlled_by": {q: self.controlled_by(i, q) for q in FEATURES},
                "controlled_by_interface": {q: self.controlled_by(i, q, interface) for q in FEATURES},
            })
        table = []
        for j, name in enumerate(self.parameters):
            row: dict[str, Any] = {"parameter": name, "value": float(self.values[j])}
            for q in FEATURES:
                row[q] = [_num(x) for x in self.sensitivity[q][:, j]]
            i = self.controlled_mode(name)
            row["controls_mode"] = i
            row["controls_frequency_hz"] = None if i is None else float(self.frequency_hz[i])
            table.append(row)
        return {
            "band_hz": list(self.band_hz),
            "relative_step": self.relative_step,
            "sensitivity": "d ln(feature) / d ln(parameter), central finite differences of the exact model",
            "features": list(FEATURES),
            "modes": modes,
            "parameters": table,
            "notes": list(self.notes),
        }


def _num(x: float) -> float | None:
    x = float(x)
    return x if math.isfinite(x) else None


def _band_modes(chain: Chain, band_hz: tuple[float, float], margin: float = 0.12) -> np.ndarray:
    """Natural frequencies in the band widened by ``margin`` (relative) on both sides."""
    return natural_frequencies_hz(chain, band_hz[0] / (1 + margin), band_hz[1] * (1 + margin))


def _track(base_hz: np.ndarray, other_hz: np.ndarray, window_rel: np.ndarray) -> np.ndarray:
    """Index in ``other_hz`` of each base mode (−1 where no unique nearest mode in its window)."""
    out = np.full(base_hz.size, -1)
    if other_hz.size == 0:
        return out
    d = np.abs(np.log(other_hz[None, :]) - np.log(base_hz[:, None]))
    nearest = np.argmin(d, axis=1)
    back = np.argmin(d, axis=0)
    for i, j in enumerate(nearest):
        within = d[i, j] < np.log1p(min(window_rel[i]))
        if within and back[j] == i:
            out[i] = j
    return out


def _features_at(spec: AssemblySpec, base: ModeFeatures, band_hz: tuple[float, float],
                 reuse_frequencies: bool) -> tuple[ModeFeatures, bool]:
    """Features of a perturbed model, for the base modes (tracked); ``ok`` = all tracked."""
    chain = build_model(spec).chain()
    if reuse_frequencies:  # damping never moves the undamped natural frequencies
        fn, ok = base.frequency_hz, True
    else:
        all_hz = _band_modes(chain, band_hz)
        idx = _track(base.frequency_hz, all_hz, base.window_rel)
        ok = bool(np.all(idx >= 0))
        fn = np.where(idx >= 0, all_hz[np.maximum(idx, 0)] if all_hz.size else np.nan, np.nan)
    good = np.isfinite(fn)
    feats = mode_features(chain, fn[good], base.window_rel[good])
    if good.all():
        return feats, ok
    full = {k: np.full(fn.size, np.nan) for k in ("tip_residue_1_kg", "peak_frequency_hz",
                                                  "peak_magnitude_m_n", "damping_ratio")}
    for k, arr in full.items():
        arr[good] = getattr(feats, k)
    return ModeFeatures(fn, full["tip_residue_1_kg"], full["peak_frequency_hz"], full["peak_magnitude_m_n"],
                        full["damping_ratio"], base.window_rel), ok


def _band_of(spec: AssemblySpec, band_hz: Sequence[float] | None) -> tuple[float, float]:
    if band_hz is None:
        return float(spec.frequency_hz[0]), float(spec.frequency_hz[-1])
    if len(band_hz) != 2 or not 0 < band_hz[0] < band_hz[1]:
        raise InputError("band_hz", f"must be [start_hz, stop_hz] with 0 < start < stop, got {list(band_hz)}")
    return float(band_hz[0]), float(band_hz[1])


def nominal_features(spec: AssemblySpec, band_hz: Sequence[float] | None = None) -> ModeFeatures:
    """Features of the modes of ``spec`` whose natural frequency lies in the band.

    Parameters
    ----------
    spec : AssemblySpec
        Analytical assembly.
    band_hz : (float, float), optional
        Default: the assembly's frequency range.
    """
    band = _band_of(spec, band_hz)
    chain = build_model(spec).chain()
    all_hz = _band_modes(chain, band)
    fn = all_hz[(all_hz >= band[0]) & (all_hz <= band[1])]
    return mode_features(chain, fn, neighbours_hz=all_hz)


def effect_analysis(assembly: Mapping[str, Any] | AssemblySpec, *, parameters: Sequence[str] | None = None,
                    relative_step: float = DEFAULT_RELATIVE_STEP,
                    band_hz: Sequence[float] | None = None) -> EffectReport:
    """Normalised sensitivities of every mode in a band to bearing, joint and tool parameters.

    Parameters
    ----------
    assembly : dict or AssemblySpec
        Contract assembly document (analytical spindle).
    parameters : sequence of str, optional
        Names as in :func:`parameter_names` (default: all of them).
    relative_step : float
        δ of the central difference in ln(parameter), in (0, 0.1].
    band_hz : (float, float), optional
        Modes whose undamped natural frequency lies here (default: the assembly's grid range).

    Returns
    -------
    EffectReport

    References
    ----------
    Ertürk, Özgüven, Budak, IJMTM 47 (2007) 23–32 ("effect analysis").
    """
    spec = assembly if isinstance(assembly, AssemblySpec) else parse_assembly(assembly)
    if not isinstance(spec.spindle, SpindleSpec):
        raise InputError("spindle", "effect analysis needs an analytical spindle (segments and bearings), "
                         "not a measured one")
    if not 0 < relative_step <= 0.1:
        raise InputError("relative_step", f"must be in (0, 0.1], got {relative_step:g}")
    available = parameter_names(spec)
    if parameters is None:
        names = available
    else:
        names = tuple(parameters)
        for n in names:
            if n not in available:
                get_parameter(spec, n)  # raises for an unknown name
                raise InputError("parameters", f"{n!r} is zero or rigid in this assembly: its normalised "
                                 "sensitivity is not defined")
        if len(set(names)) != len(names):
            raise InputError("parameters", "names must be unique")
    band = _band_of(spec, band_hz)
    base = nominal_features(spec, band)
    values = np.array([get_parameter(spec, n) for n in names], dtype=float)
    nm = base.frequency_hz.size
    sens = {q: np.full((nm, len(names)), np.nan) for q in FEATURES}
    notes: list[str] = []
    for j, name in enumerate(names):
        runs = []
        for sign in (+1.0, -1.0):
            perturbed = set_parameter(spec, name, values[j] * math.exp(sign * relative_step))
            feats, ok = _features_at(perturbed, base, band, reuse_frequencies=_is_damping(name))
            if not ok:
                notes.append(f"{name}: some modes could not be tracked between the perturbed runs")
            runs.append(feats)
        for q in FEATURES:
            with np.errstate(invalid="ignore", divide="ignore"):
                sens[q][:, j] = (np.log(runs[0].feature(q)) - np.log(runs[1].feature(q))) / (2 * relative_step)
    if nm == 0:
        notes.append(f"no natural frequency lies in the band {band[0]:g}–{band[1]:g} Hz: nothing to analyse")
    hidden = [f"{f:.1f}" for f, p in zip(base.frequency_hz, base.peak_magnitude_m_n, strict=True)
              if not math.isfinite(p)]
    if hidden:
        notes.append(f"modes at {', '.join(hidden)} Hz show no peak of |h| at the tool point: peak and "
                     "damping sensitivities are null there")
    return EffectReport(band, relative_step, base, names, values, sens, tuple(dict.fromkeys(notes)))


# ---------------------------------------------------------------------------- application layer


_REQUEST_FIELDS = ("assembly", "parameters", "relative_step", "band_hz")


def effects_report(request: Mapping[str, Any]) -> EffectReport:
    """Parse an effect-analysis request and run it (see :func:`effects` for the request).

    Returns
    -------
    EffectReport
    """
    if not isinstance(request, Mapping):
        raise InputError("", "the request must be a JSON object")
    if "assembly" not in request:
        return effect_analysis(request)
    unknown = sorted(set(request) - set(_REQUEST_FIELDS))
    if unknown:
        raise InputError(unknown[0], f"unknown field (allowed: {', '.join(_REQUEST_FIELDS)})")
    params = request.get("parameters")
    if params is not None and (not isinstance(params, list) or not all(isinstance(p, str) for p in params)):
        raise InputError("parameters", "must be a list of parameter names")
    step = request.get("relative_step", DEFAULT_RELATIVE_STEP)
    if isinstance(step, bool) or not isinstance(step, int | float):
        raise InputError("relative_step", "must be a number")
    band = request.get("band_hz")
    if band is not None and (not isinstance(band, list) or len(band) != 2
                             or not all(isinstance(b, int | float) and not isinstance(b, bool) for b in band)):
        raise InputError("band_hz", "must be [start_hz, stop_hz]")
    try:
        spec = parse_assembly(request["assembly"])
    except InputError as exc:
        raise InputError(f"assembly.{exc.field}".rstrip("."), exc.rule) from None
    return effect_analysis(spec, parameters=params, relative_step=float(step), band_hz=band)


def effects(request: Mapping[str, Any]) -> dict[str, Any]:
    """Effect analysis as a JSON document (the CLI's and the REST route's entry point).

    Parameters
    ----------
    request : dict
        Either a contract assembly document (all parameters, the assembly's frequency
        range, δ = 1e-3), or ``{"assembly": {...}, "parameters": [names] (optional, default
        all, see :func:`parameter_names`), "relative_step": 0.001 (optional, in (0, 0.1]),
        "band_hz": [start, stop] (optional, default the assembly's frequency range)}``.
        The spindle must be analytical (segments and bearings).

    Returns
    -------
    dict
        :meth:`EffectReport.to_dict`: ``band_hz``, ``relative_step``, ``modes`` (each with
        ``frequency_hz``, ``tip_residue_1_kg``, ``tip_participation``, peak, damping ratio,
        ``controlled_by`` and ``controlled_by_interface`` per feature) and ``parameters``
        (each with its ``value`` and a list of sensitivities per feature, one per mode).

    Raises
    ------
    InputError
        For a malformed request.
    """
    return effects_report(request).to_dict()


# ---------------------------------------------------------------------------- figure


def effects_figure(report: EffectReport, features: Sequence[str] = ("frequency_hz", "peak_magnitude_m_n",
                                                                      "damping_ratio")) -> Any:
    """Heat map of the sensitivities, modes × parameters, one panel per feature.

    Uses :class:`matplotlib.figure.Figure` with the Agg canvas (never pyplot).

    Returns
    -------
    matplotlib.figure.Figure
        Save it with :func:`rcsa.plots.save_figure`.

    Raises
    ------
    InputError
        When the report holds no mode or no parameter.
    """
    import matplotlib
    from matplotlib.colors import TwoSlopeNorm

    from .plots import _freeze_layout, _new_figure

    nm, npar = report.frequency_hz.size, len(report.parameters)
    if nm == 0 or npar == 0:
        raise InputError("band_hz", "the report has no mode (or no parameter) to draw")
    fig = _new_figure(max(6.0, 0.5 * npar + 2.5), 2.2 + len(features) * max(1.6, 0.3 * nm + 0.8))
    axes = fig.subplots(len(features), 1, squeeze=False, sharex=True)[:, 0]
    part = report.tip_participation
    ylabels = [f"{f:.0f} Hz ({100 * p:.2g} %)" for f, p in zip(report.frequency_hz, part, strict=True)]
    titles = {"frequency_hz": "natural frequency", "peak_magnitude_m_n": "peak |h|",
              "damping_ratio": "damping ratio", "peak_frequency_hz": "peak frequency"}
    cmap = matplotlib.colormaps["RdBu_r"].with_extremes(bad="0.85")
    for ax, q in zip(axes, features, strict=True):
        s = np.asarray(report.sensitivity[q], dtype=float)
        lim = float(np.nanmax(np.abs(s))) if np.any(np.isfinite(s)) else 1.0
        lim = lim if lim > 0 else 1.0
        image = ax.imshow(np.ma.masked_invalid(s), aspect="auto", cmap=cmap,
                          norm=TwoSlopeNorm(0.0, -lim, lim), interpolation="nearest")
        for (i, j), v in np.ndenumerate(s):
            if math.isfinite(v) and abs(v) >= 0.01 * lim:
                ax.text(j, i, f"{v:.2g}", ha="center", va="center", fontsize=6)
        ax.set_yticks(range(nm), ylabels, fontsize=7)
        ax.set_title(f"d ln({titles.get(q, q)}) / d ln(parameter)", fontsize=9)
        fig.colorbar(image, ax=ax, shrink=0.9)
    axes[-1].set_xticks(range(npar), report.parameters, rotation=60, ha="right", fontsize=7)
    axes[0].text(0.0, 1.12, "modes: natural frequency (tip participation); grey: no peak at the tool point",
                 transform=axes[0].transAxes, fontsize=7)
    return _freeze_layout(fig)
