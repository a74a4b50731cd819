"""Mode-localised features of a tool-point FRF — the coordinates in which the gap is judged.

For each measurement, the windows are fixed once from the **base** model (``diagnosis.md``
§4.2): the dominant peaks of the base ``|h|`` in the valid band, window edges at the
geometric midpoints between consecutive peaks, and a quasi-static band below the first one.
The same extractor with the same windows is then applied to measured and to modelled FRFs,
so extractor bias cancels. Per window j:

* ``peak.frequency`` — ln f of the maximum of ln|h| (least-squares parabola over five
  lines in ln f around the largest line);
* ``peak.amplitude`` — ln|h| at that vertex;
* ``antiresonance.frequency`` — ln f of the minimum of ln|h| between peaks j and j+1 of the
  analysed FRF itself (a driving-point antiresonance is the natural frequency with the tip
  pinned, so it is blind to a tip mass);
* ``band.level`` — the mean ln|h| over the whole window (the FRF's level between the
  peaks: weak modes that get no window of their own still move it; smooth in the
  parameters, no window switching);
* ``static`` — the mean ln|h| over the quasi-static band (compliance, blind to mass).

Logarithms make every feature a relative quantity: a difference of 0.01 is a 1 % shift in
frequency or amplitude. Many FRFs are handled at once: arrays are ``(nfrf, nlines)``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rcsa.model.peaks import peak_lines

__all__ = ["Windows", "band_rms_db", "design_windows", "extract"]

# Peaks smaller than this fraction of the largest one are not used as features: at the
# benchmark's 1 % noise with a -50 dB floor their frequency would be mostly noise.
MIN_RELATIVE_PEAK = 0.05
# Prominence in ln|h| of a base peak (0.35 ≈ 3 dB): a visible resonance, not a ripple. On the
# log scale, unlike the linear |h| rule of predictions (rcsa.model.peaks.find_frf_peaks): the
# windows must catch weak modes far below the dominant one, whose gap features still count.
MIN_PROMINENCE_LN = 0.35
# Two base peaks closer than this frequency ratio share one window (the larger one is kept).
MIN_PEAK_RATIO = 1.08


@dataclass(frozen=True)
class Windows:
    """Feature windows of one measurement, on its analysis lines.

    Attributes
    ----------
    peaks_hz : numpy.ndarray, shape (K,)
        Base-model peak frequencies, Hz.
    edges : numpy.ndarray of int, shape (K + 1,)
        Line indices bounding the windows (window j is ``edges[j]:edges[j+1]``).
    static : slice
        Lines of the quasi-static band (empty slice: no static feature).
    names : tuple of str
        Feature names in vector order.
    """

    peaks_hz: np.ndarray
    edges: np.ndarray
    static: slice
    names: tuple[str, ...]

    @property
    def size(self) -> int:
        """Number of features."""
        return len(self.names)


def design_windows(frequency_hz: np.ndarray, h_base: np.ndarray, max_modes: int = 5) -> Windows:
    """Windows from the base model's FRF on the analysis lines.

    Parameters
    ----------
    frequency_hz : numpy.ndarray, shape (nlines,)
        Analysis lines (valid band), Hz, increasing.
    h_base : numpy.ndarray, shape (nlines,), complex
        Base-model receptance, m/N.
    max_modes : int
        Largest number of windows (the most prominent peaks are kept).

    Returns
    -------
    Windows
    """
    f = np.asarray(frequency_hz, dtype=float)
    y = np.log(np.abs(h_base))
    idx, prominences = peak_lines(y, MIN_PROMINENCE_LN)
    keep = y[idx] >= y[idx].max() + np.log(MIN_RELATIVE_PEAK) if idx.size else np.zeros(0, bool)
    idx, prom = idx[keep], prominences[keep]
    chosen: list[int] = []
    for k in np.argsort(-prom):  # most prominent first, drop close neighbours
        if all(max(f[idx[k]], f[c]) / min(f[idx[k]], f[c]) >= MIN_PEAK_RATIO for c in chosen):
            chosen.append(int(idx[k]))
        if len(chosen) == max_modes:
            break
    peaks = np.sort(np.array(chosen, dtype=int))
    static_hi = min(4.0 * f[0], f[peaks[0]] / 2.5) if peaks.size else 4.0 * f[0]
    while True:
        if peaks.size == 0:
            raise ValueError("the base model has no resonance peak in the valid band")
        edges = _edges(f, peaks, static_hi)
        # A weak peak beside a strong one may not be the maximum of its own window (the
        # strong mode's skirt is higher at the window edge): drop it, the weakest first.
        bad = [j for j in range(peaks.size)
               if y[peaks[j]] - max(y[edges[j]], y[edges[j + 1] - 1]) < MIN_PROMINENCE_LN
               or np.argmax(y[edges[j]:edges[j + 1]]) + edges[j] != peaks[j]]
        if not bad:
            break
        peaks = np.delete(peaks, min(bad, key=lambda j: y[peaks[j]]))
    fp = f[peaks]
    n_static = int(np.searchsorted(f, static_hi))
    static = slice(0, n_static) if n_static >= 3 and static_hi > 1.2 * f[0] else slice(0, 0)
    names: list[str] = ["static"] if static.stop > 0 else []
    for j in range(peaks.size):
        names += [f"peak{j}.frequency", f"peak{j}.amplitude", f"band{j}.level"]
        if j + 1 < peaks.size:
            names.append(f"antiresonance{j}.frequency")
    return Windows(fp, edges, static, tuple(names))


def _edges(f: np.ndarray, peaks: np.ndarray, static_hi: float) -> np.ndarray:
    """Window edges (line indices): geometric midpoints, outer edges mirrored in ln f."""
    fp = f[peaks]
    mids = np.sqrt(fp[1:] * fp[:-1])
    first_ratio = np.sqrt(fp[1] / fp[0]) if fp.size > 1 else 1.4
    last_ratio = np.sqrt(fp[-1] / fp[-2]) if fp.size > 1 else 1.4
    lo_edge = max(fp[0] / first_ratio, static_hi, f[0])
    hi_edge = min(fp[-1] * last_ratio, f[-1] * (1 + 1e-12))
    edges = np.searchsorted(f, np.concatenate([[lo_edge], mids, [hi_edge]]))
    edges[-1] = min(max(edges[-1], peaks[-1] + 3), f.size)
    edges[0] = max(min(edges[0], peaks[0] - 2), 0)
    return edges


def _vertex(x: np.ndarray, y: np.ndarray, i: np.ndarray, lo: np.ndarray, hi: np.ndarray, sign: float
            ) -> tuple[np.ndarray, np.ndarray]:
    """Least-squares parabola through the lines ``i-2 … i+2`` (clipped to [lo, hi)); its vertex.

    ``sign`` = +1 for a maximum, −1 for a minimum. Falls back to the line itself when the
    parabola opens the wrong way. Vectorised over rows: ``y`` (m, n), ``i``, ``lo``, ``hi`` (m,).
    """
    rows = np.arange(y.shape[0])
    offsets = np.arange(-2, 3)
    j = np.clip(i[:, None] + offsets, lo[:, None], hi[:, None] - 1)  # (m, 5)
    d = x[j] - x[i][:, None]
    yy = y[rows[:, None], j]
    # Normal equations of y = c0 + c1 d + c2 d² over five points (duplicates from clipping
    # only reweight; three distinct points are enough, fewer fall back to the line).
    v = np.stack([np.ones_like(d), d, d * d], axis=-1)  # (m, 5, 3)
    a = np.einsum("mki,mkj->mij", v, v)
    b = np.einsum("mki,mk->mi", v, yy)
    ok = np.linalg.det(a) > 1e-30 * np.maximum(np.abs(a).max(axis=(1, 2)), 1e-300) ** 3
    c = np.zeros((y.shape[0], 3))
    if ok.any():
        c[ok] = np.linalg.solve(a[ok], b[ok][..., None])[..., 0]
    good = ok & (sign * c[:, 2] < 0)
    span_lo = x[np.maximum(i - 1, lo)] - x[i]
    span_hi = x[np.minimum(i + 1, hi - 1)] - x[i]
    with np.errstate(divide="ignore", invalid="ignore"):
        dv = np.where(good, -c[:, 1] / (2 * c[:, 2]), 0.0)
    dv = np.clip(dv, span_lo, span_hi)
    yv = np.where(good, c[:, 0] + c[:, 1] * dv + c[:, 2] * dv * dv, y[rows, i])
    return x[i] + dv, yv


def extract(frequency_hz: np.ndarray, h: np.ndarray, w: Windows) -> np.ndarray:
    """Features of many FRFs on the same analysis lines.

    Parameters
    ----------
    frequency_hz : numpy.ndarray, shape (nlines,)
    h : numpy.ndarray, shape (nfrf, nlines) or (nlines,), complex
        Receptances, m/N.
    w : Windows

    Returns
    -------
    numpy.ndarray, shape (nfrf, w.size) (or (w.size,) for one FRF)
        In the order of ``w.names``.
    """
    single = np.ndim(h) == 1
    y = np.log(np.maximum(np.abs(np.atleast_2d(h)), 1e-300))
    x = np.log(np.asarray(frequency_hz, dtype=float))
    m = y.shape[0]
    out: list[np.ndarray] = []
    if w.static.stop > 0:
        out.append(y[:, w.static].mean(axis=1))
    k = w.peaks_hz.size
    peak_i = []
    for j in range(k):
        lo, hi = int(w.edges[j]), int(w.edges[j + 1])
        i = lo + np.argmax(y[:, lo:hi], axis=1)
        peak_i.append(i)
    for j in range(k):
        lo, hi = int(w.edges[j]), int(w.edges[j + 1])
        xf, yf = _vertex(x, y, peak_i[j], np.full(m, lo), np.full(m, hi), +1.0)
        out += [xf, yf, y[:, lo:hi].mean(axis=1)]
        if j + 1 < k:
            a, b = peak_i[j], peak_i[j + 1]
            cols = np.arange(y.shape[1])
            inside = (cols[None, :] > a[:, None]) & (cols[None, :] < b[:, None])
            masked = np.where(inside, y, np.inf)
            ia = np.argmin(masked, axis=1)
            none = ~inside.any(axis=1)  # adjacent peaks: take the midpoint line
            ia = np.where(none, (a + b) // 2, ia)
            xa, _ = _vertex(x, y, ia, np.minimum(a + 1, ia), np.maximum(b, ia + 1), -1.0)
            out.append(xa)
    feats = np.stack(out, axis=1)
    return feats[0] if single else feats


def band_rms_db(h_a: np.ndarray, h_b: np.ndarray, bands: list[np.ndarray]) -> np.ndarray:
    """RMS over each band of ``20 log10 |h_a / h_b|``, dB.

    Parameters
    ----------
    h_a : numpy.ndarray, shape (..., nlines), complex
    h_b : numpy.ndarray, shape (nlines,) or (..., nlines), complex
    bands : list of numpy.ndarray of int
        Lines of each band.

    Returns
    -------
    numpy.ndarray, shape (..., nbands)
    """
    err = 20.0 * np.log10(np.abs(h_a) / np.abs(h_b))
    return np.stack([np.sqrt(np.mean(err[..., b] ** 2, axis=-1)) for b in bands], axis=-1)
