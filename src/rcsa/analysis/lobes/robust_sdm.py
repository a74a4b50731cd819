"""Robust semi-discretization limits from a reduced model of the drawn assemblies.

One semi-discretization per drawn assembly (200 draws × hundreds of speeds) is far too slow.
The draws move each mode of the tool point a little: its natural frequency, damping ratio
and residue. For one mode the SDM depth limit obeys an exact similarity law: the period map
depends on ``ωT`` (speed over natural frequency), on ``ζ`` and on ``b Kt R/ω²`` only, so

    b(n; ω, ζ, R) = (ω²/R) · Φ(n/ω, ζ).

The reduced model applies that law mode by mode:

1. **Modal changes of each draw** (:func:`modal_ratios`). Around every mode ``r`` of the
   nominal modal model, the nominal FRF and each draw's FRF are fitted by the same one-mode
   Levy fit (with residual terms) on the same window; the draw's ratios to the nominal fit
   ``s = ω_d/ω``, ``c = ζ_d/ζ`` and ``κ = (ω_d²/R_d)/(ω²/R)`` (modal stiffness) cancel most of
   the fit's own bias. All draws are fitted at once (batched normal equations).
2. **Three SDM diagrams instead of one per draw** (:func:`robust_sdm_limits`): the nominal
   modal model with every damping ratio scaled by the draws' smallest and largest ``c`` (1st
   and 99th percentiles) and by 1, on a speed grid stretched by the draws' frequency shifts —
   one batch of three models (:func:`~rcsa.analysis.lobes.semi_discretization.
   semi_discretization_lobes_many`), on a grid twice as dense as the diagram's.
3. **Each draw's limit** at speed ``n``: the mode ``r`` governing there (the nominal chatter
   frequency's nearest mode) gives ``b_d(n) = κ_r · B(n/s_r; c_r)``, ``log B`` interpolated
   linearly in ``log n`` on the stretched grid and in ``log c`` between the damping levels.
4. The robust limit is the ``(1 − confidence)`` quantile over draws, never above the
   nominal limit (the rule of :mod:`rcsa.analysis.lobes.robust`).

It is exact for one mode whose draws change only that mode (measured: 0.6 % median, 5 % at
the 90th percentile per draw and speed, from the interpolations). With several modes a draw
that shifts them by different amounts is approximated by the governing mode's shift, and the
lobes of the other mode move with it: against one full SDM per draw on RA-1's two modes
(a_e/D = 0.05, one tooth, 24 draws of the default tolerances) the error is 12 % median and
48 % at the 90th percentile per draw, 7 % median for the 10th-percentile limit
(``tests/analysis/lobes/test_robust_sdm.py``). It is the screening model of robust
pockets; the verified window of a robust preset is solved again with every draw's own modes.
The draws' FRFs come in from outside (:meth:`rcsa.model.spindle_side.SpindleSide.
tool_point_draws`, or any reduced model of the draws): only ``h_draws`` is read here.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from rcsa.analysis.lobes.modal_model import ModalModel
from rcsa.analysis.lobes.robust import robust_depth_limit
from rcsa.analysis.lobes.semi_discretization import (
    DiagramsSolver,
    SemiDiscretizationResult,
    solve_diagrams_here,
)
from rcsa.errors import InputError

__all__ = ["REDUCED_COST_DIAGRAMS", "VERIFY_DRAWS", "ModalRatios", "drawn_models", "modal_ratios",
           "robust_sdm_limits"]

#: Drawn modal models a robust preset's chosen window is verified with (a seeded subset when
#: there are more draws).
VERIFY_DRAWS = 40

_TWO_PI = 2.0 * np.pi
# Fit window around each mode: ± this many damping ratios (relative), at least this wide.
_WINDOW_ZETAS = 3.0
_WINDOW_MIN_REL = 0.04
# Damping levels beyond which two extra diagrams are solved (else the nominal one serves all).
_DAMPING_SPREAD = 0.03
_DAMPING_LEVELS = 3
# The stretched grid is this many times denser than the diagram's (its reading error shrinks
# with the square of the spacing: 0.6 % median at 2×, single mode).
_GRID_REFINE = 2.0
#: What the reduced model costs beside the nominal diagram, in nominal diagrams: the damping
#: levels on the stretched, denser grid (±10 % of frequency spread widens it by about 20 %),
#: whatever the number of draws.
REDUCED_COST_DIAGRAMS = (_DAMPING_LEVELS + 1) * _GRID_REFINE * 1.2
_NO_LIMIT = 1e3  # m: a draw without a limit below its search depth, inside the quantile


@dataclass(frozen=True)
class ModalRatios:
    """Each draw's modal changes relative to the nominal, per mode of the nominal model.

    Attributes
    ----------
    frequency : numpy.ndarray, shape (ndraws, nmodes)
        ``ω_d / ω``.
    damping : numpy.ndarray, shape (ndraws, nmodes)
        ``ζ_d / ζ``.
    stiffness : numpy.ndarray, shape (ndraws, nmodes)
        ``(ω_d²/R_d) / (ω²/R)``.
    """

    frequency: np.ndarray
    damping: np.ndarray
    stiffness: np.ndarray


def _levy(f: np.ndarray, h: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Batched one-mode Levy fits with residual terms: natural frequency (Hz), ζ and residue (1/kg).

    ``h ≈ (c0 + c1 s + c2 s²)/(s² + a1 s + a0)``, ``s = iω/scale``, for each row of ``h``
    (shape (nb, nf)); the residue is that of the pole pair as a real mode,
    ``R = 2 ζ ω_n² |h_mode(ω_n)|``.
    """
    s = _TWO_PI * 1j * f
    scale = float(np.abs(s).max())
    sn = s / scale
    cols = np.stack([h, h * sn, -np.ones_like(h), -np.broadcast_to(sn, h.shape), -np.broadcast_to(sn**2, h.shape)],
                    axis=-1)  # (nb, nf, 5)
    rhs = -h * sn**2
    a = np.concatenate([cols.real, cols.imag], axis=1)
    b = np.concatenate([rhs.real, rhs.imag], axis=1)
    norm = np.linalg.norm(a, axis=1, keepdims=True)
    norm[norm == 0] = 1.0
    a = a / norm
    x = np.linalg.solve(np.swapaxes(a, 1, 2) @ a, (np.swapaxes(a, 1, 2) @ b[..., None]))[..., 0] / norm[:, 0, :]
    a0, a1 = x[:, 0], x[:, 1]
    with np.errstate(invalid="ignore", divide="ignore"):
        wn = np.sqrt(a0) * scale
        zeta = a1 / (2.0 * np.sqrt(a0))
        at = 1j * np.sqrt(a0)  # s at ω_n
        num = x[:, 2] + x[:, 3] * at + x[:, 4] * at**2
        peak = np.abs(num / (a1 * at))  # the pole pair's part of h at ω_n: residue over 2iζω_n²
        residue = 2.0 * zeta * wn**2 * peak
    return wn / _TWO_PI, zeta, residue


