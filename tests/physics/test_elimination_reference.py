"""The fast elimination (work arrays, unrolled 2×2 algebra) equals the plain one.

``rcsa.physics.elimination_reference`` assembles each item's 4×4 stiffness with the carried
one, constrains rigid joint DOFs and condenses with ``numpy.linalg.solve``; each item's
``eliminate`` does the same in place. Both are exact, so one step agrees to rounding: 1e-12 of
the largest entry the step combines (carried stiffness, element stiffness, result; measured
≤ 3e-13 over 40 random chains, 5 Hz–30 kHz). A result much smaller than what it is made of
(cancellation) cannot be compared tighter than that, and along a whole chain such steps
amplify the rounding: end to end, RA-1's tool point agrees to 5e-12 of each line's largest
entry (measured 9e-13 on one machine and 1.2e-12 on another: the BLAS kernels differ by CPU, and
rounding accumulates over the chain's ~20 steps), a random chain at 30 kHz only to ~1e-7 (both
solvers equally).
"""

from __future__ import annotations

import numpy as np
import pytest

from rcsa.model.assembly import build_model
from rcsa.model.contract import parse_assembly
from rcsa.physics.chain import Beam, Ground, Spring
from rcsa.physics.elimination import march, tip_receptance
from rcsa.physics.elimination_reference import (
    reference_march,
    reference_step,
    reference_tip_receptance,
)
from rcsa.physics.materials import Material
from rcsa.physics.sections import tube
from rcsa.physics.segments import dynamic_stiffness
from rcsa.physics.subassembly_cache import SubassemblyCache
from rcsa.reference import ra1

RTOL = 1e-12
#: A whole chain: the step's rounding accumulated over its steps (module docstring).
CHAIN_RTOL = 5e-12
OMEGA = 2 * np.pi * np.geomspace(5.0, 30000.0, 160)   # across the shear cut-off of the thick sections
STEEL = Material(210.0e9, 0.30, 7850.0, 0.004)
CARBIDE = Material(600.0e9, 0.22, 14500.0, 0.002)


def _random_chain(rng: np.random.Generator) -> tuple:
    """A grounded chain of 4–14 random beams, joints (some DOFs rigid) and grounded items."""
    items: list = [Ground(stiffness_n_m=float(rng.uniform(1e7, 1e9)), damping_ns_m=float(rng.uniform(10, 1e3)),
                          rotational_stiffness_nm_rad=float(rng.uniform(0, 1e6)))]
    for _ in range(int(rng.integers(4, 15))):
        kind = rng.choice(["beam", "beam", "beam", "spring", "ground"])
        if kind == "beam":
            outer = float(rng.uniform(0.006, 0.09))
            inner = float(rng.uniform(0.0, 0.7)) * outer * float(rng.integers(0, 2))
            section = tube(outer, inner, STEEL if rng.random() < 0.6 else CARBIDE,
                           theory="euler_bernoulli" if rng.random() < 0.2 else "timoshenko")
            items.append(Beam(section, float(rng.uniform(0.003, 0.4))))
        elif kind == "spring":
            rigid = rng.integers(0, 3)  # 0: none, 1: translation rigid, 2: rotation rigid
            items.append(Spring(None if rigid == 1 else float(rng.uniform(1e6, 1e9)), float(rng.uniform(0, 500)),
                                None if rigid == 2 else float(rng.uniform(1e4, 1e7)), float(rng.uniform(0, 50))))
        else:
            items.append(Ground(float(rng.uniform(0, 1e8)), float(rng.uniform(0, 1e3)), 0.0, 0.0,
                                float(rng.uniform(0, 0.5)), float(rng.uniform(0, 1e-4))))
    return tuple(items)


def _assert_lines_close(actual, expected, rtol=RTOL, scale=None):
    scale = np.max(np.abs(expected), axis=(1, 2)) if scale is None else scale
    err = np.max(np.max(np.abs(actual - expected), axis=(1, 2)) / scale)
    assert err <= rtol, f"largest difference {err:.2e} of a line's scale (bound {rtol:g})"


