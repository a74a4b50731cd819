"""Modal models of the tool point in x and y, for time-domain stability analyses.

A time-domain method (:mod:`.semi_discretization`) needs the tool point as a set of modes,
not as a sampled FRF. Each mode ``r`` acts in one direction (x = feed, y = normal; cross
terms are not modelled) and contributes

    h(ω) = R_r / (ω_r² − ω² + 2i ζ_r ω_r ω)        (m/N, exp(iωt) convention)

to that direction's direct receptance: a real (proportionally damped) mode with residue
``R_r = φ_r² = 1/m_r`` (1/kg), modal stiffness ``k_r = ω_r²/R_r``.

Three sources:

* :func:`modal_model_from_table` — a modal table per direction (natural frequency, damping
  ratio, modal mass or modal stiffness), as CutPro and MetalMAX users have them from a modal fit
  of their own tap tests.

* :func:`modal_model_from_assembly` — an analytical assembly: its exact undamped natural
  frequencies (Wittrick–Williams), the exact undamped tip residue of each mode and the
  damping ratio of a single-mode fit to the damped tool-point FRF around the peak
  (:func:`rcsa.analysis.effects.mode_features.mode_features`). Axisymmetric: the same modes in y.
* :func:`fit_modal_model` — inline FRFs: the peaks of ``|h|`` give starting values
  (single-mode Levy fits, :func:`rcsa.model.peaks.single_mode_fit`), then all modes are
  fitted together by nonlinear least squares on the complex FRF near the peaks, with the
  residues (and a lower and an upper residual term for the modes outside the band) solved
  linearly inside (variable projection). Modes with a non-positive residue are dropped.

Either way the result carries its fit quality: the relative RMS misfit of the modal sum
(without residual terms: exactly what the time-domain model uses) against the FRF over the
windows around the peaks, and the relative misfit at each mode's peak.

References
----------
.. [1] D. J. Ewins, *Modal Testing: Theory, Practice and Application*, 2nd ed., Research
   Studies Press, 2000, §4.3–4.4 (residues, residual terms, multi-mode curve fitting).
.. [2] G. H. Golub, V. Pereyra, "The differentiation of pseudo-inverses and nonlinear least
   squares problems whose variables separate", SIAM J. Numer. Anal. 10:413–432, 1973.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from rcsa.analysis.effects.mode_features import mode_features
from rcsa.errors import InputError
from rcsa.model.assembly import build_model
from rcsa.model.contract import AssemblySpec, SpindleSpec
from rcsa.model.peaks import find_frf_peaks, single_mode_fit
from rcsa.physics.algebra2x2 import inv2
from rcsa.physics.elimination import march
from rcsa.physics.natural_frequencies import natural_frequencies_hz

__all__ = [
    "DEFAULT_MODES_PER_DIRECTION",
    "MAX_MODES_PER_DIRECTION",
    "MIN_PEAK_FRACTION",
    "kept_peaks_hz",
    "ModalModel",
    "fit_modal_model",
    "modal_model_from_assembly",
    "modal_model_from_table",
]

#: Modes per direction kept (the most flexible ones above ``MIN_PEAK_FRACTION``), at most; by
#: default every one up to this bound (a mode left out moved limits by −32 %…+60 % on a published
#: five-mode table: docs/lobes.md "Modes").
MAX_MODES_PER_DIRECTION = 8
DEFAULT_MODES_PER_DIRECTION = MAX_MODES_PER_DIRECTION
#: Modes whose peak ``|h|`` is below this fraction of the largest are left out.
MIN_PEAK_FRACTION = 0.05

_TWO_PI = 2.0 * np.pi
_DIRECTIONS = ("x", "y")
# Fit windows: ± this many damping ratios around a peak (relative), within these bounds, and
# at least this many grid lines on each side.
_WINDOW_ZETAS = 4.0
_WINDOW_MIN_REL, _WINDOW_MAX_REL = 0.01, 0.15
_WINDOW_MIN_LINES = 4
_START_HALF_LINES = 6
_DENSE_WINDOW_LINES = 61


@dataclass(frozen=True)
class ModalModel:
    """Real modes of the tool point, arrays of shape (nmodes,).

    Attributes
    ----------
    frequency_hz : numpy.ndarray
        Undamped natural frequencies ``ω_r/2π``, Hz (> 0).
    damping_ratio : numpy.ndarray
        ``ζ_r`` in (0, 1).
    residue_1_kg : numpy.ndarray
        ``R_r = 1/m_r`` (> 0), 1/kg.
    direction : numpy.ndarray of int
        0 = x (feed), 1 = y (normal).
    source : str
        ``"given"``, ``"fit"`` (inline FRFs) or ``"exact_modes"`` (analytical assembly).
    same_in_y : bool
        The y modes copy the x modes (no y receptance given, or an axisymmetric assembly).
    relative_rms_error : numpy.ndarray, shape (2,)
        Misfit ``‖Σ modes − h‖/‖h‖`` over the peak windows, per direction (NaN: not checked).
    peak_relative_error : numpy.ndarray
        ``|Σ modes − h|/|h|`` at each mode's peak (NaN: not checked).
    omitted : tuple of (int, float, float)
        Modes (or FRF peaks) left out: ``(direction, frequency_hz, peak / largest peak)``
        (the fraction is NaN for a mode without a peak at the tool point).

    Examples
    --------
    >>> m = ModalModel.of([922.0], [0.011], [1 / 0.03993], [0])
    >>> round(float(abs(m.receptance(np.array([922.0]), 0)[0])) * 1e6, 2)  # µm/N
    33.92
    """

    frequency_hz: np.ndarray
    damping_ratio: np.ndarray
    residue_1_kg: np.ndarray
    direction: np.ndarray
    source: str = "given"
    same_in_y: bool = False
    relative_rms_error: np.ndarray = field(default_factory=lambda: np.full(2, np.nan))
    peak_relative_error: np.ndarray | None = None
    omitted: tuple[tuple[int, float, float], ...] = ()

    def __post_init__(self) -> None:
        for name, dtype in (("frequency_hz", float), ("damping_ratio", float), ("residue_1_kg", float),
                            ("direction", np.int64), ("relative_rms_error", float)):
            object.__setattr__(self, name, np.array(getattr(self, name), dtype=dtype))  # own copies
        n = self.frequency_hz.shape
        if len(n) != 1 or n[0] == 0:
            raise InputError("modal_model", "needs at least one mode")
        checks = (
            ("frequency_hz", self.frequency_hz, lambda a: a > 0, "> 0"),
            ("damping_ratio", self.damping_ratio, lambda a: (a > 0) & (a < 1), "in (0, 1)"),
            ("residue_1_kg", self.residue_1_kg, lambda a: a > 0, "> 0"),
            ("direction", self.direction, lambda a: (a == 0) | (a == 1), "0 (x) or 1 (y)"),
        )
        for name, arr, rule, text in checks:
            if arr.shape != n or not np.all(np.isfinite(arr)) or not np.all(rule(arr)):
                raise InputError(f"modal_model.{name}", f"one finite value {text} per mode")
        peak = np.full(n, np.nan) if self.peak_relative_error is None else self.peak_relative_error
        object.__setattr__(self, "peak_relative_error", np.array(peak, dtype=float))
        for name in ("frequency_hz", "damping_ratio", "residue_1_kg", "direction",
                     "relative_rms_error", "peak_relative_error"):
            getattr(self, name).flags.writeable = False

    @classmethod
    def of(cls, frequency_hz: Any, damping_ratio: Any, residue_1_kg: Any, direction: Any,
           **kwargs: Any) -> ModalModel:
        """Build from sequences (the model keeps read-only copies, as the constructor does)."""
        return cls(frequency_hz, damping_ratio, residue_1_kg, direction, **kwargs)

    @property
    def n_modes(self) -> int:
        """Number of modes (both directions)."""
        return int(self.frequency_hz.size)

    def frf_grid(self) -> np.ndarray:
        """A frequency grid (Hz) that resolves every mode: 2 000 lines from half the lowest to twice
        the highest natural frequency, and 400 lines across ``0.8–1.25 ×`` each."""
        fn = np.asarray(self.frequency_hz, dtype=float)
        return np.unique(np.concatenate([np.geomspace(0.5 * fn.min(), 2.0 * fn.max(), 2000)]
                                        + [f * np.linspace(0.8, 1.25, 400) for f in fn]))

    def receptance(self, frequency_hz: np.ndarray, direction: int) -> np.ndarray:
        """Direct receptance of one direction, m/N, shape (nfreq,) (zero without modes)."""
        w = _TWO_PI * np.asarray(frequency_hz, dtype=float)[:, None]
        sel = self.direction == direction
        wn = _TWO_PI * self.frequency_hz[sel]
        den = wn**2 - w**2 + 2j * self.damping_ratio[sel] * wn * w
        return np.asarray((self.residue_1_kg[sel] / den).sum(axis=1), dtype=complex)

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready description: source, modes (with modal mass and stiffness), fit quality."""
        def num(x: float) -> float | None:
            return float(x) if math.isfinite(x) else None

        w = _TWO_PI * self.frequency_hz
        assert self.peak_relative_error is not None
        modes = [
            {"direction": _DIRECTIONS[int(d)], "frequency_hz": float(f), "damping_ratio": float(z),
             "residue_1_kg": float(r), "modal_mass_kg": float(1.0 / r), "stiffness_n_m": float(wi**2 / r),
             "peak_relative_error": num(float(e))}
            for d, f, z, r, wi, e in zip(self.direction, self.frequency_hz, self.damping_ratio,
                                         self.residue_1_kg, w, self.peak_relative_error, strict=True)
        ]
        omitted = [{"direction": _DIRECTIONS[d], "frequency_hz": float(f), "peak_fraction": num(p)}
                   for d, f, p in self.omitted]
        return {"source": self.source, "same_in_y": self.same_in_y, "modes": modes,
                "relative_rms_error": {d: num(float(e)) for d, e in zip(_DIRECTIONS, self.relative_rms_error,
                                                                         strict=True)},
                "omitted_modes": omitted}

    def notes(self) -> list[str]:
        """Plain-language notes: every mode (or FRF peak) left out, with its share of the largest peak.

        Modes without a peak at the tool point (an assembly's modes the tool point does not take
        part in) are listed in :meth:`to_dict` only; a mode left out in x and y alike is named once.
        """
        seen: dict[tuple[float, float], list[str]] = {}
        for d, f, share in self.omitted:
            if math.isfinite(share):
                seen.setdefault((round(f, 3), round(share, 6)), []).append(_DIRECTIONS[d])
        return [f"mode at {f:.0f} Hz in {' and '.join(dirs)} left out ({share:.0%} of the largest peak: "
                + (f"below the {MIN_PEAK_FRACTION:.0%} threshold)" if share < MIN_PEAK_FRACTION
                   else "beyond modes_per_direction)")
                for (f, share), dirs in seen.items()]

    def with_quality(self, frequency_hz: np.ndarray, h_by_direction: tuple[np.ndarray | None, np.ndarray | None]
                     ) -> ModalModel:
        """The same modes with their misfit against measured/predicted FRFs (see class)."""
        f = np.asarray(frequency_hz, dtype=float)
        rms = np.full(2, np.nan)
        peak_err = np.full(self.n_modes, np.nan)
        for d, h in enumerate(h_by_direction):
            sel = np.flatnonzero(self.direction == d)
            if h is None or sel.size == 0:
                continue
            windows = _windows(f, self.frequency_hz[sel], self.damping_ratio[sel])
            model_h = self.receptance(f, d)
            mask = windows.any(axis=0)
            rms[d] = float(np.linalg.norm(model_h[mask] - h[mask]) / np.linalg.norm(h[mask]))
            for r, win in zip(sel, windows, strict=True):  # a loop over modes
                i = np.flatnonzero(win)[np.argmax(np.abs(h[win]))]
                peak_err[r] = float(abs(model_h[i] - h[i]) / abs(h[i]))
        return ModalModel(self.frequency_hz, self.damping_ratio, self.residue_1_kg, self.direction,
                          self.source, self.same_in_y, rms, peak_err, self.omitted)


