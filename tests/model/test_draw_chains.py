"""The draws' chains built stacked from the knobs equal the draws built one by one.

Oracle: :func:`rcsa.model.tolerances.perturbed_spec` + :func:`rcsa.model.assembly.build_model`
for every draw (the plain way), stacked. Every number of every item must agree.
"""

from __future__ import annotations

import numpy as np
import pytest

from rcsa.model.assembly import build_model
from rcsa.model.contract import parse_assembly
from rcsa.model.draw_chains import CHECK_RTOL, drawn_chains, stacked_from_models
from rcsa.model.tolerances import DEFAULT_TOLERANCES, draw_nuisance, perturbed_spec
from rcsa.physics.chain import Beam
from rcsa.physics.stacking import chain_signature
from rcsa.reference import ra1

GRID = {"start_hz": 100.0, "stop_hz": 2000.0, "step_hz": 100.0}


def numbers(chain) -> list:
    out = []
    for item in chain:
        if isinstance(item, Beam):
            s = item.section
            out += [s.ei, s.shear_flexibility, s.rho_a, s.rho_i, item.length_m]
        else:
            out += [getattr(item, name) for name in item.__dataclass_fields__]
    return out


def assert_same(drawn, plain, n):
    for d in range(n):
        a, b = drawn.chain(d), plain.chain(d)
        assert chain_signature(a) == chain_signature(b)
        for x, y in zip(numbers(a), numbers(b), strict=True):
            assert (x is None) == (y is None)
            if x is not None:
                np.testing.assert_allclose(np.asarray(x), np.asarray(y), rtol=CHECK_RTOL, atol=0.0)


def plain_build(spec, knobs, plane=None):
    return stacked_from_models([build_model(perturbed_spec(spec, knobs.fields(d)), plane)
                                for d in range(knobs.n_draws)])


@pytest.mark.parametrize("tolerances", [DEFAULT_TOLERANCES, {**DEFAULT_TOLERANCES, "stickout_m": 0.0},
                                        {**DEFAULT_TOLERANCES, "loss_factor_log": 1.0, "tool_density_rel": 0.2}])
def test_the_fast_build_equals_the_plain_one_on_ra1(tolerances):
    spec = parse_assembly(ra1(GRID))
    knobs = draw_nuisance(np.random.default_rng(4), tolerances, 9)
    fast = drawn_chains(spec, knobs)
    assert fast.fast and len(fast.groups) == 1
    assert_same(fast, plain_build(spec, knobs), 9)


def test_a_necked_tool_and_a_holder_tip_base():
    doc = ra1(GRID)
    doc["tool"] = {**doc["tool"], "shoulder_length_m": 0.045, "shoulder_diameter_m": 0.011}
    spec = parse_assembly(doc)
    knobs = draw_nuisance(np.random.default_rng(5), DEFAULT_TOLERANCES, 6)
    for plane in (None, "spindle_nose"):
        fast = drawn_chains(spec, knobs, plane)
        assert fast.fast
        assert_same(fast, plain_build(spec, knobs, plane), 6)


def test_a_stickout_that_moves_the_insertion_across_a_holder_segment_is_built_the_plain_way():
    """RA-1's insertion starts inside a holder segment; a stickout tolerance of centimetres moves
    it across a segment end in some draws, which changes the chain's structure: the draws are
    then built one by one, grouped by structure, and still equal the plain build."""
    spec = parse_assembly(ra1(GRID))
    knobs = draw_nuisance(np.random.default_rng(6), {**DEFAULT_TOLERANCES, "stickout_m": 0.02}, 10)
    drawn = drawn_chains(spec, knobs)
    assert not drawn.fast and len(drawn.groups) > 1
    assert_same(drawn, plain_build(spec, knobs), 10)
