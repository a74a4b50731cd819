"""Natural frequencies of a chain, and peaks of an FRF.

:func:`natural_frequencies_hz` is exact for the analytical model: the Wittrick–Williams
count ``J(f)`` of the undamped, subdivided chain (:mod:`rcsa.dsm`) tells how many natural
frequencies lie below any f, so every mode in the band is bracketed (none missed, none
spurious, even when a mode barely shows at the tool point) and then located by bisection on
the count — not a peak pick.
"""

from __future__ import annotations

import numpy as np
from scipy.signal import find_peaks

from .chain import Chain, undamped
from .dsm import subdivide, wittrick_williams_count

__all__ = ["find_frf_peaks", "modal_fit_peaks", "natural_frequencies_hz"]

_TWO_PI = 2.0 * np.pi


def natural_frequencies_hz(chain: Chain, start_hz: float, stop_hz: float, *, rtol: float = 1e-11,
                           scan_points: int = 64) -> np.ndarray:
    """Undamped natural frequencies of a chain in ``[start_hz, stop_hz]``.

    Parameters
    ----------
    chain : Chain
        Damping is removed before counting.
    start_hz, stop_hz : float
        Band, Hz (``0 < start_hz < stop_hz``).
    rtol : float
        Relative width of the final bracket of every frequency.
    scan_points : int
        Points of the first vectorised count over the band (brackets all modes at once).

    Returns
    -------
    numpy.ndarray, shape (nmodes,)
        Ascending, Hz. A repeated frequency appears as often as its multiplicity.
    """
    ch = subdivide(undamped(chain), _TWO_PI * stop_hz)

    def count(f_hz: np.ndarray) -> np.ndarray:
        return wittrick_williams_count(ch, _TWO_PI * f_hz)

    grid = np.geomspace(start_hz, stop_hz, scan_points)
    j = count(grid)
    # Mode k (0-based, counting from zero frequency) lies where J first exceeds k.
    modes = np.arange(j[0], j[-1])
    if modes.size == 0:
        return np.empty(0)
    hi_idx = np.searchsorted(j, modes, side="right")
    lo = grid[hi_idx - 1].copy()
    hi = grid[hi_idx].copy()
    while np.any(hi - lo > rtol * hi):
        mid = 0.5 * (lo + hi)
        above = count(mid) > modes
        hi = np.where(above, mid, hi)
        lo = np.where(above, lo, mid)
    return 0.5 * (lo + hi)


def find_frf_peaks(frequency_hz: np.ndarray, h: np.ndarray, *, rel_prominence: float = 0.01
                   ) -> list[dict[str, float]]:
    """Local maxima of ``|h|`` on the grid, with a prominence of at least ``rel_prominence·max|h|``.

    Parameters
    ----------
    frequency_hz : numpy.ndarray, shape (nfreq,)
    h : numpy.ndarray, shape (nfreq,), complex
        Receptance, m/N.

    Returns
    -------
    list of dict
        ``{"frequency_hz", "magnitude_m_n"}`` in ascending frequency.
    """
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
        s = 2j * np.pi * frequency_hz[lo:hi]
        hh = h[lo:hi]
        scale = float(np.abs(s).max())
        sn = s / scale
        # unknowns: a0, a1, c0, c1, c2 (real), normalised frequency sn
        cols = np.stack([hh, hh * sn, -np.ones_like(sn), -sn, -(sn**2)], axis=1)
        rhs = -hh * sn**2
        a = np.concatenate([cols.real, cols.imag])
        b = np.concatenate([rhs.real, rhs.imag])
        col_scale = np.linalg.norm(a, axis=0)
        x = np.linalg.lstsq(a / col_scale, b, rcond=None)[0] / col_scale
        a0, a1 = x[0], x[1]
        if a0 <= 0 or a1 <= 0:
            continue
        wn = np.sqrt(a0) * scale
        out.append({"frequency_hz": float(wn / (2 * np.pi)), "damping_ratio": float(a1 / (2 * np.sqrt(a0)))})
    return out
