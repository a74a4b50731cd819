"""Peaks of a tool-point FRF, and single-mode fits around them.

Every prediction reports the local maxima of ``|h|``; a hybrid prediction (measured
spindle, no exact eigenvalues) also reports single-mode fits around them.
"""

from __future__ import annotations

import numpy as np

__all__ = ["find_frf_peaks", "modal_fit_peaks", "single_mode_fit"]

_TWO_PI = 2.0 * np.pi


def find_frf_peaks(frequency_hz: np.ndarray, h: np.ndarray, *, rel_prominence: float = 0.01
                   ) -> list[dict[str, float]]:
    """Local maxima of ``|h|`` on the grid, with a prominence of at least ``rel_prominence·max|h|``.

    Parameters
    ----------
    frequency_hz : numpy.ndarray, shape (nfreq,)
    h : numpy.ndarray, shape (nfreq,), complex
        Receptance, m/N.
    rel_prominence : float
        Smallest prominence of a peak, relative to ``max|h|``.

    Returns
    -------
    list of dict
        ``{"frequency_hz", "magnitude_m_n"}`` in ascending frequency.
    """
    from scipy.signal import find_peaks  # local: scipy.signal is most of the import time

    mag = np.abs(h)
    if mag.size < 3:
        return []
    idx, _ = find_peaks(mag, prominence=rel_prominence * float(mag.max()))
    return [{"frequency_hz": float(frequency_hz[i]), "magnitude_m_n": float(mag[i])} for i in idx]


def modal_fit_peaks(frequency_hz: np.ndarray, h: np.ndarray, *, rel_prominence: float = 0.01,
                    half_width_lines: int = 6) -> list[dict[str, float]]:
    """Single-mode fits around each peak of ``h`` (for FRFs without an exact model).

    Around every peak, ``h ≈ (c₀ + c₁ iω + c₂ (iω)²) / (ω_n² + 2ζω_n iω + (iω)²)`` is fitted by
    Levy's linearised least squares (one mode plus residual terms). Used for hybrid
    predictions, where the spindle is known only through measured FRFs.

    Parameters
    ----------
    frequency_hz : numpy.ndarray, shape (nfreq,)
    h : numpy.ndarray, shape (nfreq,), complex
        Receptance, m/N.
    rel_prominence : float
        Smallest prominence of a peak, relative to ``max|h|`` (:func:`find_frf_peaks`).
    half_width_lines : int
        Lines fitted on each side of a peak.

    Returns
    -------
    list of dict
        ``{"frequency_hz", "damping_ratio"}`` per peak whose fit is a stable mode.
    """
    out = []
    for peak in find_frf_peaks(frequency_hz, h, rel_prominence=rel_prominence):
        i = int(np.searchsorted(frequency_hz, peak["frequency_hz"]))
        lo, hi = max(0, i - half_width_lines), min(frequency_hz.size, i + half_width_lines + 1)
        if hi - lo < 5:
            continue
        fit = single_mode_fit(frequency_hz[lo:hi], h[lo:hi])
        if fit is None:
            continue
        (a0, a1, *_), scale = fit
        out.append({"frequency_hz": float(np.sqrt(a0) * scale / _TWO_PI),
                    "damping_ratio": float(a1 / (2 * np.sqrt(a0)))})
    return out


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
