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
    "CUT_WINDOW",
    "DEFAULT_STEPS_PER_PERIOD",
    "DiagramsSolver",
    "FULL_PERIOD",
    "MANY_FIELDS",
    "MAX_REFINEMENTS",
    "MAX_STEPS_PER_PERIOD",
    "MIN_CUT_STEPS",
    "MIN_PERIOD_STEPS",
    "MIN_STEPS_PER_PERIOD",
    "RESOLVED_RTOL",
    "RESOLVING_STEPS_PER_CYCLE",
    "SemiDiscretizationResult",
    "band_steps",
    "cut_scheme",
    "merged_result",
    "resolving_steps",
    "semi_discretization_lobes",
    "semi_discretization_lobes_many",
    "solve_diagrams_here",
    "speed_costs",
    "speed_parts",
    "stable_at_depth_many",
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

#: Automatic steps (:func:`resolving_steps`): this many steps per cycle of a vibration just above
#: the highest natural frequency kept (``1.2 f_top``), over the time in the cut (cut-window scheme)
#: or the tooth period (full-period scheme). First-order semi-discretization over-estimates the
#: limit by about ``C/s²`` (s steps per cycle): 3–5 % at 10 where that mode governs the cut, 1–1.4 %
#: at 20, 0.4–0.7 % at 28 (measured against 40–60 steps a cycle on single-flute and
#: Insperger–Stépán cuts; docs/lobes.md "Resolution"), far less where a lower mode governs. Every speed is
#: checked at ``1/√2`` of its steps and refined where the two differ by more than
#: ``RESOLVED_RTOL``, so the steps start where they usually suffice and grow only where needed.
RESOLVING_STEPS_PER_CYCLE = 10.0
#: Fewest steps over the cut (cut-window scheme) and over the period (full-period scheme).
MIN_CUT_STEPS = 16
MIN_PERIOD_STEPS = DEFAULT_STEPS_PER_PERIOD
#: Step counts are rounded up to ``⌈least · 2^(j/4)⌉`` (four per octave) so that speeds share
#: batches; the convergence check takes the count two places below (``1/√2`` of the steps).
_BANDS_PER_OCTAVE = 4
_CHECK_BANDS = 2
#: A speed is resolved when the limit with ``1/√2`` of its steps lies within this relative
#: distance of its own (first-order error ∝ h²: the difference then equals the error of the
#: finer answer, so the answer is within about this of the converged one).
RESOLVED_RTOL = 0.01
#: Unresolved speeds are solved again with √2 times the steps (compared with the answer before),
#: at most this many times.
MAX_REFINEMENTS = 3
#: Schemes of the period map.
CUT_WINDOW, FULL_PERIOD = "cut_window", "full_period"


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
        The largest step count used (over the cut for ``scheme == "cut_window"``).
    steps_per_chatter_cycle : numpy.ndarray, shape (nspeed,)
        ``1 / (f_c h)``: how finely the steps sample the chatter (``h``: one step, s).
    depth_search_max_m : float
        Ceiling of the depth search, m.
    modal_model : ModalModel
        The modes the map was built from (with their source and fit report).
    top_mode_steps_per_cycle : numpy.ndarray, shape (nspeed,)
        ``1 / (1.2 f_top h)``: how finely the steps sample a vibration just above the model's
        highest mode ``f_top``. Below ``MIN_STEPS_PER_CHATTER_CYCLE`` an instability of that
        mode can be missed altogether (too coarse a discretisation damps it), so such speeds
        are noted even where the limit found looks resolved.
    scheme : {"cut_window", "full_period"}
        What the steps discretise: the time in the cut (the free flight one exact step) or
        the whole tooth period.
    steps : numpy.ndarray of int, shape (nspeed,)
        Steps of each speed's answer.
    check_steps : numpy.ndarray of int, shape (nspeed,)
        Steps of the second resolution it was compared with (0: not checked).
    resolved : numpy.ndarray of bool, shape (nspeed,)
        The limits at ``steps`` and ``check_steps`` agree within ``RESOLVED_RTOL`` (both
        without a limit below the search ceiling counts as agreeing).
    """

    instability: np.ndarray
    critical_multiplier: np.ndarray
    lobe_kinds: tuple[str, ...]
    steps_per_period: int
    steps_per_chatter_cycle: np.ndarray
    depth_search_max_m: float
    modal_model: ModalModel
    top_mode_steps_per_cycle: np.ndarray
    scheme: str
    steps: np.ndarray
    check_steps: np.ndarray
    resolved: np.ndarray

    def __post_init__(self) -> None:
        LobeResult.__post_init__(self)
        for name in ("instability", "critical_multiplier", "steps_per_chatter_cycle", "top_mode_steps_per_cycle",
                     "steps", "check_steps", "resolved"):
            getattr(self, name).flags.writeable = False

    @property
    def under_resolved(self) -> np.ndarray:
        """Speeds whose limit is not resolved (``~resolved``)."""
        return np.asarray(~self.resolved)

    def to_dict(self) -> dict[str, Any]:
        """The contract's response (as :meth:`LobeResult.to_dict`) plus the SDM's fields.

        Added: ``method`` (``"semi_discretization"``), ``instability`` (per speed, null
        where none), ``critical_multiplier`` (``{"real", "imag"}``), ``kind`` on every lobe,
        ``resolved`` (per speed), ``discretization`` (``scheme``, per-speed ``steps`` and
        ``check_steps``, ``resolved_rtol``), ``steps_per_period`` (the largest step count),
        ``steps_per_chatter_cycle``, ``depth_search_max_m``, ``modal_model``
        (:meth:`ModalModel.to_dict`) and ``notes`` (unresolved speeds, modes left out).
        """
        out = LobeResult.to_dict(self)
        for lobe, kind in zip(out["lobes"], self.lobe_kinds, strict=True):
            lobe["kind"] = kind
        mu = self.critical_multiplier
        out.update(
            method="semi_discretization",
            instability=[str(k) if k else None for k in self.instability.tolist()],
            critical_multiplier=complex_to_wire(mu, nonfinite_as_none=True),
            resolved=[bool(v) for v in self.resolved.tolist()],
            discretization={"scheme": self.scheme, "steps": [int(v) for v in self.steps.tolist()],
                            "check_steps": [int(v) for v in self.check_steps.tolist()],
                            "resolved_rtol": RESOLVED_RTOL},
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
        checked = self.check_steps > 0
        bad = self.spindle_speed_rpm[~self.resolved & checked]
        if bad.size:
            out.append(f"{bad.size} speed(s) between {bad.min():.0f} and {bad.max():.0f} rpm are not resolved: their "
                       f"limits at two resolutions differ by more than {RESOLVED_RTOL:.0%} (marked resolved: false; "
                       "do not choose a depth there from this answer)")
        unchecked = self.spindle_speed_rpm[~checked]
        if unchecked.size:
            out.append(f"{unchecked.size} speed(s) were not checked at a second resolution (a screening pass)")
        coarse = self.spindle_speed_rpm[(self.top_mode_steps_per_cycle < MIN_STEPS_PER_CHATTER_CYCLE)]
        if coarse.size:
            f_top = float(np.max(self.modal_model.frequency_hz))
            out.append(f"{coarse.size} speed(s) between {coarse.min():.0f} and {coarse.max():.0f} rpm sample "
                       f"a vibration of the highest mode ({f_top:.0f} Hz) with fewer than "
                       f"{MIN_STEPS_PER_CHATTER_CYCLE:g} steps per cycle: an instability of that mode can be "
                       f"missed there (leave steps_per_period out: the steps are then chosen to resolve it)")
        out.extend(self.modal_model.notes())
        return out


# --------------------------------------------------------------------------- search


class _Evaluator:
    """Largest multiplier of the period map for batches of (pair, depth); a pair is one speed
    of one system (tool), with its own step count ``steps``. Full-period pairs of one count share
    a plan; cut-window pairs whose counts lie within a factor ``_PAD_RATIO`` are solved as one
    padded plan (:func:`~rcsa.analysis.lobes.monodromy.padded_cut_window`: exactly each pair's
    own multipliers, far fewer passes over the steps); chunks are bounded in memory. Every
    unstable evaluation also records its chatter frequency, so the critical multiplier and
    frequency at the final unstable end of each bracket are known when the search ends (no
    extra evaluation)."""

    def __init__(self, systems: md.StateSpace, system_of_pair: np.ndarray, cut: _Cut, steps: np.ndarray,
                 period_s: np.ndarray) -> None:
        self.systems = systems
        self.system_of_pair = system_of_pair
        self.cut = cut
        self.kt = cut.kt
        self.period_s = period_s
        self.steps = np.asarray(steps, dtype=np.int64)
        self.plans = {int(k): cut.plan(int(k)) for k in np.unique(self.steps)}
        self.step_s = period_s * np.array([self.plans[int(k)].step_fraction for k in self.steps])
        self._free: dict[int, tuple[np.ndarray, np.ndarray, np.ndarray]] = {}
        self.mu_unstable = np.full(period_s.size, np.nan + 0j)
        self.freq_unstable = np.full(period_s.size, np.nan)
        self.evaluations = 0

    def _system(self, idx: np.ndarray) -> md.StateSpace:
        return self.systems.take(self.system_of_pair[idx])

    def _free_maps(self, key: int, idx: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The depth-free exponentials of the pairs ``idx``, computed once per pair: the free
        flight (cut window: ``key = 0``, the same for every step count) or the free stretches of
        the full-period plan of ``key`` steps."""
        if key not in self._free:
            pairs = np.arange(self.steps.size) if key == 0 else np.flatnonzero(self.steps == key)
            where = np.full(self.steps.size, -1)
            where[pairs] = np.arange(pairs.size)
            parts = []
            for lo in range(0, pairs.size, _CHUNK):  # bounded batches of exponentials
                sel = pairs[lo : lo + _CHUNK]
                if key == 0:
                    plan = self.plans[int(self.steps[sel[0]])]
                    seconds = self.period_s[sel] * (1.0 - plan.step_fraction * (plan.steps - 1))
                    parts.append(md.free_maps(self._system(sel), plan, seconds / plan.free_length[0]))
                else:
                    parts.append(md.free_maps(self._system(sel), self.plans[key], self.step_s[sel]))
            self._free[key] = (where, np.concatenate([p[0] for p in parts]), np.concatenate([p[1] for p in parts]))
        where, free, step = self._free[key]
        return free[where[idx]], step[where[idx]]

    def _groups(self, idx: np.ndarray) -> list[np.ndarray]:
        """Rows of ``idx`` solved together: one step count (full period), or counts within
        ``_PAD_RATIO`` (cut window), each group split into memory-bounded chunks."""
        steps = self.steps[idx]
        out = []
        if self.cut.scheme == CUT_WINDOW:
            order = np.argsort(steps, kind="stable")
            start = 0
            while start < order.size:
                end = int(np.searchsorted(steps[order], _PAD_RATIO * steps[order[start]], side="right"))
                chunk = _chunk_size(self.systems.n, self.plans[int(steps[order[end - 1]])])
                end = min(end, start + chunk)
                out.append(order[start:end])
                start = end
            return out
        for k in np.unique(steps):  # pairs of one step count share a plan
            rows = np.flatnonzero(steps == k)
            chunk = _chunk_size(self.systems.n, self.plans[int(k)])
            out.extend(rows[lo : lo + chunk] for lo in range(0, rows.size, chunk))
        return out

    def maps(self, idx: np.ndarray, depth_m: np.ndarray) -> tuple[md.CuttingPlan, md.PeriodMaps]:
        """The plan and period maps of the pairs ``idx`` (one group of :meth:`_groups`) at ``depth_m``."""
        steps = self.steps[idx]
        if self.cut.scheme == CUT_WINDOW:
            plan, force, frac = md.padded_cut_window(self.cut.teeth, steps, self.cut.phi_st, self.cut.phi_ex,
                                                     self.cut.kr)
            return plan, md.period_maps(self._system(idx), plan, self.kt, self.period_s[idx, None] * frac, depth_m,
                                        self._free_maps(0, idx), force=force, active=steps)
        k = int(steps[0])
        return self.plans[k], md.period_maps(self._system(idx), self.plans[k], self.kt, self.step_s[idx], depth_m,
                                             self._free_maps(k, idx))

    def __call__(self, idx: np.ndarray, depth_m: np.ndarray, record_stable: bool = False) -> np.ndarray:
        """``μ`` of each (pair, depth); ``record_stable``: stable evaluations record theirs too
        (moved onto the unit circle: the estimate of the crossing multiplier for a limit closed
        from its stable side; used on pairs not evaluated before)."""
        check_time()  # every round of evaluations: a sync request's time limit stops the search
        self.evaluations += idx.size
        mu = np.empty(idx.size, dtype=complex)
        for rows in self._groups(idx):
            mu[rows] = self._chunk(idx[rows], depth_m[rows], record_stable)
        return mu

    def _chunk(self, idx: np.ndarray, depth_m: np.ndarray, record_stable: bool) -> np.ndarray:
        system = self._system(idx)
        plan, maps = self.maps(idx, depth_m)
        mu, vec = md.critical_multipliers(system, plan, maps, vectors=True if record_stable else "unstable")
        assert vec is not None
        up = np.abs(mu) >= 1.0
        keep = np.flatnonzero(up | record_stable)
        if keep.size:
            on_circle = np.where(mu[keep].imag == 0.0, np.sign(mu[keep].real) + 0j, np.exp(1j * np.angle(mu[keep])))
            self.mu_unstable[idx[keep]] = np.where(up[keep], mu[keep], on_circle)
            self.freq_unstable[idx[keep]] = md.chatter_frequency(system.take(keep), plan, maps.take(keep), mu[keep],
                                                               vec[keep], self.period_s[idx[keep]])
        return mu


