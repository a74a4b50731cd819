"""Natural frequencies refined from estimates, against the full search and a textbook beam.

Oracles: the Euler–Bernoulli free-free beam (βL = 4.7300, 7.8532, 10.9956) and
:func:`rcsa.physics.natural_frequencies.natural_frequencies_batch`, which finds every mode of
a band from a count on a grid (no estimate). Whatever the estimate — good, on the wrong side
of a neighbouring mode, far off — the k-th natural frequency found is the same.
"""

from __future__ import annotations

import numpy as np
import pytest

from rcsa.model.assembly import build_model
from rcsa.model.contract import parse_assembly
from rcsa.model.draw_chains import drawn_chains
from rcsa.model.tolerances import DEFAULT_TOLERANCES, draw_nuisance
from rcsa.physics.chain import Beam, undamped
from rcsa.physics.elimination import subdivide, wittrick_williams_count
from rcsa.physics.materials import Material
from rcsa.physics.natural_frequencies import natural_frequencies_batch
from rcsa.physics.sections import tube
from rcsa.physics.seeded_modes import natural_frequencies_near
from rcsa.reference import ra1

#: The bracket's root is refined to 1e-10 here; both searches agree to their brackets.
RTOL = 1e-9

STEEL = Material(210e9, 0.3, 7850.0)
BAR = (Beam(tube(0.05, 0.0, STEEL, theory="euler_bernoulli"), 0.4),)


def textbook_hz(beta_l: float) -> float:
    """Free-free Euler–Bernoulli frequency of BAR for a root βL."""
    ei = STEEL.youngs_modulus_pa * np.pi * 0.05**4 / 64
    rho_a = STEEL.density_kg_m3 * np.pi * 0.05**2 / 4
    return beta_l**2 / 0.4**2 * np.sqrt(ei / rho_a) / (2 * np.pi)


@pytest.mark.parametrize("estimate_ratio", [1.0, 0.7, 1.4])
def test_a_free_free_beam_gives_the_textbook_frequencies_from_any_estimate(estimate_ratio):
    expected = np.array([textbook_hz(b) for b in (4.730041, 7.853205, 10.995608)])
    got = natural_frequencies_near(BAR, np.zeros(3, dtype=int), np.array([2, 3, 4]), expected * estimate_ratio,
                                   relative_half_width=0.01, rtol=1e-10)
    np.testing.assert_allclose(got, expected, rtol=2e-6)  # the βL roots to 7 digits


@pytest.fixture(scope="module")
def draws():
    grid = {"start_hz": 100.0, "stop_hz": 5000.0, "step_hz": 50.0}
    spec = parse_assembly(ra1(grid))
    knobs = draw_nuisance(np.random.default_rng(5), DEFAULT_TOLERANCES, 12)
    drawn = drawn_chains(spec, knobs)
    chains = [drawn.chain(d) for d in range(12)]
    found = natural_frequencies_batch((), chains, 300.0, 5500.0, rtol=1e-12)
    below = [int(wittrick_williams_count(subdivide(undamped(c), 2 * np.pi * 300.0), np.array([2 * np.pi * 300.0]))[0])
             for c in chains]
    return drawn, found, below


def test_every_drawn_mode_equals_the_full_search_whatever_the_estimate(draws):
    drawn, found, below = draws
    group = drawn.groups[0]
    rng = np.random.default_rng(1)
    rows, order, estimate, expected = [], [], [], []
    for j, d in enumerate(group.draws):
        for i, f in enumerate(found[d]):
            rows.append(j)
            order.append(below[d] + i)
            expected.append(f)
            estimate.append(f * (1.0 + 0.05 * rng.standard_normal()))  # often on the wrong side of a neighbour
    got = natural_frequencies_near(group.chain, np.array(rows), np.array(order), np.array(estimate),
                                   relative_half_width=0.002, rtol=1e-10)
    np.testing.assert_allclose(got, expected, rtol=RTOL)


def test_close_modes_are_told_apart_by_the_count(draws):
    """RA-1's 1384 and 1445 Hz modes are 4 % apart: estimates of both at their midpoint still
    give each its own mode (the count says which is which)."""
    drawn, found, below = draws
    group = drawn.groups[0]
    d = int(group.draws[0])
    i = int(np.argmin(np.abs(found[d] - 1384.0)))
    mid = 0.5 * (found[d][i] + found[d][i + 1])
    got = natural_frequencies_near(group.chain, np.zeros(2, dtype=int), np.array([below[d] + i, below[d] + i + 1]),
                                   np.array([mid, mid]), relative_half_width=0.05, rtol=1e-10)
    np.testing.assert_allclose(got, found[d][i:i + 2], rtol=RTOL)


def test_the_nominal_chain_unstacked():
    chain = build_model(parse_assembly(ra1({"start_hz": 100.0, "stop_hz": 2000.0, "step_hz": 50.0}))).chain()
    expected = natural_frequencies_batch((), [chain], 100.0, 2000.0, rtol=1e-12)[0]
    got = natural_frequencies_near(chain, np.zeros(expected.size, dtype=int), np.arange(expected.size),
                                   expected * 1.01, rtol=1e-10)
    np.testing.assert_allclose(got, expected, rtol=RTOL)