def modal_ratios(model: ModalModel, frequency_hz: np.ndarray, h: np.ndarray, h_draws: np.ndarray) -> ModalRatios:
    """Each draw's ``ω``, ``ζ`` and modal-stiffness ratios to the nominal, per mode (module docstring, step 1).

    Parameters
    ----------
    model : ModalModel
        The nominal modes (one direction is read: the FRF is the same in x and y).
    frequency_hz : numpy.ndarray, shape (nfreq,)
    h : numpy.ndarray, shape (nfreq,), complex
        Nominal tool-point FRF, m/N.
    h_draws : numpy.ndarray, shape (ndraws, nfreq), complex
        The drawn assemblies' FRFs, m/N.

    Returns
    -------
    ModalRatios
        Ratios of every draw for the x modes of ``model`` (columns in their order); a mode
        whose window holds fewer than 5 lines or whose fit fails keeps ratios of 1.
    """
    f = np.asarray(frequency_hz, dtype=float)
    draws = np.asarray(h_draws)
    sel = np.flatnonzero(model.direction == 0)
    n, m = draws.shape[0], sel.size
    out = {k: np.ones((n, m)) for k in ("frequency", "damping", "stiffness")}
    for j, r in enumerate(sel):  # a loop over modes (a few)
        fn, zeta = float(model.frequency_hz[r]), float(model.damping_ratio[r])
        rel = max(_WINDOW_ZETAS * zeta, _WINDOW_MIN_REL)
        win = np.flatnonzero(np.abs(f / fn - 1.0) <= rel)
        if win.size < 5:
            continue
        both = np.concatenate([np.asarray(h)[None, win], draws[:, win]])
        f_fit, z_fit, r_fit = _levy(f[win], both)
        ok = np.isfinite(f_fit) & np.isfinite(z_fit) & np.isfinite(r_fit) & (z_fit > 0) & (r_fit > 0)
        if not ok[0]:
            continue
        good = ok[1:]
        ratio_f = f_fit[1:] / f_fit[0]
        out["frequency"][good, j] = ratio_f[good]
        out["damping"][good, j] = z_fit[1:][good] / z_fit[0]
        out["stiffness"][good, j] = (ratio_f[good] ** 2) * r_fit[0] / r_fit[1:][good]
    return ModalRatios(out["frequency"], out["damping"], out["stiffness"])


