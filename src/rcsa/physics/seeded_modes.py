"""Exact natural frequencies of many chains near known estimates (the k-th mode of each chain).

:func:`rcsa.physics.natural_frequencies.natural_frequencies_batch` finds every mode in a band
from scratch: a count on a grid, then a lockstep refinement with a ladder of seven points per
mode and step. When good estimates are known — the modes of drawn assemblies, estimated by a
reduced model — far fewer evaluations are needed. :func:`natural_frequencies_near` refines,
for every chain ``c`` and requested mode number ``k`` (counted from 0 Hz, the k-th natural
frequency), a bracket around the estimate:

1. **Bracket** ``[e(1 − δ), e(1 + δ)]``; the Wittrick–Williams count ``J`` of the undamped,
   subdivided chain (:func:`rcsa.physics.elimination.wittrick_williams_count`) at both ends
   says how many modes lie below each. An end on the wrong side of mode k is moved out (by 1,
   3 and 7 of the bracket's widths at once); a bracket holding mode k and others is searched
   on the count (its quartiles at each step) until it holds mode k alone (``J(lo) = k``,
   ``J(hi) = k + 1``).
2. **Refine** the single-mode bracket on the determinant of the dynamic stiffness (the
   product of the pivots: ``φ = ±exp(log|det| − ref)``, its sign from the count, so ``φ``
   changes sign exactly at the mode): the secant estimate and a point either side of it at
   a fraction of the bracket that shrinks with the bracket (the secant's error falls like its
   square), plus the midpoint, per step. Which side a point lies on is
   decided by the count, so the bracket stays exact; the result is the interpolated root of
   a bracket no wider than ``rtol``.

Every (chain, mode) pair is one row of one stacked elimination per step. A pair whose bracket
cannot be made valid within :data:`MAX_STEPS` steps is NaN (the caller falls back to a full
search).
"""

from __future__ import annotations

import numpy as np

from rcsa.physics.arrays import FloatArray, IntArray
from rcsa.physics.chain import Chain, undamped
from rcsa.physics.elementwise import local_scratch
from rcsa.physics.elimination import close, march_undamped, subdivide
from rcsa.physics.stacking import take_rows

__all__ = ["MAX_STEPS", "natural_frequencies_near"]

#: Steps (bracket repairs, separations and refinements) before a pair gives up.
MAX_STEPS = 60

_TWO_PI = 2.0 * np.pi
#: Chains are subdivided for this multiple of the highest first bracket end: room for a
#: bracket to grow upwards (no point is evaluated beyond it).
_HEADROOM = 1.25


class _Evaluator:
    """Count and ``log|det|`` of a (stacked) chain at one frequency per row."""

    def __init__(self, chain: Chain, omega_max_rad_s: float) -> None:
        self.omega_max = omega_max_rad_s
        self.chain = subdivide(undamped(chain), omega_max_rad_s)
        self.stacked = any(item.is_stacked for item in self.chain)
        self.scratch = local_scratch()

    def __call__(self, rows: IntArray, omega: FloatArray) -> tuple[IntArray, FloatArray, bool]:
        chain = take_rows(self.chain, rows) if self.stacked else self.chain
        k, pivots = march_undamped(chain, omega, scratch=self.scratch)
        assert pivots is not None  # count=True
        close(k, pivots)
        return pivots.negatives.copy(), pivots.log_abs_det.copy(), pivots.det_known


def natural_frequencies_near(chain: Chain, rows: IntArray, order: IntArray, estimate_hz: FloatArray, *,
                             relative_half_width: float | FloatArray = 0.02, rtol: float = 1e-8) -> FloatArray:
    """Natural frequency number ``order[j]`` of row ``rows[j]`` of a stacked chain, refined from an estimate.

    Parameters
    ----------
    chain : Chain
        One chain, or chains of one structure stacked (:func:`rcsa.physics.stacking.stack_chains`);
        damping is removed.
    rows : numpy.ndarray of int, shape (npairs,)
        The stacked row of each request (ignored for an unstacked chain).
    order : numpy.ndarray of int, shape (npairs,)
        Mode numbers counted from 0 Hz: ``order[j] = k`` asks for the (k+1)-th natural
        frequency (``J`` rises from k to k + 1 across it).
    estimate_hz : numpy.ndarray, shape (npairs,)
        Estimates, Hz (> 0).
    relative_half_width : float or numpy.ndarray, shape (npairs,)
        Half-width δ of the first bracket relative to the estimate (0 < δ < 1).
    rtol : float
        Relative width of the final bracket.

    Returns
    -------
    numpy.ndarray, shape (npairs,)
        Hz; NaN where no valid bracket was found within :data:`MAX_STEPS` steps.

    Examples
    --------
    >>> from rcsa.physics.chain import Beam
    >>> from rcsa.physics.materials import Material
    >>> from rcsa.physics.sections import tube
    >>> bar = (Beam(tube(0.05, 0.0, Material(210e9, 0.3, 7850.0), theory="euler_bernoulli"), 0.4),)
    >>> # free-free: two rigid-body modes at 0 Hz, then βL = 4.7300, 7.8532 (1438.85, 3966.24 Hz)
    >>> natural_frequencies_near(bar, np.zeros(2, int), np.array([2, 3]), np.array([1400.0, 4100.0])).round(3)
    array([1438.847, 3966.238])
    """
    e = np.asarray(estimate_hz, dtype=float)
    half = np.broadcast_to(np.asarray(relative_half_width, dtype=float), e.shape)
    lo = _TWO_PI * e * (1.0 - half)
    hi = _TWO_PI * e * (1.0 + half)
    if e.size == 0:
        return np.empty(0)
    found = _refine(chain, np.asarray(rows), np.asarray(order, dtype=np.int64), lo, hi, rtol)
    out: FloatArray = found / _TWO_PI
    return out


