"""Modal fit of a sampled FRF: natural frequencies, damping ratios and their uncertainty.

Where no exact model gives the natural frequencies (a hybrid prediction on a measured
spindle, a tap test), they are estimated from the sampled tool-point ``h`` itself. A noisy
peak must give one mode, not one per ripple, and each value must say how well it is known.

Procedure (:func:`modal_fit`):

1. **Candidates**: local maxima of ``|h|`` whose prominence reaches ``rel_prominence`` of
   ``max|h|`` (:func:`rcsa.model.peaks.peak_lines`, the prediction's rule).
2. **Noise gate**: a candidate must also rise by ``noise_sigmas·σ·|h_peak|`` above its
   surroundings, ``σ`` its local relative noise: the smaller of the third-difference
   estimate on ±``NOISE_LINES`` lines (:func:`relative_noise`; robust to a model misfit)
   and the residual of a first one-mode fit on ±1 % (robust to coarse sampling, where the
   third differences see the curvature of a sharp peak).
3. **Fit and merge**: each surviving candidate owns a cell (up to the geometric midpoints
   toward its neighbours); one mode with residual terms (below) is fitted in it and the
   band re-centred on the fitted pole, ``±K·ζ·f_n`` (K = 2.5, at least ±``MIN_HALF_LINES``
   lines and 0.3 %), until the pole settles. Candidates whose poles coincide (within the
   half-power half-width ``ζ·f_n``) or whose pole leaves its own cell toward a neighbour are
   one mode: they are merged, their cells joined, and fitted again.
4. **Close modes**: two modes whose bands overlap are fitted together (two poles on the
   union band); the pair is kept when both poles are stable and inside it.
5. **Uncertainty**: ``sd = √(sd_fit² + sd_band²)``. ``sd_fit`` is the fit's covariance
   ``s²(AᴴA)⁻¹`` (``s²`` from the residual) carried to the pole by the delta method;
   ``sd_band`` is the spread (sample standard deviation) of ``f_n`` over the band choices
   K ∈ {1.5, 2.5, 4}, which covers what the residual terms do not model.
6. The modes are sorted; those outside the grid, and those whose own peak
   ``|φ²|/(2ζω_n²)`` stands less than ``noise_sigmas`` times the fit's residual noise above
   it (:attr:`FittedMode.significance`), are dropped; any two of different fits closer
   than the half-power half-width of either are one (the better determined is kept).

The fitted form on a band of centre ``ω_c`` and half-width ``Δ`` (``x = (ω − ω_c)/Δ`` in
[−1, 1])::

    h(x) ≈ N(x) / D(x),   D monic of degree n, N of degree n + 1, complex coefficients

holds the n poles near the band; their conjugates and the modes outside the band are smooth
there and are absorbed by N's extra degrees (residual terms). It is linear least squares in
the coefficients (Levy), iterated with rows weighted by ``1/|h·D_prev|`` (Sanathanan–Koerner,
relative errors, as the noise is relative). A pole ``x_k`` gives ``ω_k = ω_c + Δ·x_k =
ω_d + iζω_n`` (poles of ``h`` in the upper half plane under ``e^{iωt}``): ``f_n = |ω_k|/2π``,
``ζ = Im ω_k / |ω_k|``, and the mass-normalised modal constant (tip residue, 1/kg)
``φ² = Re(−2 ω_d Δ N(x_k)/D'(x_k))``.

References
----------
Levy, IRE Trans. Autom. Control AC-4 (1959) 37–43; Sanathanan & Koerner, IEEE Trans.
Autom. Control 8 (1963) 56–58; Richardson & Formenti, Proc. IMAC 1 (1982) (rational
fraction polynomial modal fitting).
"""

from __future__ import annotations

import hashlib
import math
import threading
from dataclasses import dataclass
from typing import Any

import numpy as np

from rcsa.model.peaks import peak_lines
from rcsa.physics.arrays import ComplexArray, FloatArray, IntArray
from rcsa.physics.subassembly_cache import LruStore

__all__ = ["BAND_FACTORS", "FITS_KEPT", "FittedMode", "ModalFit", "RationalFit", "kept_modal_fit",
           "local_relative_noise", "modal_fit", "rational_fit", "refit_mode", "relative_noise"]

