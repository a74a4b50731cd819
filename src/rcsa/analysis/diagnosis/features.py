"""Mode-localised features of a tool-point FRF — the coordinates in which the gap is judged.

For each measurement, the windows are fixed once from the **base** model (``docs/diagnosis.md``
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

from dataclasses import dataclass, field

import numpy as np

from rcsa.model.peaks import peak_lines

__all__ = ["Windows", "band_rms_db", "design_windows", "extract", "parabola_stencils"]

_OFFSETS = np.arange(-2, 3)

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
    stencils : numpy.ndarray, shape (nlines, 3, 5), optional
        The least-squares parabola of the five lines around each line (:func:`parabola_stencils`):
        a vertex away from the window's edges is one small product, not the normal equations.
    """

    peaks_hz: np.ndarray
    edges: np.ndarray
    static: slice
    names: tuple[str, ...]
    stencils: np.ndarray | None = field(default=None, repr=False, compare=False)

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
    return Windows(fp, edges, static, tuple(names), parabola_stencils(np.log(f)))


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


def parabola_stencils(x: np.ndarray) -> np.ndarray:
    """Least-squares parabola coefficients of the five lines around every line, as matrices.

    ``c = P[i] @ y[i-2 … i+2]`` gives ``y ≈ c0 + c1 d + c2 d²`` with ``d = x − x[i]`` (the
    normal equations of :func:`_vertex`, solved once per line); lines within two of an end
    have no five-line stencil (zeros: never used).

    Parameters
    ----------
    x : numpy.ndarray, shape (nlines,)
        ln f of the analysis lines.

    Returns
    -------
    numpy.ndarray, shape (nlines, 3, 5)
    """
    out = np.zeros((x.size, 3, 5))
    if x.size >= 5:
        i = np.arange(2, x.size - 2)
        d = x[i[:, None] + np.arange(-2, 3)] - x[i][:, None]
        v = np.stack([np.ones_like(d), d, d * d], axis=2)  # (m, 5, 3)
        out[i] = np.linalg.solve(np.einsum("mki,mkj->mij", v, v), v.transpose(0, 2, 1))
    return out


def _vertex(x: np.ndarray, y: np.ndarray, i: np.ndarray, lo: np.ndarray, hi: np.ndarray, sign: float,
            rows: np.ndarray | None = None, stencils: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Least-squares parabola through the lines ``i-2 … i+2`` (clipped to [lo, hi)); its vertex.

    ``sign`` = +1 for a maximum, −1 for a minimum. Falls back to the line itself when the
    parabola opens the wrong way. Vectorised: ``i``, ``lo``, ``hi`` (m,) on rows ``rows`` of
    ``y`` (n, nlines) (default: row k for entry k). With ``stencils`` (:func:`parabola_stencils`)
    and no line clipped, the parabola is their product with the five values (the same least
    squares, rounded otherwise: ~1e-15 relative).
    """
    rows = np.arange(y.shape[0]) if rows is None else rows
    if stencils is not None and i.size and bool(np.all((i - 2 >= lo) & (i + 2 < hi))):
        c = np.einsum("mkj,mj->mk", stencils[i], y[rows[:, None], i[:, None] + _OFFSETS])
        good = sign * c[:, 2] < 0
        with np.errstate(divide="ignore", invalid="ignore"):
            dv = np.where(good, -c[:, 1] / (2 * c[:, 2]), 0.0)
        xi = x[i]
        dv = np.clip(dv, x[i - 1] - xi, x[i + 1] - xi)
        return xi + dv, np.where(good, c[:, 0] + dv * (c[:, 1] + c[:, 2] * dv), y[rows, i])
    offsets = np.arange(-2, 3)
    j = np.clip(i[:, None] + offsets, lo[:, None], hi[:, None] - 1)  # (m, 5)
    d = x[j] - x[i][:, None]
    yy = y[rows[:, None], j]
    # Normal equations of y = c0 + c1 d + c2 d² over five points (duplicates from clipping
    # only reweight; three distinct points are enough, fewer fall back to the line).
    # A = VᵀV = [[s0, s1, s2], [s1, s2, s3], [s2, s3, s4]], b = Vᵀy, V = [1, d, d²]; solved by its
    # adjugate (the vectorised form of np.linalg.solve on the (m, 3, 3) stack).
    d2 = d * d
    s0, s1, s2, s3, s4 = float(d.shape[1]), d.sum(1), d2.sum(1), (d2 * d).sum(1), (d2 * d2).sum(1)
    t0, t1, t2 = yy.sum(1), (yy * d).sum(1), (yy * d2).sum(1)
    a00, a01, a02 = s2 * s4 - s3 * s3, s2 * s3 - s1 * s4, s1 * s3 - s2 * s2
    a11, a12, a22 = s0 * s4 - s2 * s2, s1 * s2 - s0 * s3, s0 * s2 - s1 * s1
    det = s0 * a00 + s1 * a01 + s2 * a02
    ok = det > 1e-30 * np.maximum(np.maximum(np.maximum(s0, np.abs(s1)), np.maximum(s2, np.abs(s3))), s4) ** 3
    with np.errstate(divide="ignore", invalid="ignore"):
        c = np.where(ok[:, None], np.stack([a00 * t0 + a01 * t1 + a02 * t2, a01 * t0 + a11 * t1 + a12 * t2,
                                            a02 * t0 + a12 * t1 + a22 * t2], axis=1) / det[:, None], 0.0)
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
    lo_w, hi_w = w.edges[:-1].astype(int), w.edges[1:].astype(int)
    peak_i = np.stack([lo + np.argmax(y[:, lo:hi], axis=1) for lo, hi in zip(lo_w, hi_w, strict=True)])  # (k, m)
    rows = np.tile(np.arange(m), k)
    xf, yf = _vertex(x, y, peak_i.ravel(), np.repeat(lo_w, m), np.repeat(hi_w, m), +1.0, rows,
                     w.stencils)  # all windows at once
    xf, yf = xf.reshape(k, m), yf.reshape(k, m)
    anti = np.empty((max(k - 1, 0), m))
    if k > 1:
        ia = np.empty((k - 1, m), dtype=int)
        for j in range(k - 1):  # the minimum strictly between consecutive peaks, over their span of lines only
            a, b = peak_i[j], peak_i[j + 1]
            c0, c1 = int(a.min()) + 1, max(int(b.max()), int(a.min()) + 1)
            cols = np.arange(c0, c1)
            inside = (cols[None, :] > a[:, None]) & (cols[None, :] < b[:, None])
            found = c0 + np.argmin(np.where(inside, y[:, c0:c1], np.inf), axis=1) if cols.size else a
            ia[j] = np.where(inside.any(axis=1), found, (a + b) // 2)  # adjacent peaks: the midpoint line
        a, b = peak_i[:-1].ravel(), peak_i[1:].ravel()
        flat = ia.ravel()
        anti = _vertex(x, y, flat, np.minimum(a + 1, flat), np.maximum(b, flat + 1), -1.0,
                       np.tile(np.arange(m), k - 1), w.stencils)[0].reshape(k - 1, m)
    for j in range(k):
        out += [xf[j], yf[j], y[:, lo_w[j]:hi_w[j]].mean(axis=1)]
        if j + 1 < k:
            out.append(anti[j])
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
