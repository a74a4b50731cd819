"""Chain items own their steps: the solvers run any item that follows the protocol.

* stacking: a stacked chain solved row by row equals each chain solved alone;
* subdivision and undamping are the items' own copies and change nothing they should not;
* a measured (compliance) base gives what its inverse as a stiffness start gives;
* a new item type needs nothing but the protocol (a point mass written from scratch).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rcsa.model.assembly import build_model
from rcsa.model.contract import parse_assembly
from rcsa.physics.algebra2x2 import inv2
from rcsa.physics.chain import Beam, Grid, Ground, Lumped, Spring, Sym, undamped
from rcsa.physics.elimination import march, static_condense, subdivide, tip_receptance
from rcsa.physics.stacking import chain_signature, stack_chains, take_rows
from rcsa.reference import ra1
from tests.helpers import RTOL_ALGEBRA, assert_receptance_close

OMEGA = 2 * np.pi * np.geomspace(20.0, 8000.0, 60)


def ra1_model(stickout_m: float = 0.074):
    doc = ra1({"start_hz": 20.0, "stop_hz": 8000.0, "step_hz": 20.0})
    doc["tool"] = {**doc["tool"], "stickout_m": stickout_m}
    return build_model(parse_assembly(doc))


def test_stacked_tails_solve_like_each_tail_alone():
    models = [ra1_model(s) for s in (0.05, 0.062, 0.081)]
    prefix = models[0].to_holder_tip()
    tails = [m.tool_side() for m in models]
    assert len({chain_signature(t) for t in tails}) == 1
    k0 = march(prefix, OMEGA)[0]
    stacked = stack_chains(tails)
    assert all(item.is_stacked for item in stacked)
    for row, tail in enumerate(tails):
        rows = np.full(OMEGA.size, row)
        got = inv2(march(take_rows(stacked, rows), OMEGA, k0)[0])
        assert_receptance_close(got, inv2(march(tail, OMEGA, k0)[0]), RTOL_ALGEBRA)


def test_subdivision_and_undamping_are_the_items_own_copies():
    chain = ra1_model().chain()
    pieces = subdivide(chain, 2 * np.pi * 8000.0)
    assert len(pieces) > len(chain)
    assert_receptance_close(tip_receptance(pieces, OMEGA), tip_receptance(chain, OMEGA), 1e-9)
    real = undamped(chain)
    assert all(isinstance(i, Beam) or (i.damping_ns_m == 0.0 and i.rotational_damping_nms_rad == 0.0)
               for i in real)
    assert all(np.imag(i.section.ei) == 0.0 for i in real if isinstance(i, Beam))
    np.testing.assert_array_equal(static_condense(real), static_condense(chain))


def test_a_compliance_base_equals_its_inverse_as_a_stiffness_start():
    model = ra1_model()
    spindle, rest = model.spindle_side(), model.holder + model.tool_side()
    base = tip_receptance(spindle, OMEGA)
    by_compliance = inv2(march(rest, OMEGA, start_compliance=base)[0])
    by_stiffness = inv2(march(rest, OMEGA, inv2(base))[0])
    assert_receptance_close(by_compliance, by_stiffness, 1e-8)


@dataclass(frozen=True, slots=True)
class PointMass(Lumped):
    """A test-only item: a lumped mass ``m`` (kg), dynamic stiffness ``−ω²m`` on the translation."""

    mass_kg: float

    def eliminate(self, k: Sym, grid: Grid, count: bool = False):
        return (k[0] - grid.omega_rad_s**2 * self.mass_kg, k[1], k[2]), None

    def eliminate_static(self, k: Sym) -> Sym:
        return k

    def absorb_compliance(self, compliance, grid):
        return Ground(mass_kg=self.mass_kg).absorb_compliance(compliance, grid)

    def undamped(self):
        return self


def test_a_new_item_type_needs_only_the_protocol():
    chain = ra1_model().chain()
    with_ground = chain + (Ground(mass_kg=0.004),)
    with_new = chain + (PointMass(0.004),)
    assert_receptance_close(tip_receptance(with_new, OMEGA), tip_receptance(with_ground, OMEGA), RTOL_ALGEBRA)
    assert subdivide(with_new, 1e4)[-1] == PointMass(0.004)
    stacked = stack_chains([(Spring(1e7), PointMass(0.004)), (Spring(2e7), PointMass(0.005))])
    assert stacked[1].mass_kg.tolist() == [0.004, 0.005]
    assert take_rows(stacked, np.array([1, 1, 0]))[1].mass_kg.tolist() == [0.005, 0.005, 0.004]