_TWO_PI = 2.0 * np.pi
#: Lines each side of a candidate for its local third-difference noise estimate.
NOISE_LINES = 25
#: Least half-width of a fitted band, in lines (and relative).
MIN_HALF_LINES = 6
_MIN_HALF_REL = 0.003
#: Half-width of the noise gate's fit around a candidate, and of the first fit of a mode
#: (within its cell), relative.
_FIRST_HALF_REL = 0.01
_START_HALF_REL = 0.1
#: Band half-width in half-power half-widths ζ·f_n: the one reported, and the choices whose
#: spread enters the uncertainty.
BAND_FACTOR = 2.5
BAND_FACTORS = (1.5, 2.5, 4.0)
#: Sanathanan–Koerner passes, and re-centring passes of a band.
_SK_PASSES = 3
_SETTLE_PASSES = 6
#: Points of the dense grid on which a fitted band's peak is looked for.
_PEAK_POINTS = 801


def relative_noise(h: ComplexArray, lines: IntArray | None = None, robust: bool = True) -> float:
    """Standard deviation of the relative complex noise of an FRF, from third differences.

    For ``h_k = s_k (1 + n_k)`` with white complex noise ``E|n|² = σ²`` and a smooth ``s``
    (many lines per half-power bandwidth), ``|Δ³h|²/|h|² ≈ 20σ²·Exp(1)``, whose median is
    ``20σ² ln 2``. Smooth curvature adds about ``|h'''|Δf³``, negligible at ≥ 10 lines
    per bandwidth.

    Parameters
    ----------
    h : numpy.ndarray, shape (nfreq,), complex
        Receptance on consecutive lines, m/N.
    lines : numpy.ndarray of int, optional
        Use only these (ascending) lines; differences are taken within each run of
        consecutive lines, never across a gap.
    robust : bool
        The median (default: outliers such as single bad lines do not count) or the mean
        (``E|Δ³h|²/|h|² = 20σ²``: the RMS noise, spikes included, as a residual sees it).

    Returns
    -------
    float
        σ (relative), e.g. 0.01 for 1 % noise; NaN without 4 consecutive lines.
    """
    h = np.asarray(h, dtype=complex)
    idx = np.arange(h.size) if lines is None else np.asarray(lines, dtype=int)
    runs = np.split(idx, np.flatnonzero(np.diff(idx) > 1) + 1) if idx.size else []
    ratios = [np.abs(np.diff(h[r], 3)) ** 2 / np.abs(h[r][1:-2]) ** 2 for r in runs if r.size >= 4]
    if not ratios:
        return math.nan
    all_ratios = np.concatenate(ratios)
    if not robust:
        return float(np.sqrt(np.mean(all_ratios) / 20.0))
    return float(np.sqrt(np.median(all_ratios) / (20.0 * math.log(2.0))))