def _windows(f: np.ndarray, fn: np.ndarray, zeta: np.ndarray) -> np.ndarray:
    """Boolean masks (nmodes, nfreq) of the fit window around each mode."""
    rel = np.clip(_WINDOW_ZETAS * zeta, _WINDOW_MIN_REL, _WINDOW_MAX_REL)
    mask = np.abs(f[None, :] / fn[:, None] - 1.0) <= rel[:, None]
    centre = np.searchsorted(f, fn)
    lines = np.arange(f.size)[None, :]
    mask |= np.abs(lines - centre[:, None]) <= _WINDOW_MIN_LINES
    return mask


def _select_peaks(f: np.ndarray, h: np.ndarray, max_modes: int) -> tuple[list[float], list[tuple[float, float]]]:
    """Frequencies of the largest peaks of ``|h|`` to fit, and the others with their size."""
    peaks = find_frf_peaks(f, h)
    if not peaks:
        return [], []
    top = max(p["magnitude_m_n"] for p in peaks)
    ranked = sorted(peaks, key=lambda p: -p["magnitude_m_n"])
    keep = [p for p in ranked if p["magnitude_m_n"] >= MIN_PEAK_FRACTION * top][:max_modes]
    left = [(p["frequency_hz"], p["magnitude_m_n"] / top) for p in ranked if p not in keep]
    return sorted(p["frequency_hz"] for p in keep), sorted(left)