def _element_scale(item, omega):
    """Largest entry of the item's own stiffness per line."""
    if isinstance(item, Beam):
        return np.max(np.abs(dynamic_stiffness(omega, item.section, item.length_m)), axis=(1, 2))
    if isinstance(item, Ground):
        return np.max(np.abs(item.stiffness(omega)), axis=(1, 2))
    parts = [np.abs(v) for v in (item.translational(omega), item.rotational(omega)) if v is not None]
    return np.max(parts, axis=0) if parts else np.zeros(omega.size)


@pytest.mark.parametrize("seed", range(12))
def test_every_step_equals_the_plain_elimination_on_random_chains(seed):
    chain = _random_chain(np.random.default_rng(seed))
    k = np.zeros((OMEGA.size, 2, 2), dtype=complex)
    for item in chain:
        plain = reference_step(k, item, OMEGA)
        fast = march((item,), OMEGA, k)[0]      # the item's own eliminate, through the production march
        scale = np.maximum.reduce([np.max(np.abs(plain), axis=(1, 2)), np.max(np.abs(k), axis=(1, 2)),
                                   _element_scale(item, OMEGA)])
        _assert_lines_close(fast, plain, scale=scale)
        k = plain


def test_a_whole_assembly_equals_the_plain_elimination():
    doc = ra1({"start_hz": 5.0, "stop_hz": 10000.0, "step_hz": 5.0})
    chain = build_model(parse_assembly(doc)).chain()
    omega = 2 * np.pi * np.arange(5.0, 10001.0, 5.0)
    _assert_lines_close(tip_receptance(chain, omega), reference_tip_receptance(chain, omega), CHAIN_RTOL)


def test_the_cache_condenses_and_marches_the_rest_as_the_plain_elimination_does():
    doc = ra1({"start_hz": 5.0, "stop_hz": 10000.0, "step_hz": 5.0})
    model = build_model(parse_assembly(doc))
    omega = 2 * np.pi * np.arange(5.0, 10001.0, 5.0)
    prefix, rest = model.to_holder_tip(), model.tool_side()
    expected = reference_tip_receptance(prefix + rest, omega)
    for max_beams in (0, 64):  # marched in blocks, or item by item on a grid that keeps beam terms
        cache = SubassemblyCache(omega, max_beams=max_beams)
        state = cache.condensed((prefix,))
        # the stiffness at the holder tip is a small difference of large beam terms: 4e-12 measured
        _assert_lines_close(state.stiffness, reference_march(prefix, omega), 1e-11)
        _assert_lines_close(cache.tip_receptance(state, rest), expected, CHAIN_RTOL)
        np.testing.assert_allclose(cache.tip_h(state, rest), expected[:, 0, 0], rtol=0,
                                   atol=CHAIN_RTOL * np.max(np.abs(expected)))


def test_a_rigid_joint_dof_is_shared_and_a_fully_rigid_joint_changes_nothing():
    beam = Beam(tube(0.02, 0.0, STEEL), 0.1)
    k0 = march((Ground(stiffness_n_m=1e8), beam), OMEGA)[0]
    np.testing.assert_array_equal(reference_step(k0, Spring(None, 0.0, None, 0.0), OMEGA), k0)
    # a very stiff joint is the rigid one, DOF by DOF (the limit the constraint stands for)
    # (penalty error ~ k/k_joint <= 1e-6, k up to 1e10 at 30 kHz; cancellation ~ eps·k_joint/k ~ 1e-8)
    for stiff, rigid in ((Spring(1e16, 0.0, 1e6, 0.0), Spring(None, 0.0, 1e6, 0.0)),
                         (Spring(1e7, 0.0, 1e16, 0.0), Spring(1e7, 0.0, None, 0.0))):
        _assert_lines_close(reference_step(k0, stiff, OMEGA), reference_step(k0, rigid, OMEGA), 1e-5)