def local_relative_noise(h: ComplexArray, half_lines: int = NOISE_LINES) -> FloatArray:
    """:func:`relative_noise` along the band: the median in consecutive blocks of
    ``2·half_lines + 1`` lines, each line taking its block's value.

    Noise that varies along the band (a measured spindle's noise, amplified where its
    identification is ill-conditioned or where the joints make the tool point sensitive to
    it) is seen where it is, at a cost linear in the number of lines.

    Parameters
    ----------
    h : numpy.ndarray, shape (nfreq,), complex
        Receptance on consecutive lines, m/N.
    half_lines : int
        Half the block length, lines.

    Returns
    -------
    numpy.ndarray, shape (nfreq,)
        σ per line (relative); NaN everywhere with fewer than 4 lines.
    """
    h = np.asarray(h, dtype=complex)
    if h.size < 4:
        return np.full(h.size, np.nan)
    ratios = np.abs(np.diff(h, 3)) ** 2 / np.abs(h[1:-2]) ** 2          # one per line 1 … n − 3
    width = min(2 * half_lines + 1, ratios.size)
    nblocks = -(-ratios.size // width)
    padded = np.pad(ratios, (0, nblocks * width - ratios.size), mode="edge")
    med = np.median(padded.reshape(nblocks, width), axis=1)
    sigma = np.sqrt(med / (20.0 * math.log(2.0)))
    out: FloatArray = sigma[np.clip((np.arange(h.size) - 1) // width, 0, nblocks - 1)]
    return out


# ---------------------------------------------------------------------------- one band


@dataclass(frozen=True)
class RationalFit:
    """``h ≈ N(x)/D(x)`` on one band, ``x = (ω − ω_c)/Δ`` (see the module docstring).

    Attributes
    ----------
    center_rad_s, half_width_rad_s : float
        ``ω_c`` and ``Δ``, rad/s.
    den : numpy.ndarray, shape (n,), complex
        ``d_0 … d_{n−1}`` of the monic ``D = xⁿ + Σ d_j x^j``.
    num : numpy.ndarray, shape (n + 2,), complex
        ``N = Σ c_j x^j``.
    cov_den : numpy.ndarray, shape (n, n), complex
        Covariance ``E[δd δdᴴ]`` of ``den`` (circular complex errors).
    residual_rel : float
        RMS relative residual ``|h_fit/h − 1|`` over the band.
    band_hz : (float, float)
        First and last line of the band, Hz.
    """

    center_rad_s: float
    half_width_rad_s: float
    den: ComplexArray
    num: ComplexArray
    cov_den: ComplexArray
    residual_rel: float
    band_hz: tuple[float, float]

    @property
    def n_modes(self) -> int:
        """Number of poles fitted."""
        return int(self.den.size)

    def _x(self, frequency_hz: FloatArray) -> FloatArray:
        out: FloatArray = (_TWO_PI * np.asarray(frequency_hz, dtype=float) - self.center_rad_s) / self.half_width_rad_s
        return out

    def evaluate(self, frequency_hz: FloatArray) -> ComplexArray:
        """The fitted ``h`` at any frequencies (Hz) near the band, m/N, same shape.

        Parameters
        ----------
        frequency_hz : numpy.ndarray
            Frequencies, Hz, any shape (the fit is meaningful near its band only).

        Returns
        -------
        numpy.ndarray of complex
            The fitted receptance, m/N, shape of ``frequency_hz``.
        """
        return _ratio(self.num, self.den, self._x(frequency_hz))

    def modes(self) -> dict[str, FloatArray]:
        """The stable poles: ``frequency_hz``, ``damping_ratio``, their standard deviations
        ``sd_hz`` and ``damping_ratio_sd`` (fit covariance only) and ``residue_1_kg``,
        each shape (nstable,), ascending in frequency."""
        n = self.den.size
        coeffs = np.r_[1.0 + 0j, self.den[::-1]]  # descending, monic
        xk = np.roots(coeffs) if n > 1 else np.array([-self.den[0]])
        omega = self.center_rad_s + self.half_width_rad_s * xk
        stable = (omega.real > 0) & (omega.imag > 0)
        xk, omega = xk[stable], omega[stable]
        d_prime = np.polyval(np.polyder(coeffs), xk)
        mag = np.abs(omega)
        # ∂x_k/∂d_j = −x_k^j / D'(x_k); rows: poles, columns: coefficients
        g = -(xk[:, None] ** np.arange(n)[None, :]) / d_prime[:, None] * self.half_width_rad_s
        u = (np.conj(omega) / mag)[:, None] * g                                    # δ|ω| = Re(u δd)
        v = (-1j / mag - omega.imag * np.conj(omega) / mag**3)[:, None] * g        # δζ = Re(v δd)
        var_w = 0.5 * np.einsum("ij,jk,ik->i", u, self.cov_den, np.conj(u)).real
        var_z = 0.5 * np.einsum("ij,jk,ik->i", v, self.cov_den, np.conj(v)).real
        residue_x = np.polyval(self.num[::-1], xk) / d_prime
        residue = (-2.0 * omega.real * self.half_width_rad_s * residue_x).real
        order = np.argsort(mag)
        return {"frequency_hz": (mag / _TWO_PI)[order], "damping_ratio": (omega.imag / mag)[order],
                "sd_hz": (np.sqrt(np.clip(var_w, 0.0, None)) / _TWO_PI)[order],
                "damping_ratio_sd": np.sqrt(np.clip(var_z, 0.0, None))[order], "residue_1_kg": residue[order]}

    def peak(self, near_hz: float | None = None) -> tuple[float, float]:
        """``(frequency_hz, magnitude_m_n)`` of an interior maximum of the fitted ``|h|`` on the
        band (parabola-refined): the largest, or the one nearest ``near_hz``; NaN when ``|h|``
        has none there.

        Parameters
        ----------
        near_hz : float, optional
            Pick the maximum nearest this frequency, Hz, instead of the largest.

        Returns
        -------
        tuple of (float, float)
            Frequency, Hz, and ``|h|``, m/N.
        """
        f = np.linspace(*self.band_hz, _PEAK_POINTS)
        mag = np.abs(self.evaluate(f))
        inner = np.flatnonzero((mag[1:-1] > mag[:-2]) & (mag[1:-1] >= mag[2:])) + 1
        if inner.size == 0:
            return math.nan, math.nan
        i = int(inner[np.argmax(mag[inner])] if near_hz is None else inner[np.argmin(np.abs(f[inner] - near_hz))])
        y0, y1, y2 = mag[i - 1], mag[i], mag[i + 1]
        curv = y0 - 2 * y1 + y2
        shift = 0.5 * (y0 - y2) / curv if curv < 0 else 0.0
        fp = float(f[i] + shift * (f[1] - f[0]))
        return fp, float(np.abs(self.evaluate(np.array([fp])))[0])


def _ratio(num: ComplexArray, den: ComplexArray, x: FloatArray) -> ComplexArray:
    d = np.polyval(np.r_[1.0 + 0j, den[::-1]], x)
    out: ComplexArray = np.polyval(num[::-1], x) / d
    return out


def rational_fit(frequency_hz: FloatArray, h: ComplexArray, n_modes: int = 1) -> RationalFit | None:
    """Fit ``n_modes`` poles with residual terms to ``h`` on its band (see the module docstring).

    Parameters
    ----------
    frequency_hz : numpy.ndarray, shape (m,)
        The band's lines, Hz, increasing; ``m ≥ 2 n_modes + 3``.
    h : numpy.ndarray, shape (m,), complex
        Receptance there, m/N (non-zero).
    n_modes : int
        Poles in the band.

    Returns
    -------
    RationalFit or None
        None when the band is too short or the least squares problem is degenerate.
    """
    f = np.asarray(frequency_hz, dtype=float)
    h = np.asarray(h, dtype=complex)
    n = int(n_modes)
    p = 2 * n + 2
    if f.size < p + 1 or f[-1] <= f[0] or not np.all(np.abs(h) > 0):
        return None
    w = _TWO_PI * f
    wc, dw = 0.5 * (w[0] + w[-1]), 0.5 * (w[-1] - w[0])
    x = (w - wc) / dw
    v_num = x[:, None] ** np.arange(n + 2)[None, :]
    v_den = x[:, None] ** np.arange(n)[None, :]
    base = np.concatenate([v_num, -h[:, None] * v_den], axis=1)
    rhs = h * x**n
    weight = 1.0 / np.abs(h)
    theta = np.zeros(p, dtype=complex)
    a_scaled, col = base, np.ones(p)
    for _ in range(_SK_PASSES):
        a = base * weight[:, None]
        col = np.linalg.norm(a, axis=0)
        if not np.all(col > 0):
            return None
        a_scaled = a / col
        theta = np.linalg.lstsq(a_scaled, rhs * weight, rcond=None)[0] / col
        d_prev = np.abs(np.polyval(np.r_[1.0 + 0j, theta[n + 2:][::-1]], x))
        if not np.all(np.isfinite(d_prev)) or not np.all(d_prev > 0):
            return None
        weight = 1.0 / (np.abs(h) * d_prev)
    num, den = theta[:n + 2], theta[n + 2:]
    fit_h = _ratio(num, den, x)
    rel = fit_h / h - 1.0
    residual = float(np.sqrt(np.mean(np.abs(rel) ** 2)))
    r = (base @ theta - rhs) * weight
    s2 = float(np.vdot(r, r).real) / max(f.size - p, 1)
    gram = a_scaled.conj().T @ a_scaled
    try:
        cov: ComplexArray = (s2 * np.linalg.inv(gram) / np.outer(col, col)).astype(complex)
    except np.linalg.LinAlgError:
        return None
    return RationalFit(float(wc), float(dw), den, num, cov[n + 2:, n + 2:], residual, (float(f[0]), float(f[-1])))


# ---------------------------------------------------------------------------- the whole grid


@dataclass(frozen=True)
class FittedMode:
    """One mode of a modal fit.

    Attributes
    ----------
    frequency_hz : float
        Natural frequency ``|ω_k|/2π``, Hz.
    damping_ratio : float
        ``ζ``.
    sd_hz : float
        Its standard uncertainty, Hz: ``√(sd_fit_hz² + sd_band_hz²)``.
    damping_ratio_sd : float
        Standard uncertainty of ``ζ`` (fit covariance and band spread likewise).
    sd_fit_hz, sd_band_hz : float
        The two parts of ``sd_hz``: the fit's covariance, the spread over band choices.
    residue_1_kg : float
        Mass-normalised modal constant ``φ²`` at the measured point, 1/kg.
    peak_frequency_hz, peak_magnitude_m_n : float
        The fitted ``|h|``'s maximum next to the mode (NaN when it has none), Hz and m/N.
    band_hz : (float, float)
        The lines the reported fit used, Hz.
    modes_in_band : int
        Poles fitted together on that band (2 for close modes).
    residual_rel : float
        RMS relative residual of that fit.
    significance : float
        Peak height of the mode's own term, ``|φ²|/(2ζω_n²)``, over the fit's residual
        noise ``residual_rel·|h_fit(f_n)|``: how far the mode stands out of the noise.
    """

    frequency_hz: float
    damping_ratio: float
    sd_hz: float
    damping_ratio_sd: float
    sd_fit_hz: float
    sd_band_hz: float
    residue_1_kg: float
    peak_frequency_hz: float
    peak_magnitude_m_n: float
    band_hz: tuple[float, float]
    modes_in_band: int
    residual_rel: float
    significance: float

    def to_dict(self) -> dict[str, Any]:
        """JSON form (NaN → null)."""
        return {"frequency_hz": self.frequency_hz, "damping_ratio": self.damping_ratio, "sd_hz": self.sd_hz,
                "damping_ratio_sd": self.damping_ratio_sd, "sd_fit_hz": self.sd_fit_hz,
                "sd_band_hz": self.sd_band_hz, "band_hz": list(self.band_hz), "modes_in_band": self.modes_in_band,
                "residual_rel": _num(self.residual_rel), "significance": _num(self.significance),
                "peak_frequency_hz": _num(self.peak_frequency_hz),
                "peak_magnitude_m_n": _num(self.peak_magnitude_m_n)}


@dataclass(frozen=True)
class ModalFit:
    """Result of :func:`modal_fit`.

    Attributes
    ----------
    modes : tuple of FittedMode
        Ascending in frequency, distinct (no two of separate fits within either's half-power
        half-width; the two poles of a close pair are resolved by their joint fit).
    peak_lines : numpy.ndarray of int
        One line per mode found: the highest of the peaks of ``|h|`` that passed the noise
        gate and were fitted as that mode, ascending.
    noise_rel : float
        Median local relative noise σ of the candidate peaks (NaN without any).
    """

    modes: tuple[FittedMode, ...]
    peak_lines: IntArray
    noise_rel: float

    @property
    def frequency_hz(self) -> FloatArray:
        """Natural frequencies, Hz, shape (nmodes,)."""
        return np.array([m.frequency_hz for m in self.modes], dtype=float)

    @property
    def sd_hz(self) -> FloatArray:
        """Their standard uncertainties, Hz, shape (nmodes,)."""
        return np.array([m.sd_hz for m in self.modes], dtype=float)


def _num(x: float) -> float | None:
    return float(x) if math.isfinite(x) else None


@dataclass(frozen=True)
class _Settled:
    fit: RationalFit
    pole: int
    frequency_hz: float
    damping_ratio: float


def _band_lines(f: FloatArray, center_hz: float, half_rel: float, cell: tuple[int, int]) -> tuple[int, int]:
    """``[lo, hi)`` of the lines within ``center·(1 ± half_rel)``, at least ±MIN_HALF_LINES, inside ``cell``."""
    clo, chi = cell
    i = int(np.clip(np.searchsorted(f, center_hz), clo, chi))
    lo = int(np.searchsorted(f, center_hz * (1 - half_rel)))
    hi = int(np.searchsorted(f, center_hz * (1 + half_rel), side="right")) - 1
    lo, hi = min(lo, i - MIN_HALF_LINES), max(hi, i + MIN_HALF_LINES)
    return max(lo, clo), min(hi, chi) + 1


def _nearest(fit: RationalFit, near_hz: float) -> tuple[int, float, float] | None:
    poles = fit.modes()
    if poles["frequency_hz"].size == 0:
        return None
    k = int(np.argmin(np.abs(poles["frequency_hz"] - near_hz)))
    return k, float(poles["frequency_hz"][k]), float(poles["damping_ratio"][k])


def _settle(f: FloatArray, h: ComplexArray, start_hz: float, cell: tuple[int, int]) -> _Settled | None:
    """One mode re-centred on its own pole until it settles (step 3 of the module docstring)."""
    center, half = start_hz, _START_HALF_REL
    out = None
    for _ in range(_SETTLE_PASSES):
        lo, hi = _band_lines(f, center, half, cell)
        fit = rational_fit(f[lo:hi], h[lo:hi]) if hi - lo >= 2 * MIN_HALF_LINES else None
        pole = None if fit is None else _nearest(fit, center)
        if fit is None or pole is None:
            return out
        k, fn, zeta = pole
        out = _Settled(fit, k, fn, zeta)
        new_half = max(BAND_FACTOR * zeta, _MIN_HALF_REL)
        if abs(fn - center) <= 0.05 * zeta * fn and abs(new_half - half) <= 0.1 * half:
            break
        center, half = fn, new_half
        if not f[cell[0]] <= fn <= f[cell[1]]:
            break
    return out


def _cells(f: FloatArray, groups: list[list[int]]) -> list[tuple[int, int]]:
    """Line ranges (inclusive) of each group of candidate lines, split at geometric midpoints."""
    cuts = [0]
    for a, b in zip(groups[:-1], groups[1:], strict=True):
        mid = math.sqrt(f[max(a)] * f[min(b)])
        cuts.append(int(np.searchsorted(f, mid)))
    cuts.append(f.size)
    return [(cuts[k], cuts[k + 1] - 1) for k in range(len(groups))]


def _same_mode(a: _Settled, b: _Settled) -> bool:
    return abs(a.frequency_hz - b.frequency_hz) < max(a.damping_ratio * a.frequency_hz,
                                                       b.damping_ratio * b.frequency_hz)


def _noise_gate(f: FloatArray, h: ComplexArray, rel_prominence: float, noise_sigmas: float
                ) -> tuple[list[int], list[float]]:
    mag = np.abs(h)
    lines, prominences = peak_lines(mag, rel_prominence * float(mag.max()))
    kept, noise = [], []
    for i, prom in zip(lines.tolist(), prominences.tolist(), strict=True):
        third = relative_noise(h, np.arange(max(0, i - NOISE_LINES), min(f.size, i + NOISE_LINES + 1)))
        lo, hi = _band_lines(f, float(f[i]), _FIRST_HALF_REL, (0, f.size - 1))
        first = rational_fit(f[lo:hi], h[lo:hi])
        sigma = min(third if math.isfinite(third) else math.inf,
                    first.residual_rel if first is not None else math.inf)
        sigma = sigma if math.isfinite(sigma) else 0.0
        noise.append(sigma)
        if prom >= noise_sigmas * sigma * mag[i]:
            kept.append(i)
    return kept, noise


def _settle_all(f: FloatArray, h: ComplexArray, kept: list[int]
                ) -> list[tuple[_Settled, tuple[int, int], int]]:
    """Step 3 of the module docstring: fit each group, merge groups of one mode, repeat.

    Returns each mode's settled fit, its cell and the highest line of its group.
    """
    mag = np.abs(h)
    groups = [[i] for i in kept]
    memo: dict[tuple[tuple[int, ...], tuple[int, int]], _Settled | None] = {}

    def settled(group: list[int], cell: tuple[int, int]) -> _Settled | None:
        key = (tuple(group), cell)
        if key not in memo:
            top = max(group, key=lambda i: mag[i])
            memo[key] = _settle(f, h, float(f[top]), cell)
        return memo[key]

    while True:
        cells = _cells(f, groups) if groups else []
        results = [settled(g, c) for g, c in zip(groups, cells, strict=True)]
        join = [False] * max(len(groups) - 1, 0)  # join[k]: groups k and k + 1 are one mode
        for k, r in enumerate(results):
            if r is None:
                continue
            if k > 0 and r.frequency_hz < f[cells[k][0]]:
                join[k - 1] = True
            if k + 1 < len(groups) and r.frequency_hz > f[cells[k][1]]:
                join[k] = True
            nxt = results[k + 1] if k + 1 < len(groups) else None
            if nxt is not None and _same_mode(r, nxt):
                join[k] = True
        if not any(join):
            break
        merged = [list(groups[0])]
        for k, j in enumerate(join):
            if j:
                merged[-1].extend(groups[k + 1])
            else:
                merged.append(list(groups[k + 1]))
        groups = merged
    return [(r, c, max(g, key=lambda i: mag[i])) for r, c, g in zip(results, cells, groups, strict=True)
            if r is not None and f[c[0]] <= r.frequency_hz <= f[c[1]]]


def _mode_from(f: FloatArray, h: ComplexArray, fit: RationalFit, near_hz: float,
               bands: list[tuple[int, int]]) -> FittedMode | None:
    """The reported mode of ``fit`` nearest ``near_hz``, with the spread over ``bands``."""
    pole = _nearest(fit, near_hz)
    if pole is None:
        return None
    k = pole[0]
    poles = fit.modes()
    spread_f, spread_z = [], []
    for lo, hi in bands:
        other = rational_fit(f[lo:hi], h[lo:hi], fit.n_modes) if hi - lo >= 2 * MIN_HALF_LINES else None
        hit = None if other is None else _nearest(other, float(poles["frequency_hz"][k]))
        if hit is not None:
            spread_f.append(hit[1])
            spread_z.append(hit[2])
    sd_band = float(np.std(spread_f, ddof=1)) if len(spread_f) > 1 else 0.0
    sd_band_z = float(np.std(spread_z, ddof=1)) if len(spread_z) > 1 else 0.0
    fn, sd_fit, zeta = float(poles["frequency_hz"][k]), float(poles["sd_hz"][k]), float(poles["damping_ratio"][k])
    residue = float(poles["residue_1_kg"][k])
    peak_f, peak_m = fit.peak(fn)
    own = abs(residue) / (2.0 * zeta * (_TWO_PI * fn) ** 2)
    noise = fit.residual_rel * float(np.abs(fit.evaluate(np.array([fn])))[0])
    significance = own / noise if noise > 0 else math.inf
    return FittedMode(fn, zeta, math.hypot(sd_fit, sd_band), math.hypot(float(poles["damping_ratio_sd"][k]), sd_band_z),
                      sd_fit, sd_band, residue, peak_f, peak_m, fit.band_hz, fit.n_modes, fit.residual_rel,
                      significance)


def _close_pair(f: FloatArray, h: ComplexArray, a: tuple[_Settled, tuple[int, int], int],
                b: tuple[_Settled, tuple[int, int], int]) -> list[FittedMode] | None:
    """Step 4: two modes whose bands overlap, fitted together on the union band."""
    (ra, ca, _), (rb, cb, _) = a, b
    cell = (ca[0], cb[1])

    def band(factor: float) -> tuple[int, int]:
        lo = _band_lines(f, ra.frequency_hz, max(factor * ra.damping_ratio, _MIN_HALF_REL), cell)[0]
        hi = _band_lines(f, rb.frequency_hz, max(factor * rb.damping_ratio, _MIN_HALF_REL), cell)[1]
        return lo, hi

    lo, hi = band(BAND_FACTOR)
    fit = rational_fit(f[lo:hi], h[lo:hi], 2)
    if fit is None:
        return None
    poles = fit.modes()["frequency_hz"]
    if poles.size != 2 or not (f[lo] <= poles[0] < poles[1] <= f[hi - 1]):
        return None
    bands = [band(x) for x in BAND_FACTORS]
    out = [_mode_from(f, h, fit, float(p), bands) for p in poles]
    return None if any(m is None for m in out) else [m for m in out if m is not None]


def modal_fit(frequency_hz: FloatArray, h: ComplexArray, *, rel_prominence: float = 0.01,
              noise_sigmas: float = 4.0) -> ModalFit:
    """Natural frequencies, damping ratios and their uncertainties from a sampled FRF.

    See the module docstring for the procedure.

    Parameters
    ----------
    frequency_hz : numpy.ndarray, shape (nfreq,)
        Increasing grid, Hz.
    h : numpy.ndarray, shape (nfreq,), complex
        Receptance (e.g. a predicted tool-point ``h`` on a measured spindle), m/N.
    rel_prominence : float
        Least prominence of a candidate peak relative to ``max|h|``.
    noise_sigmas : float
        Least prominence of a peak in units of its local noise ``σ·|h_peak|``.

    Returns
    -------
    ModalFit

    Examples
    --------
    Two modes of 1 % damping at 500 and 800 Hz, with 2 % relative noise:

    >>> f = np.arange(300.0, 1000.0, 1.0)
    >>> w = 2 * np.pi * f
    >>> h = sum(1.0 / (wn**2 - w**2 + 2j * 0.01 * wn * w) for wn in 2 * np.pi * np.array([500.0, 800.0]))
    >>> rng = np.random.default_rng(1)
    >>> h = h * (1 + 0.02 * (rng.standard_normal(f.size) + 1j * rng.standard_normal(f.size)) / np.sqrt(2))
    >>> fit = modal_fit(f, h)
    >>> [round(m.frequency_hz) for m in fit.modes], all(m.sd_hz < 0.5 for m in fit.modes)
    ([500, 800], True)
    """
    f = np.asarray(frequency_hz, dtype=float)
    h = np.asarray(h, dtype=complex)
    empty = ModalFit((), np.empty(0, dtype=int), math.nan)
    if f.size < 2 * MIN_HALF_LINES + 1 or not np.all(np.abs(h) > 0):
        return empty
    kept, noise = _noise_gate(f, h, rel_prominence, noise_sigmas)
    noise_rel = float(np.median(noise)) if noise else math.nan
    settled = _settle_all(f, h, kept)
    found: list[tuple[FittedMode, int]] = []  # each mode and the highest peak line of its group
    k = 0
    while k < len(settled):
        r, cell, top = settled[k]
        if k + 1 < len(settled):
            r2 = settled[k + 1][0]
            overlap = r.frequency_hz * (1 + BAND_FACTOR * r.damping_ratio) > \
                r2.frequency_hz * (1 - BAND_FACTOR * r2.damping_ratio)
            pair = _close_pair(f, h, settled[k], settled[k + 1]) if overlap else None
            if pair is not None:
                found.extend(zip(pair, (top, settled[k + 1][2]), strict=True))
                k += 2
                continue
        bands = [_band_lines(f, r.frequency_hz, max(x * r.damping_ratio, _MIN_HALF_REL), cell)
                 for x in BAND_FACTORS]
        mode = _mode_from(f, h, r.fit, r.frequency_hz, bands)
        if mode is not None:
            found.append((mode, top))
        k += 1
    found = [(m, top) for m, top in sorted(found, key=lambda mt: mt[0].frequency_hz)
             if f[0] <= m.frequency_hz <= f[-1] and m.significance >= noise_sigmas]
    distinct: list[tuple[FittedMode, int]] = []
    for m, top in found:
        last = distinct[-1][0] if distinct else None
        together = last is not None and last.modes_in_band > 1 and last.band_hz == m.band_hz  # two poles of one fit
        if last is not None and not together and abs(m.frequency_hz - last.frequency_hz) < max(
                m.damping_ratio * m.frequency_hz, last.damping_ratio * last.frequency_hz):
            if m.sd_hz < last.sd_hz:
                distinct[-1] = (m, top if abs(h[top]) > abs(h[distinct[-1][1]]) else distinct[-1][1])
            continue
        distinct.append((m, top))
    return ModalFit(tuple(m for m, _ in distinct), np.asarray([top for _, top in distinct], dtype=int), noise_rel)


#: Modal fits :func:`kept_modal_fit` keeps per process (least recently used dropped; each is a few
#: hundred bytes: the modes and their peak lines).
FITS_KEPT = 512
_FITS: LruStore[bytes, ModalFit] = LruStore(FITS_KEPT)
_FITS_LOCK = threading.Lock()


def kept_modal_fit(frequency_hz: FloatArray, h: ComplexArray) -> ModalFit:
    """:func:`modal_fit` with the default thresholds, kept per process by the content of its inputs.

    The fit is a pure function of the grid and the samples, so one computed before for the
    same bytes (the same hybrid prediction asked again: a CAM system asking for its tools each
    time it opens a job) is the same result; it is found by a BLAKE2b digest of both arrays
    (a few tens of µs at 20 000 lines, against milliseconds for the fit) under rcsa's one
    eviction policy (:class:`rcsa.physics.subassembly_cache.LruStore`, :data:`FITS_KEPT`
    fits). The peak lines of a kept fit are read-only.

    Parameters
    ----------
    frequency_hz : numpy.ndarray, shape (nfreq,)
        Grid, Hz.
    h : numpy.ndarray, shape (nfreq,), complex
        Receptance, m/N.

    Returns
    -------
    ModalFit
    """
    f = np.ascontiguousarray(frequency_hz, dtype=float)
    hc = np.ascontiguousarray(h, dtype=complex)
    digest = hashlib.blake2b(f.tobytes(), digest_size=32)
    digest.update(hc.tobytes())
    key = digest.digest()
    with _FITS_LOCK:
        hit = _FITS.peek(key)
    if hit is not None:
        return hit
    fit = modal_fit(f, hc)
    fit.peak_lines.setflags(write=False)
    with _FITS_LOCK:
        _FITS.put(key, fit)
    return fit


def refit_mode(frequency_hz: FloatArray, h: ComplexArray, mode: FittedMode) -> FittedMode | None:
    """The same mode fitted again on the same band of another ``h`` (e.g. a perturbed model).

    The band's lines and the number of poles are those of ``mode``; the pole nearest its
    frequency is taken. Used to track modes across small perturbations (effect analysis):
    the band never moves, so the features are smooth functions of the model.

    Parameters
    ----------
    frequency_hz : numpy.ndarray, shape (nfreq,)
        Grid, Hz (containing ``mode.band_hz``).
    h : numpy.ndarray, shape (nfreq,), complex
        m/N.
    mode : FittedMode

    Returns
    -------
    FittedMode or None
        With ``sd_band_hz = 0`` (no band choices); None when no stable pole remains.
    """
    f = np.asarray(frequency_hz, dtype=float)
    lo = int(np.searchsorted(f, mode.band_hz[0] * (1 - 1e-12)))
    hi = int(np.searchsorted(f, mode.band_hz[1] * (1 + 1e-12), side="right"))
    fit = rational_fit(f[lo:hi], np.asarray(h, dtype=complex)[lo:hi], mode.modes_in_band)
    return None if fit is None else _mode_from(f, h, fit, mode.frequency_hz, [])