def _refine(chain: Chain, rows: IntArray, k: IntArray, lo: FloatArray, hi: FloatArray, rtol: float) -> FloatArray:
    """Roots (rad/s) of the brackets ``[lo, hi]`` of mode ``k`` of chain ``rows`` (module docstring).

    The chain is subdivided for :data:`_HEADROOM` times the highest bracket end; a bracket that
    grows beyond has the chain subdivided again for twice its new end (and every bracket's ends
    evaluated again: determinants of differently subdivided chains differ by a factor).
    """
    n = rows.size
    evaluate = _Evaluator(chain, _HEADROOM * float(np.max(hi)))
    j_lo, j_hi, f_lo, f_hi, det_known = _ends(evaluate, rows, lo, hi)
    root = np.full(n, np.nan)
    for _ in range(MAX_STEPS):
        single = (j_lo == k) & (j_hi == k + 1)
        done = single & (hi - lo <= rtol * hi) & np.isnan(root)
        if np.any(done):
            root[done] = _secant(lo[done], hi[done], f_lo[done], f_hi[done], k[done], j_lo[done], j_hi[done])
        todo = np.flatnonzero(np.isnan(root))
        if todo.size == 0:
            break
        x = _points(lo[todo], hi[todo], f_lo[todo], f_hi[todo], k[todo], j_lo[todo], j_hi[todo], rtol, det_known)
        if np.nanmax(x, initial=0.0) > evaluate.omega_max:  # beyond the subdivision: subdivide again
            evaluate = _Evaluator(chain, 2.0 * float(np.nanmax(x)))
            j_lo, j_hi, f_lo, f_hi, det_known = _ends(evaluate, rows, lo, hi)
        valid = np.isfinite(x)
        r_idx = np.broadcast_to(todo[:, None], x.shape)[valid]
        j_x, f_x, known_x = evaluate(rows[r_idx], x[valid])
        det_known = det_known and known_x
        jj = np.full(x.shape, -1, dtype=np.int64)
        ff = np.zeros(x.shape)
        jj[valid], ff[valid] = j_x, f_x
        _update(todo, x, jj, ff, k, lo, hi, j_lo, j_hi, f_lo, f_hi)
    return root


def _ends(evaluate: _Evaluator, rows: IntArray, lo: FloatArray, hi: FloatArray
          ) -> tuple[IntArray, IntArray, FloatArray, FloatArray, bool]:
    """Count and ``log|det|`` at both ends of every bracket, in one elimination."""
    n = rows.size
    j, f, known = evaluate(np.concatenate([rows, rows]), np.concatenate([lo, hi]))
    return j[:n].copy(), j[n:].copy(), f[:n].copy(), f[n:].copy(), known


def _phi(j: IntArray, f: FloatArray, k: IntArray, ref: FloatArray) -> FloatArray:
    """``±exp(log|det| − ref)``: positive below mode k, negative above (by the count)."""
    return np.where(j <= k, 1.0, -1.0) * np.exp(np.clip(f - ref, -700.0, 700.0))


def _secant(lo: FloatArray, hi: FloatArray, f_lo: FloatArray, f_hi: FloatArray, k: IntArray, j_lo: IntArray,
            j_hi: IntArray) -> FloatArray:
    """The secant root of ``φ`` in each bracket (its midpoint where the secant leaves it)."""
    ref = np.maximum(f_lo, f_hi)
    a, b = _phi(j_lo, f_lo, k, ref), _phi(j_hi, f_hi, k, ref)
    with np.errstate(divide="ignore", invalid="ignore"):
        x = lo - a * (hi - lo) / (b - a)
    return np.where((x > lo) & (x < hi), x, 0.5 * (lo + hi))


