"""Features of the modes of an exact model: natural frequency, damped peak, damping ratio.

For every undamped natural frequency in a band (exact, Wittrick–Williams) the damped
tool-point ``|h|`` is searched for its local maximum inside a window bounded by the
neighbouring modes, refined on a dense local grid, and a single-mode Levy fit
(:func:`rcsa.physics.natural_frequencies.single_mode_fit`) gives the damping ratio. Used by the effect analysis
(:mod:`rcsa.analysis.effects.sensitivities`) and the joint identification (:mod:`rcsa.analysis.joint_identification.identify`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from rcsa.model.peaks import single_mode_fit
from rcsa.physics.algebra2x2 import inv2
from rcsa.physics.chain import Chain, undamped
from rcsa.physics.elimination import march

__all__ = ["ModeFeatures", "mode_features", "mode_windows", "tip_residues_1_kg", "window_peaks"]

_TWO_PI = 2.0 * np.pi

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


def mode_windows(frequency_hz: np.ndarray, neighbours_hz: np.ndarray) -> np.ndarray:
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
        Its exact undamped natural frequencies (from :func:`rcsa.physics.natural_frequencies.natural_frequencies_hz`).
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
        window_rel = mode_windows(fn, fn if neighbours_hz is None else np.asarray(neighbours_hz, dtype=float))
    residue = tip_residues_1_kg(chain, fn)
    zeta = np.full(nm, np.nan)
    lo_hz, hi_hz = fn * (1 - window_rel[:, 0]), fn * (1 + window_rel[:, 1])
    found, peak_f, peak_m = window_peaks(chain, lo_hz, hi_hz)
    peak_f, peak_m = np.where(found, peak_f, np.nan), np.where(found, peak_m, np.nan)
    for i in np.flatnonzero(found):  # the window, seen from the peak
        below, above = 1 - lo_hz[i] / peak_f[i], hi_hz[i] / peak_f[i] - 1
        zeta[i] = _fit_damping(chain, float(peak_f[i]), (max(below, 1e-4), max(above, 1e-4)))
    return ModeFeatures(fn, residue, peak_f, peak_m, zeta, np.asarray(window_rel, dtype=float))
