"""Segment receptances against independent forms: matrix exponential, static stiffness,
Euler–Bernoulli closed forms (Bishop & Johnson, ``docs/physics.md`` §2.5) and rigid-body limits."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg

from rcsa.physics.materials import Material
from rcsa.physics.sections import tube
from rcsa.physics.segments import (
    dynamic_stiffness,
    free_free_receptance,
    static_stiffness,
    transfer_matrix,
)
from tests.helpers import RTOL_ALGEBRA, assert_receptance_close

STEEL = Material(210e9, 0.30, 7850.0, 0.0)
DAMPED_STEEL = Material(210e9, 0.30, 7850.0, 0.01)


def expm_transfer(omega: float, section, length_m: float) -> np.ndarray:
    """T = expm(A L) of the first-order state equations (``docs/physics.md`` §2.3), scaled state."""
    ei, fs, ra, ri = section.ei, section.shear_flexibility, section.rho_a, section.rho_i
    a = np.array([[0, 1, fs, 0], [0, 0, 0, 1 / ei], [-ra * omega**2, 0, 0, 0], [0, -ri * omega**2, -1, 0]],
                 dtype=complex)
    s = np.diag([1 / length_m, 1, length_m**2 / abs(ei), length_m / abs(ei)])
    si = np.linalg.inv(s)
    return si @ scipy.linalg.expm(s @ a @ si * length_m) @ s


@pytest.mark.parametrize("material", [STEEL, DAMPED_STEEL], ids=["undamped", "eta=0.01"])
def test_transfer_matrix_equals_matrix_exponential_across_cutoff(material):
    # Ø50×400 mm steel, 10 Hz–60 kHz, across its 39.3 kHz shear cut-off (docs/physics.md §2.9:
    # 3.5e-9 agreement); expm is accurate to ~1e-12 on the scaled state, so 1e-8 leaves margin.
    section = tube(0.05, 0.0, material)
    f_hz = np.array([10.0, 100.0, 1e3, 5e3, 2e4, 39e3, 39.3e3, 39.4e3, 6e4])
    t = transfer_matrix(2 * np.pi * f_hz, section, 0.4)
    for i, f in enumerate(f_hz):
        ref = expm_transfer(2 * np.pi * f, section, 0.4)
        col_scale = np.abs(ref).max(axis=0)
        assert np.max(np.abs(t[i] - ref) / col_scale) < 1e-8, f"T vs expm at {f} Hz"


def test_continuous_through_the_shear_cutoff():
    # At ω_c = sqrt(κGA/ρI) the second wavenumber is exactly zero; the entire-function form
    # must give the same receptance just below, at and just above it.
    section = tube(0.05, 0.0, STEEL)
    wc = np.sqrt(1 / (section.shear_flexibility.real * section.rho_i))
    w = wc * np.array([1 - 1e-9, 1.0, 1 + 1e-9])
    r = free_free_receptance(w, section, 0.4)
    assert np.all(np.isfinite(r))
    # a 1e-9 relative step in ω moves R by at most ~1e-9·(ω/R)·dR/dω ≲ 1e-6 of its largest entry
    assert_receptance_close(r[0], r[1], rtol=1e-6, atol_scale=1e-7)
    assert_receptance_close(r[2], r[1], rtol=1e-6, atol_scale=1e-7)


@pytest.mark.parametrize("material", [STEEL, DAMPED_STEEL], ids=["undamped", "eta=0.01"])
def test_receptance_inverts_dynamic_stiffness_and_both_are_symmetric(material):
    section = tube(0.08, 0.03, material)
    w = 2 * np.pi * np.array([7.0, 330.0, 4100.0, 25000.0])
    r = free_free_receptance(w, section, 0.25)
    d = dynamic_stiffness(w, section, 0.25)
    assert_receptance_close(r, np.swapaxes(r, 1, 2), rtol=RTOL_ALGEBRA)
    assert_receptance_close(d, np.swapaxes(d, 1, 2), rtol=RTOL_ALGEBRA)
    assert_receptance_close(d @ r, np.broadcast_to(np.eye(4), d.shape), rtol=0, atol_scale=1e-8)


def test_dynamic_stiffness_tends_to_the_static_timoshenko_matrix():
    # docs/physics.md §2.4: D(ω→0) equals the exact static stiffness (3e-9 at 0.01 Hz there).
    section = tube(0.05, 0.0, STEEL)
    d = dynamic_stiffness(np.array([2 * np.pi * 0.01]), section, 0.3)[0]
    assert_receptance_close(d, static_stiffness(section, 0.3), rtol=1e-7, atol_scale=1e-9)


def bishop_eb_receptance(omega: np.ndarray, ei: float, rho_a: float, length_m: float) -> np.ndarray:
    """Closed-form Euler–Bernoulli free-free receptance in our convention (``docs/physics.md`` §2.5)."""
    lam = (rho_a * omega**2 / ei) ** 0.25
    ell = lam * length_m
    c, s, ch, sh = np.cos(ell), np.sin(ell), np.cosh(ell), np.sinh(ell)
    c1, c2, c3 = c * sh - s * ch, s * sh, s - sh
    c4, c5, c6, c7 = c - ch, c * sh + s * ch, s + sh, ei * (c * ch - 1)
    out = np.empty((omega.size, 4, 4))
    h00 = -c1 / (lam**3 * c7)
    p00 = c5 / (lam * c7)
    l00 = -c2 / (lam**2 * c7)
    h0l = c3 / (lam**3 * c7)
    p0l = c6 / (lam * c7)
    l0l = c4 / (lam**2 * c7)
    out[:, 0, 0] = out[:, 2, 2] = h00
    out[:, 1, 1] = out[:, 3, 3] = p00
    out[:, 0, 1] = out[:, 1, 0] = l00
    out[:, 2, 3] = out[:, 3, 2] = -l00
    out[:, 0, 2] = out[:, 2, 0] = h0l
    out[:, 1, 3] = out[:, 3, 1] = p0l
    out[:, 0, 3] = out[:, 3, 0] = l0l   # L_0L = N_L0
    out[:, 1, 2] = out[:, 2, 1] = -l0l  # N_0L = L_L0
    return out


def test_euler_bernoulli_equals_bishop_closed_form():
    section = tube(0.05, 0.0, STEEL, theory="euler_bernoulli")
    w = 2 * np.pi * np.array([3.0, 150.0, 1200.0, 5000.0, 9000.0])
    ours = free_free_receptance(w, section, 0.4)
    ref = bishop_eb_receptance(w, section.ei.real, section.rho_a, 0.4)
    for i in range(w.size):
        assert_receptance_close(ours[i], ref[i], rtol=1e-8, atol_scale=1e-10, err_msg=f"row {i}")


def test_rigid_body_limits_of_a_uniform_beam():
    # docs/physics.md §2.7 / O6: H00·mω² → −4, N00·mLω² → +6, P00·mL²ω² → −12, H_L0·mω² → +2.
    section = tube(0.05, 0.0, STEEL, theory="euler_bernoulli")
    length = 0.4
    mass = section.rho_a * length
    w = np.array([2 * np.pi * 0.05])
    r = free_free_receptance(w, section, length)[0].real
    np.testing.assert_allclose(
        [r[0, 0] * mass * w[0] ** 2, r[1, 0] * mass * length * w[0] ** 2,
         r[1, 1] * mass * length**2 * w[0] ** 2, r[2, 0] * mass * w[0] ** 2],
        [-4.0, 6.0, -12.0, 2.0], rtol=1e-5)
    # Timoshenko adds the sections' rotary inertia: H00·mω² → −3.965 for Ø50×400 (§2.7).
    timo = free_free_receptance(w, tube(0.05, 0.0, STEEL), length)[0].real
    assert timo[0, 0] * mass * w[0] ** 2 == pytest.approx(-3.965, abs=5e-4)
