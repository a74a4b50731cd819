"""The best stable pocket of a stability lobe diagram: a spindle speed and an axial depth to run.

The rule (what "best" means here)
---------------------------------
Given the lobe diagram's depth limit ``b(n)`` (nominal, or a robust limit at a confidence)
on a speed grid, a speed range ``[n_min, n_max]``, a relative speed tolerance ``τ`` and a
safety factor ``S >= 1``:

1. **Tolerance window.** At a candidate speed ``n`` the depth that may be taken is set by the
   *worst* limit within ``n (1 − τ) … n (1 + τ)``: ``b_τ(n) = min b(n')`` over that window
   (on the grid: the speeds in it and the two bracketing its ends).
   Lobe positions scale with the natural frequencies, so a relative error of the predicted
   frequencies (and of the spindle's speed) shifts the lobes by the same fraction: a speed
   whose window is stable still is after such a shift. This makes every recommended pocket at
   least ``2 τ n`` wide. A window holding an unsettled speed (NaN limit) or reaching past the
   grid is not stable.
2. **Allowed depth.** ``a(n) = min(b_τ(n) / S, a_max)``, ``a_max`` the tool's usable flute
   length (a stepdown cannot exceed it).
3. **Best speed.** The speed of the range maximising the material removal rate, which for a
   fixed radial engagement and feed per tooth is proportional to ``n · a(n)``; the lowest such
   speed on ties.
4. **Pocket.** The contiguous speeds around it where ``b(n) >= S · a`` (the chosen depth stays
   stable): its ends and width are reported.

Speeds below every lobe (the absolute limit) count like any other: when no lobe gives more
than the absolute limit within the range, the rule picks the highest speed of the range.

The grid should resolve the window: a relative spacing of ``τ / 10`` or finer
(:func:`pocket_speed_grid`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from rcsa.errors import InputError
from rcsa.model import fields
from rcsa.model.bounds import MAX_SPEED_RPM, MIN_SPEED_RPM

__all__ = [
    "DEFAULT_SAFETY_FACTOR",
    "DEFAULT_SPEED_TOLERANCE",
    "MAX_POCKET_GRID",
    "Pocket",
    "PocketRule",
    "best_pocket",
    "pocket_speed_grid",
    "window_minimum",
]

#: Default safety factor: the stepdown is 80 % of the window's depth limit.
DEFAULT_SAFETY_FACTOR = 1.25
#: Default relative speed tolerance τ: ± 3 % (spindle speed error and a few % error of the
#: predicted natural frequencies, which move the lobes by the same fraction).
DEFAULT_SPEED_TOLERANCE = 0.03
#: Largest speed grid :func:`pocket_speed_grid` makes.
MAX_POCKET_GRID = 4000


@dataclass(frozen=True, slots=True)
class PocketRule:
    """The parameters of the pocket rule (module docstring).

    Attributes
    ----------
    safety_factor : float
        ``S >= 1``: the stepdown is the window's depth limit divided by ``S``.
    speed_tolerance : float
        ``τ`` in [0, 0.5): relative half-width of the window each speed must keep stable.
    max_depth_m : float or None
        Largest stepdown (the tool's flute length), m; None for no cap.
    """

    safety_factor: float = DEFAULT_SAFETY_FACTOR
    speed_tolerance: float = DEFAULT_SPEED_TOLERANCE
    max_depth_m: float | None = None

    def __post_init__(self) -> None:
        fields.number(self.safety_factor, "safety_factor", ge=1.0, le=100.0)
        fields.number(self.speed_tolerance, "speed_tolerance", ge=0.0, le=0.49)
        if self.max_depth_m is not None:
            fields.number(self.max_depth_m, "max_depth_m", gt=0.0)

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready parameters."""
        return {"safety_factor": self.safety_factor, "speed_tolerance": self.speed_tolerance,
                "max_depth_m": self.max_depth_m}


@dataclass(frozen=True, slots=True)
class Pocket:
    """The chosen speed and depth, and the pocket around them.

    Attributes
    ----------
    spindle_speed_rpm : float
        The best speed (a grid speed), rpm.
    depth_limit_m : float
        ``b_τ``: the smallest depth limit within the speed window, m.
    stepdown_m : float
        The axial depth to run, ``min(b_τ / S, a_max)``, m.
    limited_by : {"stability", "flute_length"}
        Which bound set the stepdown.
    pocket_low_rpm, pocket_high_rpm : float
        The contiguous grid speeds around the best one where ``b >= S · stepdown``, rpm.
    chatter_frequency_hz : float
        Chatter frequency at the window's weakest speed, Hz (NaN when not given).
    governing_lobe : int
        Lobe governing at that speed (−1 when not given).
    removal_index_rpm_m : float
        ``n · stepdown``, rpm·m (proportional to the material removal rate).
    pocket_low_open, pocket_high_open : bool
        The pocket was followed only that far (stable there, the speed grid going on beyond): a
        semi-discretization pocket is followed at most a factor
        :data:`rcsa.analysis.lobes.tool_pockets.POCKET_FOLLOWED_SPAN` either side of its speed.
    """

    spindle_speed_rpm: float
    depth_limit_m: float
    stepdown_m: float
    limited_by: str
    pocket_low_rpm: float
    pocket_high_rpm: float
    chatter_frequency_hz: float
    governing_lobe: int
    removal_index_rpm_m: float
    pocket_low_open: bool = False
    pocket_high_open: bool = False

    @property
    def pocket_width_rpm(self) -> float:
        """Width of the pocket, rpm."""
        return self.pocket_high_rpm - self.pocket_low_rpm

    def pocket_dict(self) -> dict[str, Any]:
        """The pocket's wire form: its ends and width, rpm, and whether it is open at each end."""
        return {"low_rpm": self.pocket_low_rpm, "high_rpm": self.pocket_high_rpm, "width_rpm": self.pocket_width_rpm,
                "low_open": self.pocket_low_open, "high_open": self.pocket_high_open}

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready result (NaN as None)."""
        def num(x: float) -> float | None:
            return float(x) if math.isfinite(x) else None
        return {"spindle_speed_rpm": self.spindle_speed_rpm, "depth_limit_m": self.depth_limit_m,
                "stepdown_m": self.stepdown_m, "limited_by": self.limited_by,
                "pocket": self.pocket_dict(),
                "chatter_frequency_hz": num(self.chatter_frequency_hz), "governing_lobe": self.governing_lobe,
                "removal_index_rpm_m": self.removal_index_rpm_m}


def pocket_speed_grid(min_rpm: float, max_rpm: float, speed_tolerance: float,
                      max_count: int = MAX_POCKET_GRID) -> np.ndarray:
    """A geometric speed grid covering every window of ``[min_rpm, max_rpm]``, rpm.

    It runs from ``min_rpm (1 − τ)`` to ``max_rpm (1 + τ)`` with a relative spacing of
    ``τ / 10`` (at least 400 points, at most ``max_count``).

    Examples
    --------
    >>> g = pocket_speed_grid(2000.0, 20000.0, 0.03)
    >>> round(float(g[0]), 6), round(float(g[-1]), 6), g.size
    (1940.0, 20600.0, 790)
    """
    lo = fields.number(min_rpm, "min_rpm", gt=0.0)
    hi = fields.number(max_rpm, "max_rpm", gt=0.0)
    tol = fields.number(speed_tolerance, "speed_tolerance", ge=0.0, le=0.49)
    if not lo < hi:
        raise InputError("max_rpm", f"must be greater than min_rpm ({lo:g}), got {hi:g}")
    start = max(lo * (1.0 - tol), MIN_SPEED_RPM)
    stop = min(hi * (1.0 + tol), MAX_SPEED_RPM)
    step = math.log1p(tol / 10.0) if tol > 0 else math.log1p(0.001)
    count = int(min(max(math.ceil(math.log(stop / start) / step) + 1, 400), max_count))
    return np.geomspace(start, stop, count)


def window_minimum(speed_rpm: np.ndarray, depth_m: np.ndarray, speed_tolerance: float) -> np.ndarray:
    """``min b(n')`` over ``n' ∈ [n (1 − τ), n (1 + τ)]`` at every grid speed ``n``.

    The grid speeds within the window and the two that bracket its ends are taken, so that
    the whole interval lies between grid speeds that were looked at. NaN where they hold a
    NaN (an unsettled speed) or the window reaches past the grid.
    Vectorised with a sparse table of running minima (``O(n log n)``), no loop over speeds.

    Examples
    --------
    A dip at 105 rpm is seen from every speed whose ± 2 % window (bracketed by the grid)
    reaches it:

    >>> n = np.arange(100.0, 111.0)
    >>> window_minimum(n, np.where(n == 105.0, 1.0, 5.0), 0.02).tolist()
    [nan, nan, nan, 1.0, 1.0, 1.0, 1.0, 1.0, nan, nan, nan]
    """
    n = np.asarray(speed_rpm, dtype=float)
    b = np.asarray(depth_m, dtype=float)
    # the grid speeds bracketing the window's ends count too: the whole interval is covered
    lo = np.maximum(np.searchsorted(n, n * (1.0 - speed_tolerance) * (1.0 + 1e-12), side="right") - 1, 0)
    hi = np.minimum(np.searchsorted(n, n * (1.0 + speed_tolerance) * (1.0 - 1e-12), side="left"), n.size - 1)
    inside = (n * (1.0 - speed_tolerance) >= n[0] * (1.0 - 1e-12)) & \
             (n * (1.0 + speed_tolerance) <= n[-1] * (1.0 + 1e-12))
    values = np.where(np.isfinite(b), b, -np.inf)
    table = [values]
    span = 1
    while 2 * span <= n.size:
        prev = table[-1]
        table.append(np.minimum(prev[:-span], prev[span:]))
        span *= 2
    length = hi - lo + 1
    level = np.floor(np.log2(np.maximum(length, 1))).astype(int)
    out = np.empty(n.size)
    for k in np.unique(level):  # at most log2(n) levels: a loop over table levels, not speeds
        sel = level == k
        row = table[k]
        out[sel] = np.minimum(row[lo[sel]], row[hi[sel] - (1 << k) + 1])
    out[~inside | ~np.isfinite(out)] = np.nan
    return out


def best_pocket(speed_rpm: object, depth_limit_m: object, *, min_rpm: float, max_rpm: float,
                rule: PocketRule = PocketRule(), chatter_frequency_hz: object | None = None,
                governing_lobe: object | None = None) -> Pocket | None:
    """The best stable pocket of a lobe diagram within a speed range (module docstring).

    Parameters
    ----------
    speed_rpm : array_like, shape (nspeed,)
        Strictly increasing speed grid, rpm (covering ``min_rpm (1 − τ)`` to
        ``max_rpm (1 + τ)``: :func:`pocket_speed_grid`).
    depth_limit_m : array_like, shape (nspeed,)
        Depth limit at each speed, m (NaN: unsettled). A robust limit may be given instead
        of the nominal one.
    min_rpm, max_rpm : float
        The speeds that may be chosen, rpm.
    rule : PocketRule
        Safety factor, speed tolerance and depth cap.
    chatter_frequency_hz : array_like, shape (nspeed,), optional
        Chatter frequency of the governing lobe, Hz (reported).
    governing_lobe : array_like, shape (nspeed,), optional
        Governing lobe index (reported).

    Returns
    -------
    Pocket or None
        None when no speed of the range has a stable window.

    Examples
    --------
    Two lobes with a high pocket between them at 10 000 rpm:

    >>> n = pocket_speed_grid(5000.0, 15000.0, 0.03)
    >>> b = 1e-3 + 4e-3 * np.exp(-((n - 10000.0) / 800.0) ** 2)
    >>> p = best_pocket(n, b, min_rpm=5000.0, max_rpm=15000.0)
    >>> round(p.spindle_speed_rpm, -2), p.stepdown_m < b.max() / 1.25, p.limited_by
    (10000.0, True, 'stability')
    """
    n = np.asarray(speed_rpm, dtype=float)
    b = np.asarray(depth_limit_m, dtype=float)
    if n.ndim != 1 or n.shape != b.shape or n.size < 2:
        raise InputError("depth_limit_m", f"expected one depth per speed, got shapes {n.shape} and {b.shape}")
    if np.any(np.diff(n) <= 0):
        raise InputError("spindle_speed_rpm", "speeds must be strictly increasing")
    lo_rpm = fields.number(min_rpm, "min_rpm", gt=0.0)
    hi_rpm = fields.number(max_rpm, "max_rpm", gt=0.0)
    window = window_minimum(n, b, rule.speed_tolerance)
    allowed = window / rule.safety_factor
    if rule.max_depth_m is not None:
        allowed = np.minimum(allowed, rule.max_depth_m)
    candidate = (n >= lo_rpm * (1 - 1e-12)) & (n <= hi_rpm * (1 + 1e-12)) & np.isfinite(allowed) & (allowed > 0)
    if not np.any(candidate):
        return None
    score = np.where(candidate, n * np.where(candidate, allowed, 0.0), -np.inf)
    i = int(np.argmax(score))
    stepdown = float(allowed[i])
    need = stepdown * rule.safety_factor * (1 - 1e-12)
    ok = np.isfinite(b) & (b >= need)
    low = high = i
    while low > 0 and ok[low - 1]:
        low -= 1
    while high < n.size - 1 and ok[high + 1]:
        high += 1
    w_lo = max(int(np.searchsorted(n, n[i] * (1.0 - rule.speed_tolerance) * (1 + 1e-12), side="right")) - 1, 0)
    w_hi = min(int(np.searchsorted(n, n[i] * (1.0 + rule.speed_tolerance) * (1 - 1e-12), side="left")), n.size - 1)
    weakest = w_lo + int(np.argmin(b[w_lo:w_hi + 1]))
    freq = float(np.asarray(chatter_frequency_hz, dtype=float)[weakest]) if chatter_frequency_hz is not None \
        else math.nan
    lobe = int(np.asarray(governing_lobe)[weakest]) if governing_lobe is not None else -1
    capped = rule.max_depth_m is not None and stepdown >= rule.max_depth_m
    return Pocket(spindle_speed_rpm=float(n[i]), depth_limit_m=float(window[i]), stepdown_m=stepdown,
                  limited_by="flute_length" if capped else "stability", pocket_low_rpm=float(n[low]),
                  pocket_high_rpm=float(n[high]), chatter_frequency_hz=freq, governing_lobe=lobe,
                  removal_index_rpm_m=float(n[i] * stepdown))