def drawn_models(model: ModalModel, ratios: ModalRatios, count: int | None = None, seed: int = 0) -> list[ModalModel]:
    """Each draw's own modal model: every nominal mode moved by that draw's ratios (step 1).

    Parameters
    ----------
    model : ModalModel
        The nominal modes (x modes; the y modes are the same when ``same_in_y``).
    ratios : ModalRatios
        :func:`modal_ratios` of the draws.
    count : int, optional
        At most this many draws (a seeded subset, in draw order).
    seed : int

    Returns
    -------
    list of ModalModel
    """
    n = ratios.frequency.shape[0]
    rows = np.arange(n)
    if count is not None and count < n:
        rows = np.sort(np.random.default_rng(seed).choice(n, count, replace=False))
    xmodes = np.flatnonzero(model.direction == 0)
    column = np.array([int(np.flatnonzero(xmodes == r)[0]) if r in xmodes else
                       int(np.argmin(np.abs(model.frequency_hz[xmodes] - model.frequency_hz[r]))) for r in
                       range(model.n_modes)])
    out = []
    for d in rows:  # a loop over draws (at most a few dozen)
        s, c, k = ratios.frequency[d, column], ratios.damping[d, column], ratios.stiffness[d, column]
        out.append(ModalModel(model.frequency_hz * s, np.clip(model.damping_ratio * c, 1e-5, 0.95),
                              model.residue_1_kg * s**2 / k, model.direction, "drawn", model.same_in_y))
    return out


def _damped(model: ModalModel, factor: float) -> ModalModel:
    return ModalModel(model.frequency_hz, np.clip(model.damping_ratio * factor, 1e-5, 0.95), model.residue_1_kg,
                      model.direction, model.source, model.same_in_y)


def _read(grid: np.ndarray, values: np.ndarray, at: np.ndarray) -> np.ndarray:
    """``values`` (last axis on ``grid``) interpolated linearly in ``log n`` at the speeds ``at``."""
    i = np.clip(np.searchsorted(grid, at), 1, grid.size - 1)
    t = np.clip((np.log(at) - np.log(grid[i - 1])) / (np.log(grid[i]) - np.log(grid[i - 1])), 0.0, 1.0)
    return values[..., i - 1] * (1.0 - t) + values[..., i] * t


