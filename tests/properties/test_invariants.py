"""Property-based invariants (hypothesis; derandomized in CI: the ``ci`` profile, tests/conftest.py).

Reciprocity, split-beam identity, rigid joint = limit of a stiff elastic joint,
Timoshenko → Euler–Bernoulli in the slender limit, passivity of damped assemblies, and
chain associativity — on random sections, lengths and frequencies.
"""

from __future__ import annotations

import numpy as np
from hypothesis import given
from hypothesis import strategies as st

from rcsa.physics.chain import Beam, Ground, Spring
from rcsa.physics.coupling import couple
from rcsa.physics.elimination import tip_receptance
from rcsa.physics.materials import Material
from rcsa.physics.natural_frequencies import natural_frequencies_hz
from rcsa.physics.sections import tube
from rcsa.physics.segments import free_free_receptance
from tests.helpers import assert_receptance_close

diameters = st.floats(0.005, 0.1)
ratios = st.floats(0.0, 0.8)
lengths = st.floats(0.01, 0.4)
freqs = st.floats(5.0, 20000.0)
etas = st.floats(0.0, 0.02)


def material(eta: float) -> Material:
    return Material(210e9, 0.3, 7850.0, eta)


@st.composite
def beams(draw):
    d = draw(diameters)
    return Beam(tube(d, d * draw(ratios), material(draw(etas))), draw(lengths))


@given(beams(), freqs)
def test_segment_reciprocity(beam, f):
    r = free_free_receptance(np.array([2 * np.pi * f]), beam.section, beam.length_m)
    assert_receptance_close(r, np.swapaxes(r, 1, 2), rtol=1e-8, atol_scale=1e-9)


@given(beams(), st.floats(0.1, 0.9), freqs)
def test_split_beam_identity(beam, fraction, f):
    w = np.array([2 * np.pi * f])
    a = free_free_receptance(w, beam.section, beam.length_m * fraction)
    b = free_free_receptance(w, beam.section, beam.length_m * (1 - fraction))
    whole = free_free_receptance(w, beam.section, beam.length_m)
    assert_receptance_close(couple(a, b), whole, rtol=1e-6, atol_scale=1e-7)


@st.composite
def grounded_chains(draw):
    """Spindle-like chain: random beams, a grounded bearing pair, an elastic joint, more beams."""
    first = [draw(beams()) for _ in range(draw(st.integers(1, 3)))]
    second = [draw(beams()) for _ in range(draw(st.integers(1, 3)))]
    k = draw(st.floats(1e6, 1e9))
    ground = Ground(k, draw(st.floats(1.0, 5e3)))
    joint = Spring(draw(st.floats(1e6, 1e9)), draw(st.floats(0.0, 500.0)), draw(st.floats(1e4, 1e8)),
                   draw(st.floats(0.0, 50.0)))
    return (ground, *first, ground, joint, *second)


@given(grounded_chains(), freqs)
def test_tool_point_reciprocity_and_passivity(chain, f):
    g = tip_receptance(chain, np.array([2 * np.pi * f]))[0]
    assert abs(g[0, 1] - g[1, 0]) <= 1e-9 * abs(g).max()
    # e^{iωt}: a damped driving-point receptance dissipates energy, so Im h ≤ 0 and Im p ≤ 0,
    # and more generally the Hermitian part of Im G is negative semi-definite.
    eig = np.linalg.eigvalsh((g - g.conj().T) / 2j)
    assert np.all(eig <= 1e-9 * abs(g).max())


@given(grounded_chains(), freqs)
def test_rigid_joint_is_the_limit_of_a_stiff_elastic_joint(chain, f):
    w = np.array([2 * np.pi * f])
    rigid = tuple(Spring(None, 0.0, None) if isinstance(i, Spring) else i for i in chain)
    stiff = tuple(Spring(1e16, 0.0, 1e16) if isinstance(i, Spring) else i for i in chain)
    assert_receptance_close(tip_receptance(stiff, w), tip_receptance(rigid, w), rtol=1e-5, atol_scale=1e-6)


@given(st.floats(0.002, 0.05))
def test_timoshenko_tends_to_euler_bernoulli_for_slender_beams(d_over_l):
    # Shear and rotary inertia lower mode n of a free-free bar by ≈ 1.2 n² (d/L)² (Rayleigh–
    # Timoshenko correction with κ ≈ 0.9, E/G = 2.6), so the first three modes must agree with
    # Euler–Bernoulli within 20 (d/L)² and the gap must vanish as d/L → 0.
    length = 1.0
    d = d_over_l * length
    eb_chain = (Beam(tube(d, 0.0, material(0.0), theory="euler_bernoulli"), length),)
    # band up to just above the third free-free mode (βL = 10.9956, Blevins) keeps it cheap
    f3_hz = 10.9956**2 / (2 * np.pi * length**2) * np.sqrt(eb_chain[0].section.ei.real / eb_chain[0].section.rho_a)
    eb = natural_frequencies_hz(eb_chain, 0.01 * f3_hz, 1.05 * f3_hz)
    timo = natural_frequencies_hz((Beam(tube(d, 0.0, material(0.0)), length),), eb[0] * 0.5, eb[2] * 1.01)[:3]
    gap = 1 - timo / eb
    assert np.all(gap > 0)
    assert np.all(gap < 20 * d_over_l**2)


@given(beams(), beams(), beams(), freqs)
def test_chain_associativity(a, b, c, f):
    w = np.array([2 * np.pi * f])
    ra, rb, rc = (free_free_receptance(w, x.section, x.length_m) for x in (a, b, c))
    assert_receptance_close(couple(couple(ra, rb), rc), couple(ra, couple(rb, rc)), rtol=1e-6, atol_scale=1e-7)
