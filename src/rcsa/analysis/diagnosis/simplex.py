"""A bounded Nelder–Mead simplex search: SciPy's, step for step, without importing SciPy's optimiser.

A diagnosis polishes the evidence's MAP and fits held-out folds with a few dozen function
evaluations of Nelder–Mead (:func:`scipy.optimize.minimize` with ``method="Nelder-Mead"``).
Importing :mod:`scipy.optimize` (and :mod:`scipy.stats`, which the diagnosis used for one
normal CDF) took 0.4–0.9 s of a first diagnosis in a process — more than the search itself.
:func:`nelder_mead` is SciPy 1.17's ``_minimize_neldermead`` with bounds and without the
adaptive variant, transcribed (same coefficients, same order of operations, same stopping
rules and evaluation budget), so it returns the same point: ``tests/analysis/diagnosis/
test_simplex.py`` compares the two on test functions.

Reflection ρ = 1, expansion χ = 2, contraction ψ = 1/2, shrink σ = 1/2; every trial point is
clipped to the bounds; the search stops when the simplex is within ``xatol`` of its best vertex
and the function within ``fatol`` of its best value, or after ``maxfev`` evaluations.

References
----------
J. A. Nelder, R. Mead, "A simplex method for function minimization", The Computer Journal 7
(1965) 308–313; F. Gao, L. Han, "Implementing the Nelder-Mead simplex algorithm with adaptive
parameters", Computational Optimization and Applications 51 (2012) 259–277 (SciPy's variant).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

__all__ = ["nelder_mead"]

_RHO, _CHI, _PSI, _SIGMA = 1.0, 2.0, 0.5, 0.5
#: The default simplex's steps: 5 % of a non-zero coordinate, else this absolute step.
_NONZDELT, _ZDELT = 0.05, 0.00025


class _Budget(Exception):
    """The evaluation budget is spent."""


def nelder_mead(fun: Callable[[np.ndarray], float], x0: np.ndarray, lo: np.ndarray, hi: np.ndarray, *,
                xatol: float = 1e-4, fatol: float = 1e-4, maxfev: int | None = None,
                initial_simplex: np.ndarray | None = None) -> tuple[np.ndarray, float]:
    """Minimise ``fun`` over the box ``[lo, hi]`` from ``x0`` (module docstring).

    Parameters
    ----------
    fun : callable
        ``fun(x) -> float`` for ``x`` of shape (n,) (a copy: it may keep it).
    x0 : numpy.ndarray, shape (n,)
        Starting point (clipped to the box).
    lo, hi : numpy.ndarray, shape (n,)
        Bounds.
    xatol, fatol : float
        Stop when every vertex is within ``xatol`` of the best (each coordinate) and every
        value within ``fatol`` of the best.
    maxfev : int, optional
        Most evaluations of ``fun`` (200 n by default).
    initial_simplex : numpy.ndarray, shape (n + 1, n), optional
        The starting simplex; by default ``x0`` and ``x0`` with each coordinate moved by 5 %.

    Returns
    -------
    x : numpy.ndarray, shape (n,)
        The best vertex.
    value : float
        ``fun(x)``.

    Examples
    --------
    >>> x, v = nelder_mead(lambda p: float((p[0] - 0.3) ** 2 + 2 * (p[1] + 0.2) ** 2), np.array([1.0, 1.0]),
    ...                    np.array([-1.0, -1.0]), np.array([2.0, 2.0]), xatol=1e-8, fatol=1e-12)
    >>> np.round(x, 4).tolist(), round(v, 10)
    ([0.3, -0.2], 0.0)
    """
    lower, upper = np.asarray(lo, dtype=float), np.asarray(hi, dtype=float)
    x0 = np.clip(np.atleast_1d(np.asarray(x0, dtype=float)), lower, upper)
    if initial_simplex is None:
        n = x0.size
        sim = np.empty((n + 1, n))
        sim[0] = x0
        for k in range(n):
            y = np.array(x0, copy=True)
            y[k] = (1 + _NONZDELT) * y[k] if y[k] != 0 else _ZDELT
            sim[k + 1] = y
    else:
        sim = np.array(np.atleast_2d(initial_simplex), dtype=float)
        n = sim.shape[1]
    maxfun = n * 200 if maxfev is None else maxfev
    sim = np.clip(np.where(sim > upper, 2 * upper - sim, sim), lower, upper)
    calls = [0]

    def f(x: np.ndarray) -> float:
        if calls[0] >= maxfun:
            raise _Budget
        calls[0] += 1
        return float(fun(np.copy(x)))

    fsim = np.full(n + 1, np.inf)
    try:
        for k in range(n + 1):
            fsim[k] = f(sim[k])
    except _Budget:
        pass
    order = np.argsort(fsim)
    sim, fsim = np.take(sim, order, 0), np.take(fsim, order, 0)
    while calls[0] < maxfun:
        try:
            if np.max(np.abs(sim[1:] - sim[0])) <= xatol and np.max(np.abs(fsim[0] - fsim[1:])) <= fatol:
                break
            _step(f, sim, fsim, lower, upper)
        except _Budget:
            pass
        order = np.argsort(fsim)
        sim, fsim = np.take(sim, order, 0), np.take(fsim, order, 0)
    return sim[0], float(np.min(fsim))


def _step(f: Callable[[np.ndarray], float], sim: np.ndarray, fsim: np.ndarray, lower: np.ndarray,
          upper: np.ndarray) -> None:
    """One reflection (expansion, contraction or shrink) of the sorted simplex, in place."""
    n = sim.shape[1]
    xbar = np.add.reduce(sim[:-1], 0) / n
    xr = np.clip((1 + _RHO) * xbar - _RHO * sim[-1], lower, upper)
    fxr = f(xr)
    if fxr < fsim[0]:
        xe = np.clip((1 + _RHO * _CHI) * xbar - _RHO * _CHI * sim[-1], lower, upper)
        fxe = f(xe)
        sim[-1], fsim[-1] = (xe, fxe) if fxe < fxr else (xr, fxr)
        return
    if fxr < fsim[-2]:
        sim[-1], fsim[-1] = xr, fxr
        return
    if fxr < fsim[-1]:  # contraction outside
        xc = np.clip((1 + _PSI * _RHO) * xbar - _PSI * _RHO * sim[-1], lower, upper)
        fxc = f(xc)
        if fxc <= fxr:
            sim[-1], fsim[-1] = xc, fxc
            return
    else:  # contraction inside
        xcc = np.clip((1 - _PSI) * xbar + _PSI * sim[-1], lower, upper)
        fxcc = f(xcc)
        if fxcc < fsim[-1]:
            sim[-1], fsim[-1] = xcc, fxcc
            return
    for j in range(1, n + 1):  # shrink towards the best vertex
        sim[j] = np.clip(sim[0] + _SIGMA * (sim[j] - sim[0]), lower, upper)
        fsim[j] = f(sim[j])