def robust_sdm_limits(model: ModalModel, frequency_hz: np.ndarray, h: np.ndarray, h_draws: np.ndarray,
                      nominal: SemiDiscretizationResult, confidence: float, *, teeth: int,
                      tangential_coefficient_n_m2: float, radial_ratio: float, radial_immersion: float,
                      milling: Any, draws_out: list[np.ndarray] | None = None,
                      diagrams: DiagramsSolver | None = None) -> np.ndarray:
    """The robust SDM depth limit at the speeds of ``nominal`` (module docstring).

    Parameters
    ----------
    model : ModalModel
        The nominal modes the diagram ``nominal`` was computed with.
    frequency_hz, h : numpy.ndarray, shape (nfreq,)
        The nominal tool-point FRF.
    h_draws : numpy.ndarray, shape (ndraws, nfreq), complex
        The drawn assemblies' FRFs.
    nominal : SemiDiscretizationResult
        The nominal diagram (its speeds, limits, chatter frequencies and search depth).
    confidence : float
        In (0.5, 1).
    teeth, tangential_coefficient_n_m2, radial_ratio, radial_immersion, milling
        The cut of ``nominal``.
    draws_out : list, optional
        Receives every draw's reduced limit, shape (ndraws, nspeed) (NaN: none below the
        search depth).
    diagrams : DiagramsSolver, optional
        How the damping levels' diagrams are solved (default: together, in this process,
        :func:`~rcsa.analysis.lobes.semi_discretization.solve_diagrams_here`); the application
        layer may share them among workers.

    Returns
    -------
    numpy.ndarray, shape (nspeed,)
        m; NaN where neither the nominal nor any draw has a limit below the search depth.

    Raises
    ------
    InputError
        ``h_draws`` not on the FRF's grid.
    """
    f = np.asarray(frequency_hz, dtype=float)
    draws = np.asarray(h_draws)
    if draws.ndim != 2 or draws.shape[1] != f.size:
        raise InputError("uncertainty", f"drawn FRFs must have one row per draw on the {f.size}-line grid")
    ratios = modal_ratios(model, f, h, draws)
    speed = nominal.spindle_speed_rpm
    xmodes = np.flatnonzero(model.direction == 0)
    fx = model.frequency_hz[xmodes]
    chat = np.where(np.isfinite(nominal.chatter_frequency_hz), nominal.chatter_frequency_hz, fx[0])
    governing = np.argmin(np.abs(np.log(chat[:, None] / fx[None, :])), axis=1)  # (nspeed,)
    s = ratios.frequency[:, governing]  # (ndraws, nspeed)
    c = ratios.damping[:, governing]
    kappa = ratios.stiffness[:, governing]
    c_lo, c_hi = np.percentile(ratios.damping, [1.0, 99.0])
    levels = [1.0] if (c_hi - c_lo) < _DAMPING_SPREAD else sorted(
        {float(x) for x in np.geomspace(c_lo, c_hi, _DAMPING_LEVELS)} | {1.0})
    span = np.log(speed.max() / speed.min() * s.max() / s.min())
    step = np.log(speed.max() / speed.min()) / max(speed.size - 1, 1) / _GRID_REFINE if speed.size > 1 else 0.01
    grid = np.geomspace(speed.min() / s.max() * 0.999, speed.max() / s.min() * 1.001, int(span / step) + 2)
    kw = {"teeth": teeth, "tangential_coefficient_n_m2": tangential_coefficient_n_m2, "radial_ratio": radial_ratio,
          "radial_immersion": radial_immersion, "milling": milling}
    # the reduced model's own error (module docstring) dwarfs the discretisation's: its diagrams are
    # solved with the resolving steps but not checked or refined (a screening pass)
    solve = solve_diagrams_here if diagrams is None else diagrams
    solved = solve([_damped(model, lv) for lv in levels], [grid] * len(levels),
                   {**kw, "min_depth_search_max_m": [nominal.depth_search_max_m] * len(levels),
                    "depth_rtol": 5e-3, "check": False})
    table = np.log(np.stack([np.where(np.isfinite(r.depth_limit_m), r.depth_limit_m, _NO_LIMIT) for r in solved]))
    shifted = speed[None, :] / s  # (ndraws, nspeed)
    at_levels = _read(grid, table, shifted)  # (nlevels, ndraws, nspeed)
    if len(levels) == 1:
        log_b = at_levels[0]
    else:
        x = np.log(np.clip(c, levels[0], levels[-1]))
        xs = np.log(np.array(levels))
        k = np.clip(np.searchsorted(xs, x) - 1, 0, len(levels) - 2)
        t = (x - xs[k]) / (xs[k + 1] - xs[k])
        lo = np.take_along_axis(at_levels, k[None], 0)[0]
        hi = np.take_along_axis(at_levels, k[None] + 1, 0)[0]
        log_b = lo + t * (hi - lo)
    per_draw = kappa * np.exp(log_b)
    per_draw = np.where(per_draw >= 0.5 * _NO_LIMIT, np.nan, per_draw)
    if draws_out is not None:
        draws_out.append(per_draw)
    filled = np.where(np.isnan(per_draw), _NO_LIMIT, per_draw)
    nominal_limit = np.where(np.isfinite(nominal.depth_limit_m), nominal.depth_limit_m, _NO_LIMIT)
    robust = np.array(robust_depth_limit(filled, nominal_limit, confidence))
    return np.where(robust >= 0.5 * _NO_LIMIT, np.nan, robust)
