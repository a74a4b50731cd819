"""Stability lobes of milling by first-order semi-discretization (SDM).

The zero-order solution (:mod:`.zoa`) averages the cutting force over a tooth period; at low
radial immersion the force is a short pulse and the average misses both the shape of the
Hopf lobes and the flip (period-doubling) lobes. Semi-discretization keeps the time-periodic
force: the delay-differential equation of the cut is turned into a map over one tooth period
(:mod:`.monodromy`), and a cut is stable when every eigenvalue ("multiplier") of that map
lies inside the unit circle (Floquet theory; Insperger & Stépán 2004).

Per spindle speed, the depth limit is the smallest axial depth at which the largest
multiplier reaches modulus 1:

1. *Scan* upwards from ``b_ref/4`` (``b_ref``: the ZOA absolute limit of the same modal
   model): each step goes to just past the depth where ``log|μ|`` extrapolates to 0,
   between 1.1× and 2× the last depth, until ``|μ| >= 1`` (bracket found) or the search
   ceiling ``64 b_ref`` is passed (then the speed has no limit below the ceiling: NaN).
2. *Refine* the bracket by regula falsi on ``log|μ|`` with the Illinois safeguard to a
   relative width ``DEPTH_RTOL``; the stable end is reported (never optimistic by more
   than the tolerance).

Speeds are solved coarse to fine: every 8th speed (and the last) by the scan and the
refinement; then the midpoints of the solved ones, halving the spacing each time. A midpoint
whose two neighbours lie on the same lobe segment (same lobe number, same kind) is *guided*:
its limit is interpolated (cubic in ``log b`` from four neighbours on the segment, else
linear) and bracketed directly around the guess — two depths ``g e^{∓δ}`` evaluated together,
``δ`` from the interpolation's own error estimate, ``DEPTH_RTOL/2.2`` at adjacent speeds, where
one pair of evaluations usually closes the bracket. A precise guess whose neighbours agree
on the slope of ``log|μ|`` in ``log b`` is tried from its stable side alone: one evaluation
just below the guess, and when the slope puts the crossing within ``DEPTH_RTOL/2`` above it,
that stable depth is the limit (its critical multiplier, moved onto the unit circle, and its
chatter frequency are reported). A guess that misses (the lower depth unstable, or a root
farther than 15 %) is solved from scratch; a speed between two neighbours stable up to the
ceiling is evaluated once, at the ceiling. This needs under half the evaluations of scanning
every speed and gives the same limits (tests/analysis/lobes/test_sdm_reference.py compares
with the limits of the per-speed search it replaced: within 2·DEPTH_RTOL, same kinds).

Every evaluation runs for all open (tool, speed) pairs at once — one batch of period maps,
one monodromy matrix per pair built in a single pass over the steps of a period, Arnoldi on
those matrices (:func:`.monodromy.critical_multipliers`) — and every unstable evaluation
also records its chatter frequency, so the critical multiplier at the final bracket end
costs nothing more. Several tools in one cut are solved as one batch
(:func:`semi_discretization_lobes_many`).

At the limit the critical multiplier ``μ = |μ| e^{iθ}`` gives the kind of instability:
``"hopf"`` (complex pair, quasi-periodic chatter), ``"flip"`` (real, ``μ = −1``: period
doubling) or ``"fold"`` (real, ``μ = +1``). The motion then contains the frequencies
``f_j = (θ/2π + j)/T`` for every integer ``j``; the chatter frequency is the ``|f_j|`` with
the largest amplitude in the critical eigenvector's displacement over one period (its
discrete Fourier series, ``k`` samples; Dombovári, Zatarain & Insperger 2010). The
structure filters the motion, so this is the branch nearest the modes that take part in the
chatter (the dominant mode, unless another mode governs that lobe). The lobe number is
``floor(f_c T)`` (whole waves between teeth, as in ZOA); flip lobes sit at
``f_c T = k + ½``.

Limitations: the modes are real (proportional damping) and act in x or y only (no cross
receptance); the cutting force is linear (no process damping, no helix, no run-out); an
unstable band thinner than one scan step (1.1–2×) that lies below the first bracket would
be stepped over, and a guided speed checks only the two depths around its guess (a
400-point depth grid finds no missed band on the test cases); the accuracy needs
several steps per chatter cycle (``steps_per_chatter_cycle`` flags the speeds with fewer
than ``MIN_STEPS_PER_CHATTER_CYCLE``).

References
----------
.. [1] T. Insperger, G. Stépán, "Updated semi-discretization method for periodic
   delay-differential equations with discrete delay", Int. J. Numer. Meth. Engng
   61:117–141, 2004.
.. [2] T. Insperger, G. Stépán, J. Turi, "On the higher-order semi-discretizations for
   periodic delayed systems", J. Sound Vib. 313:334–341, 2008.
.. [3] Z. Dombovári, M. Zatarain, T. Insperger, "Dominant vibration frequencies in milling
   using semi-discretization method", 2nd CIRP Conf. on Process Machine Interactions, 2010.
.. [4] Y. Altintas, *Manufacturing Automation*, 2nd ed., Cambridge University Press, 2012,
   §4.4 (milling forces, directional factors, ZOA).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from rcsa.analysis.lobes import monodromy as md
from rcsa.analysis.lobes.modal_model import ModalModel
from rcsa.analysis.lobes.zoa import (
    Lobe,
    LobeResult,
    Milling,
    directional_factors,
    engagement_angles_rad,
    zoa_depth_limit,
)
from rcsa.analysis.progress import check_time
from rcsa.errors import InputError
from rcsa.model.wire import complex_to_wire, json_float, json_list

__all__ = [
    "DEFAULT_STEPS_PER_PERIOD",
    "MANY_FIELDS",
    "MAX_STEPS_PER_PERIOD",
    "MIN_STEPS_PER_PERIOD",
    "SemiDiscretizationResult",
    "MAX_RESOLVING_STEPS",
    "RESOLVING_STEPS_PER_CYCLE",
    "resolving_steps",
    "semi_discretization_lobes",
    "semi_discretization_lobes_many",
]

#: Steps per tooth period (Insperger & Stépán use 40); range accepted in requests (the
#: Python API takes up to ``4000`` for convergence studies).
DEFAULT_STEPS_PER_PERIOD = 40
MIN_STEPS_PER_PERIOD = 8
MAX_STEPS_PER_PERIOD = 200
_API_MAX_STEPS = 4000
#: Relative width of the final depth bracket.
DEPTH_RTOL = 1e-3
#: Fewer steps than this per chatter cycle flag a speed as under-resolved (first-order SDM
#: error of a few % there; see tests/analysis/lobes/test_semi_discretization.py).
MIN_STEPS_PER_CHATTER_CYCLE = 8.0
# Scan: start at this fraction of b_ref, steps between these ratios, ceiling at this multiple.
_SCAN_START = 0.25
_SCAN_MIN_RATIO = 1.1
_SCAN_MAX_RATIO = 2.0
_SCAN_CEILING = 64.0
_MAX_REFINE = 40
# Speeds per batch of period maps: bounds the memory (~50 MB for 12 states and k = 40); larger
# batches run slower per map here (the work arrays leave the cache).
_CHUNK = 256
# Coarse-to-fine search: every _COARSE-th speed is solved from scratch, the others are guided
# by their solved neighbours; the guide's half-width (relative) is at most this.
_COARSE = 8
_GUIDE_MAX_DELTA = 0.15
_GUIDE_ROUNDS = 3
#: Neighbours' slopes of log|μ| in log b that differ by more than this factor are not used.
_SLOPE_SPREAD = 1.5

# --------------------------------------------------------------------------- result


@dataclass(frozen=True, slots=True)
class SemiDiscretizationResult(LobeResult):
    """Stability lobes by semi-discretization: :class:`LobeResult` plus what the SDM knows.

    The inherited fields keep their meaning with these differences: ``lobes`` are the
    segments of the lower envelope (split where the lobe number or the kind of instability
    changes; ``lobe_kinds`` says which), ``governing_lobe`` is ``floor(f_c T)``,
    ``min_depth_limit_m`` is the smallest envelope value on the speed grid (with its chatter
    frequency) and ``min_depth_spindle_speed_rpm`` the speed of each segment's lowest point.
    ``depth_limit_m`` is NaN where no instability exists below ``depth_search_max_m``.

    Attributes
    ----------
    instability : numpy.ndarray of str, shape (nspeed,)
        ``"hopf"``, ``"flip"``, ``"fold"``, or ``""`` where no limit was found.
    critical_multiplier : numpy.ndarray, shape (nspeed,), complex
        The multiplier that crosses the unit circle (at the unstable end of the bracket; for a
        limit closed from its stable side, that side's critical multiplier moved onto the circle).
    lobe_kinds : tuple of str
        Kind of each entry of ``lobes``.
    steps_per_period : int
    steps_per_chatter_cycle : numpy.ndarray, shape (nspeed,)
        ``k / (f_c T)``: how finely the steps sample the chatter; below
        ``MIN_STEPS_PER_CHATTER_CYCLE`` the limit is under-resolved (raise
        ``steps_per_period``; ZOA is the cheaper answer at such many-wave, low speeds).
    depth_search_max_m : float
        Ceiling of the depth search, m.
    modal_model : ModalModel
        The modes the map was built from (with their source and fit report).
    top_mode_steps_per_cycle : numpy.ndarray, shape (nspeed,)
        ``k / (1.2 f_top T)``: how finely the steps sample a vibration just above the model's
        highest mode ``f_top``. Below ``MIN_STEPS_PER_CHATTER_CYCLE`` an instability of that
        mode can be missed altogether (too coarse a discretisation damps it), so such speeds
        are noted even where the limit found looks resolved.
    """

    instability: np.ndarray
    critical_multiplier: np.ndarray
    lobe_kinds: tuple[str, ...]
    steps_per_period: int
    steps_per_chatter_cycle: np.ndarray
    depth_search_max_m: float
    modal_model: ModalModel
    top_mode_steps_per_cycle: np.ndarray

    def __post_init__(self) -> None:
        LobeResult.__post_init__(self)
        for name in ("instability", "critical_multiplier", "steps_per_chatter_cycle", "top_mode_steps_per_cycle"):
            getattr(self, name).flags.writeable = False

    @property
    def under_resolved(self) -> np.ndarray:
        """Speeds whose limit has fewer than ``MIN_STEPS_PER_CHATTER_CYCLE`` steps per chatter cycle."""
        return np.asarray(self.steps_per_chatter_cycle < MIN_STEPS_PER_CHATTER_CYCLE)

    def to_dict(self) -> dict[str, Any]:
        """The contract's response (as :meth:`LobeResult.to_dict`) plus the SDM's fields.

        Added: ``method`` (``"semi_discretization"``), ``instability`` (per speed, null
        where none), ``critical_multiplier`` (``{"real", "imag"}``), ``kind`` on every lobe,
        ``steps_per_period``, ``steps_per_chatter_cycle``, ``depth_search_max_m``,
        ``modal_model`` (:meth:`ModalModel.to_dict`) and ``notes`` (under-resolved speeds).
        """
        out = LobeResult.to_dict(self)
        for lobe, kind in zip(out["lobes"], self.lobe_kinds, strict=True):
            lobe["kind"] = kind
        mu = self.critical_multiplier
        out.update(
            method="semi_discretization",
            instability=[str(k) if k else None for k in self.instability.tolist()],
            critical_multiplier=complex_to_wire(mu, nonfinite_as_none=True),
            steps_per_period=self.steps_per_period,
            steps_per_chatter_cycle=json_list(self.steps_per_chatter_cycle),
            depth_search_max_m=json_float(self.depth_search_max_m),
            modal_model=self.modal_model.to_dict(),
            notes=self.notes(),
        )
        return out

    def notes(self) -> list[str]:
        """Plain-language caveats of this result."""
        out = []
        bad = self.spindle_speed_rpm[self.under_resolved]
        if bad.size:
            out.append(f"{bad.size} speed(s) between {bad.min():.0f} and {bad.max():.0f} rpm have fewer than "
                       f"{MIN_STEPS_PER_CHATTER_CYCLE:g} steps per chatter cycle: their limits are under-resolved "
                       f"(raise steps_per_period, or use method zoa there)")
        coarse = self.spindle_speed_rpm[(self.top_mode_steps_per_cycle < MIN_STEPS_PER_CHATTER_CYCLE)
                                        & ~self.under_resolved]
        if coarse.size:
            f_top = float(np.max(self.modal_model.frequency_hz))
            out.append(f"{coarse.size} speed(s) between {coarse.min():.0f} and {coarse.max():.0f} rpm sample "
                       f"a vibration of the highest mode ({f_top:.0f} Hz) with fewer than "
                       f"{MIN_STEPS_PER_CHATTER_CYCLE:g} steps per cycle: an instability of that mode can be "
                       f"missed there (raise steps_per_period, or leave the mode out)")
        return out


# --------------------------------------------------------------------------- search


class _Evaluator:
    """Largest multiplier of the period map for batches of (pair, depth); a pair is one speed
    of one system (tool). Every unstable evaluation also records its chatter frequency, so the
    critical multiplier and frequency at the final unstable end of each bracket are known when
    the search ends (no extra evaluation)."""

    def __init__(self, systems: md.StateSpace, system_of_pair: np.ndarray, plan: md.CuttingPlan, kt: float,
                 period_s: np.ndarray) -> None:
        self.systems = systems
        self.system_of_pair = system_of_pair
        self.plan = plan
        self.kt = kt
        self.period_s = period_s
        self.step_s = period_s / plan.steps
        parts = [md.free_maps(self._system(np.arange(lo, min(lo + _CHUNK, period_s.size))), plan,
                              self.step_s[lo : lo + _CHUNK]) for lo in range(0, period_s.size, _CHUNK)]
        self.free = (np.concatenate([p[0] for p in parts]), np.concatenate([p[1] for p in parts]))
        self.mu_unstable = np.full(period_s.size, np.nan + 0j)
        self.freq_unstable = np.full(period_s.size, np.nan)
        self.evaluations = 0

    def _system(self, idx: np.ndarray) -> md.StateSpace:
        return self.systems.take(self.system_of_pair[idx])

    def maps(self, idx: np.ndarray, depth_m: np.ndarray) -> md.PeriodMaps:
        return md.period_maps(self._system(idx), self.plan, self.kt, self.step_s[idx], depth_m,
                              (self.free[0][idx], self.free[1][idx]))

    def __call__(self, idx: np.ndarray, depth_m: np.ndarray, record_stable: bool = False) -> np.ndarray:
        """``μ`` of each (pair, depth); ``record_stable``: stable evaluations record theirs too
        (moved onto the unit circle: the estimate of the crossing multiplier for a limit closed
        from its stable side; used on pairs not evaluated before)."""
        check_time()  # every round of evaluations: a sync request's time limit stops the search
        self.evaluations += idx.size
        mu = np.empty(idx.size, dtype=complex)
        for lo in range(0, idx.size, _CHUNK):
            part = slice(lo, lo + _CHUNK)
            mu[part] = self._chunk(idx[part], depth_m[part], record_stable)
        return mu

    def _chunk(self, idx: np.ndarray, depth_m: np.ndarray, record_stable: bool) -> np.ndarray:
        system, maps = self._system(idx), self.maps(idx, depth_m)
        mu, vec = md.critical_multipliers(system, self.plan, maps, vectors=True if record_stable else "unstable")
        assert vec is not None
        up = np.abs(mu) >= 1.0
        keep = np.flatnonzero(up | record_stable)
        if keep.size:
            sub = md.PeriodMaps(maps.p[keep], maps.g[keep], maps.free[keep], maps.step[keep])
            on_circle = np.where(mu[keep].imag == 0.0, np.sign(mu[keep].real) + 0j, np.exp(1j * np.angle(mu[keep])))
            self.mu_unstable[idx[keep]] = np.where(up[keep], mu[keep], on_circle)
            self.freq_unstable[idx[keep]] = _chatter_frequency(system.take(keep), self.plan, sub, mu[keep],
                                                               vec[keep], self.period_s[idx[keep]])
        return mu


def _chatter_frequency(system: md.StateSpace, plan: md.CuttingPlan, maps: md.PeriodMaps, mu: np.ndarray,
                       vec: np.ndarray, period_s: np.ndarray) -> np.ndarray:
    """Dominant vibration frequency (Hz) of critical eigenvectors (module docstring)."""
    k = plan.steps
    r = md.trajectory(system, plan, maps, vec)  # (nb, k, 2)
    log_mu = np.log(mu.astype(complex))
    floquet = np.exp(-np.outer(log_mu, np.arange(k) / k))  # remove the growth μ^{s/k}
    coef = np.fft.fft(r * floquet[:, :, None], axis=1)
    power = (np.abs(coef) ** 2).sum(axis=2)
    j = np.fft.fftfreq(k, d=1.0 / k)[np.argmax(power, axis=1)]
    theta = np.angle(mu)
    return np.asarray(np.abs(theta / (2 * np.pi) + j) / period_s)


def _log_modulus(mu: np.ndarray) -> np.ndarray:
    with np.errstate(divide="ignore"):
        return np.log(np.abs(mu))


@dataclass
class _Brackets:
    """Per pair: the highest depth known stable (``lo``, ``g_lo = log|μ|``) and the lowest known
    unstable above it (``hi``, NaN while none)."""

    lo: np.ndarray
    g_lo: np.ndarray
    hi: np.ndarray
    g_hi: np.ndarray

    @classmethod
    def empty(cls, n: int) -> _Brackets:
        nan = np.full(n, np.nan)
        return cls(np.zeros(n), nan.copy(), nan.copy(), nan.copy())


def _scan(evaluate: _Evaluator, idx: np.ndarray, br: _Brackets, first_m: np.ndarray, ceiling_m: np.ndarray) -> None:
    """Bracket the first crossing of ``log|μ| = 0`` above ``br.lo`` for the pairs ``idx``, starting at ``first_m``.

    Each step goes to just past the depth where ``log|μ|`` extrapolates (from the last two
    depths) to 0, between ``_SCAN_MIN_RATIO`` and ``_SCAN_MAX_RATIO`` times the last depth, until
    an unstable depth is met (``br.hi``) or ``ceiling_m`` is passed (``br.hi`` stays NaN).
    """
    b = np.minimum(np.asarray(first_m, dtype=float), ceiling_m)
    active = np.arange(idx.size)
    while active.size:
        pair = idx[active]
        g = _log_modulus(evaluate(pair, b[active]))
        up = g >= 0.0
        br.hi[pair[up]], br.g_hi[pair[up]] = b[active[up]], g[up]
        go = active[~up]
        g_go = g[~up]
        pg = idx[go]
        slope = (g_go - br.g_lo[pg]) / (b[go] - br.lo[pg])
        with np.errstate(divide="ignore", invalid="ignore"):
            guess = np.where(slope > 0.0, b[go] - g_go / slope, np.inf)
        step = np.clip(1.05 * guess / b[go], _SCAN_MIN_RATIO, _SCAN_MAX_RATIO)
        br.lo[pg], br.g_lo[pg] = b[go], g_go
        at_ceiling = b[go] >= ceiling_m[go]
        b[go] = np.minimum(b[go] * step, ceiling_m[go])
        active = go[~at_ceiling]


def _refine(evaluate: _Evaluator, idx: np.ndarray, br: _Brackets, rtol: float) -> None:
    """Illinois regula falsi on ``log|μ|`` until ``hi − lo <= rtol·hi`` for the pairs ``idx``."""
    a, ga, c, gc = br.lo[idx], br.g_lo[idx], br.hi[idx], br.g_hi[idx]
    true_a, true_c = ga.copy(), gc.copy()  # log|μ| at the ends (ga, gc are halved by Illinois)
    side = np.zeros(idx.size, dtype=np.int8)
    for _ in range(_MAX_REFINE):
        check_time()
        open_ = np.flatnonzero(c - a > rtol * c)
        if open_.size == 0:
            break
        w = c[open_] - a[open_]
        x = (a[open_] * gc[open_] - c[open_] * ga[open_]) / (gc[open_] - ga[open_])
        x = np.clip(x, a[open_] + 0.01 * rtol * w, c[open_] - 0.01 * rtol * w)
        gx = _log_modulus(evaluate(idx[open_], x))
        up = gx >= 0.0
        iu, id_ = open_[up], open_[~up]
        ga[iu[side[iu] > 0]] *= 0.5  # a kept twice: Illinois
        gc[id_[side[id_] < 0]] *= 0.5
        c[iu], gc[iu], true_c[iu] = x[up], gx[up], gx[up]
        a[id_], ga[id_], true_a[id_] = x[~up], gx[~up], gx[~up]
        side[iu], side[id_] = 1, -1
    br.lo[idx], br.hi[idx], br.g_lo[idx], br.g_hi[idx] = a, c, true_a, true_c


def _reference_depth(model: ModalModel, teeth: int, kt: float, alpha: np.ndarray) -> float:
    """ZOA absolute limit of the modal model (scale of the depth search), m."""
    fn = np.asarray(model.frequency_hz, dtype=float)
    grid = np.unique(np.concatenate(
        [np.geomspace(0.5 * fn.min(), 2.0 * fn.max(), 2000)]
        + [f * np.linspace(0.8, 1.25, 400) for f in fn]))
    hxx, hyy = model.receptance(grid, 0), model.receptance(grid, 1)
    depth, _ = zoa_depth_limit(hxx, hyy, teeth=teeth, tangential_coefficient_n_m2=kt, alpha=alpha)
    if np.any(np.isfinite(depth)):
        return float(np.nanmin(depth))
    w = 2 * np.pi * fn  # no ZOA limit (e.g. a degenerate average force): 2ζk/Kt
    return float(np.min(2 * np.asarray(model.damping_ratio) * w**2 / np.asarray(model.residue_1_kg)) / kt)


def _levels(n: int) -> list[tuple[int, np.ndarray]]:
    """Positions ``0 … n−1`` of one speed grid in the order they are solved: ``(h, positions)``.

    First every ``_COARSE``-th position and the last (``h = 0``: solved from scratch), then the
    midpoints of the known ones, halving the spacing each level (``h``: distance to the known
    neighbours on either side).
    """
    if n <= 2 * _COARSE:
        return [(0, np.arange(n))]
    levels = [(0, np.unique(np.append(np.arange(0, n, _COARSE), n - 1)))]
    h = _COARSE // 2
    while h >= 1:
        pos = np.arange(h, n, 2 * h)
        levels.append((h, pos[pos < n - 1]))
        h //= 2
    return levels


def _straddle_root(lo: np.ndarray, g_lo: np.ndarray, hi: np.ndarray, g_hi: np.ndarray) -> np.ndarray:
    """Where the line through ``(ln lo, g_lo)`` and ``(ln hi, g_hi)`` crosses 0 (NaN: not rising;
    inf where it rises too slowly to cross in floating point — the callers move no further than
    ``_GUIDE_MAX_DELTA``)."""
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        slope = (g_hi - g_lo) / (np.log(hi) - np.log(lo))
        return np.where(slope > 0.0, np.exp(np.log(lo) - g_lo / slope), np.nan)


def _guided(evaluate: _Evaluator, pairs: np.ndarray, guess: np.ndarray, delta: np.ndarray, br: _Brackets,
            rtol: float, ceiling_m: np.ndarray, slope: np.ndarray) -> np.ndarray:
    """Bracket the pairs around their guessed limits; returns the pairs left to solve from scratch.

    A precise guess (``delta <= rtol/4``) with a known slope ``s`` of ``log|μ|`` in ``log b``
    (the neighbours') is first tried from its stable side alone: one evaluation at
    ``x e^{−rtol/4}``; stable, with the crossing ``log|μ|/s`` within ``rtol/2`` above it, closes
    the limit there (the depth reported is that stable one; the multiplier and chatter frequency
    are its critical ones, the multiplier moved onto the unit circle). Otherwise the pair is
    straddled around the crossing the slope gives, as below.

    A round evaluates ``x e^{∓δ}`` together. Stable below and unstable above: bracketed.
    Both on one side: the line through the two ``log|μ|`` values gives the next ``x``, and the
    next round straddles it by ``rtol/2.2`` (at most ``_GUIDE_ROUNDS`` rounds, and only while
    ``x`` moves by less than ``_GUIDE_MAX_DELTA``); pairs stable at both depths after the last
    round continue the scan upwards. A bracket wider than ``rtol`` is then straddled once more
    at its own secant root, which closes it in nearly every case (the refinement does the rest).
    """
    x, d = guess.copy(), np.maximum(delta, rtol / 2.2)
    active = np.arange(pairs.size)
    scratch, climb = [], []
    bracketed = np.zeros(pairs.size, dtype=bool)
    one = np.flatnonzero((delta <= rtol / 4) & (slope > 0.0))  # NaN slope: False
    if one.size:
        p = pairs[one]
        b = x[one] * np.exp(-rtol / 4)
        g = _log_modulus(evaluate(p, b, record_stable=True))
        root = b * np.exp(-g / slope[one])
        stable = g < 0.0
        close = stable & (np.log(root / b) <= rtol / 2)
        br.lo[p[stable]], br.g_lo[p[stable]] = b[stable], g[stable]
        br.hi[p[close]], br.g_hi[p[close]] = root[close], 0.0
        x[one], d[one] = root, rtol / 2.2
        active = np.setdiff1d(active, one[close])
    for rounds_left in range(_GUIDE_ROUNDS - 1, -1, -1):
        if not active.size:
            break
        p = pairs[active]
        lo, hi = x[active] * np.exp(-d[active]), x[active] * np.exp(d[active])
        g = _log_modulus(evaluate(np.concatenate([p, p]), np.concatenate([lo, hi])))
        g_lo, g_hi = g[: p.size], g[p.size :]
        ok = (g_lo < 0.0) & (g_hi >= 0.0)
        br.lo[p[ok]], br.g_lo[p[ok]], br.hi[p[ok]], br.g_hi[p[ok]] = lo[ok], g_lo[ok], hi[ok], g_hi[ok]
        bracketed[active[ok]] = True
        stable = (g_lo < 0.0) & (g_hi < 0.0)
        br.lo[p[stable]], br.g_lo[p[stable]] = hi[stable], g_hi[stable]
        both = ((g_lo >= 0.0) & (g_hi >= 0.0)) | stable
        root = _straddle_root(lo, g_lo, hi, g_hi)
        with np.errstate(divide="ignore", invalid="ignore"):  # a straddle root at or below 0 moves nowhere
            step = np.abs(np.log(root / x[active]))
        moves = both & np.isfinite(root) & (root > 0.0) & (step <= _GUIDE_MAX_DELTA)
        scratch.append(p[~ok & ~moves & ~stable])
        if rounds_left == 0:
            climb.append(p[stable])
            scratch.append(p[moves & ~stable])
            break
        climb.append(p[stable & ~moves])
        nxt = active[moves]
        x[nxt], d[nxt] = root[moves], rtol / 2.2
        active = nxt
    wide = active_wide = np.flatnonzero(bracketed & (br.hi[pairs] - br.lo[pairs] > rtol * br.hi[pairs]))
    if active_wide.size:
        p = pairs[wide]
        root = _straddle_root(br.lo[p], br.g_lo[p], br.hi[p], br.g_hi[p])
        root = np.clip(root, br.lo[p] * np.exp(rtol / 2.2), br.hi[p] * np.exp(-rtol / 2.2))
        inside = np.isfinite(root) & (br.lo[p] * np.exp(rtol / 2.2) < br.hi[p] * np.exp(-rtol / 2.2))
        p, root = p[inside], root[inside]
        lo, hi = root * np.exp(-rtol / 2.2), root * np.exp(rtol / 2.2)
        g = _log_modulus(evaluate(np.concatenate([p, p]), np.concatenate([lo, hi])))
        for depth, gd in ((lo, g[: p.size]), (hi, g[p.size :])):  # the two sides of the straddle
            up = gd >= 0.0
            raise_lo = ~up & (depth > br.lo[p])
            lower_hi = up & (depth < br.hi[p])
            br.lo[p[raise_lo]], br.g_lo[p[raise_lo]] = depth[raise_lo], gd[raise_lo]
            br.hi[p[lower_hi]], br.g_hi[p[lower_hi]] = depth[lower_hi], gd[lower_hi]
    up = np.concatenate(climb) if climb else np.empty(0, dtype=np.int64)
    up = up[br.lo[up] < ceiling_m[up]]  # stable at the ceiling: no limit (hi stays NaN)
    _scan(evaluate, up, br, br.lo[up] * _SCAN_MIN_RATIO, ceiling_m[up])
    return np.concatenate(scratch) if scratch else np.empty(0, dtype=np.int64)


def _search(evaluate: _Evaluator, grids: list[np.ndarray], g0: np.ndarray, start_m: np.ndarray,
            ceiling_m: np.ndarray, rtol: float, progress: Callable[[int, int], None] | None = None,
            scan_from_neighbours: bool = False, scan_start_m: np.ndarray | None = None) -> _Brackets:
    """Depth brackets of every pair (module docstring), coarse to fine along each speed grid.

    ``grids[i]`` are the pair indices of system ``i`` in speed order. Coarse speeds are solved
    by the scan from ``start_m`` and the refinement. A finer speed between two solved ones
    that lie on the same lobe segment (same lobe number and kind of instability) is *guided*
    (:func:`_guided`): its limit is interpolated from them (cubic in ``log b`` when two more
    neighbours on the segment are known, else linear) and bracketed around the guess, the
    first half-width from the interpolation's own error estimate (``rtol/2.2`` when the guess is
    that good). A guess that fails (the lower depth unstable, or a jump beyond
    ``_GUIDE_MAX_DELTA``) is solved from scratch like a coarse speed.
    """
    br = _Brackets.empty(g0.size)
    br.g_lo[:] = g0
    kind = np.zeros(g0.size, dtype=np.int8)  # 0 none, 1 hopf, 2 flip, 3 fold
    lobe = np.full(g0.size, -1, dtype=np.int64)
    root = np.full(g0.size, np.nan)  # best estimate of each solved limit: its bracket's secant root
    slope = np.full(g0.size, np.nan)  # d log|μ| / d log b across each solved bracket
    given = np.full(g0.size, np.nan) if scan_start_m is None else np.asarray(scan_start_m, dtype=float)
    hint = given.copy()  # where a scratch pair's scan starts (NaN: start_m)

    def settle(idx: np.ndarray) -> None:
        _refine(evaluate, idx[np.isfinite(br.hi[idx])], br, rtol)
        mu, f = evaluate.mu_unstable[idx], evaluate.freq_unstable[idx]
        found = np.isfinite(br.hi[idx])
        est = _straddle_root(br.lo[idx], br.g_lo[idx], br.hi[idx], br.g_hi[idx])
        root[idx] = np.where(np.isfinite(est) & (est >= br.lo[idx]) & (est <= br.hi[idx]), est,
                             0.5 * (br.lo[idx] + br.hi[idx]))
        with np.errstate(divide="ignore", invalid="ignore"):
            s = (br.g_hi[idx] - br.g_lo[idx]) / np.log(br.hi[idx] / br.lo[idx])
        slope[idx] = np.where(found & (s > 0.0), s, np.nan)
        kind[idx] = np.where(found, np.where(mu.imag == 0.0, np.where(mu.real < 0, 2, 3), 1), 0)
        lobe[idx] = np.where(found, np.floor(f * evaluate.period_s[idx] + 1e-9), -1).astype(np.int64)

    def same(a: np.ndarray, b: np.ndarray) -> np.ndarray:
        return np.isfinite(br.hi[a]) & np.isfinite(br.hi[b]) & (kind[a] == kind[b]) & (lobe[a] == lobe[b])

    depth_levels = [_levels(g.size) for g in grids]
    total = g0.size
    solved = 0
    for level in range(max(len(lv) for lv in depth_levels)):
        scratch, guided, guess, delta, slopes, ceiling_only = [], [], [], [], [], []
        for grid, lv in zip(grids, depth_levels, strict=True):  # a loop over systems (tools)
            if level >= len(lv):
                continue
            h, pos = lv[level]
            pairs = grid[pos]
            if h == 0:
                scratch.append(pairs)
                continue
            left, right = grid[pos - h], grid[np.minimum(pos + h, grid.size - 1)]
            ok = same(left, right)
            # both neighbours stable up to the ceiling: one evaluation there (stable: no limit either)
            free = ~np.isfinite(br.hi[left]) & ~np.isfinite(br.hi[right])
            ceiling_only.append(pairs[free])
            scratch.append(pairs[~ok & ~free])
            if scan_from_neighbours:
                with np.errstate(invalid="ignore"):
                    near = 0.5 * np.fmin(root[left], root[right])[~ok & ~free]
                    hint[pairs[~ok & ~free]] = np.where(np.isfinite(given[pairs[~ok & ~free]]),
                                                        given[pairs[~ok & ~free]], near)
            pos, pairs, left, right = pos[ok], pairs[ok], left[ok], right[ok]
            bl, bright = np.log(root[left]), np.log(root[right])
            linear = 0.5 * (bl + bright)
            far_l, far_r = pos - 3 * h, pos + 3 * h
            ll, rr = grid[np.clip(far_l, 0, grid.size - 1)], grid[np.clip(far_r, 0, grid.size - 1)]
            cubic_ok = (far_l >= 0) & (far_r <= grid.size - 1) & same(ll, left) & same(rr, right)
            cubic = (9.0 * (bl + bright) - np.log(root[ll]) - np.log(root[rr])) / 16.0
            # half-width: the cubic's error is a small fraction of its distance from the line (measured
            # on RA-1: 3 % at adjacent speeds, 40 % four speeds apart); the line's, of the step
            err = np.where(cubic_ok, (0.1 + 0.1 * h) * np.abs(cubic - linear), 0.75 * np.abs(bl - bright))
            guided.append(pairs)
            sl, sr = slope[left], slope[right]
            consistent = np.maximum(sl, sr) <= _SLOPE_SPREAD * np.minimum(sl, sr)  # NaN: False
            slopes.append(np.where(consistent, np.minimum(sl, sr), np.nan))
            guess.append(np.exp(np.where(cubic_ok, cubic, linear)))
            delta.append(np.minimum(err, _GUIDE_MAX_DELTA))  # the straddles are at least rtol/2.2 wide
        fresh = [np.concatenate(scratch)] if scratch else []
        top = np.concatenate(ceiling_only) if ceiling_only else np.empty(0, dtype=np.int64)
        if top.size:
            g_top = _log_modulus(evaluate(top, ceiling_m[top]))
            stable = g_top < 0.0
            br.lo[top[stable]], br.g_lo[top[stable]], br.hi[top[stable]] = ceiling_m[top[stable]], g_top[stable], np.nan
            fresh.append(top[~stable])
            scratch.append(top)  # settled with the others (no limit, or solved from scratch)
        if guided:
            pairs = np.concatenate(guided)
            fresh.append(_guided(evaluate, pairs, np.concatenate(guess), np.concatenate(delta), br, rtol,
                                 ceiling_m, np.concatenate(slopes)))
        fresh_pairs = np.concatenate(fresh) if fresh else np.empty(0, dtype=np.int64)
        if fresh_pairs.size:
            br.lo[fresh_pairs], br.g_lo[fresh_pairs], br.hi[fresh_pairs] = 0.0, g0[fresh_pairs], np.nan
            hinted = np.isfinite(hint[fresh_pairs]) & (hint[fresh_pairs] > start_m[fresh_pairs])
            plain, hp = fresh_pairs[~hinted], fresh_pairs[hinted]
            _scan(evaluate, plain, br, start_m[plain], ceiling_m[plain])
            if hp.size:
                _scan(evaluate, hp, br, np.minimum(hint[hp], ceiling_m[hp]), ceiling_m[hp])
                low = hp[br.hi[hp] == np.minimum(hint[hp], ceiling_m[hp])]  # unstable at the start: scan below it
                br.lo[low], br.g_lo[low], br.hi[low] = 0.0, g0[low], np.nan
                _scan(evaluate, low, br, start_m[low], np.minimum(hint[low], ceiling_m[low]))
        settled = np.concatenate([*guided, *scratch]) if (guided or scratch) else np.empty(0, dtype=np.int64)
        settle(settled)
        solved += settled.size
        if progress is not None:
            progress(solved, total)
    return br


def _segments(speed: np.ndarray, depth: np.ndarray, kind: np.ndarray, lobe: np.ndarray
              ) -> tuple[list[Lobe], list[str], np.ndarray]:
    ok = np.isfinite(depth)
    key_change = np.ones(speed.size, dtype=bool)
    key_change[1:] = (kind[1:] != kind[:-1]) | (lobe[1:] != lobe[:-1]) | (ok[1:] != ok[:-1])
    starts = np.flatnonzero(key_change)
    ends = np.append(starts[1:], speed.size)
    lobes, kinds, lowest = [], [], []
    for s, e in zip(starts, ends, strict=True):  # a loop over envelope segments
        if not ok[s]:
            continue
        sp, dp = speed[s:e].copy(), depth[s:e].copy()
        sp.flags.writeable = dp.flags.writeable = False
        lobes.append(Lobe(int(lobe[s]), sp, dp))
        kinds.append(str(kind[s]))
        lowest.append(float(sp[np.argmin(dp)]))
    return lobes, kinds, np.array(lowest)


def _check_arguments(teeth: object, kt: float, kr: float, steps: object, speed: np.ndarray) -> None:
    """The scalar rules of :func:`semi_discretization_lobes` (the request parser checks them first)."""
    for field, value, low, high in (("teeth", teeth, 1, None),
                                    ("steps_per_period", steps, MIN_STEPS_PER_PERIOD, _API_MAX_STEPS)):
        if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < low or (
                high is not None and value > high):
            raise InputError(field, f"must be an integer >= {low}" + (f" and <= {high}" if high else "")
                             + f", got {value!r}")
    if not (math.isfinite(kt) and kt > 0):
        raise InputError("tangential_coefficient_n_m2", f"must be finite and > 0, got {kt}")
    if not (math.isfinite(float(kr)) and kr >= 0):
        raise InputError("radial_ratio", f"must be finite and >= 0 (Kr = Kn/Kt), got {kr}")
    if speed.ndim != 1 or speed.size == 0 or not np.all(np.isfinite(speed) & (speed > 0)):
        raise InputError("spindle_speed_rpm", "must be a non-empty 1-D grid of finite speeds > 0 rpm")


def semi_discretization_lobes(
    model: ModalModel,
    *,
    teeth: int,
    tangential_coefficient_n_m2: float,
    radial_ratio: float,
    radial_immersion: float,
    milling: Milling,
    spindle_speed_rpm: np.ndarray,
    steps_per_period: int = DEFAULT_STEPS_PER_PERIOD,
    depth_rtol: float = DEPTH_RTOL,
) -> SemiDiscretizationResult:
    """Depth limit, kind of instability and chatter frequency per speed, by SDM.

    Parameters
    ----------
    model : ModalModel
        Modes in x (feed) and y (normal); cross terms are not modelled.
    teeth : int
        ``N``.
    tangential_coefficient_n_m2 : float
        ``Kt``, N/m².
    radial_ratio : float
        ``Kr = Kn/Kt``.
    radial_immersion : float
        ``a_e/D`` in (0, 1].
    milling : {"up", "down"}
    spindle_speed_rpm : numpy.ndarray, shape (nspeed,)
        Validated speed grid, rpm.
    steps_per_period : int
        ``k``: steps per tooth period (error ∝ 1/k²); 8 … 4000 here, 8 … 200 in requests.
    depth_rtol : float
        Relative width of the final depth bracket.

    Returns
    -------
    SemiDiscretizationResult

    Raises
    ------
    InputError
        An argument out of its range (named as in the request: ``teeth``, ``steps_per_period``, …).

    References
    ----------
    Insperger & Stépán (2004); Insperger, Stépán & Turi (2008) (see module docstring).

    Examples
    --------
    Insperger & Stépán's single-mode benchmark (a/D = 0.05, down-milling): at 18 000 rpm
    the cut becomes unstable by period doubling at 1.3 mm, where ZOA predicts 5 mm:

    >>> m = ModalModel.of([922.0], [0.011], [1 / 0.03993], [0])
    >>> r = semi_discretization_lobes(m, teeth=2, tangential_coefficient_n_m2=6e8,
    ...     radial_ratio=1 / 3, radial_immersion=0.05, milling="down",
    ...     spindle_speed_rpm=np.array([18000.0]))
    >>> str(r.instability[0]), round(float(r.depth_limit_m[0]) * 1e3, 2), round(float(r.chatter_frequency_hz[0]), 6)
    ('flip', 1.31, 900.0)
    """
    return semi_discretization_lobes_many(
        [model], teeth=teeth, tangential_coefficient_n_m2=tangential_coefficient_n_m2, radial_ratio=radial_ratio,
        radial_immersion=radial_immersion, milling=milling, spindle_speed_rpm=[spindle_speed_rpm],
        steps_per_period=steps_per_period, depth_rtol=depth_rtol)[0]


#: :func:`resolving_steps`: steps per cycle of the chatter it aims at, and the largest step
#: count it gives.
RESOLVING_STEPS_PER_CYCLE = 10.0
MAX_RESOLVING_STEPS = 320


def resolving_steps(model: ModalModel, teeth: int, spindle_speed_rpm: np.ndarray, *,
                    chatter_frequency_hz: np.ndarray | None = None,
                    steps_per_cycle: float = RESOLVING_STEPS_PER_CYCLE,
                    max_steps: int = MAX_RESOLVING_STEPS) -> np.ndarray:
    """Steps per tooth period that resolve the chatter at each speed: a band per speed.

    Chatter lies a little above a natural frequency: without ``chatter_frequency_hz`` the
    highest natural frequency of the model (×1.2) sets the vibration cycles per tooth period
    ``c``. Not the mode with the largest peak: a weaker, higher mode can govern a pocket of the
    strongest one (a single flute at half immersion chatters at a 6.2 kHz tool mode of 0.6 × the
    largest peak, 4.1 mm deep, where steps resolving only the 635 Hz mode saw 12 mm — too few
    steps per cycle hide a mode's instability instead of flagging it), and every mode of a
    :class:`ModalModel` fitted to an FRF has a peak of at least
    ``rcsa.analysis.lobes.modal_model.MIN_PEAK_FRACTION`` of the largest. With
    ``chatter_frequency_hz`` (e.g. from an under-resolved first solve) the larger of that
    frequency and the highest mode does. The steps are
    ``steps_per_cycle · c`` rounded up to a multiple of 20, between
    ``DEFAULT_STEPS_PER_PERIOD`` and ``max_steps`` (speeds needing more keep ``max_steps`` and
    are flagged by ``steps_per_chatter_cycle``). First-order SDM errs by about 2 % at 12 steps
    per chatter cycle (module docstring); few bands keep the batches large.

    Examples
    --------
    >>> m = ModalModel.of([1400.0, 4000.0], [0.02, 0.03], [1.0, 0.5], [0, 0])
    >>> resolving_steps(m, 1, np.array([3000.0, 12000.0, 24000.0])).tolist()
    [320, 240, 120]
    >>> resolving_steps(m, 1, np.array([24000.0]), chatter_frequency_hz=np.array([5100.0])).tolist()
    [140]
    """
    speed = np.asarray(spindle_speed_rpm, dtype=float)
    f_top = np.full(speed.shape, 1.2 * float(np.max(np.asarray(model.frequency_hz, dtype=float))))
    if chatter_frequency_hz is not None:
        f_top = np.maximum(f_top, np.where(np.isfinite(chatter_frequency_hz), chatter_frequency_hz, 0.0))
    cycles = f_top * 60.0 / (teeth * speed)
    k = np.ceil(steps_per_cycle * cycles / 20.0) * 20
    return np.clip(k, DEFAULT_STEPS_PER_PERIOD, max_steps).astype(np.int64)


#: What :func:`semi_discretization_lobes_many` shares across its models (one cut).
MANY_FIELDS = ("teeth", "tangential_coefficient_n_m2", "radial_ratio", "radial_immersion", "milling",
               "steps_per_period")


def semi_discretization_lobes_many(
    models: Sequence[ModalModel],
    *,
    teeth: int,
    tangential_coefficient_n_m2: float,
    radial_ratio: float,
    radial_immersion: float,
    milling: Milling,
    spindle_speed_rpm: Sequence[np.ndarray],
    steps_per_period: int | Sequence[np.ndarray] = DEFAULT_STEPS_PER_PERIOD,
    depth_rtol: float = DEPTH_RTOL,
    progress: Callable[[int, int], None] | None = None,
    min_depth_search_max_m: Sequence[float] | None = None,
    scan_from_neighbours: bool = False,
    scan_start_m: Sequence[np.ndarray] | None = None,
) -> list[SemiDiscretizationResult]:
    """SDM lobes of several modal models (tools) in one cut, solved together.

    Every (model, speed) pair is one member of the same batches of period maps, so a whole
    tool library costs a few dozen vectorised passes rather than one search per tool; the
    result of each model is the one :func:`semi_discretization_lobes` gives for it alone (the
    same search, the same brackets).

    Parameters
    ----------
    models : sequence of ModalModel
        The tools' modes (any numbers of modes: smaller models are padded with inert modes,
        :func:`~rcsa.analysis.lobes.monodromy.state_spaces`).
    teeth, tangential_coefficient_n_m2, radial_ratio, radial_immersion, milling, depth_rtol
        As in :func:`semi_discretization_lobes` (the same for every model).
    steps_per_period : int or sequence of numpy.ndarray
        One step count for all, or one per speed of each model (:func:`resolving_steps`): the
        speeds of each step count are solved as one band; a result's ``steps_per_period`` is
        then its largest.
    spindle_speed_rpm : sequence of numpy.ndarray
        One speed grid (rpm) per model.
    progress : callable, optional
        ``progress(done, total)`` after each level of the coarse-to-fine search.
    min_depth_search_max_m : sequence of float, optional
        Per model, search at least this deep (m): the ceiling is ``max(64 b_ref, this)``,
        so a NaN limit then says "stable up to at least this depth" (a preset capped at the
        flute length needs the search to reach it).
    scan_from_neighbours : bool
        A screening search: a finer speed solved from scratch starts its scan at half the
        smaller limit of its two solved neighbours instead of a quarter of the ZOA absolute
        limit (when unstable there, it scans up to that depth from the usual start). Fewer
        evaluations; an unstable band entirely below half the neighbours' limits is missed.
    scan_start_m : sequence of numpy.ndarray, optional
        Per model, per speed: where a speed solved from scratch starts its scan (m; NaN or
        below the usual start: the usual start), e.g. half a limit known from a coarser
        solution; the same caveat.

    Returns
    -------
    list of SemiDiscretizationResult
        One per model, in order.

    Raises
    ------
    InputError
        As :func:`semi_discretization_lobes`; ``spindle_speed_rpm`` not one grid per model.

    Examples
    --------
    >>> a = ModalModel.of([922.0], [0.011], [1 / 0.03993], [0])
    >>> b = ModalModel.of([922.0, 1500.0], [0.011, 0.02], [1 / 0.03993, 5.0], [0, 1])
    >>> ra, rb = semi_discretization_lobes_many([a, b], teeth=2, tangential_coefficient_n_m2=6e8,
    ...     radial_ratio=1 / 3, radial_immersion=0.05, milling="down",
    ...     spindle_speed_rpm=[np.array([18000.0]), np.array([18000.0])])
    >>> round(float(ra.depth_limit_m[0]) * 1e3, 2), str(rb.instability[0])
    (1.31, 'flip')
    """
    if len(spindle_speed_rpm) != len(models) or not models:
        raise InputError("spindle_speed_rpm", f"give one speed grid per model ({len(models)}), got "
                                              f"{len(spindle_speed_rpm)}")
    kt = float(tangential_coefficient_n_m2)
    speeds = [np.array(s, dtype=float) for s in spindle_speed_rpm]  # copies: the results freeze their arrays
    per_speed = not isinstance(steps_per_period, (int, np.integer))
    steps = ([np.asarray(k) for k in steps_per_period] if per_speed  # type: ignore[union-attr]
             else [np.full(s.size, steps_per_period) for s in speeds])
    if len(steps) != len(models) or any(k.shape != s.shape for k, s in zip(steps, speeds, strict=True)):
        raise InputError("steps_per_period", "give one step count per speed of each model, or one for all")
    for speed, k in zip(speeds, steps, strict=True):
        for value in np.unique(k) if k.size else [DEFAULT_STEPS_PER_PERIOD]:
            _check_arguments(teeth, kt, radial_ratio, value.item() if isinstance(value, np.generic) else value,
                             speed)
    phi_st, phi_ex = engagement_angles_rad(radial_immersion, milling)
    alpha = directional_factors(phi_st, phi_ex, radial_ratio)
    b_ref = np.array([_reference_depth(m, teeth, kt, alpha) for m in models])
    ceiling = _SCAN_CEILING * b_ref
    if min_depth_search_max_m is not None:
        floor = np.asarray(min_depth_search_max_m, dtype=float)
        if floor.shape != b_ref.shape or not np.all(np.isfinite(floor)):
            raise InputError("min_depth_search_max_m", "give one finite depth (m) per model")
        ceiling = np.maximum(ceiling, floor)
    starts = ([np.asarray(x, dtype=float) for x in scan_start_m] if scan_start_m is not None
              else [np.full(s.size, np.nan) for s in speeds])
    if len(starts) != len(speeds) or any(x.shape != sp.shape for x, sp in zip(starts, speeds, strict=True)):
        raise InputError("scan_start_m", "give one start depth per speed of each model")
    fields = [{name: np.full(s.size, fill, dtype=dtype) for name, fill, dtype in _FIELDS} for s in speeds]
    bands = sorted({int(k) for ks in steps for k in ks})
    done = 0
    total = sum(s.size for s in speeds)
    for k in bands:  # one search per step count (a few bands)
        members = [i for i in range(len(models)) if np.any(steps[i] == k)]
        picks = [np.flatnonzero(steps[i] == k) for i in members]

        def band_progress(part: int, _total: int, base: int = done) -> None:
            if progress is not None:
                progress(base + part, total)

        solved = _solve_band([models[i] for i in members], [speeds[i][p] for i, p in zip(members, picks, strict=True)],
                             k, teeth, kt, radial_ratio, phi_st, phi_ex, b_ref[members], ceiling[members], depth_rtol,
                             band_progress, scan_from_neighbours,
                             np.concatenate([starts[i][p] for i, p in zip(members, picks, strict=True)]))
        for i, p, part in zip(members, picks, solved, strict=True):
            for name, values in part.items():
                fields[i][name][p] = values
        done += sum(p.size for p in picks)
    return [_result(models[i], speeds[i], fields[i], steps[i], teeth, float(ceiling[i])) for i in range(len(models))]


# Per-speed arrays of a result: name, fill value, dtype.
_FIELDS = (("depth", np.nan, float), ("mu", np.nan + 0j, complex), ("freq", np.nan, float), ("kind", "", "<U4"),
           ("lobe", -1, np.int64), ("cycles", np.nan, float))


def _solve_band(models: Sequence[ModalModel], speeds: Sequence[np.ndarray], steps: int, teeth: int, kt: float,
                kr: float, phi_st: float, phi_ex: float, b_ref: np.ndarray, ceiling: np.ndarray, rtol: float,
                progress: Callable[[int, int], None] | None,
                scan_from_neighbours: bool = False, scan_start_m: np.ndarray | None = None) -> list[dict[str, np.ndarray]]:
    """The search (:func:`_search`) for the given models and speeds at one step count; per-speed arrays."""
    plan = md.cutting_plan(teeth, steps, phi_st, phi_ex, kr)
    sizes = np.array([s.size for s in speeds])
    system_of_pair = np.repeat(np.arange(len(models)), sizes)
    speed = np.concatenate(speeds)
    period = 60.0 / (teeth * speed)
    systems = md.state_space(models[0]) if len(models) == 1 else md.state_spaces(models)
    evaluate = _Evaluator(systems, system_of_pair if len(models) > 1 else np.zeros(speed.size, dtype=np.int64),
                          plan, kt, period)
    slowest = np.array([np.min(m.damping_ratio * 2 * np.pi * m.frequency_hz) for m in models])
    g0 = -slowest[system_of_pair] * period  # log|μ| at b = 0 (exact)
    offsets = np.concatenate([[0], np.cumsum(sizes)])
    grids = [np.arange(offsets[i], offsets[i + 1]) for i in range(len(models))]
    br = _search(evaluate, grids, g0, (_SCAN_START * b_ref)[system_of_pair], ceiling[system_of_pair], rtol, progress,
                 scan_from_neighbours, scan_start_m)
    found = np.isfinite(br.hi)
    depth = np.where(found, br.lo, np.nan)
    mu = np.where(found, evaluate.mu_unstable, np.nan + 0j)
    freq = np.where(found, evaluate.freq_unstable, np.nan)
    real = mu.imag == 0.0
    kind = np.where(found, np.where(real, np.where(mu.real < 0, "flip", "fold"), "hopf"), "").astype("<U4")
    lobe = np.where(np.isfinite(freq), np.floor(freq * period + 1e-9), -1).astype(np.int64)
    with np.errstate(divide="ignore", invalid="ignore"):  # a fold at 0 Hz is resolved by any step
        cycles = steps / (freq * period)
    return [{"depth": depth[a:b], "mu": mu[a:b], "freq": freq[a:b], "kind": kind[a:b], "lobe": lobe[a:b],
             "cycles": cycles[a:b]} for a, b in zip(offsets[:-1], offsets[1:], strict=True)]


def _result(model: ModalModel, speed: np.ndarray, f: dict[str, np.ndarray], steps: np.ndarray, teeth: int,
            ceiling: float) -> SemiDiscretizationResult:
    depth, mu, freq, kind, lobe, cycles = (f[k] for k in ("depth", "mu", "freq", "kind", "lobe", "cycles"))
    top_cycles = 1.2 * float(np.max(model.frequency_hz)) * 60.0 / (teeth * speed)  # per tooth period
    lobes, kinds, lowest = _segments(speed, depth, kind, lobe)
    found = np.isfinite(depth)
    best = int(np.nanargmin(depth)) if found.any() else -1
    return SemiDiscretizationResult(
        spindle_speed_rpm=speed,
        depth_limit_m=depth,
        chatter_frequency_hz=freq,
        governing_lobe=lobe,
        lobes=tuple(lobes),
        same_frf_in_y=model.same_in_y,
        min_depth_limit_m=float(depth[best]) if best >= 0 else math.nan,
        min_depth_chatter_frequency_hz=float(freq[best]) if best >= 0 else math.nan,
        min_depth_spindle_speed_rpm=lowest,
        instability=kind,
        critical_multiplier=mu,
        lobe_kinds=tuple(kinds),
        steps_per_period=int(steps.max()) if steps.size else DEFAULT_STEPS_PER_PERIOD,
        steps_per_chatter_cycle=cycles,
        depth_search_max_m=ceiling,
        modal_model=model,
        top_mode_steps_per_cycle=steps / top_cycles,
    )
