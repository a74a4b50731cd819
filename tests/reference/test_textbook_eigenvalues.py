"""Natural frequencies of single beams against textbook and closed-form values.

Sources (``docs/physics.md`` §6): O1/O2 Euler–Bernoulli βL eigenvalues (Blevins, *Formulas for
Natural Frequency and Mode Shape*: free-free 4.7300407, 7.8532046, 10.9956078; clamped-free
1.8751041, 4.6940911, 7.8547574); O3 hinged–hinged Timoshenko closed form (code_aster
V2.04.302); O4/O5 free-free Timoshenko frequencies verified exact-vs-FE (400 elements,
≤6e-5). Steel E = 210 GPa, ν = 0.3, ρ = 7850 kg/m³, Hutchinson κ.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.optimize import brentq

from rcsa.physics.chain import Beam
from rcsa.physics.materials import Material
from rcsa.physics.natural_frequencies import natural_frequencies_hz
from rcsa.physics.sections import tube
from rcsa.physics.segments import dynamic_stiffness, free_free_receptance

STEEL = Material(210e9, 0.30, 7850.0, 0.0)
pytestmark = pytest.mark.reference

# (case, diameter_m, length_m, theory, expected_hz); printed to 7–8 digits → rtol 1e-6,
# the values of O4/O5 to 6 digits → 2e-6.
FREE_FREE = [
    ("O1 EB Ø50×400", 0.05, 0.4, "euler_bernoulli", [1438.8474, 3966.2383, 7775.413], 1e-6),
    ("O4 Timoshenko Ø80×250", 0.08, 0.25, "timoshenko",
     [4823.72, 10526.82, 16753.17, 22161.90, 27089.08, 27158.18, 33522.81, 33527.55], 2e-6),
    ("O4 EB Ø80×250", 0.08, 0.25, "euler_bernoulli", [5893.52, 16245.71, 31848.09], 2e-6),
    ("O5 Timoshenko Ø20×300", 0.02, 0.3, "timoshenko", [1011.50, 2732.44, 5209.91], 5e-6),
    ("O5 EB Ø20×300", 0.02, 0.3, "euler_bernoulli", [1023.18, 2820.44, 5529.18], 5e-6),
]


@pytest.mark.parametrize("case, diameter_m, length_m, theory, expected_hz, rtol", FREE_FREE,
                         ids=[row[0] for row in FREE_FREE])
def test_free_free_natural_frequencies(case, diameter_m, length_m, theory, expected_hz, rtol):
    chain = (Beam(tube(diameter_m, 0.0, STEEL, theory=theory), length_m),)
    found = natural_frequencies_hz(chain, 1.0, expected_hz[-1] * 1.0005)
    np.testing.assert_allclose(found, expected_hz, rtol=rtol, err_msg=case)


def _refine(fun, f_hz: float, rel: float = 0.01) -> float:
    return brentq(fun, f_hz * (1 - rel), f_hz * (1 + rel), xtol=1e-12, rtol=1e-14)


@pytest.mark.parametrize("expected_hz", [241.193, 1511.530, 4232.327])
def test_o2_euler_bernoulli_cantilever(expected_hz):
    # Clamped at x = 0: the free end's dynamic stiffness is D22; det D22 = 0 at the modes.
    section = tube(0.03, 0.0, STEEL, theory="euler_bernoulli")

    def det_d22(f):
        d = dynamic_stiffness(np.array([2 * np.pi * f]), section, 0.3)[0].real
        return np.linalg.det(d[2:, 2:] / np.abs(d[2:, 2:]).max())

    # D22 has poles at the clamped–clamped frequencies; the second one (βL = 7.8532) lies only
    # 0.04 % below the third cantilever mode (βL = 7.8548), so bracket within ±0.02 %.
    assert _refine(det_d22, expected_hz, rel=2e-4) == pytest.approx(expected_hz, rel=2e-6)


def hinged_hinged_closed_form_hz(d: float, length: float, n: int) -> float:
    """code_aster V2.04.302 closed form for a simply supported Timoshenko beam."""
    section = tube(d, 0.0, STEEL)
    ei, kga, ra = section.ei.real, 1 / section.shear_flexibility.real, section.rho_a
    area = np.pi * d**2 / 4
    inertia = np.pi * d**4 / 64
    j, g, lam = inertia / (area * length**2), ei / (kga * length**2), n * np.pi
    omega_bar = ((g + j) * lam**2 + 1 - np.sqrt((g - j) ** 2 * lam**4 + 2 * (g + j) * lam**2 + 1)) / (2 * g * j)
    return float(np.sqrt(omega_bar * ei / (ra * length**4)) / (2 * np.pi))


@pytest.mark.parametrize("n, expected_hz", [(1, 2342.689), (2, 7611.664), (3, 13867.128)])
def test_o3_hinged_hinged_timoshenko(n, expected_hz):
    # Pinned ends (w = 0, M = 0): the translational block of the free-free receptance is singular.
    section = tube(0.08, 0.0, STEEL)
    assert hinged_hinged_closed_form_hz(0.08, 0.25, n) == pytest.approx(expected_hz, rel=1e-6)

    def det_rww(f):
        r = free_free_receptance(np.array([2 * np.pi * f]), section, 0.25)[0].real
        return r[0, 0] * r[2, 2] - r[0, 2] * r[2, 0]

    # det R_ww has poles at the free-free modes; bracket tightly around the closed form.
    assert _refine(det_rww, expected_hz, rel=2e-3) == pytest.approx(expected_hz, rel=1e-6)
