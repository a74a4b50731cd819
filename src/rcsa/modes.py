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

__all__ = ["find_frf_peaks", "natural_frequencies_hz"]

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