def kept_peaks_hz(frequency_hz: np.ndarray, h: np.ndarray, modes_per_direction: int) -> list[float]:
    """The FRF peaks a fit keeps, Hz, ascending: the largest ``modes_per_direction`` of ``|h|`` at
    or above ``MIN_PEAK_FRACTION`` of the largest (what :func:`fit_modal_model` fits; found without
    fitting, for a cost estimate).

    Parameters
    ----------
    frequency_hz : numpy.ndarray, shape (nfreq,)
        Grid, Hz.
    h : numpy.ndarray, shape (nfreq,), complex
        Direct receptance, m/N.
    modes_per_direction : int
        At most this many peaks.

    Returns
    -------
    list of float
    """
    return _select_peaks(np.asarray(frequency_hz, dtype=float), np.asarray(h), modes_per_direction)[0]


def _start(f: np.ndarray, h: np.ndarray, peak_hz: float) -> tuple[float, float]:
    """Natural frequency (Hz) and damping ratio of a single-mode Levy fit at a peak."""
    i = int(np.searchsorted(f, peak_hz))
    lo, hi = max(0, i - _START_HALF_LINES), min(f.size, i + _START_HALF_LINES + 1)
    fit = single_mode_fit(f[lo:hi], h[lo:hi]) if hi - lo >= 5 else None
    if fit is not None:
        (a0, a1, *_), scale = fit
        fn, zeta = math.sqrt(a0) * scale / _TWO_PI, a1 / (2.0 * math.sqrt(a0))
        if abs(fn / peak_hz - 1.0) < 0.1 and 0.0 < zeta < 0.5:
            return fn, zeta
    return peak_hz, 0.02