def _points(lo: FloatArray, hi: FloatArray, f_lo: FloatArray, f_hi: FloatArray, k: IntArray, j_lo: IntArray,
            j_hi: IntArray, rtol: float, det_known: bool) -> FloatArray:
    """The points of one step, shape (nrows, 3) (NaN where unused).

    A single-mode bracket: the secant estimate ± a fraction of the bracket (at least
    ``rtol/2``) and the midpoint. An end on the wrong side: that end moved out by 1, 3 and 7
    bracket widths. Several modes: the quartiles (a search on the count).
    """
    width = hi - lo
    pts = np.full((lo.size, 3), np.nan)
    single = (j_lo == k) & (j_hi == k + 1)
    low_bad = j_lo > k
    high_bad = j_hi <= k
    several = ~single & ~low_bad & ~high_bad
    out_steps = np.array([1.0, 3.0, 7.0])                          # the end moved out by 1, 3, 7 widths at once
    pts[low_bad] = np.maximum(lo[low_bad, None] - width[low_bad, None] * out_steps, 0.5 * lo[low_bad, None])
    pts[high_bad] = hi[high_bad, None] + width[high_bad, None] * out_steps
    pts[several] = lo[several, None] + width[several, None] * np.array([0.25, 0.5, 0.75])
    if np.any(single):
        s = np.flatnonzero(single)
        mid = 0.5 * (lo[s] + hi[s])
        x = _secant(lo[s], hi[s], f_lo[s], f_hi[s], k[s], j_lo[s], j_hi[s]) if det_known else mid
        # the secant's error shrinks like the square of the bracket: the side points at a fraction
        # of the bracket that shrinks with it (a quarter of it for a wide bracket)
        eps = np.maximum(0.45 * rtol * hi[s], width[s] * np.minimum(0.25, 10.0 * width[s] / hi[s]))
        ladder = np.stack([x - eps, mid, x + eps], axis=1)
        inside = (ladder > lo[s, None]) & (ladder < hi[s, None])
        pts[s] = np.where(inside, ladder, np.nan)
    return pts


def _update(todo: IntArray, x: FloatArray, jj: IntArray, ff: FloatArray, k: IntArray, lo: FloatArray,
            hi: FloatArray, j_lo: IntArray, j_hi: IntArray, f_lo: FloatArray, f_hi: FloatArray) -> None:
    """Take the new points in (in place): the highest with ``J ≤ k`` raises ``lo``, the lowest
    with ``J > k`` lowers ``hi``. Points outside the bracket repair an end: the nearest one on
    the right side of mode k, else the farthest."""
    kk = k[todo, None]
    valid = jj >= 0
    below_out = valid & (x < lo[todo, None])
    above_out = valid & (x > hi[todo, None])
    n = np.arange(todo.size)
    if np.any(below_out):
        good = np.where(below_out & (jj <= kk), x, -np.inf)
        far = np.where(below_out, x, np.inf)
        col = np.where(np.isfinite(good.max(axis=1)), np.argmax(good, axis=1), np.argmin(far, axis=1))
        has = below_out.any(axis=1)
        r = todo[has]
        lo[r], j_lo[r], f_lo[r] = x[n[has], col[has]], jj[n[has], col[has]], ff[n[has], col[has]]
    if np.any(above_out):
        good = np.where(above_out & (jj > kk), x, np.inf)
        far = np.where(above_out, x, -np.inf)
        col = np.where(np.isfinite(good.min(axis=1)), np.argmin(good, axis=1), np.argmax(far, axis=1))
        has = above_out.any(axis=1)
        r = todo[has]
        hi[r], j_hi[r], f_hi[r] = x[n[has], col[has]], jj[n[has], col[has]], ff[n[has], col[has]]
    inner = valid & ~below_out & ~above_out
    xb = np.where(inner & (jj <= kk), x, -np.inf)
    ib = np.argmax(xb, axis=1)
    take = xb[np.arange(todo.size), ib] > lo[todo]
    r = todo[take]
    lo[r], j_lo[r], f_lo[r] = x[take, ib[take]], jj[take, ib[take]], ff[take, ib[take]]
    xa = np.where(inner & (jj > kk), x, np.inf)
    ia = np.argmin(xa, axis=1)
    take = xa[np.arange(todo.size), ia] < hi[todo]
    r = todo[take]
    hi[r], j_hi[r], f_hi[r] = x[take, ia[take]], jj[take, ia[take]], ff[take, ia[take]]
