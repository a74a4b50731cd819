"""What a joint identification reads from a measured tool-point FRF: noise level and peaks.

* :func:`relative_noise` — the relative noise of a measured FRF from its third differences
  (a smooth FRF sampled finely has negligible third differences; white noise does not;
  it lives in :mod:`rcsa.model.modal_fit`, which gates peaks by it too).
* :func:`measured_peaks` — the resonance peaks that stand out of the noise, each refined by
  a single-mode (Levy) fit so that its frequency, height and damping ratio are not those of
  one noisy line.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from rcsa.model.modal_fit import relative_noise
from rcsa.model.peaks import peak_lines, single_mode_fit

__all__ = ["LENIENT_PROMINENCE", "PEAK_PROMINENCE", "MeasuredPeak", "coherence_weights", "measured_peaks",
           "peaks_ln_hz", "relative_noise"]

#: A peak is prominent when it rises by this fraction of the largest |h| above its
#: surroundings (:func:`rcsa.model.peaks.peak_lines` on the linear |h|, as a user reads a
#: measured FRF); peaks down to LENIENT_PROMINENCE (the prediction's own rule,
#: :func:`rcsa.model.peaks.find_frf_peaks`) are still listed, so that a borderline peak seen
#: on one side (model or measurement) can be matched on the other.
PEAK_PROMINENCE = 0.03
LENIENT_PROMINENCE = 0.01
#: … and by this many noise standard deviations of its own height.
PEAK_NOISE_SIGMAS = 4.0
#: Largest coherence used in weights (γ² → 1 would give an infinite weight).
_MAX_COHERENCE = 0.999


@dataclass(frozen=True, slots=True)
class MeasuredPeak:
    """A resonance peak of a measured FRF.

    Attributes
    ----------
    frequency_hz : float
        Where the fitted single-mode FRF peaks, Hz.
    magnitude_m_n : float
        Its height ``|h|``, m/N.
    damping_ratio : float
        Fitted modal damping ratio (NaN when the fit is not a stable mode).
    prominence : float
        Prominence of the peak relative to the largest ``|h|`` of the measurement.
    """

    frequency_hz: float
    magnitude_m_n: float
    damping_ratio: float
    prominence: float = 1.0


def coherence_weights(coherence: np.ndarray | None, n: int) -> np.ndarray:
    """Weights ``∝ 1/σ_rel`` of each line from the coherence, median 1.

    Bendat & Piersol: the random error of |H| is ``√(1−γ²)/(|γ|√(2 n_d))``; the number of
    averages ``n_d`` is common to all lines and drops out of the relative weights.

    Returns
    -------
    numpy.ndarray, shape (n,)
        All ones without coherence.
    """
    if coherence is None:
        return np.ones(n)
    g2 = np.clip(np.asarray(coherence, dtype=float), 0.0, _MAX_COHERENCE)
    w = np.sqrt(g2 / (1.0 - g2))
    med = float(np.median(w))
    return w / med if med > 0 else np.ones(n)


def _fitted_peak(f: np.ndarray, h: np.ndarray, i: int, half_width_rel: float,
                 prominence: float = 1.0) -> MeasuredPeak | None:
    lo = int(np.searchsorted(f, f[i] * (1 - half_width_rel)))
    hi = int(np.searchsorted(f, f[i] * (1 + half_width_rel), side="right"))
    lo, hi = min(lo, max(i - 5, 0)), max(hi, min(i + 6, f.size))
    if hi - lo < 7:
        return None
    fit = single_mode_fit(f[lo:hi], h[lo:hi])
    if fit is None:
        return None
    x, scale = fit
    dense = np.linspace(f[lo], f[hi - 1], 801)
    sn = 2j * np.pi * dense / scale
    model = np.abs((x[2] + x[3] * sn + x[4] * sn**2) / (sn**2 + x[1] * sn + x[0]))
    k = int(np.argmax(model))
    if k in (0, dense.size - 1):
        return None
    return MeasuredPeak(float(dense[k]), float(model[k]), float(x[1] / (2 * math.sqrt(x[0]))), prominence)


def measured_peaks(frequency_hz: np.ndarray, h: np.ndarray, noise_rel: float) -> list[MeasuredPeak]:
    """Resonance peaks of a measured FRF that stand out of its noise.

    A line is a peak when ``|h|`` has a local maximum with a prominence of at least
    ``max(1 % of max|h|, 4 σ |h_peak|)`` (it is *prominent* from 3 % on, see
    :class:`MeasuredPeak`); each is refined by a single-mode fit on about ±1.5 half-power
    bandwidths (at least ±5 lines).

    Parameters
    ----------
    frequency_hz : numpy.ndarray, shape (nfreq,)
    h : numpy.ndarray, shape (nfreq,), complex
        Measured receptance, m/N.
    noise_rel : float
        Relative noise σ (:func:`relative_noise`).

    Returns
    -------
    list of MeasuredPeak
        Ascending in frequency.
    """
    f = np.asarray(frequency_hz, dtype=float)
    mag = np.abs(h)
    if mag.size < 3:
        return []
    top = float(mag.max())
    idx, prominences = peak_lines(mag, LENIENT_PROMINENCE * top)
    out = []
    sigma = noise_rel if math.isfinite(noise_rel) else 0.0
    for i, prom in zip(idx, prominences, strict=True):
        if prom < PEAK_NOISE_SIGMAS * sigma * mag[i]:
            continue
        first = _fitted_peak(f, h, int(i), 0.01)
        zeta = first.damping_ratio if first is not None else 0.01
        peak = _fitted_peak(f, h, int(i), float(np.clip(1.5 * zeta, 0.002, 0.1)), float(prom / top))
        if peak is not None:
            out.append(peak)
    return out


def peaks_ln_hz(frequency_hz: np.ndarray, h: np.ndarray, noise_rel: float | np.ndarray = 0.0
                ) -> tuple[np.ndarray, np.ndarray]:
    """ln(frequency) of the peaks of a model FRF, parabola-refined.

    Parameters
    ----------
    frequency_hz : numpy.ndarray, shape (nfreq,)
        Any increasing grid (a geometric one gives uniform resolution).
    h : numpy.ndarray, shape (nfreq,), complex
    noise_rel : float or numpy.ndarray, shape (nfreq,)
        Relative noise of ``h``, overall or per line (a model on a measured spindle carries
        the spindle's): a peak that does not rise by :data:`PEAK_NOISE_SIGMAS`
        ``· noise_rel · |h_peak|`` is still listed, but never as prominent (its prominence is
        capped at the lenient 1 %), so it can be matched but is never required.

    Returns
    -------
    ln_hz : numpy.ndarray, shape (npeaks,)
        Peaks with a prominence of at least 1 % of max ``|h|``.
    prominence : numpy.ndarray, shape (npeaks,)
        Their prominence relative to max ``|h|``.
    """
    mag = np.abs(h)
    idx, prominences = peak_lines(mag, LENIENT_PROMINENCE * float(mag.max()))
    sigma = np.broadcast_to(np.nan_to_num(np.asarray(noise_rel, dtype=float)), mag.shape)
    keep = (idx > 0) & (idx < mag.size - 1)
    idx, prom = idx[keep], prominences[keep] / float(mag.max())
    prom = np.where(prominences[keep] >= PEAK_NOISE_SIGMAS * sigma[idx] * mag[idx], prom,
                    np.minimum(prom, LENIENT_PROMINENCE))
    x = np.log(frequency_hz)
    y0, y1, y2 = mag[idx - 1], mag[idx], mag[idx + 1]
    x0, x1, x2 = x[idx - 1], x[idx], x[idx + 1]
    # vertex of the parabola through three (possibly unevenly spaced) points
    num = (x1 - x0) ** 2 * (y1 - y2) - (x1 - x2) ** 2 * (y1 - y0)
    den = (x1 - x0) * (y1 - y2) - (x1 - x2) * (y1 - y0)
    with np.errstate(divide="ignore", invalid="ignore"):
        vertex = x1 - 0.5 * num / den
    return np.where(np.isfinite(vertex) & (vertex > x0) & (vertex < x2), vertex, x1), prom
