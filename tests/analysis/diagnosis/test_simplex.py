"""The diagnosis's Nelder–Mead and running median against SciPy's, which they replace.

Oracles: :func:`scipy.optimize.minimize` with ``method="Nelder-Mead"`` and bounds (imported
here only) — the same points, evaluation for evaluation — and
:func:`scipy.ndimage.median_filter` with ``mode="nearest"``.
"""

from __future__ import annotations

import numpy as np
import pytest

from rcsa.analysis.diagnosis.problem import _median_filter  # noqa: PLC2701 (a private helper under test)
from rcsa.analysis.diagnosis.simplex import nelder_mead

optimize = pytest.importorskip("scipy.optimize")


def rosenbrock(p: np.ndarray) -> float:
    return float(100.0 * (p[1] - p[0] ** 2) ** 2 + (1.0 - p[0]) ** 2)


def bowl(p: np.ndarray) -> float:
    return float(np.sum((p - np.array([0.3, -0.7, 0.1])[:p.size]) ** 2 * np.arange(1, p.size + 1)))


CASES = [
    (rosenbrock, np.array([-1.2, 1.0]), np.array([-2.0, -2.0]), np.array([2.0, 2.0]), {}),
    (rosenbrock, np.array([1.5, 1.9]), np.array([-2.0, -2.0]), np.array([1.6, 2.0]), {"maxfev": 40}),
    (bowl, np.array([0.9, 0.9, 0.9]), np.array([-1.0, -1.0, 0.0]), np.array([1.0, 1.0, 1.0]), {"maxfev": 90}),
    (bowl, np.array([0.0]), np.array([-1.0]), np.array([1.0]), {}),
]


@pytest.mark.parametrize(("fun", "x0", "lo", "hi", "extra"), CASES)
def test_the_simplex_search_is_scipys(fun, x0, lo, hi, extra):
    opts = {"xatol": 1e-4, "fatol": 1e-3, **extra}
    expected = optimize.minimize(fun, x0, method="Nelder-Mead", bounds=list(zip(lo, hi, strict=True)),
                                 options=opts)
    x, value = nelder_mead(fun, x0, lo, hi, **opts)
    np.testing.assert_array_equal(x, expected.x)
    assert value == expected.fun


def test_a_given_initial_simplex():
    lo, hi = np.array([0.0, 0.0]), np.array([1.0, 1.0])
    simplex = np.array([[0.9, 0.9], [1.0, 0.9], [0.9, 1.0]])
    expected = optimize.minimize(bowl, simplex[0], method="Nelder-Mead", bounds=list(zip(lo, hi, strict=True)),
                                 options={"xatol": 1e-6, "fatol": 1e-9, "maxfev": 60, "initial_simplex": simplex})
    x, value = nelder_mead(bowl, simplex[0], lo, hi, xatol=1e-6, fatol=1e-9, maxfev=60, initial_simplex=simplex)
    np.testing.assert_array_equal(x, expected.x)
    assert value == expected.fun


@pytest.mark.parametrize("size", [3, 9])
def test_the_running_median_is_scipys(size):
    ndimage = pytest.importorskip("scipy.ndimage")
    x = np.random.default_rng(2).uniform(0.5, 1.0, 101)
    np.testing.assert_array_equal(_median_filter(x, size), ndimage.median_filter(x, size=size, mode="nearest"))
