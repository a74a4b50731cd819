"""Peaks of a tool-point FRF, and single-mode fits around them.

:func:`peak_lines` is the package's one peak picker: every caller that looks for resonance
peaks on a grid (predictions here, the joint identification's measured peaks, the
diagnosis's feature windows) calls it with its own, documented prominence rule.

Every analytical prediction reports the local maxima of ``|h|`` (:func:`find_frf_peaks`); a
hybrid prediction (measured spindle, no exact eigenvalues) reports a modal fit instead
(:mod:`rcsa.model.modal_fit`, which also gives the peaks that stand out of the noise).
"""

from __future__ import annotations

import numpy as np

from rcsa.physics.arrays import ComplexArray, FloatArray, IntArray

__all__ = ["find_frf_peaks", "peak_lines", "single_mode_fit"]

_TWO_PI = 2.0 * np.pi


def peak_lines(y: FloatArray, min_prominence: float) -> tuple[IntArray, FloatArray]:
    """Lines where a sampled curve has a local maximum that stands out by ``min_prominence``.

    The prominence of a peak is how far it rises above the higher of the two lowest points
    that separate it from any higher peak (topographic prominence; the peaks and prominences of
    ``scipy.signal.find_peaks``, which ``tests/model/test_peaks.py`` compares them with).
    The curve and the rule are the caller's: ``|h|`` with a fraction of ``max|h|`` (a peak
    visible on a linear plot), or ``ln|h|`` with a ratio (a peak visible on a dB plot).

    Parameters
    ----------
    y : numpy.ndarray, shape (n,), real
        The curve, e.g. ``|h|`` (m/N) or ``ln|h|``, on an increasing grid.
    min_prominence : float
        Least prominence of a peak, in the units of ``y``.

    Returns
    -------
    lines : numpy.ndarray of int, shape (npeaks,)
        Indices of the peaks, ascending; never the first or last line.
    prominences : numpy.ndarray, shape (npeaks,)
        Their prominences, in the units of ``y``.

    Examples
    --------
    The peak at line 1 rises 1.0 above the dip at line 2 that separates it from the higher
    peak at line 5; the bump at line 3 rises only 0.5:

    >>> lines, prominences = peak_lines(np.array([0.0, 2.0, 1.0, 1.5, 1.0, 3.0, 0.0]), 0.8)
    >>> lines.tolist(), prominences.tolist()
    ([1, 5], [1.0, 3.0])
    """
    y = np.asarray(y, dtype=float)
    lines = _local_maxima(y)
    prominences = np.array([_prominence(y, int(i)) for i in lines])  # a loop over the few peaks
    keep = prominences >= min_prominence
    return lines[keep], prominences[keep].astype(float)


def _local_maxima(y: FloatArray) -> IntArray:
    """Local maxima of ``y``: the middle (rounded down) of each run of equal values higher than
    both neighbours, never at the ends (``scipy.signal.find_peaks``'s rule, without importing
    scipy.signal: its import took 0.3–1.5 s of a first prediction or diagnosis in a process)."""
    n = y.size
    if n < 3:
        return np.empty(0, dtype=np.int64)
    start = np.concatenate([[0], np.flatnonzero(y[1:] != y[:-1]) + 1])    # runs of equal values
    stop = np.concatenate([start[1:] - 1, [n - 1]])
    inner = (start > 0) & (stop < n - 1)
    start, stop = start[inner], stop[inner]
    peak = (y[start - 1] < y[start]) & (y[stop + 1] < y[stop])
    out: IntArray = (start[peak] + stop[peak]) // 2
    return out


def _prominence(y: FloatArray, i: int) -> float:
    """Topographic prominence of the peak at line ``i``: its height above the higher of the
    lowest points on each side before a strictly higher sample (or the end)."""
    higher_left = np.flatnonzero(y[:i] > y[i])
    higher_right = np.flatnonzero(y[i + 1:] > y[i])
    left = y[(higher_left[-1] + 1 if higher_left.size else 0):i + 1]
    right = y[i:(i + 1 + higher_right[0] if higher_right.size else y.size)]
    return float(y[i] - max(float(left.min()), float(right.min())))


def find_frf_peaks(frequency_hz: FloatArray, h: ComplexArray, *, rel_prominence: float = 0.01
                   ) -> list[dict[str, float]]:
    """Local maxima of ``|h|`` on the grid, with a prominence of at least ``rel_prominence·max|h|``.

    The prediction's rule: a peak that shows on a linear plot of ``|h|`` (1 % of the largest
    peak by default), so the list names the modes a user sees, not numerical ripples.

    Parameters
    ----------
    frequency_hz : numpy.ndarray, shape (nfreq,)
        Hz.
    h : numpy.ndarray, shape (nfreq,), complex
        Receptance, m/N.
    rel_prominence : float
        Least prominence relative to ``max|h|``.

    Returns
    -------
    list of dict
        ``{"frequency_hz", "magnitude_m_n"}`` in ascending frequency.
    """
    mag = np.abs(h)
    if mag.size < 3:
        return []
    idx, _ = peak_lines(mag, rel_prominence * float(mag.max()))
    return [{"frequency_hz": float(frequency_hz[i]), "magnitude_m_n": float(mag[i])} for i in idx]


def single_mode_fit(frequency_hz: FloatArray, h: ComplexArray) -> tuple[FloatArray, float] | None:
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
