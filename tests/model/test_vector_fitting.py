"""Vector fitting against rational functions whose poles and residues are known.

The oracle is the rational function itself: samples of ``Σ A/(ω − p) + polynomial`` with
chosen poles, residues and background are fitted from starting poles away from the true ones;
vector fitting must find them (to the precision of the arithmetic) and reproduce the
function between the samples.
"""

from __future__ import annotations

import numpy as np
import pytest

from rcsa.model.vector_fitting import RationalFit, vector_fit

#: Exact data and a model of the right order: the fit is limited by the arithmetic of a few
#: relocations (least squares on normal equations, eigenvalues), measured ~1e-11.
RTOL_FIT = 1e-8

POLES = np.array([600.0 + 9.0j, 1385.0 + 21.0j, 1440.0 + 25.0j, 4030.0 + 55.0j]) * 2 * np.pi
RESIDUES = np.array([2.7e-4 + 4e-6j, 8.0e-4 - 2.6e-5j, 2.5e-5 + 1.8e-5j, 7.2e-4 + 2e-6j])
BACKGROUND = np.array([1.0e-7 + 2e-9j, -3.0e-8 + 1e-9j, 5.0e-9 + 0j])


def rational(w: np.ndarray, poles: np.ndarray, residues: np.ndarray, background: np.ndarray,
             scale: float) -> np.ndarray:
    """The oracle, written out term by term."""
    out = np.zeros(w.shape, dtype=complex)
    for p, a in zip(poles, residues, strict=True):
        out += a / (w - p)
    for j, c in enumerate(background):
        out += c * (w / scale) ** j
    return out


def test_the_poles_residues_and_background_of_a_rational_function_are_found():
    w = 2 * np.pi * np.linspace(100.0, 5000.0, 120)
    h = rational(w, POLES, RESIDUES, BACKGROUND, w.max())
    start = POLES.real * np.array([0.97, 1.02, 1.01, 0.95]) + 1j * 0.02 * POLES.real
    fit = vector_fit(w, h, start, degree=2, iterations=6, weights=1.0 / np.abs(h))
    np.testing.assert_allclose(fit.poles_rad_s, POLES, rtol=RTOL_FIT)
    np.testing.assert_allclose(fit.residues, RESIDUES, rtol=RTOL_FIT)
    np.testing.assert_allclose(fit.background, BACKGROUND, rtol=1e-6, atol=1e-12 * np.abs(BACKGROUND).max())
    between = 2 * np.pi * np.linspace(101.0, 4999.0, 777)
    expected = rational(between, POLES, RESIDUES, BACKGROUND, w.max())
    assert np.max(np.abs(fit.evaluate(between) - expected)) <= RTOL_FIT * np.max(np.abs(expected))


def test_many_responses_are_fitted_at_once_each_on_its_own_lines():
    rng = np.random.default_rng(3)
    shift = 1.0 + 0.05 * rng.standard_normal((5, 1))               # each response's poles moved
    poles = POLES[None, :] * shift
    w = np.sort(2 * np.pi * rng.uniform(100.0, 5000.0, (5, 90)), axis=1)
    h = np.stack([rational(w[i], poles[i], RESIDUES, BACKGROUND, float(w.max())) for i in range(5)])
    weights = 1.0 / np.abs(h)
    weights[:, :7] = 0.0                                           # left out: padding
    h[:, :7] = 1.0
    fit = vector_fit(w, h, np.broadcast_to(POLES, (5, POLES.size)), degree=2, iterations=6, weights=weights)
    np.testing.assert_allclose(fit.poles_rad_s, poles, rtol=RTOL_FIT)
    np.testing.assert_allclose(fit.residues, np.broadcast_to(RESIDUES, (5, 4)), rtol=1e-7)


def test_zero_iterations_solve_the_residues_for_given_poles():
    w = 2 * np.pi * np.linspace(100.0, 5000.0, 60)
    h = rational(w, POLES, RESIDUES, BACKGROUND, w.max())
    fit = vector_fit(w, h, POLES, degree=2, iterations=0)
    np.testing.assert_allclose(fit.residues, RESIDUES, rtol=1e-9)
    np.testing.assert_array_equal(fit.poles_rad_s, POLES)


def test_poles_that_would_be_unstable_are_mirrored_into_the_upper_half_plane():
    w = np.linspace(50.0, 150.0, 30)
    h = 2.0 / (w - (100.0 + 3.0j))
    fit = vector_fit(w, h, np.array([100.0 - 3.0j]), degree=0, iterations=3)
    assert fit.poles_rad_s[0].imag > 0
    np.testing.assert_allclose(fit.poles_rad_s, [100.0 + 3.0j], rtol=1e-10)


@pytest.mark.parametrize("degree", [0, 1, 3])
def test_the_background_polynomial_alone(degree):
    w = np.linspace(1.0, 10.0, 25)
    coef = np.arange(1, degree + 2) * (1.0 - 0.5j)
    fit = RationalFit(np.empty(0, dtype=complex), np.empty(0, dtype=complex), coef, 10.0)
    expected = sum(c * (w / 10.0) ** j for j, c in enumerate(coef))
    np.testing.assert_allclose(fit.evaluate(w), expected, rtol=1e-14)
    np.testing.assert_allclose(fit.evaluate(w, background=False), 0.0)
