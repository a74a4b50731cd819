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

Both run for all open speeds at once (one batch of period maps per iteration).

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
be stepped over (a 400-point depth grid finds none on the test cases); the accuracy needs
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
    "MAX_STEPS_PER_PERIOD",
    "MIN_STEPS_PER_PERIOD",
    "SemiDiscretizationResult",
    "semi_discretization_lobes",
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
# Speeds per batch of period maps: bounds the memory (~50 MB for 12 states and k = 40).
_CHUNK = 256

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
        The multiplier that crosses the unit circle (at the unstable end of the bracket).
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
    """

    instability: np.ndarray
    critical_multiplier: np.ndarray
    lobe_kinds: tuple[str, ...]
    steps_per_period: int
    steps_per_chatter_cycle: np.ndarray
    depth_search_max_m: float
    modal_model: ModalModel

    def __post_init__(self) -> None:
        LobeResult.__post_init__(self)
        for name in ("instability", "critical_multiplier", "steps_per_chatter_cycle"):
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
        bad = self.spindle_speed_rpm[self.under_resolved]
        if not bad.size:
            return []
        return [f"{bad.size} speed(s) between {bad.min():.0f} and {bad.max():.0f} rpm have fewer than "
                f"{MIN_STEPS_PER_CHATTER_CYCLE:g} steps per chatter cycle: their limits are under-resolved "
                f"(raise steps_per_period, or use method zoa there)"]


# --------------------------------------------------------------------------- search


class _Evaluator:
    """Largest multiplier of the period map for given speeds (indices) and depths."""

    def __init__(self, model: ModalModel, plan: md.CuttingPlan, kt: float, period_s: np.ndarray) -> None:
        self.system = md.state_space(model)
        self.plan = plan
        self.kt = kt
        self.step_s = period_s / plan.steps
        self.free = md.free_maps(self.system, plan, self.step_s)
        self.evaluations = 0

    def maps(self, idx: np.ndarray, depth_m: np.ndarray) -> md.PeriodMaps:
        return md.period_maps(self.system, self.plan, self.kt, self.step_s[idx], depth_m,
                              (self.free[0][idx], self.free[1][idx]))

    def __call__(self, idx: np.ndarray, depth_m: np.ndarray) -> np.ndarray:
        self.evaluations += idx.size
        mu = np.empty(idx.size, dtype=complex)
        for lo in range(0, idx.size, _CHUNK):
            part = slice(lo, lo + _CHUNK)
            mu[part] = md.critical_multipliers(self.system, self.plan, self.maps(idx[part], depth_m[part]))[0]
        return mu


def _log_modulus(mu: np.ndarray) -> np.ndarray:
    with np.errstate(divide="ignore"):
        return np.log(np.abs(mu))


def _scan(evaluate: _Evaluator, g0: np.ndarray, start_m: float, ceiling_m: float
          ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Brackets ``[lo, hi]`` of the first crossing of ``log|μ| = 0`` (hi NaN: none)."""
    n = g0.size
    lo, g_lo = np.zeros(n), g0.copy()
    hi, g_hi = np.full(n, np.nan), np.full(n, np.nan)
    b = np.full(n, start_m)
    active = np.arange(n)
    while active.size:
        check_time()
        g = _log_modulus(evaluate(active, b[active]))
        up = g >= 0.0
        hi[active[up]], g_hi[active[up]] = b[active[up]], g[up]
        go = active[~up]
        g_go = g[~up]
        slope = (g_go - g_lo[go]) / (b[go] - lo[go])
        with np.errstate(divide="ignore", invalid="ignore"):
            guess = np.where(slope > 0.0, b[go] - g_go / slope, np.inf)
        step = np.clip(1.05 * guess / b[go], _SCAN_MIN_RATIO, _SCAN_MAX_RATIO)
        lo[go], g_lo[go] = b[go], g_go
        nxt = b[go] * step
        at_ceiling = b[go] >= ceiling_m
        b[go] = np.minimum(nxt, ceiling_m)
        active = go[~at_ceiling]
    return lo, g_lo, hi, g_hi