def _linear_part(w: np.ndarray, h: np.ndarray, wn: np.ndarray, zeta: np.ndarray
                 ) -> tuple[np.ndarray, np.ndarray]:
    """Real residues and residual terms for fixed poles; returns (coefficients, residual)."""
    cols = 1.0 / (wn[None, :] ** 2 - w[:, None] ** 2 + 2j * zeta[None, :] * wn[None, :] * w[:, None])
    cols = np.concatenate([cols, -1.0 / w[:, None] ** 2 + 0j, np.ones((w.size, 1), dtype=complex)], axis=1)
    a = np.concatenate([cols.real, cols.imag])
    b = np.concatenate([h.real, h.imag])
    scale = np.linalg.norm(a, axis=0)
    scale[scale == 0] = 1.0
    coef = np.linalg.lstsq(a / scale, b, rcond=None)[0] / scale
    return coef, a @ coef - b


def _fit_modes(f: np.ndarray, h: np.ndarray, starts: list[tuple[float, float]]
               ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Fit modes from starting ``(f_n, ζ)`` pairs: natural frequencies (Hz), ζ, residues (1/kg).

    Variable projection: ``least_squares`` over ``(ln ω_r, ln ζ_r)`` (ω within −20 %/+25 % of
    its start), residues and residual terms solved linearly for every trial; modes whose
    residue comes out non-positive are dropped and the rest refitted.
    """
    from scipy.optimize import least_squares  # local: keeps `import rcsa` light

    while starts:
        fn0 = np.array([s[0] for s in starts])
        z0 = np.array([s[1] for s in starts])
        mask = _windows(f, fn0, z0).any(axis=0)
        w, hw = _TWO_PI * f[mask], h[mask]
        norm = float(np.linalg.norm(hw))
        m = fn0.size

        def residual(x: np.ndarray, w: np.ndarray = w, hw: np.ndarray = hw, m: int = m,
                     norm: float = norm) -> np.ndarray:
            return _linear_part(w, hw, np.exp(x[:m]), np.exp(x[m:]))[1] / norm

        x0 = np.concatenate([np.log(_TWO_PI * fn0), np.log(z0)])
        lo = np.concatenate([x0[:m] + math.log(0.8), np.full(m, math.log(1e-4))])
        hi = np.concatenate([x0[:m] + math.log(1.25), np.full(m, math.log(0.5))])
        x = least_squares(residual, np.clip(x0, lo, hi), bounds=(lo, hi), x_scale="jac").x
        wn, zeta = np.exp(x[:m]), np.exp(x[m:])
        residues = _linear_part(w, hw, wn, zeta)[0][:m]
        good = residues > 0.0
        if good.all():
            order = np.argsort(wn)
            return wn[order] / _TWO_PI, zeta[order], residues[order]
        starts = [s for s, g in zip(starts, good, strict=True) if g]
    return np.empty(0), np.empty(0), np.empty(0)


def _fit_direction(f: np.ndarray, h: np.ndarray, max_modes: int
                   ) -> tuple[tuple[np.ndarray, np.ndarray, np.ndarray], list[tuple[float, float]]]:
    """Modes of one direct FRF, started from its largest peaks; the peaks left out."""
    keep, left = _select_peaks(f, h, max_modes)
    return _fit_modes(f, h, [_start(f, h, p) for p in keep]), left


def fit_modal_model(frequency_hz: np.ndarray, frf_xx: np.ndarray, frf_yy: np.ndarray | None = None, *,
                    modes_per_direction: int = DEFAULT_MODES_PER_DIRECTION) -> ModalModel:
    """Fit real modes to the direct tool-point receptances in x and (optionally) y.

    Parameters
    ----------
    frequency_hz : numpy.ndarray, shape (nfreq,)
        Validated grid, Hz.
    frf_xx : numpy.ndarray, shape (nfreq,), complex
        Receptance in x, m/N (``exp(iωt)``: ``Im <= 0`` at peaks).
    frf_yy : numpy.ndarray, shape (nfreq,), complex, optional
        Receptance in y; ``None``: the x modes are used in y (``same_in_y``). An FRF without
        any peak (e.g. all zeros: rigid in y) gives no y modes.
    modes_per_direction : int
        At most this many modes per direction: the largest peaks of ``|h|`` (those below
        ``MIN_PEAK_FRACTION`` of the largest are left out).

    Returns
    -------
    ModalModel
        ``source="fit"``, with its fit quality.

    Raises
    ------
    InputError
        ``frf_x`` has no resonance peak that fits a stable mode.

    Examples
    --------
    Two modes are recovered from their own FRF:

    >>> f = np.arange(200.0, 3000.0, 2.0)
    >>> true = ModalModel.of([700.0, 1800.0], [0.03, 0.02], [0.5, 2.0], [0, 0])
    >>> fit = fit_modal_model(f, true.receptance(f, 0), modes_per_direction=2)
    >>> np.round(fit.frequency_hz[:2], 3).tolist(), fit.same_in_y
    ([700.0, 1800.0], True)
    >>> bool(fit.relative_rms_error[0] < 1e-6)
    True
    """
    f = np.asarray(frequency_hz, dtype=float)
    fx, left_x = _fit_direction(f, np.asarray(frf_xx), modes_per_direction)
    if fx[0].size == 0:
        raise InputError("frf_x", "no resonance peak of |h| could be fitted by a stable mode with a "
                                  "positive residue (a time-domain method needs the modes)")
    same = frf_yy is None
    fy, left_y = (fx, left_x) if same else _fit_direction(f, np.asarray(frf_yy), modes_per_direction)
    omitted = tuple((0, fo, p) for fo, p in left_x) + tuple((1, fo, p) for fo, p in left_y)
    model = ModalModel(
        np.concatenate([fx[0], fy[0]]), np.concatenate([fx[1], fy[1]]), np.concatenate([fx[2], fy[2]]),
        np.concatenate([np.zeros(fx[0].size, dtype=np.int64), np.ones(fy[0].size, dtype=np.int64)]),
        source="fit", same_in_y=same, omitted=omitted)
    return model.with_quality(f, (np.asarray(frf_xx), np.asarray(frf_xx) if same else np.asarray(frf_yy)))


def modal_model_from_assembly(spec: AssemblySpec, *, modes_per_direction: int = DEFAULT_MODES_PER_DIRECTION,
                              frequency_hz: np.ndarray | None = None, h: np.ndarray | None = None
                              ) -> ModalModel:
    """Modes of an analytical assembly in its frequency band, the same in x and y.

    The exact modes choose and seed the model: natural frequencies are exact (Wittrick–
    Williams), and the ``modes_per_direction`` modes with the largest damped tool-point peaks
    are kept (none below ``MIN_PEAK_FRACTION`` of the largest; modes hidden at the tool point
    are left out), started from their damping ratio and exact undamped tip residue
    (:func:`rcsa.analysis.effects.mode_features.mode_features`). Joint and bearing damping are not
    proportional, so the damped peaks sit slightly off the undamped frequencies (RA-1: up to
    0.2 %, i.e. a 4–14 % misfit at the peaks); the kept modes are therefore refined together,
    as in :func:`fit_modal_model`, against the exact damped FRF of the chain on dense grids
    around each mode (61 lines per window), which the modal sum then matches to about 1 %.

    Parameters
    ----------
    spec : AssemblySpec
        An analytical assembly (a measured spindle has no exact modes: fit its predicted FRF
        with :func:`fit_modal_model` instead).
    modes_per_direction : int
    frequency_hz, h : numpy.ndarray, shape (nfreq,), optional
        The predicted tool-point receptance, to report the fit quality against.

    Returns
    -------
    ModalModel
        ``source="exact_modes"``, ``same_in_y=True``.

    Examples
    --------
    >>> from rcsa.model.contract import parse_assembly
    >>> from rcsa.reference import ra1
    >>> spec = parse_assembly(ra1({"start_hz": 200.0, "stop_hz": 3000.0, "step_hz": 2.0}))
    >>> m = modal_model_from_assembly(spec, modes_per_direction=2)
    >>> m.source, m.n_modes, m.same_in_y
    ('exact_modes', 4, True)
    """
    if not isinstance(spec.spindle, SpindleSpec):
        raise InputError("assembly.spindle", "a measured spindle has no exact modes: fit the predicted FRF")
    chain = build_model(spec).chain()
    band = float(spec.frequency_hz[0]), float(spec.frequency_hz[-1])
    neighbours = natural_frequencies_hz(chain, band[0] / 1.12, band[1] * 1.12)
    fn = neighbours[(neighbours >= band[0]) & (neighbours <= band[1])]
    if fn.size == 0:
        raise InputError("assembly.frequency", "no natural frequency in the band: widen it to include "
                                               "the modes that can chatter")
    feats = mode_features(chain, fn, neighbours_hz=neighbours)
    peak = feats.peak_magnitude_m_n
    usable = np.flatnonzero(np.isfinite(peak) & np.isfinite(feats.damping_ratio) & (feats.damping_ratio > 0))
    if usable.size == 0:
        raise InputError("assembly", "no mode shows a peak at the tool point in the band")
    usable = usable[peak[usable] >= MIN_PEAK_FRACTION * peak[usable].max()]
    keep = np.sort(usable[np.argsort(-peak[usable])][:modes_per_direction])
    top = float(np.nanmax(peak[keep]))
    left = [(float(feats.frequency_hz[i]), float(peak[i] / top)) for i in range(fn.size) if i not in set(keep)]
    omitted = tuple((d, f, p) for d in (0, 1) for f, p in left)
    z0 = np.clip(feats.damping_ratio[keep], 1e-4, 0.5)
    rel = np.clip(_WINDOW_ZETAS * z0, _WINDOW_MIN_REL, _WINDOW_MAX_REL)
    dense = np.unique(np.concatenate([f * np.linspace(1 - r, 1 + r, _DENSE_WINDOW_LINES)
                                      for f, r in zip(feats.frequency_hz[keep], rel, strict=True)]))
    h_dense = inv2(march(chain, _TWO_PI * dense)[0])[:, 0, 0]
    f_k, z_k, r_k = _fit_modes(dense, h_dense, list(zip(feats.frequency_hz[keep], z0, strict=True)))
    if f_k.size == 0:
        raise InputError("assembly", "the tool-point modes could not be fitted with positive residues")
    model = ModalModel(np.concatenate([f_k, f_k]), np.concatenate([z_k, z_k]), np.concatenate([r_k, r_k]),
                       np.repeat(np.array([0, 1], dtype=np.int64), f_k.size), source="exact_modes",
                       same_in_y=True, omitted=omitted)
    if frequency_hz is None or h is None:
        return model
    return model.with_quality(np.asarray(frequency_hz, dtype=float), (np.asarray(h), np.asarray(h)))


def modal_model_from_table(modes_x: Sequence[tuple[float, float, float]],
                           modes_y: Sequence[tuple[float, float, float]] | None = None, *,
                           modes_per_direction: int = DEFAULT_MODES_PER_DIRECTION) -> ModalModel:
    """Modes given as a table per direction: ``(frequency_hz, damping_ratio, modal_mass_kg)`` rows.

    The rows are taken as they are (natural frequency ``f``, damping ratio ``ζ``, modal mass
    ``m``: residue ``1/m``; a modal stiffness ``k`` is the mass ``k/(2πf)²``). Modes whose peak
    ``|h(ω_r)| ≈ 1/(2ζ k)`` is below ``MIN_PEAK_FRACTION`` of the largest of their direction, and
    those beyond the ``modes_per_direction`` largest, are left out and listed (``omitted``).

    Parameters
    ----------
    modes_x : sequence of (float, float, float)
        The feed direction's modes.
    modes_y : sequence of (float, float, float), optional
        The normal direction's; None: the same as x (``same_in_y``); empty: rigid in y.
    modes_per_direction : int

    Returns
    -------
    ModalModel
        ``source="given"``.

    Examples
    --------
    Mode 1 of a published table (Ji & Liu 2024, 35 mm overhang, x):

    >>> m = modal_model_from_table([(565.1, 0.0322, 0.1966)])
    >>> m.source, m.same_in_y, round(float(m.residue_1_kg[0]), 3), m.n_modes
    ('given', True, 5.086, 2)
    """
    def pick(rows: Sequence[tuple[float, float, float]], d: int) -> tuple[list[tuple[float, float, float]],
                                                                           list[tuple[int, float, float]]]:
        if not rows:
            return [], []
        f = np.array([r[0] for r in rows], dtype=float)
        z = np.array([r[1] for r in rows], dtype=float)
        mass = np.array([r[2] for r in rows], dtype=float)
        peak = 1.0 / (2.0 * z * mass * (_TWO_PI * f) ** 2)
        top = float(peak.max())
        ranked = np.argsort(-peak, kind="stable")
        keep = [int(i) for i in ranked if peak[i] >= MIN_PEAK_FRACTION * top][:modes_per_direction]
        left = [(d, float(f[i]), float(peak[i] / top)) for i in range(f.size) if i not in keep]
        return [rows[i] for i in sorted(keep, key=lambda i: f[i])], sorted(left, key=lambda x: x[1])

    kept_x, left_x = pick(modes_x, 0)
    if not kept_x:
        raise InputError("modal_x", "give at least one mode of the feed direction")
    same = modes_y is None
    kept_y, left_y = (kept_x, [(1, f, p) for _, f, p in left_x]) if same else pick(modes_y or [], 1)
    rows = kept_x + kept_y
    return ModalModel(np.array([r[0] for r in rows]), np.array([r[1] for r in rows]),
                      np.array([1.0 / r[2] for r in rows]),
                      np.array([0] * len(kept_x) + [1] * len(kept_y), dtype=np.int64), source="given",
                      same_in_y=same, omitted=tuple(left_x) + tuple(left_y))