#: Cut-window pairs whose step counts differ by at most this factor are padded to one plan.
_PAD_RATIO = 1.6


#: Working memory of one chunk of evaluations, bytes (the period maps, the Krylov basis, and the
#: monodromy matrices where they are formed).
_CHUNK_BYTES = 96 * 2**20


def _chunk_size(n: int, plan: md.CuttingPlan) -> int:
    """Pairs evaluated together: at most ``_CHUNK``, and within ``_CHUNK_BYTES``."""
    size = n + 2 * plan.n_samples
    ncut = plan.cut_step.size
    per_pair = 8 * (ncut * n * (n + 4) + 2 * size * (md.KRYLOV_DIM + n + md.KRYLOV_EXTRA) + plan.steps * n * 2)
    if size <= md.DENSE_MAX_SIZE or not md.matrix_free_cheaper(n, plan):
        per_pair += 8 * size * size * 2
    return int(max(1, min(_CHUNK, _CHUNK_BYTES // per_pair)))


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
    grid = model.frf_grid()
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
    rules = [("teeth", teeth, 1, None)]
    if steps is not None:
        rules.append(("steps_per_period", steps, MIN_STEPS_PER_PERIOD, _API_MAX_STEPS))
    for field, value, low, high in rules:
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
    steps_per_period: int | None = None,
    depth_rtol: float = DEPTH_RTOL,
    steps_per_cycle: float | None = None,
    refinements: int = MAX_REFINEMENTS,
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
    steps_per_period : int, optional
        Fixed steps per tooth period, over the whole period (error ∝ 1/k²; 8 … 4000 here,
        8 … 200 in requests); each speed is still checked (``resolved``) but never refined.
        None (default): the steps resolve the cut (:func:`resolving_steps`), each speed is
        checked and, where unresolved, solved again with more steps
        (:func:`semi_discretization_lobes_many`).
    depth_rtol : float
        Relative width of the final depth bracket.
    steps_per_cycle, refinements
        The automatic steps' resolution and the refinements allowed (as in
        :func:`semi_discretization_lobes_many`).

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
    ('flip', 1.3, 900.0)
    >>> r.scheme, bool(r.resolved[0]), int(r.steps[0])
    ('cut_window', True, 16)
    """
    return semi_discretization_lobes_many(
        [model], teeth=teeth, tangential_coefficient_n_m2=tangential_coefficient_n_m2, radial_ratio=radial_ratio,
        radial_immersion=radial_immersion, milling=milling, spindle_speed_rpm=[spindle_speed_rpm],
        steps_per_period=steps_per_period, depth_rtol=depth_rtol, steps_per_cycle=steps_per_cycle,
        refinements=refinements)[0]




def cut_scheme(teeth: int, radial_immersion: float, milling: Milling) -> tuple[str, float]:
    """The scheme for a cut and the share of the tooth period in the cut.

    Fewer than one tooth in the cut (``N (φex − φst)/2π < 1``): ``"cut_window"`` — only the time
    in the cut is discretised (:func:`~rcsa.analysis.lobes.monodromy.cut_window_plan`); else
    ``"full_period"`` (:func:`~rcsa.analysis.lobes.monodromy.cutting_plan`).

    Examples
    --------
    >>> cut_scheme(1, 0.05, "down")[0], cut_scheme(4, 0.5, "down")
    ('cut_window', ('full_period', 1.0))
    """
    phi_st, phi_ex = engagement_angles_rad(radial_immersion, milling)
    fraction = md.cut_window_fraction(teeth, phi_st, phi_ex)
    if fraction < 1.0 - 1e-9:
        return CUT_WINDOW, fraction
    return FULL_PERIOD, 1.0


def band_steps(band: np.ndarray | int, least: int) -> np.ndarray:
    """Step count of band ``j``: ``⌈least · 2^(j/4)⌉`` (``j`` may be negative; at least 4).

    Examples
    --------
    >>> band_steps(np.array([-2, 0, 1, 2, 4]), 16).tolist()
    [12, 16, 20, 23, 32]
    """
    j = np.asarray(band, dtype=float)
    return np.maximum(np.ceil(least * 2.0 ** (j / _BANDS_PER_OCTAVE) - 1e-9), 4).astype(np.int64)


def _band_of(steps: np.ndarray, least: int) -> np.ndarray:
    """The smallest band whose step count is at least ``steps`` (and at least band 0)."""
    j = np.ceil(_BANDS_PER_OCTAVE * np.log2(np.maximum(steps, least) / least) - 1e-9).astype(np.int64)
    return np.where(band_steps(j - 1, least) >= steps, j - 1, j).clip(0)


def resolving_steps(model: ModalModel, teeth: int, spindle_speed_rpm: np.ndarray, *, radial_immersion: float = 1.0,
                    milling: Milling = "down", steps_per_cycle: float = RESOLVING_STEPS_PER_CYCLE,
                    chatter_frequency_hz: np.ndarray | None = None) -> np.ndarray:
    """Steps that resolve the cut at each speed (over the cut, or over the period: :func:`cut_scheme`).

    A vibration just above the highest natural frequency of the model (``1.2 f_top``; with
    ``chatter_frequency_hz``, the larger of the two) goes through ``c`` cycles in the time the
    scheme discretises (the time in the cut, or the tooth period); the steps are
    ``steps_per_cycle · c`` rounded up to a band (:func:`band_steps`), at least
    ``MIN_CUT_STEPS`` / ``MIN_PERIOD_STEPS``. There is no upper cap: the cost is bounded by the
    caller's budget (``rcsa.app.budget``), never by quietly fewer steps. Not the mode with the
    largest peak: a weaker, higher mode can govern a pocket of the strongest one (a single flute
    at half immersion chatters at a 6.2 kHz tool mode of 0.6 × the largest peak, 4.1 mm deep,
    where steps resolving only the 635 Hz mode saw 12 mm).

    Examples
    --------
    >>> m = ModalModel.of([1400.0, 4000.0], [0.02, 0.03], [1.0, 0.5], [0, 0])
    >>> resolving_steps(m, 1, np.array([3000.0, 12000.0, 24000.0]), radial_immersion=0.05).tolist()
    [77, 20, 16]
    >>> resolving_steps(m, 4, np.array([3000.0, 24000.0]), radial_immersion=0.5).tolist()
    [270, 40]
    """
    speed = np.asarray(spindle_speed_rpm, dtype=float)
    scheme, fraction = cut_scheme(teeth, radial_immersion, milling)
    f_top = np.full(speed.shape, 1.2 * float(np.max(np.asarray(model.frequency_hz, dtype=float))))
    if chatter_frequency_hz is not None:
        f_top = np.maximum(f_top, np.where(np.isfinite(chatter_frequency_hz), chatter_frequency_hz, 0.0))
    cycles = f_top * fraction * 60.0 / (teeth * speed)
    least = MIN_CUT_STEPS if scheme == CUT_WINDOW else MIN_PERIOD_STEPS
    return band_steps(_band_of(np.ceil(steps_per_cycle * cycles), least), least)


#: What :func:`semi_discretization_lobes_many` shares across its models (one cut).
MANY_FIELDS = ("teeth", "tangential_coefficient_n_m2", "radial_ratio", "radial_immersion", "milling")


@dataclass(frozen=True)
class _Cut:
    """One cut (shared by every model of a call)."""

    teeth: int
    kt: float
    kr: float
    phi_st: float
    phi_ex: float
    scheme: str

    def plan(self, steps: int) -> md.CuttingPlan:
        if self.scheme == CUT_WINDOW:
            return md.cut_window_plan(self.teeth, steps, self.phi_st, self.phi_ex, self.kr)
        return md.cutting_plan(self.teeth, steps, self.phi_st, self.phi_ex, self.kr)


def semi_discretization_lobes_many(
    models: Sequence[ModalModel],
    *,
    teeth: int,
    tangential_coefficient_n_m2: float,
    radial_ratio: float,
    radial_immersion: float,
    milling: Milling,
    spindle_speed_rpm: Sequence[np.ndarray],
    steps_per_period: int | Sequence[np.ndarray] | None = None,
    depth_rtol: float = DEPTH_RTOL,
    progress: Callable[[int, int], None] | None = None,
    min_depth_search_max_m: Sequence[float] | None = None,
    scan_from_neighbours: bool = False,
    scan_start_m: Sequence[np.ndarray] | None = None,
    steps_per_cycle: float | None = None,
    refinements: int = MAX_REFINEMENTS,
    check: bool = True,
) -> list[SemiDiscretizationResult]:
    """SDM lobes of several modal models (tools) in one cut, solved together.

    Every (model, speed) pair is one member of the same batches of period maps, so a whole
    tool library costs a few dozen vectorised passes rather than one search per tool; the
    result of each model is the one :func:`semi_discretization_lobes` gives for it alone (the
    same search, the same brackets).

    **Resolution.** By default (``steps_per_period=None``) each speed gets the steps that
    resolve its cut (:func:`resolving_steps`, the scheme of :func:`cut_scheme`), and is then
    *checked*: its limit is solved again — two evaluations around it — with ``1/√2`` of the
    steps. Where the two lie within ``RESOLVED_RTOL`` the speed is ``resolved``. Where not, it is
    solved again with ``√2`` times the steps and compared with the answer before, up to
    ``refinements`` times; a speed still apart is reported with its finest answer and
    ``resolved = False`` (said in the notes). A speed without a limit below the search ceiling is
    resolved when the check finds it stable there too.

    Parameters
    ----------
    models : sequence of ModalModel
        The tools' modes (any numbers of modes: models of one size are solved together, each
        size on its own; :func:`~rcsa.analysis.lobes.monodromy.state_spaces` pads smaller
        models with inert modes where a caller stacks them).
    teeth, tangential_coefficient_n_m2, radial_ratio, radial_immersion, milling, depth_rtol
        As in :func:`semi_discretization_lobes` (the same for every model).
    spindle_speed_rpm : sequence of numpy.ndarray
        One speed grid (rpm) per model.
    steps_per_period : int or sequence of numpy.ndarray, optional
        Fixed steps per tooth period over the whole period (the full-period scheme), one for all
        or one per speed of each model: checked, never refined. None: automatic (above).
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
    steps_per_cycle : float, optional
        Automatic steps' resolution (default ``RESOLVING_STEPS_PER_CYCLE``).
    refinements : int
        Refinements allowed per speed (automatic steps only).
    check : bool
        Check each speed's resolution (False: a screening pass; ``resolved`` is then False).

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
    (1.3, 'flip')
    """
    if len(spindle_speed_rpm) != len(models) or not models:
        raise InputError("spindle_speed_rpm", f"give one speed grid per model ({len(models)}), got "
                                              f"{len(spindle_speed_rpm)}")
    if len({m.n_modes for m in models}) > 1:  # one batch per size: a padded system costs (n_max / n)³ per product
        return _by_size(models, progress, spindle_speed_rpm=spindle_speed_rpm, steps_per_period=steps_per_period,
                        min_depth_search_max_m=min_depth_search_max_m, scan_start_m=scan_start_m,
                        common={"teeth": teeth, "tangential_coefficient_n_m2": tangential_coefficient_n_m2,
                                "radial_ratio": radial_ratio, "radial_immersion": radial_immersion,
                                "milling": milling, "depth_rtol": depth_rtol, "scan_from_neighbours": scan_from_neighbours,
                                "steps_per_cycle": steps_per_cycle, "refinements": refinements, "check": check})
    kt = float(tangential_coefficient_n_m2)
    speeds = [np.array(s, dtype=float) for s in spindle_speed_rpm]  # copies: the results freeze their arrays
    automatic = steps_per_period is None
    per_cycle = RESOLVING_STEPS_PER_CYCLE if steps_per_cycle is None else float(steps_per_cycle)
    if not (math.isfinite(per_cycle) and 2.0 <= per_cycle <= 1000.0):
        raise InputError("steps_per_cycle", f"must lie within 2 … 1000, got {steps_per_cycle!r}")
    phi_st, phi_ex = engagement_angles_rad(radial_immersion, milling)
    if automatic:
        for speed in speeds:
            _check_arguments(teeth, kt, radial_ratio, None, speed)
        scheme = cut_scheme(teeth, radial_immersion, milling)[0]
        steps = [resolving_steps(m, teeth, s, radial_immersion=radial_immersion, milling=milling,
                                 steps_per_cycle=per_cycle) for m, s in zip(models, speeds, strict=True)]
    else:
        scheme = FULL_PERIOD
        per_speed = not isinstance(steps_per_period, (int, np.integer))
        steps = ([np.asarray(k) for k in steps_per_period] if per_speed  # type: ignore[union-attr]
                 else [np.full(s.size, steps_per_period) for s in speeds])
        if len(steps) != len(models) or any(k.shape != s.shape for k, s in zip(steps, speeds, strict=True)):
            raise InputError("steps_per_period", "give one step count per speed of each model, or one for all")
        for speed, k in zip(speeds, steps, strict=True):
            for value in np.unique(k) if k.size else [DEFAULT_STEPS_PER_PERIOD]:
                _check_arguments(teeth, kt, radial_ratio, value.item() if isinstance(value, np.generic) else value,
                                 speed)
    cut = _Cut(int(teeth), kt, float(radial_ratio), phi_st, phi_ex, scheme)
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
    solve = _Solver(models, speeds, cut, b_ref, ceiling, depth_rtol, scan_from_neighbours)
    fields = solve.bands(steps, starts, progress)
    least = MIN_CUT_STEPS if scheme == CUT_WINDOW else MIN_PERIOD_STEPS
    for f, k in zip(fields, steps, strict=True):
        f["steps"] = k.astype(np.int64)
        f["check_steps"] = np.zeros(k.size, dtype=np.int64)
        f["resolved"] = np.zeros(k.size, dtype=bool)
    if check:
        check_steps = [band_steps(_band_of(k, least) - _CHECK_BANDS, least) if automatic
                       else np.maximum(np.round(k / math.sqrt(2.0)), 4).astype(np.int64) for k in steps]
        solve.check(fields, check_steps)
        if automatic:
            for _ in range(refinements):
                todo = [np.flatnonzero(~f["resolved"]) for f in fields]
                if not any(t.size for t in todo):
                    break
                solve.refine(fields, todo, least)
    return [_result(models[i], speeds[i], fields[i], float(ceiling[i]), scheme) for i in range(len(models))]


#: How several diagrams are solved: ``solver(models, spindle_speed_rpm, settings)`` answers as
#: :func:`semi_discretization_lobes_many` ``(models, spindle_speed_rpm=..., **settings)`` — by default
#: that very call, in this process (:func:`solve_diagrams_here`); the application layer may share the
#: (model, speeds) work among worker processes or a cluster and join each model's parts again
#: (:func:`merged_result`).
DiagramsSolver = Callable[[Sequence[ModalModel], Sequence[np.ndarray], dict[str, Any]],
                          list[SemiDiscretizationResult]]


def solve_diagrams_here(models: Sequence[ModalModel], spindle_speed_rpm: Sequence[np.ndarray],
                        settings: dict[str, Any]) -> list[SemiDiscretizationResult]:
    """:data:`DiagramsSolver` in this process: every model and speed in one call.

    Parameters
    ----------
    models : sequence of ModalModel
    spindle_speed_rpm : sequence of numpy.ndarray
        One speed grid per model, rpm.
    settings : dict
        The other keywords of :func:`semi_discretization_lobes_many`.

    Returns
    -------
    list of SemiDiscretizationResult
        One per model, in order.
    """
    return semi_discretization_lobes_many(models, spindle_speed_rpm=spindle_speed_rpm, **settings)


def stable_at_depth_many(
    models: Sequence[ModalModel],
    *,
    teeth: int,
    tangential_coefficient_n_m2: float,
    radial_ratio: float,
    radial_immersion: float,
    milling: Milling,
    spindle_speed_rpm: Sequence[np.ndarray],
    depth_m: Sequence[float | np.ndarray],
    steps_per_cycle: float | None = None,
) -> list[np.ndarray]:
    """Whether each speed of each model is stable at its depth: one evaluation of the
    period map per speed (no search), with the steps that resolve the cut at ``steps_per_cycle``
    (:func:`resolving_steps`) and no check — the same answer as "the limit found with these
    steps is at least ``depth_m``", up to the search's bracket width.

    Parameters
    ----------
    models, teeth, tangential_coefficient_n_m2, radial_ratio, radial_immersion, milling
        As in :func:`semi_discretization_lobes_many`.
    spindle_speed_rpm : sequence of numpy.ndarray
        One speed grid (rpm) per model.
    depth_m : sequence of float or numpy.ndarray
        Per model, one axial depth (m) or one per speed.
    steps_per_cycle : float, optional
        Default ``RESOLVING_STEPS_PER_CYCLE``.

    Returns
    -------
    list of numpy.ndarray of bool
        Per model, per speed: all multipliers inside the unit circle.

    Examples
    --------
    >>> m = ModalModel.of([922.0], [0.011], [1 / 0.03993], [0])
    >>> [s.tolist() for s in stable_at_depth_many([m], teeth=2, tangential_coefficient_n_m2=6e8, radial_ratio=1 / 3,
    ...     radial_immersion=0.05, milling="down", spindle_speed_rpm=[np.array([18000.0, 18000.0])], depth_m=[1e-3])]
    [[True, True]]
    """
    kt = float(tangential_coefficient_n_m2)
    speeds = [np.asarray(s, dtype=float) for s in spindle_speed_rpm]
    if len(speeds) != len(models) or len(depth_m) != len(models):
        raise InputError("depth_m", f"give one speed grid and its depths per model ({len(models)})")
    try:
        depths = [np.broadcast_to(np.asarray(d, dtype=float), s.shape) for d, s in zip(depth_m, speeds, strict=True)]
    except ValueError:
        raise InputError("depth_m", "give one depth per model or one per speed") from None
    if not all(np.all(np.isfinite(d) & (d > 0)) for d in depths):
        raise InputError("depth_m", "depths must be finite and > 0 (m)")
    per_cycle = RESOLVING_STEPS_PER_CYCLE if steps_per_cycle is None else float(steps_per_cycle)
    for speed in speeds:
        _check_arguments(teeth, kt, radial_ratio, None, speed)
    phi_st, phi_ex = engagement_angles_rad(radial_immersion, milling)
    cut = _Cut(int(teeth), kt, float(radial_ratio), phi_st, phi_ex, cut_scheme(teeth, radial_immersion, milling)[0])
    out: list[np.ndarray] = [np.empty(0, dtype=bool)] * len(models)
    for size in sorted({m.n_modes for m in models}):  # a loop over model sizes (a handful): none padded
        idx = [i for i, m in enumerate(models) if m.n_modes == size]
        steps = [resolving_steps(models[i], teeth, speeds[i], radial_immersion=radial_immersion, milling=milling,
                                 steps_per_cycle=per_cycle) for i in idx]
        evaluate = _evaluator([models[i] for i in idx], [speeds[i] for i in idx], steps, cut)
        sizes = [speeds[i].size for i in idx]
        mu = evaluate(np.arange(sum(sizes)), np.concatenate([depths[i] for i in idx]))
        for i, part in zip(idx, np.split(np.abs(mu) < 1.0, np.cumsum(sizes)[:-1]), strict=True):
            out[i] = part
    return out


def merged_result(parts: Sequence[SemiDiscretizationResult]) -> SemiDiscretizationResult:
    """One result over the speeds of ``parts`` together, in speed order: the same model and cut
    solved in separate calls on disjoint speeds (e.g. a screening pass band by band), each speed
    keeping its own answer; the envelope's segments and its lowest point are those of the union.

    Parameters
    ----------
    parts : sequence of SemiDiscretizationResult
        One model, scheme and search ceiling (the first part's ceiling is kept).

    Returns
    -------
    SemiDiscretizationResult
    """
    if not parts:
        raise InputError("parts", "give at least one result")
    first = parts[0]
    if any(p.modal_model is not first.modal_model or p.scheme != first.scheme for p in parts):
        raise InputError("parts", "results of one model (the same object) and one scheme only")
    speed = np.concatenate([p.spindle_speed_rpm for p in parts])
    order = np.argsort(speed, kind="stable")
    f_top = 1.2 * float(np.max(first.modal_model.frequency_hz))

    def cat(name: str) -> np.ndarray:
        return np.concatenate([np.asarray(getattr(p, name)) for p in parts])[order]

    fields = {"depth": cat("depth_limit_m"), "mu": cat("critical_multiplier"), "freq": cat("chatter_frequency_hz"),
              "kind": cat("instability"), "lobe": cat("governing_lobe"),
              "step_s": 1.0 / (f_top * cat("top_mode_steps_per_cycle")), "steps": cat("steps"),
              "check_steps": cat("check_steps"), "resolved": cat("resolved")}
    return _result(first.modal_model, speed[order], fields, first.depth_search_max_m, first.scheme)


#: A speed's cost in :func:`speed_costs` besides its steps, in steps: the search's share that does
#: not grow with the steps. Chosen by hand on ``benchmarks/bench_lobes.py``'s cut (500 speeds,
#: steps 16–153): its four parts cost 1.5, 2.0, 1.6 and 1.1 s CPU (cut by count alone: 2.8 … 0.8 s).
_SPEED_COST_STEPS = 8


def speed_costs(model: ModalModel, spindle_speed_rpm: np.ndarray, *, teeth: int, radial_immersion: float,
                milling: Milling, steps_per_period: int | None = None) -> np.ndarray:
    """What each speed of a semi-discretization costs, in steps: its steps (:func:`resolving_steps` —
    a slow speed has many cycles of the top mode in its cut — or ``steps_per_period``) plus
    ``_SPEED_COST_STEPS``. About 0.2–0.35 ms of one core each on the 2-core VMs of the benchmarks
    (RA-1's 16 states; a smaller model costs a little less: the per-step work dominates).

    Parameters
    ----------
    model : ModalModel
    spindle_speed_rpm : numpy.ndarray, shape (nspeed,)
    teeth, radial_immersion, milling, steps_per_period
        As in :func:`semi_discretization_lobes`.

    Returns
    -------
    numpy.ndarray, shape (nspeed,)

    Examples
    --------
    >>> m = ModalModel.of([1400.0, 4000.0], [0.02, 0.03], [1.0, 0.5], [0, 0])
    >>> speed_costs(m, np.array([3000.0, 24000.0]), teeth=1, radial_immersion=0.05, milling="down").tolist()
    [85.0, 24.0]
    """
    speed = np.asarray(spindle_speed_rpm, dtype=float)
    steps = (resolving_steps(model, teeth, speed, radial_immersion=radial_immersion, milling=milling)
             if steps_per_period is None else np.full(speed.size, int(steps_per_period)))
    return np.asarray(steps, dtype=float) + _SPEED_COST_STEPS


def speed_parts(spindle_speed_rpm: np.ndarray, cost: np.ndarray, parts: int) -> list[np.ndarray]:
    """The speed grid cut into ``parts`` consecutive parts of about equal ``cost`` (:func:`speed_costs`),
    to be solved apart (each by :func:`semi_discretization_lobes`) and joined again (:func:`merged_result`).

    Parameters
    ----------
    spindle_speed_rpm : numpy.ndarray, shape (nspeed,)
        rpm, in the order the parts keep.
    cost : numpy.ndarray, shape (nspeed,)
        Each speed's cost (any positive unit).
    parts : int
        How many parts (at most one per speed; at least 1).

    Returns
    -------
    list of numpy.ndarray
        Consecutive, non-empty, together the grid.

    Examples
    --------
    >>> [p.tolist() for p in speed_parts(np.arange(6.0), np.array([4.0, 4.0, 1.0, 1.0, 1.0, 1.0]), 2)]
    [[0.0], [1.0, 2.0, 3.0, 4.0, 5.0]]
    >>> [p.size for p in speed_parts(np.arange(6.0), np.ones(6), 3)]
    [2, 2, 2]
    """
    speed = np.asarray(spindle_speed_rpm, dtype=float)
    n = max(1, min(int(parts), speed.size))
    total = np.cumsum(np.asarray(cost, dtype=float))
    cuts = np.searchsorted(total, total[-1] * np.arange(1, n) / n, side="right")
    cuts = np.unique(np.clip(cuts, 1, speed.size - 1)) if speed.size > 1 else np.empty(0, dtype=np.int64)
    return np.split(speed, cuts)


def _by_size(models: Sequence[ModalModel], progress: Callable[[int, int], None] | None, *,
             spindle_speed_rpm: Sequence[np.ndarray], steps_per_period: int | Sequence[np.ndarray] | None,
             min_depth_search_max_m: Sequence[float] | None, scan_start_m: Sequence[np.ndarray] | None,
             common: dict[str, Any]) -> list[SemiDiscretizationResult]:
    """:func:`semi_discretization_lobes_many` of models of several sizes: one call per number of
    modes (a smaller model batched with a larger one is padded with inert modes, and every product
    of its period maps costs the larger size's), the results in the models' order; ``progress``
    counts the models' share of the calls."""
    sizes = sorted({m.n_modes for m in models})
    out: list[SemiDiscretizationResult | None] = [None] * len(models)
    done = 0
    for size in sizes:  # a loop over model sizes (a handful)
        idx = [i for i, m in enumerate(models) if m.n_modes == size]

        def part(d: int, t: int, base: int = done, share: int = len(idx)) -> None:
            if progress is not None:
                progress(base + int(share * d / max(t, 1)), len(models))

        steps = steps_per_period if steps_per_period is None or isinstance(steps_per_period, (int, np.integer)) \
            else _pick(steps_per_period, idx)
        results = semi_discretization_lobes_many([models[i] for i in idx], **common,
                                                 spindle_speed_rpm=[spindle_speed_rpm[i] for i in idx],
                                                 steps_per_period=steps, progress=part,
                                                 min_depth_search_max_m=_pick(min_depth_search_max_m, idx),
                                                 scan_start_m=_pick(scan_start_m, idx))
        for i, r in zip(idx, results, strict=True):
            out[i] = r
        done += len(idx)
    return [r for r in out if r is not None]


def _pick(seq: Sequence[Any] | None, idx: list[int]) -> list[Any] | None:
    """The entries ``idx`` of a per-model sequence (None stays None)."""
    return None if seq is None else [seq[i] for i in idx]


# Per-speed arrays of a result: name, fill value, dtype.
_FIELDS = (("depth", np.nan, float), ("hi", np.nan, float), ("mu", np.nan + 0j, complex), ("freq", np.nan, float),
           ("kind", "", "<U4"), ("lobe", -1, np.int64), ("step_s", np.nan, float))


class _Solver:
    """The searches and checks of one call: every (model, speed) pair at a given step count is one
    batch of period maps (:class:`_Evaluator`), a step count at a time."""

    def __init__(self, models: Sequence[ModalModel], speeds: Sequence[np.ndarray], cut: _Cut, b_ref: np.ndarray,
                 ceiling: np.ndarray, rtol: float, scan_from_neighbours: bool) -> None:
        self.models, self.speeds, self.cut = models, speeds, cut
        self.b_ref, self.ceiling, self.rtol = b_ref, ceiling, rtol
        self.scan_from_neighbours = scan_from_neighbours

    def bands(self, steps: Sequence[np.ndarray], starts: Sequence[np.ndarray],
              progress: Callable[[int, int], None] | None = None,
              picks: Sequence[np.ndarray] | None = None) -> list[dict[str, np.ndarray]]:
        """Search every speed (of ``picks``, default all) at its own step count, all speeds of all
        models in one coarse-to-fine search; per-model per-speed fields."""
        picks = [np.arange(s.size) for s in self.speeds] if picks is None else picks
        members = [i for i, p in enumerate(picks) if p.size]
        fields = [{name: np.full(p.size, fill, dtype=dtype) for name, fill, dtype in _FIELDS} for p in picks]
        if not members:
            return fields
        solved = _solve_band([self.models[i] for i in members], [self.speeds[i][picks[i]] for i in members],
                             [steps[i][picks[i]] for i in members], self.cut, self.b_ref[members],
                             self.ceiling[members], self.rtol, progress, self.scan_from_neighbours,
                             np.concatenate([starts[i][picks[i]] for i in members]))
        for i, part in zip(members, solved, strict=True):
            fields[i] = part
        return fields

    def check(self, fields: list[dict[str, np.ndarray]], check_steps: Sequence[np.ndarray]) -> None:
        """Mark each speed resolved when its limit at ``check_steps`` lies within ``RESOLVED_RTOL``
        (stable at ``(1 − RESOLVED_RTOL)·lo``, unstable at ``(1 + RESOLVED_RTOL)·hi``; a speed
        without a limit: stable at the ceiling)."""
        lo, hi = [], []
        for i, (f, k) in enumerate(zip(fields, check_steps, strict=True)):  # a loop over models
            f["check_steps"] = k
            found = np.isfinite(f["depth"])
            lo.append(np.where(found, f["depth"] * (1.0 - RESOLVED_RTOL), self.ceiling[i]))
            hi.append(np.where(found, f["hi"] * (1.0 + RESOLVED_RTOL), np.nan))
        evaluate = self._evaluator(check_steps)
        lo_m, hi_m = np.concatenate(lo), np.concatenate(hi)
        pairs = np.arange(lo_m.size)
        with_hi = np.flatnonzero(np.isfinite(hi_m))
        g = _log_modulus(evaluate(np.concatenate([pairs, with_hi]), np.concatenate([lo_m, hi_m[with_hi]])))
        ok = g[: pairs.size] < 0.0
        ok[with_hi] &= g[pairs.size :] >= 0.0
        at = 0
        for f in fields:  # a loop over models
            f["resolved"] = ok[at : at + f["depth"].size]
            at += f["depth"].size

    def refine(self, fields: list[dict[str, np.ndarray]], todo: Sequence[np.ndarray], least: int) -> None:
        """Solve the speeds ``todo`` (per model) again with √2 times their steps; resolved when the
        new limit lies within ``RESOLVED_RTOL`` of the one before (both without a limit: resolved).

        The search starts around the limit before (:func:`_solve_near`): first-order
        semi-discretization errs by ``C h²``, so the new limit lies a few per cent below it."""
        steps = [f["steps"].copy() for f in fields]
        for i, t in enumerate(todo):  # a loop over models
            steps[i][t] = band_steps(_band_of(steps[i][t], least) + _CHECK_BANDS, least)
        members = [i for i, t in enumerate(todo) if t.size]
        new = _solve_near([self.models[i] for i in members], [self.speeds[i][todo[i]] for i in members],
                          [steps[i][todo[i]] for i in members], self.cut, self.ceiling[members], self.rtol,
                          np.concatenate([fields[i]["depth"][todo[i]] for i in members]))
        for i, part in zip(members, new, strict=True):  # a loop over models
            f, t = fields[i], todo[i]
            old = f["depth"][t]
            with np.errstate(invalid="ignore", divide="ignore"):
                close = np.abs(np.log(part["depth"] / old)) <= math.log1p(RESOLVED_RTOL) + self.rtol
            both_free = ~np.isfinite(old) & ~np.isfinite(part["depth"])
            f["check_steps"][t] = f["steps"][t]
            f["steps"][t] = steps[i][t]
            for name in part:
                f[name][t] = part[name]
            f["resolved"][t] = close | both_free

    def _evaluator(self, steps: Sequence[np.ndarray]) -> _Evaluator:
        """One evaluator over every speed of every model, each with its step count."""
        return _evaluator(self.models, self.speeds, steps, self.cut)


def _evaluator(models: Sequence[ModalModel], speeds: Sequence[np.ndarray], steps: Sequence[np.ndarray],
               cut: _Cut) -> _Evaluator:
    sizes = np.array([s.size for s in speeds])
    speed = np.concatenate(speeds)
    systems = md.state_space(models[0]) if len(models) == 1 else md.state_spaces(models)
    system_of_pair = (np.repeat(np.arange(len(models)), sizes) if len(models) > 1
                      else np.zeros(speed.size, dtype=np.int64))
    return _Evaluator(systems, system_of_pair, cut, np.concatenate(steps), 60.0 / (cut.teeth * speed))


def _solve_band(models: Sequence[ModalModel], speeds: Sequence[np.ndarray], steps: Sequence[np.ndarray], cut: _Cut,
                b_ref: np.ndarray, ceiling: np.ndarray, rtol: float, progress: Callable[[int, int], None] | None,
                scan_from_neighbours: bool = False, scan_start_m: np.ndarray | None = None) -> list[dict[str, np.ndarray]]:
    """The search (:func:`_search`) for the given models and speeds, each speed with its step count."""
    sizes = np.array([s.size for s in speeds])
    evaluate = _evaluator(models, speeds, steps, cut)
    system_of_pair = np.repeat(np.arange(len(models)), sizes)
    period = evaluate.period_s
    slowest = np.array([np.min(m.damping_ratio * 2 * np.pi * m.frequency_hz) for m in models])
    g0 = -slowest[system_of_pair] * period  # log|μ| at b = 0 (exact)
    offsets = np.concatenate([[0], np.cumsum(sizes)])
    grids = [np.arange(offsets[i], offsets[i + 1]) for i in range(len(models))]
    br = _search(evaluate, grids, g0, (_SCAN_START * b_ref)[system_of_pair], ceiling[system_of_pair], rtol, progress,
                 scan_from_neighbours, scan_start_m)
    return _fields(br, evaluate, sizes)


#: :func:`_solve_near` brackets a refined limit this far (relative, each side) around the one before.
_NEAR_DELTA = 0.04


def _solve_near(models: Sequence[ModalModel], speeds: Sequence[np.ndarray], steps: Sequence[np.ndarray], cut: _Cut,
                ceiling: np.ndarray, rtol: float, guess_m: np.ndarray) -> list[dict[str, np.ndarray]]:
    """Limits of the given speeds, searched around known estimates ``guess_m`` (NaN: stable to the ceiling).

    Each pair is straddled at ``guess·e^{∓δ}`` (:func:`_guided`, ``δ = _NEAR_DELTA``) and the
    bracket refined; a pair the straddle does not bracket is solved from scratch (scan from a
    quarter of its guess — lower, if unstable there — then refined), so a limit far from the guess
    is still found.
    """
    sizes = np.array([s.size for s in speeds])
    evaluate = _evaluator(models, speeds, steps, cut)
    system_of_pair = np.repeat(np.arange(len(models)), sizes)
    period = evaluate.period_s
    top = ceiling[system_of_pair]
    slowest = np.array([np.min(m.damping_ratio * 2 * np.pi * m.frequency_hz) for m in models])
    g0 = -slowest[system_of_pair] * period
    br = _Brackets.empty(g0.size)
    br.g_lo[:] = g0
    pairs = np.arange(g0.size)
    known = np.isfinite(guess_m)
    scratch = [pairs[~known]]
    if known.any():
        p = pairs[known]
        scratch.append(_guided(evaluate, p, guess_m[known], np.full(p.size, _NEAR_DELTA), br, rtol, top,
                               np.full(p.size, np.nan)))
    fresh = np.concatenate(scratch)
    if fresh.size:
        br.lo[fresh], br.g_lo[fresh], br.hi[fresh] = 0.0, g0[fresh], np.nan
        start = np.where(np.isfinite(guess_m[fresh]), 0.25 * guess_m[fresh], _SCAN_START * top[fresh] / _SCAN_CEILING)
        _scan(evaluate, fresh, br, start, top[fresh])
    _refine(evaluate, pairs[np.isfinite(br.hi)], br, rtol)
    return _fields(br, evaluate, sizes)


def _fields(br: _Brackets, evaluate: _Evaluator, sizes: np.ndarray) -> list[dict[str, np.ndarray]]:
    """Per-model per-speed result arrays of a finished search."""
    period = evaluate.period_s
    found = np.isfinite(br.hi)
    depth = np.where(found, br.lo, np.nan)
    mu = np.where(found, evaluate.mu_unstable, np.nan + 0j)
    freq = np.where(found, evaluate.freq_unstable, np.nan)
    real = mu.imag == 0.0
    kind = np.where(found, np.where(real, np.where(mu.real < 0, "flip", "fold"), "hopf"), "").astype("<U4")
    lobe = np.where(np.isfinite(freq), np.floor(freq * period + 1e-9), -1).astype(np.int64)
    hi = np.where(found, br.hi, np.nan)
    offsets = np.concatenate([[0], np.cumsum(sizes)])
    return [{"depth": depth[a:b], "hi": hi[a:b], "mu": mu[a:b], "freq": freq[a:b], "kind": kind[a:b],
             "lobe": lobe[a:b], "step_s": evaluate.step_s[a:b]} for a, b in zip(offsets[:-1], offsets[1:], strict=True)]


def _result(model: ModalModel, speed: np.ndarray, f: dict[str, np.ndarray], ceiling: float,
            scheme: str) -> SemiDiscretizationResult:
    depth, mu, freq, kind, lobe, step_s = (f[k] for k in ("depth", "mu", "freq", "kind", "lobe", "step_s"))
    with np.errstate(divide="ignore", invalid="ignore"):  # a fold at 0 Hz is resolved by any step
        cycles = 1.0 / (freq * step_s)
    top = 1.0 / (1.2 * float(np.max(model.frequency_hz)) * step_s)
    lobes, kinds, lowest = _segments(speed, depth, kind, lobe)
    found = np.isfinite(depth)
    best = int(np.nanargmin(depth)) if found.any() else -1
    steps = f["steps"]
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
        top_mode_steps_per_cycle=top,
        scheme=scheme,
        steps=steps,
        check_steps=f["check_steps"],
        resolved=f["resolved"],
    )