def _refine(evaluate: _Evaluator, idx: np.ndarray, a: np.ndarray, ga: np.ndarray, c: np.ndarray,
            gc: np.ndarray, rtol: float) -> tuple[np.ndarray, np.ndarray]:
    """Illinois regula falsi on ``log|μ|`` until ``c − a <= rtol·c`` (a stable, c not)."""
    a, ga, c, gc = a.copy(), ga.copy(), c.copy(), gc.copy()
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
        c[iu], gc[iu] = x[up], gx[up]
        a[id_], ga[id_] = x[~up], gx[~up]
        side[iu], side[id_] = 1, -1
    return a, c


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


def _chatter(evaluate: _Evaluator, idx: np.ndarray, depth_m: np.ndarray, period_s: np.ndarray
             ) -> tuple[np.ndarray, np.ndarray]:
    """Critical multiplier and dominant vibration frequency (Hz) at the given depths."""
    parts = [_chatter_chunk(evaluate, idx[lo : lo + _CHUNK], depth_m[lo : lo + _CHUNK], period_s[lo : lo + _CHUNK])
             for lo in range(0, idx.size, _CHUNK)]
    return np.concatenate([p[0] for p in parts]), np.concatenate([p[1] for p in parts])


def _chatter_chunk(evaluate: _Evaluator, idx: np.ndarray, depth_m: np.ndarray, period_s: np.ndarray
                   ) -> tuple[np.ndarray, np.ndarray]:
    maps = evaluate.maps(idx, depth_m)
    mu, vec = md.critical_multipliers(evaluate.system, evaluate.plan, maps, vectors=True)
    assert vec is not None
    k = evaluate.plan.steps
    r = md.trajectory(evaluate.system, evaluate.plan, maps, vec)  # (nb, k, 2)
    log_mu = np.log(mu.astype(complex))
    floquet = np.exp(-np.outer(log_mu, np.arange(k) / k))  # remove the growth μ^{s/k}
    coef = np.fft.fft(r * floquet[:, :, None], axis=1)
    power = (np.abs(coef) ** 2).sum(axis=2)
    j = np.fft.fftfreq(k, d=1.0 / k)[np.argmax(power, axis=1)]
    theta = np.angle(mu)
    return mu, np.abs(theta / (2 * np.pi) + j) / period_s


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
    speed = np.array(spindle_speed_rpm, dtype=float)  # a copy: the result freezes its arrays
    kt = float(tangential_coefficient_n_m2)
    _check_arguments(teeth, kt, radial_ratio, steps_per_period, speed)
    phi_st, phi_ex = engagement_angles_rad(radial_immersion, milling)
    plan = md.cutting_plan(teeth, steps_per_period, phi_st, phi_ex, radial_ratio)
    period = 60.0 / (teeth * speed)
    b_ref = _reference_depth(model, teeth, kt, directional_factors(phi_st, phi_ex, radial_ratio))
    ceiling = _SCAN_CEILING * b_ref
    evaluate = _Evaluator(model, plan, kt, period)
    w = 2 * np.pi * np.asarray(model.frequency_hz, dtype=float)
    g0 = -np.min(np.asarray(model.damping_ratio) * w) * period  # log|μ| at b = 0 (exact)
    lo, g_lo, hi, g_hi = _scan(evaluate, g0, _SCAN_START * b_ref, ceiling)
    found = np.flatnonzero(np.isfinite(hi))
    depth = np.full(speed.size, np.nan)
    mu = np.full(speed.size, np.nan + 0j)
    freq = np.full(speed.size, np.nan)
    kind = np.full(speed.size, "", dtype="<U4")
    if found.size:
        a, c = _refine(evaluate, found, lo[found], g_lo[found], hi[found], g_hi[found], depth_rtol)
        depth[found] = a
        mu[found], freq[found] = _chatter(evaluate, found, c, period[found])
        real = mu[found].imag == 0.0
        kind[found] = np.where(real, np.where(mu[found].real < 0, "flip", "fold"), "hopf")
    lobe = np.where(np.isfinite(freq), np.floor(freq * period + 1e-9), -1).astype(np.int64)
    lobes, kinds, lowest = _segments(speed, depth, kind, lobe)
    with np.errstate(divide="ignore"):  # a fold at 0 Hz is resolved by any step
        steps_per_cycle = steps_per_period / (freq * period)
    best = int(np.nanargmin(depth)) if found.size else -1
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
        steps_per_period=int(steps_per_period),
        steps_per_chatter_cycle=steps_per_cycle,
        depth_search_max_m=ceiling,
        modal_model=model,
    )
