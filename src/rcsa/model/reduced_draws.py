"""A reduced model of an uncertainty band's draws: each draw solved at a few lines, fitted rationally.

The draws of an uncertainty band (:mod:`rcsa.model.draws`) change every segment's modulus,
density and loss factor and every joint and bearing, so no part of the chain is shared
between draws; solving each one exactly on every line costs one full prediction per draw.
A parameter-space expansion about the nominal (modal sensitivities, a Taylor or Padé series
of the receptance in the drawn knobs) does not hold up on real assemblies: on RA-1 the
holder–tool joint's tolerance sweeps the tool mode over ±11 % (seven half-power bandwidths
each way) and through a spindle mode, where the two veer; such expansions were 16–60 % off
the full draws' quantiles (measured while choosing this model; ``benchmarks/bench_uncertainty.py``
prints this model's own error).

Each draw's receptance is instead a rational function of frequency with the same structure
as the nominal one — a resonance per mode plus a smooth background — whose poles move with
the draw. The reduced model:

1. **Nominal structure.** The nominal ``h`` (exact, every line) is fitted by vector fitting
   (:func:`rcsa.model.vector_fitting.vector_fit`) with the exact undamped natural frequencies
   as starting poles; the poles it shows (a visible resonance) are kept, and everything else
   — far modes, the fit's own residual — is the nominal background ``B(ω) = h₀ − Σ A/(ω − p)``.
2. **Sample lines.** Each mode can move, over the drawn knobs, within the bound of the
   min–max theorem: every undamped natural frequency scales by at least ``√(min s_k / max
   s_m)`` and at most ``√(max s_k / min s_m)`` when every stiffness is scaled by some
   ``s_k`` and every mass by some ``s_m`` (:func:`frequency_ratio_bounds`). Around every
   visible pole, over that range widened by two half-power half-widths, lines are taken every
   :data:`LINE_SPACING_HALF_WIDTHS` half-widths, plus lines spread over the band
   (:data:`BACKGROUND_LINES`, :data:`BACKGROUND_RATIO`); a few more lines between them are
   kept aside as checks.
3. **Exact solves at those lines** for every draw, in one stacked march.
4. **One rational fit per draw** of ``h_d − B`` on its sample lines, starting from the
   nominal poles (vector fitting relocates them to the draw's own: a shifted mode, a veering
   pair), all draws in one batched least-squares problem per iteration.
5. **Checks.** Each draw's model is compared with its exact values at the check lines it
   was not fitted to; a draw whose |h| there is off by more than :data:`CHECK_TOLERANCE`
   (relative) is solved exactly on every line instead.

Readable form (the code is its vectorised equivalent)::

    for d in draws:
        exact = h_draw(d, lines)                       # exact at ~2.5 % of the lines
        fit = vector_fit(lines, exact − B(lines), nominal_poles)
        h[d] = B + fit(every line)
        if error(fit, h_draw(d, check_lines)) > CHECK_TOLERANCE:
            h[d] = h_draw(d, every line)

The error bound is a posteriori: the check lines measure each draw's interpolation error
where it is largest (between sample lines, within the modes' ranges), and the quantiles of
draws that are each within ε of the exact ones are within ε of the exact quantiles (order
statistics are 1-Lipschitz). The suite compares the band with the full draws on RA-1 and on
a library of tools (``tests/model/test_reduced_draws.py``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rcsa.model.draw_chains import DrawGroup, DrawnChains
from rcsa.model.draws import (
    ModeStatistics,
    order_statistics,
    tool_point_h_draws,
    tool_point_h_pairs,
)
from rcsa.model.tolerances import NuisanceDraws
from rcsa.model.vector_fitting import RationalFit, vector_fit
from rcsa.physics.arrays import ComplexArray, FloatArray, IntArray
from rcsa.physics.seeded_modes import natural_frequencies_near
from rcsa.physics.stacking import take_rows

__all__ = ["ADDED_POLES", "BACKGROUND_LINES", "BACKGROUND_RATIO", "CALIBRATION_DRAWS", "CHECK_TOLERANCE",
           "ESTIMATE_TOLERANCE", "EXTRA_POLES", "HELD_OUT_DRAWS", "HELD_OUT_FACTOR",
           "LINE_SPACING_HALF_WIDTHS", "MASS_KNOBS", "NATURAL_FREQUENCY_RTOL", "NOMINAL_FIT_TARGET",
           "NOMINAL_FIT_TOLERANCE", "OUTLIER_FACTOR", "REFIT_TOLERANCE", "REGRESSION_KNOBS", "RESIDUE_FACTOR",
           "STIFFNESS_KNOBS", "TRACKED_HALF_WIDTH", "NominalStructure", "ReducedDraws", "antiresonances",
           "frequency_ratio_bounds", "match_poles", "nominal_structure", "reduced_draws",
           "reduced_mode_statistics", "sample_lines"]

#: Spacing of the sample lines over a mode's range, in its half-power half-widths (the draw's
#: own rational fit carries the accuracy between them: on RA-1 at 2 000 lines and 200 draws
#: this spacing keeps the band within 0.4 % of the full draws', ``bench_uncertainty.py``).
LINE_SPACING_HALF_WIDTHS = 8.0
#: Lines spread geometrically over the band besides the modes' ranges: this many below half
#: the lowest resonance, and a ratio of ``BACKGROUND_RATIO`` between neighbours above.
BACKGROUND_LINES, BACKGROUND_RATIO = 6, 1.35
#: Check lines kept aside per draw.
CHECK_LINES = 4
#: Largest error of the nominal fit (all its poles), relative to the nominal peak, for the
#: reduced model to be used (measured: 1e-4 on RA-1).
NOMINAL_FIT_TOLERANCE = 1e-2
#: Error of the nominal fit below which no pole is added, relative to the peak, and the most
#: poles added (:func:`nominal_structure`).
NOMINAL_FIT_TARGET, ADDED_POLES = 3e-4, 4
#: Check error above which a draw's fit gets one more pole relocation (from its own poles).
REFIT_TOLERANCE = 1e-3
#: Largest check error of a draw's model — the relative error of its |h| at a check line —
#: before the draw is solved exactly on every line (the band's target is 2 %).
CHECK_TOLERANCE = 1e-2
#: A pole is visible when its resonance peak ``|A| / Im p`` reaches this fraction of the
#: nominal peak (weaker ones stay in the nominal background).
VISIBLE_FRACTION = 0.0
#: Starting damping ratio of the nominal fit's poles.
START_DAMPING = 0.02
#: Starting poles added to each draw's fit, relative to the band's top (rad/s): broad ones above
#: the band, free to take up how the draw's background departs from the nominal one.
EXTRA_POLES = np.array([1.3 + 0.3j, 2.0 + 0.6j])
#: Vector-fitting iterations: the nominal fit, each draw's fit.
NOMINAL_ITERATIONS, DRAW_ITERATIONS = 6, 1
#: Degree of the polynomial background of the fits.
BACKGROUND_DEGREE = 3

#: Knobs that scale a stiffness (:data:`rcsa.model.tolerances.SHARED_KNOBS` and
#: ``PER_CONFIG_KNOBS``): E (and G) of the materials, bearings, joints.
STIFFNESS_KNOBS = ("tool_youngs_scale", "structure_youngs_scale", "bearing_stiffness_scale",
                   "sh_translational_scale", "sh_rotational_scale", "ht_translational_scale",
                   "ht_rotational_scale")
#: Knobs that scale a mass (densities).
MASS_KNOBS = ("tool_density_scale", "structure_density_scale")

_TWO_PI = 2.0 * np.pi


def frequency_ratio_bounds(knobs: NuisanceDraws, stickout_m: float) -> tuple[FloatArray, FloatArray]:
    """Bounds on how far each draw's undamped natural frequencies move from the nominal ones.

    By the min–max theorem a structure whose stiffness contributions are each scaled by some
    ``s_k`` and whose mass contributions by some ``s_m`` has every eigenvalue ω² within
    ``[min s_k / max s_m, max s_k / min s_m]`` times the nominal one. A stickout moved by δ
    changes the tool's overhang; its frequencies scale at most like those of a cantilever,
    ``(L / (L ± |δ|))²``.

    Parameters
    ----------
    knobs : NuisanceDraws
        The draws' knobs (configuration 0).
    stickout_m : float
        The nominal stickout, m.

    Returns
    -------
    low, high : numpy.ndarray, shape (ndraws,)
        Ratios of a drawn to the nominal natural frequency: each draw's lie within.

    Examples
    --------
    >>> import numpy as np
    >>> from types import MappingProxyType
    >>> ones = np.ones((2, 1))
    >>> values = {k: ones for k in (*STIFFNESS_KNOBS, *MASS_KNOBS)}
    >>> values["ht_translational_scale"] = np.array([[0.64], [1.44]])
    >>> values["stickout_offset_m"] = np.zeros((2, 1))
    >>> low, high = frequency_ratio_bounds(NuisanceDraws(MappingProxyType(values)), 0.05)
    >>> low.tolist(), high.tolist()
    ([0.8, 1.0], [1.0, 1.2])
    """
    v = knobs.values
    k = np.stack([v[n][:, 0] for n in STIFFNESS_KNOBS if n in v], axis=1)
    m = np.stack([v[n][:, 0] for n in MASS_KNOBS if n in v], axis=1)
    offset = np.abs(v["stickout_offset_m"][:, 0]) if "stickout_offset_m" in v else np.zeros(k.shape[0])
    low = np.sqrt(np.min(k, axis=1) / np.max(m, axis=1)) * (stickout_m / (stickout_m + offset)) ** 2
    high = np.sqrt(np.max(k, axis=1) / np.min(m, axis=1)) * (stickout_m / np.maximum(stickout_m - offset,
                                                                                         1e-3 * stickout_m)) ** 2
    return low, high


@dataclass(frozen=True)
class NominalStructure:
    """The nominal receptance split into visible resonances and a background.

    Attributes
    ----------
    fit : RationalFit
        The visible poles (rad/s) and their residues; background polynomial zero.
    zeros_rad_s : numpy.ndarray, shape (nzeros,), complex
        The antiresonances of the nominal ``h``: ``Re`` where ``|h|`` has a local minimum,
        ``Im`` the half-width of the dip (from the curvature of ``ln|h|`` there), rad/s.
    modes_hz : numpy.ndarray, shape (nmodes,)
        The exact undamped natural frequencies the fit started from, Hz.
    mode_order : numpy.ndarray of int, shape (nmodes,)
        Their numbers counted from 0 Hz (the Wittrick–Williams count).
    background : numpy.ndarray, shape (nfreq,), complex
        ``h₀ − Σ A/(ω − p)`` on the grid, m/N.
    fit_error : float
        Largest ``|fit − h₀|`` of the nominal fit (all its poles) over the grid, relative
        to ``max |h₀|``.
    """

    fit: RationalFit
    background: ComplexArray
    fit_error: float
    zeros_rad_s: ComplexArray
    modes_hz: FloatArray
    mode_order: IntArray


def nominal_structure(frequency_hz: FloatArray, h: ComplexArray, modes_hz: FloatArray,
                      mode_order: IntArray | None = None) -> NominalStructure:
    """Fit the nominal ``h`` and keep its visible resonances (module docstring, step 1).

    The fit starts from ``modes_hz``; while its error exceeds :data:`NOMINAL_FIT_TARGET` of the
    peak, a pole is added where the relative error is largest (at most :data:`ADDED_POLES`):
    a mode that hardly shows, or one the starting list missed (a measured spindle's).

    Parameters
    ----------
    frequency_hz : numpy.ndarray, shape (nfreq,)
        The grid, Hz.
    h : numpy.ndarray, shape (nfreq,), complex
        The nominal tool-point ``h``, m/N.
    modes_hz : numpy.ndarray, shape (nmodes,)
        Undamped natural frequencies in and around the band (starting poles), Hz.
    mode_order : numpy.ndarray of int, shape (nmodes,), optional
        Their numbers counted from 0 Hz (0, 1, … by default).

    Returns
    -------
    NominalStructure
    """
    w = _TWO_PI * np.asarray(frequency_hz, dtype=float)
    poles = _TWO_PI * np.asarray(modes_hz, dtype=float) * (1.0 + 1.0j * START_DAMPING)
    peak = float(np.max(np.abs(h)))
    for added in range(ADDED_POLES + 1):  # a pole added where the fit is worst, a few times at most
        full = vector_fit(w, h, poles, degree=BACKGROUND_DEGREE, iterations=NOMINAL_ITERATIONS,
                          weights=1.0 / np.abs(h))
        residual = np.abs(full.evaluate(w) - h)
        error = float(np.max(residual)) / peak
        if error <= NOMINAL_FIT_TARGET or added == ADDED_POLES:
            break
        worst = w[int(np.argmax(residual / np.abs(h)))]
        poles = np.concatenate([full.poles_rad_s, [worst * (1.0 + 1.0j * START_DAMPING)]])
    p, a = full.poles_rad_s, full.residues
    visible = (p.real > 0.0) & (p.imag > 0.0) & (np.abs(a) / np.maximum(p.imag, 1e-300) >= VISIBLE_FRACTION * peak)
    fit = RationalFit(p[visible], a[visible], np.zeros(1, dtype=complex), full.scale_rad_s)
    order = np.arange(np.size(modes_hz)) if mode_order is None else np.asarray(mode_order)
    return NominalStructure(fit, h - fit.evaluate(w), error, antiresonances(w, h), np.asarray(modes_hz, dtype=float),
                            order)


def antiresonances(omega_rad_s: FloatArray, h: ComplexArray) -> ComplexArray:
    """The dips of ``|h|``: each local minimum and its half-width.

    Near a zero ``z`` of ``h``, ``|h| ∝ |ω − z|``, so ``ln|h|`` has the curvature ``1/(Im z)²``
    at its minimum; a minimum whose half-width exceeds a fifth of its frequency is no dip.

    Parameters
    ----------
    omega_rad_s : numpy.ndarray, shape (nfreq,)
        Increasing, rad/s.
    h : numpy.ndarray, shape (nfreq,), complex

    Returns
    -------
    numpy.ndarray, shape (nzeros,), complex
        ``frequency + i half-width`` of each dip, rad/s.
    """
    y = np.log(np.maximum(np.abs(h), 1e-300))
    i = np.flatnonzero((y[1:-1] < y[:-2]) & (y[1:-1] <= y[2:])) + 1
    w = np.asarray(omega_rad_s, dtype=float)
    d0, d1 = w[i] - w[i - 1], w[i + 1] - w[i]
    curvature = 2.0 * ((y[i + 1] - y[i]) / d1 - (y[i] - y[i - 1]) / d0) / (d0 + d1)
    half = 1.0 / np.sqrt(np.maximum(curvature, 1e-300))
    keep = (curvature > 0.0) & (half < 0.2 * w[i])
    out: ComplexArray = w[i][keep] + 1j * np.maximum(half[keep], 0.5 * (d0 + d1)[keep])
    return out


def sample_lines(frequency_hz: FloatArray, poles_rad_s: ComplexArray, low: FloatArray, high: FloatArray
                 ) -> tuple[IntArray, np.ndarray, IntArray, np.ndarray]:
    """The lines each draw is solved at: fit lines and check lines (module docstring, step 2).

    Parameters
    ----------
    frequency_hz : numpy.ndarray, shape (nfreq,)
        The grid, Hz (increasing).
    poles_rad_s : numpy.ndarray, shape (npoles,), complex
        The nominal visible poles and antiresonances (frequency + i half-width), rad/s.
    low, high : numpy.ndarray, shape (ndraws,)
        How far each draw's modes may move (:func:`frequency_ratio_bounds`).

    Returns
    -------
    fit_lines : numpy.ndarray of int, shape (ndraws, nfit)
        Indices into the grid, increasing along each row where ``fit_mask`` holds.
    fit_mask : numpy.ndarray of bool, shape (ndraws, nfit)
        Which entries are lines (the rows are padded to one length).
    check_lines : numpy.ndarray of int, shape (ndraws, ncheck)
    check_mask : numpy.ndarray of bool, shape (ndraws, ncheck)
    """
    f = np.asarray(frequency_hz, dtype=float)
    nd = low.size
    background = _background_lines_hz(f, poles_rad_s)
    cols = [np.broadcast_to(background, (nd, background.size))]
    valid = [np.ones((nd, background.size), dtype=bool)]
    span_lo, span_hi = [], []
    for p in poles_rad_s / _TWO_PI:  # a loop over the few modes
        half = p.imag
        a = np.maximum(p.real * low - 2.0 * half, f[0])
        b = np.minimum(p.real * high + 2.0 * half, f[-1])
        count = int(np.ceil(np.max(b - a, initial=0.0) / (LINE_SPACING_HALF_WIDTHS * half))) + 1
        x = a[:, None] + LINE_SPACING_HALF_WIDTHS * half * np.arange(count)
        cols.append(np.minimum(x, b[:, None]))
        valid.append(x <= b[:, None] + LINE_SPACING_HALF_WIDTHS * half)
        span_lo.append(a)
        span_hi.append(b)
    fit, fit_mask = _unique_rows(_nearest(f, np.concatenate(cols, axis=1)), np.concatenate(valid, axis=1))
    # check lines: midpoints of neighbouring fit lines inside a mode's range
    fs = np.where(fit_mask, f[fit], np.inf)
    mids = 0.5 * (fs[:, :-1] + fs[:, 1:])
    inside = np.isfinite(mids)
    if span_lo:
        lo_s, hi_s = np.stack(span_lo, axis=1), np.stack(span_hi, axis=1)
        inside &= np.any((mids[:, :, None] >= lo_s[:, None, :]) & (mids[:, :, None] <= hi_s[:, None, :]), axis=2)
    else:
        inside[:] = False
    cand = _nearest(f, np.where(inside, mids, f[0]))
    inside &= ~np.any(cand[:, :, None] == np.where(fit_mask, fit, -1)[:, None, :], axis=2)
    # spread CHECK_LINES of them over each row's candidates
    rank = np.cumsum(inside, axis=1) - 1
    total = np.sum(inside, axis=1, keepdims=True)
    step = np.maximum(total / CHECK_LINES, 1.0)
    keep = inside & (np.floor(rank / step) != np.floor((rank - 1) / step))
    check, check_mask = _unique_rows(np.where(keep, cand, 0), keep)
    return fit, fit_mask, check, check_mask


def _background_lines_hz(f: FloatArray, poles_rad_s: ComplexArray) -> FloatArray:
    """Lines spread over the band: :data:`BACKGROUND_LINES` geometric ones below half the lowest
    resonance (quasi-static, smooth), and from there up a ratio of :data:`BACKGROUND_RATIO`
    between neighbours (no wide gap for a fit to wander in between the modes' ranges)."""
    lowest = float(np.min(poles_rad_s.real, initial=_TWO_PI * f[-1])) / _TWO_PI
    knee = min(max(0.5 * lowest, f[0]), f[-1])
    low = knee ** np.linspace(0.0, 1.0, BACKGROUND_LINES) * f[0] ** np.linspace(1.0, 0.0, BACKGROUND_LINES)
    count = int(np.ceil(np.log(f[-1] / knee) / np.log(BACKGROUND_RATIO))) + 1 if f[-1] > knee else 1
    return np.concatenate([low, knee * (f[-1] / knee) ** np.linspace(0.0, 1.0, count)])


def _nearest(f: FloatArray, x: FloatArray) -> IntArray:
    """Index of the grid line nearest to each ``x``."""
    i = np.clip(np.searchsorted(f, x), 1, f.size - 1)
    out: IntArray = np.where(np.abs(f[i - 1] - x) <= np.abs(f[i] - x), i - 1, i)
    return out


def _unique_rows(idx: IntArray, mask: np.ndarray) -> tuple[IntArray, np.ndarray]:
    """Per row: the distinct masked entries, sorted and packed to the left (then padding)."""
    key = np.where(mask, idx, np.iinfo(np.int64).max)
    order = np.sort(key, axis=1)
    keep = order != np.iinfo(np.int64).max
    keep[:, 1:] &= order[:, 1:] != order[:, :-1]
    width = int(np.max(np.sum(keep, axis=1), initial=0))
    pos = np.cumsum(keep, axis=1) - 1
    out = np.zeros((idx.shape[0], max(width, 1)), dtype=np.int64)
    out_mask = np.zeros(out.shape, dtype=bool)
    r, c = np.nonzero(keep)
    out[r, pos[r, c]] = order[r, c]
    out_mask[r, pos[r, c]] = True
    return out, out_mask


@dataclass(frozen=True)
class ReducedDraws:
    """Tool-point ``h`` of every draw from the reduced model, and how well it held.

    Attributes
    ----------
    h : numpy.ndarray, shape (ndraws, nfreq), complex
        m/N.
    poles_rad_s : numpy.ndarray, shape (ndraws, npoles), complex
        Each draw's fitted poles (those of the nominal's visible resonances, moved, and the
        :data:`EXTRA_POLES`), rad/s.
    residues : numpy.ndarray, shape (ndraws, npoles), complex
        Their residues, m/N · rad/s.
    nominal : NominalStructure
    lines_per_draw : numpy.ndarray of int, shape (ndraws,)
        Lines each draw was solved at exactly (fit and check lines).
    check_error : numpy.ndarray, shape (ndraws,)
        Each draw's largest relative error of |h| at its check lines.
    exact : numpy.ndarray of bool, shape (ndraws,)
        Draws solved on every line (their check error exceeded :data:`CHECK_TOLERANCE`).
    """

    h: ComplexArray
    poles_rad_s: ComplexArray
    residues: ComplexArray
    nominal: NominalStructure
    lines_per_draw: IntArray
    check_error: FloatArray
    exact: np.ndarray

    def summary(self) -> dict[str, object]:
        """What the reduced model did, JSON-ready (the band's ``method``)."""
        return {"name": "reduced", "lines_per_draw_mean": float(np.mean(self.lines_per_draw)),
                "resonances": int(self.nominal.fit.poles_rad_s.size),
                "max_check_error": float(np.max(self.check_error, initial=0.0)),
                "check_tolerance": CHECK_TOLERANCE, "draws_solved_on_every_line": int(np.sum(self.exact))}


def reduced_draws(drawn: DrawnChains, frequency_hz: FloatArray, nominal: NominalStructure,
                  low: FloatArray, high: FloatArray, base_receptance: ComplexArray | None = None) -> ReducedDraws:
    """Tool-point ``h`` of every drawn model by the reduced model (module docstring, steps 2–5).

    Parameters
    ----------
    drawn : DrawnChains
        The draws' chains (:func:`rcsa.model.draw_chains.drawn_chains`).
    frequency_hz : numpy.ndarray, shape (nfreq,)
        The grid, Hz.
    nominal : NominalStructure
        :func:`nominal_structure` of the nominal ``h`` on this grid.
    low, high : numpy.ndarray, shape (ndraws,)
        :func:`frequency_ratio_bounds` of the draws.
    base_receptance : numpy.ndarray, shape (ndraws, nfreq, 2, 2), optional
        Each draw's measured spindle-side receptance (hybrid), smooth in frequency.

    Returns
    -------
    ReducedDraws
    """
    f = np.asarray(frequency_hz, dtype=float)
    w = _TWO_PI * f
    nd = drawn.n_draws
    fit, fit_mask, check, check_mask = sample_lines(f, np.concatenate([nominal.fit.poles_rad_s, nominal.zeros_rad_s]),
                                                    low, high)
    lines = np.concatenate([fit, check], axis=1)
    mask = np.concatenate([fit_mask, check_mask], axis=1)
    r, c = np.nonzero(mask)
    exact_lines = np.zeros(lines.shape, dtype=complex)
    exact_lines[r, c] = tool_point_h_pairs(drawn, r, f[lines[r, c]],
                                           None if base_receptance is None else base_receptance[r, lines[r, c]])
    nf = fit.shape[1]
    h_fit = np.where(fit_mask, exact_lines[:, :nf], 1.0)
    poles = np.concatenate([nominal.fit.poles_rad_s, w[-1] * EXTRA_POLES])
    target = h_fit - nominal.background[fit]
    weights = np.where(fit_mask, 1.0 / np.abs(h_fit), 0.0)
    model = vector_fit(w[fit], target, np.broadcast_to(poles, (nd, poles.size)), degree=BACKGROUND_DEGREE,
                       iterations=DRAW_ITERATIONS, weights=weights)
    error = _check_error(model, nominal, w, check, exact_lines[:, nf:], check_mask)
    again = np.flatnonzero(error > REFIT_TOLERANCE)
    if again.size:  # the draws the first relocation left short: one more, from their own poles
        refit = vector_fit(w[fit[again]], target[again], model.poles_rad_s[again], degree=BACKGROUND_DEGREE,
                           iterations=DRAW_ITERATIONS, weights=weights[again])
        model = _replace_rows(model, again, refit)
        error[again] = _check_error(refit, nominal, w, check[again], exact_lines[again, nf:], check_mask[again])
    h = model.evaluate(w, offset=nominal.background)
    exact = ~(error <= CHECK_TOLERANCE)
    if np.any(exact):
        rows = np.flatnonzero(exact)
        h[rows] = tool_point_h_draws(_subset(drawn, rows), f, None if base_receptance is None
                                     else base_receptance[rows])
    return ReducedDraws(h, model.poles_rad_s, model.residues, nominal, np.sum(mask, axis=1), error, exact)


def _check_error(model: RationalFit, nominal: NominalStructure, omega_rad_s: FloatArray, lines: IntArray,
                 exact: ComplexArray, mask: np.ndarray) -> FloatArray:
    """Each row's largest relative error of |h| at its check lines ``lines[row]`` (where ``mask``)."""
    model_h = nominal.background[lines] + _evaluate_rows(model, omega_rad_s[lines])
    with np.errstate(divide="ignore", invalid="ignore"):
        relative = np.abs(np.abs(model_h) / np.abs(exact) - 1.0)
    out: FloatArray = np.max(np.where(mask, relative, 0.0), axis=1)
    return out


def _replace_rows(fit: RationalFit, rows: IntArray, new: RationalFit) -> RationalFit:
    """``fit`` with the rows ``rows`` taken from ``new`` (same number of poles and degree)."""
    poles, residues, background = fit.poles_rad_s.copy(), fit.residues.copy(), fit.background.copy()
    poles[rows], residues[rows] = new.poles_rad_s, new.residues
    background[rows] = new.background * (fit.scale_rad_s / new.scale_rad_s) ** np.arange(background.shape[-1])
    return RationalFit(poles, residues, background, fit.scale_rad_s)


def _subset(drawn: DrawnChains, draws: IntArray) -> DrawnChains:
    """The chains of some draws (renumbered 0 … len(draws) − 1 in the order given)."""
    groups = []
    position = np.full(drawn.n_draws, -1)
    position[draws] = np.arange(draws.size)
    for g in drawn.groups:
        keep = np.flatnonzero(position[g.draws] >= 0)
        if keep.size:
            groups.append(DrawGroup(position[g.draws[keep]], take_rows(g.chain, keep)))
    return DrawnChains(tuple(groups), int(draws.size), drawn.fast)


def _evaluate_rows(fit: RationalFit, omega_rad_s: FloatArray) -> ComplexArray:
    """Each row's fit at its own frequencies ``omega_rad_s[row]``, shape (nrows, nlines)."""
    p, a = fit.poles_rad_s[:, None, :], fit.residues[:, None, :]
    out: ComplexArray = (a / (omega_rad_s[:, :, None] - p)).sum(axis=-1)
    u = omega_rad_s / fit.scale_rad_s
    for j in range(fit.background.shape[-1]):
        out = out + fit.background[:, j, None] * u ** j
    return out


#: Half-width of the first bracket around a mode estimated from its tracked pole, relative
#: (the estimates measured on RA-1 are within 1e-3 for most draws; a wrong side costs a step).
TRACKED_HALF_WIDTH = 2e-3
#: Relative width of the final bracket of a drawn natural frequency; the secant root inside
#: it is then good to ~1e-4, far below any spread a tolerance gives.
NATURAL_FREQUENCY_RTOL = 5e-3
#: Draws whose natural frequencies are all solved exactly, to calibrate the others' estimates,
#: and further draws solved exactly to check the calibrated estimates on draws they were not
#: fitted to: an estimate is used only if it is within ``HELD_OUT_FACTOR`` times its allowed
#: error in every one of them.
CALIBRATION_DRAWS, HELD_OUT_DRAWS, HELD_OUT_FACTOR = 16, 8, 3.0
#: A draw's pole estimate is taken only where it agrees with the knobs' fit within this many
#: times that fit's error (a pole mistaken in one draw's reduced model is solved exactly).
OUTLIER_FACTOR = 4.0
#: An estimate of a mode (from its pole, or from the regression) is used for the other draws
#: when its root-mean-square error on the calibration draws stays within this fraction of the
#: mode's spread (an independent error of 10 % of the spread changes the sd by 0.5 %); else
#: every draw is solved exactly.
ESTIMATE_TOLERANCE = 0.1
#: Knobs a natural frequency is regressed on (their logarithms; the stickout offset as is).
REGRESSION_KNOBS = (*STIFFNESS_KNOBS, *MASS_KNOBS)


def reduced_mode_statistics(drawn: DrawnChains, reduced: ReducedDraws, knobs: NuisanceDraws, low: FloatArray,
                            high: FloatArray, start_hz: float, stop_hz: float, band_margin: float
                            ) -> tuple[ModeStatistics, dict[str, list[float]]]:
    """Every draw's natural frequencies from exact solves of a few draws and estimates for the rest.

    1. The first :data:`CALIBRATION_DRAWS` + :data:`HELD_OUT_DRAWS` draws (random like all of
       them) are solved exactly for every nominal mode
       (:func:`rcsa.physics.seeded_modes.natural_frequencies_near`, seeded by the pole's
       estimate or bracketed by the draw's min–max bound).
    2. For each mode, its logarithm is fitted by least squares on the calibration draws
       against ``ln(|p_d| / |p_0|)`` of its pole in the draw's reduced model, where the draw
       shows it (:func:`match_poles`; "pole"), or else against the logarithms of the drawn
       stiffness and mass knobs and the stickout offset ("regression"). A fit is used for the
       other draws when its root-mean-square leave-one-out error stays within
       :data:`ESTIMATE_TOLERANCE` of the mode's spread and its error in each held-out draw within
       :data:`HELD_OUT_FACTOR` times that — the pole's fit only in the draws that show the pole
       and where it agrees with the knobs' fit within :data:`OUTLIER_FACTOR` times that fit's
       error.
    3. Every other (draw, mode) is solved exactly ("exact": no fit held), each bracketed about
       its pole's estimate (or the knobs' fit, or the min–max bound) — but for a mode outside
       the requested band, which counts only in the draws that bring it in (the result's
       ``modes_entering_band``), the knobs' fit is taken as it is ("estimated").

    The table is then that of :func:`rcsa.model.draws.mode_statistics` (modes by order, NaN
    outside the band widened by ``band_margin``).

    Parameters
    ----------
    drawn : DrawnChains
    reduced : ReducedDraws
        The draws' reduced model (its nominal structure carries the nominal modes).
    knobs : NuisanceDraws
        The drawn knobs.
    low, high : numpy.ndarray, shape (ndraws,)
        :func:`frequency_ratio_bounds` of the draws.
    start_hz, stop_hz : float
        The requested band, Hz.
    band_margin : float
        The band searched is ``[start_hz / band_margin, stop_hz · band_margin]``.

    Returns
    -------
    statistics : ModeStatistics
    how : dict
        Nominal frequencies (Hz) by how the other draws' values were obtained: ``"pole"`` (a fit
        with the pole; exact where a draw does not show it), ``"regression"`` (on the knobs
        alone), ``"estimated"`` (the knobs' fit, outside the band), ``"exact"``.
    """
    nominal = reduced.nominal
    modes = nominal.modes_hz
    nm, nd = modes.size, drawn.n_draws
    lo_w, hi_w = start_hz / band_margin, stop_hz * band_margin
    p0 = nominal.fit.poles_rad_s
    matched = match_poles(p0, reduced.poles_rad_s, low, high, nominal.fit.residues, reduced.residues)
    pole_estimate = np.full((nd, nm), np.nan)
    for k, fk in enumerate(modes):  # a loop over the few modes
        distance = np.abs(p0.real / _TWO_PI - fk) / fk
        j = int(np.argmin(distance)) if p0.size else -1
        if j >= 0 and distance[j] <= max(3.0 * p0[j].imag / p0[j].real, 0.02):
            pole_estimate[:, k] = fk * np.abs(matched[:, j]) / np.abs(p0[j])
    cal = np.arange(min(CALIBRATION_DRAWS, nd))
    held = np.arange(cal.size, min(cal.size + HELD_OUT_DRAWS, nd))
    first = np.concatenate([cal, held])
    values = np.full((nd, nm), np.nan)
    c_draw, c_mode = np.repeat(first, nm), np.tile(np.arange(nm), first.size)
    values[c_draw, c_mode] = _exact_pairs(drawn, c_draw, c_mode, nominal.mode_order, pole_estimate[c_draw, c_mode],
                                          modes, low, high)
    features = _knob_features(knobs)
    how: dict[str, list[float]] = {"pole": [], "regression": [], "estimated": [], "exact": []}
    rest = np.arange(first.size, nd)
    todo_draw, todo_mode, todo_seed, todo_half = [], [], [], []
    for k, fk in enumerate(modes):  # a loop over the few modes
        truth = np.log(values[first, k] / fk)
        limit = ESTIMATE_TOLERANCE * float(np.std(truth)) if np.all(np.isfinite(truth)) else 0.0
        by_knobs, knob_error = _regression(features, cal, truth[:cal.size])
        by_pole = np.log(pole_estimate[:, k] / fk)
        tracked = np.isfinite(by_pole)
        with_pole = np.column_stack([np.ones(nd), np.where(tracked, by_pole, 0.0)])
        by_both, pole_error = _regression(with_pole, cal[tracked[cal]], truth[:cal.size][tracked[cal]])
        check_pole = held[tracked[held]]
        pole_ok = (limit > 0.0 and pole_error <= limit and check_pole.size > 0 and
                   np.max(np.abs(by_both[check_pole] - np.log(values[check_pole, k] / fk))) <= HELD_OUT_FACTOR * limit)
        knob_ok = (limit > 0.0 and knob_error <= limit and held.size > 0 and
                   np.max(np.abs(by_knobs[held] - np.log(values[held, k] / fk))) <= HELD_OUT_FACTOR * limit)
        if pole_ok:   # the pole's fit where the draw shows the pole and the knobs' fit agrees, else exact
            spread_knobs = max(knob_error if np.isfinite(knob_error) else np.inf, limit)
            agree = tracked[rest] & (np.abs(by_both[rest] - by_knobs[rest]) <= OUTLIER_FACTOR * spread_knobs) \
                if np.isfinite(spread_knobs) else tracked[rest]
            use = rest[agree]
            values[use, k] = fk * np.exp(by_both[use])
            left = rest[~agree]
            how["pole"].append(float(fk))
        elif knob_ok:
            values[rest, k] = fk * np.exp(by_knobs[rest])
            how["regression"].append(float(fk))
            continue
        elif not start_hz <= fk <= stop_hz and np.all(np.isfinite(by_knobs[rest])):
            # a mode outside the band: it counts only where it enters it; the knobs' fit, noted
            values[rest, k] = fk * np.exp(by_knobs[rest])
            how["estimated"].append(float(fk))
            continue
        else:
            left = rest
            how["exact"].append(float(fk))
        if not start_hz <= fk <= stop_hz and np.all(np.isfinite(by_knobs[left])):
            values[left, k] = fk * np.exp(by_knobs[left])
            continue
        # a draw whose bound keeps the mode out of the widened band needs no value
        left = left[(fk * low[left] <= hi_w) & (fk * high[left] >= lo_w)]
        todo_draw.append(left)
        todo_mode.append(np.full(left.size, k))
        from_pole = tracked[left] & ~pole_ok                 # a pole the fit did not take: still a seed
        todo_seed.append(fk * np.exp(np.where(from_pole, by_pole[left], by_knobs[left])))  # NaN: the bound
        knob_half = 3.0 * knob_error if np.isfinite(knob_error) else 0.0
        todo_half.append(np.where(from_pole, TRACKED_HALF_WIDTH, max(knob_half, TRACKED_HALF_WIDTH)))
    if todo_draw:
        pair_draw, pair_mode = np.concatenate(todo_draw), np.concatenate(todo_mode)
        values[pair_draw, pair_mode] = _exact_pairs(drawn, pair_draw, pair_mode, nominal.mode_order, np.concatenate(todo_seed), modes, low, high,
                                    np.concatenate(todo_half))
    values[(values < lo_w) | (values > hi_w)] = np.nan
    columns = np.flatnonzero((modes >= start_hz) & (modes <= stop_hz))
    return order_statistics(values, columns, start_hz, stop_hz), how


def _exact_pairs(drawn: DrawnChains, draw: IntArray, mode: IntArray, order: IntArray, estimate_hz: FloatArray,
                 modes_hz: FloatArray, low: FloatArray, high: FloatArray,
                 half_width: FloatArray | None = None) -> FloatArray:
    """Exact natural frequency (Hz) of nominal mode ``mode[j]`` (number ``order[mode[j]]``) in draw
    ``draw[j]``: bracketed ± ``half_width`` (relative; :data:`TRACKED_HALF_WIDTH` by default) about
    a finite estimate, else by the draw's min–max bound."""
    ok = np.isfinite(estimate_hz)
    seed = np.where(ok, estimate_hz, modes_hz[mode] * np.sqrt(low[draw] * high[draw]))
    near = TRACKED_HALF_WIDTH if half_width is None else half_width
    half = np.where(ok, near, np.minimum(0.5 * (high[draw] / low[draw] - 1.0) + TRACKED_HALF_WIDTH, 0.9))
    out = np.full(draw.size, np.nan)
    for g in drawn.groups:  # a loop over structures (one, unless a stickout moved a split)
        position = np.full(drawn.n_draws, -1)
        position[g.draws] = np.arange(g.draws.size)
        sel = np.flatnonzero(position[draw] >= 0)
        if sel.size:
            out[sel] = natural_frequencies_near(g.chain, position[draw[sel]], order[mode[sel]], seed[sel],
                                                relative_half_width=half[sel], rtol=NATURAL_FREQUENCY_RTOL)
    return out


def _knob_features(knobs: NuisanceDraws) -> FloatArray:
    """Regressors of a drawn natural frequency's logarithm, shape (ndraws, nfeatures): 1, the
    logarithms of the stiffness and mass knobs, the stickout offset (scaled to its sd)."""
    v = knobs.values
    cols: list[FloatArray] = [np.ones(knobs.n_draws)]
    cols += [np.log(v[name][:, 0]) for name in REGRESSION_KNOBS if name in v]
    if "stickout_offset_m" in v:
        offset = v["stickout_offset_m"][:, 0]
        cols.append(offset / max(float(np.std(offset)), 1e-300))
    x = np.stack(cols, axis=1)
    return x[:, np.concatenate([[True], np.ptp(x[:, 1:], axis=0) > 0.0])]


def _regression(features: FloatArray, cal: IntArray, y: FloatArray) -> tuple[FloatArray, float]:
    """Least-squares fit of ``y`` on ``features[cal]``: the prediction for every draw and the
    root-mean-square leave-one-out error on the calibration draws (inf when underdetermined)."""
    x = features[cal]
    if not np.all(np.isfinite(y)) or x.shape[0] <= x.shape[1] + 2:
        return np.full(features.shape[0], np.nan), np.inf
    coef, *_ = np.linalg.lstsq(x, y, rcond=None)
    hat = np.einsum("ij,ji->i", x, np.linalg.pinv(x))                    # leverages
    loo = (y - x @ coef) / np.maximum(1.0 - hat, 1e-12)
    return features @ coef, float(np.sqrt(np.mean(loo ** 2)))


#: A fitted pole stands for a mode when its damping ratio ``Im p / |p|`` is below this
#: (heavily damped poles of a draw's fit stand for background), and within this factor of the
#: nominal pole's (the damping tolerances move it by e^{±0.75} at three sd).
MODE_DAMPING_LIMIT, DAMPING_FACTOR = 0.2, 2.5
#: ... and a residue within this factor of the nominal pole's (a pole a draw's fit spends on its
#: background may sit near a mode, with a residue unlike the mode's).
RESIDUE_FACTOR = 10.0


def match_poles(nominal_rad_s: ComplexArray, drawn_rad_s: ComplexArray, low: FloatArray, high: FloatArray,
                nominal_residues: ComplexArray | None = None, drawn_residues: ComplexArray | None = None
                ) -> ComplexArray:
    """Each draw's pole for each nominal one, one to one, in the nominal's order.

    A draw's fit may spend a pole on its background (heavily damped, or at negative
    frequency): only poles with ``Re p > 0``, a damping ratio below :data:`MODE_DAMPING_LIMIT`
    and within :data:`DAMPING_FACTOR` of the nominal pole's are candidates, and only within
    the draw's min–max bound ``[low, high] × |p₀|`` (:func:`frequency_ratio_bounds`, widened by
    5 %). Pairs are taken closest first in
    ``|ln(p_d / p₀)|`` (greedy, all draws at once); the poles matched in a draw are then
    handed out again in ascending order to its matched nominal poles, so the k-th matched pole
    of a draw is its k-th mode, as natural frequencies are matched (by order).

    Parameters
    ----------
    nominal_rad_s : numpy.ndarray, shape (npoles,), complex
        Ascending in real part.
    drawn_rad_s : numpy.ndarray, shape (ndraws, npoles_d), complex
    low, high : numpy.ndarray, shape (ndraws,)
        :func:`frequency_ratio_bounds` of the draws.
    nominal_residues : numpy.ndarray, shape (npoles,), complex, optional
    drawn_residues : numpy.ndarray, shape (ndraws, npoles_d), complex, optional
        With both, a candidate's residue must lie within :data:`RESIDUE_FACTOR` of the nominal one.

    Returns
    -------
    numpy.ndarray, shape (ndraws, npoles), complex
        NaN where no candidate was left.

    Examples
    --------
    >>> nominal = np.array([100.0 + 1.0j, 200.0 + 2.0j])
    >>> drawn = np.array([[205.0 + 2.0j, 98.0 + 1.0j], [-50.0 + 9.0j, 190.0 + 2.0j]])
    >>> m = match_poles(nominal, drawn, np.full(2, 0.9), np.full(2, 1.1))
    >>> m[0].tolist(), np.isnan(m[1, 0]), complex(m[1, 1])
    ([(98+1j), (205+2j)], True, (190+2j))
    """
    nd, m = drawn_rad_s.shape
    n = nominal_rad_s.size
    with np.errstate(divide="ignore", invalid="ignore"):
        log_ratio = np.log(drawn_rad_s[:, None, :] / nominal_rad_s[None, :, None])
    modulus = np.exp(log_ratio.real)
    zeta_d = drawn_rad_s.imag / np.abs(drawn_rad_s)
    zeta_0 = nominal_rad_s.imag / np.abs(nominal_rad_s)
    damping = zeta_d[:, None, :] / zeta_0[None, :, None]
    candidate = ((drawn_rad_s.real > 0.0) & (zeta_d < MODE_DAMPING_LIMIT))[:, None, :] \
        & (modulus >= 0.95 * low[:, None, None]) & (modulus <= 1.05 * high[:, None, None]) \
        & (damping <= DAMPING_FACTOR) & (damping >= 1.0 / DAMPING_FACTOR)
    if nominal_residues is not None and drawn_residues is not None:
        with np.errstate(divide="ignore", invalid="ignore"):
            strength = np.abs(drawn_residues)[:, None, :] / np.abs(nominal_residues)[None, :, None]
        candidate &= (strength <= RESIDUE_FACTOR) & (strength >= 1.0 / RESIDUE_FACTOR)
    cost = np.where(candidate, np.abs(log_ratio), np.inf)
    taken = np.full((nd, n), -1)
    rows = np.arange(nd)
    for _ in range(min(n, m)):  # one assignment per step, in every draw at once
        flat = np.argmin(cost.reshape(nd, -1), axis=1)
        i, j = np.divmod(flat, m)
        ok = np.isfinite(cost[rows, i, j])
        taken[rows[ok], i[ok]] = j[ok]
        cost[rows, i, :] = np.inf
        cost[rows, :, j] = np.inf
    out = np.full((nd, n), complex(np.nan, np.nan))
    hit = taken >= 0
    poles = np.where(hit, np.take_along_axis(drawn_rad_s, np.maximum(taken, 0), axis=1), np.nan + 0j)
    # the matched poles in ascending order, to the matched nominal poles in theirs
    order = np.argsort(np.where(hit, poles.real, np.inf), axis=1)
    sorted_poles = np.take_along_axis(poles, order, axis=1)
    slot = np.cumsum(hit, axis=1) - 1
    out[hit] = np.take_along_axis(sorted_poles, np.maximum(slot, 0), axis=1)[hit]
    return out
