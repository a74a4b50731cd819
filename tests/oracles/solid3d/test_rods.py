"""The 3-D reference on plain rods against Timoshenko beam theory (``docs/physics.md`` §6, O4, O5).

Free-free rods are meshed as quarter models (bending in x); their first three elastic
natural frequencies must lie within 0.5 % of exact Timoshenko theory (Hutchinson's κ), the
target issue 24 sets for the reference. A hollow rod and a composite rod (a steel tube
bonded to a carbide core, the contract's composite insertion section) are compared with
rcsa's exact Timoshenko chain (its own section formulas, nothing of them used here). The
cantilever compares the fully fixed base face with the beam's clamp (w = ψ = 0): the 3-D
clamp also stops the section's Poisson contraction and warping at the root, which makes
the solid slightly stiffer: +0.57 %, +0.43 %, +0.33 % on the first three modes of a
Ø20 × 150 mm steel rod (L/d = 7.5); the test bounds it at 1 %.
"""

from __future__ import annotations

import numpy as np
import pytest

from rcsa.physics.chain import Beam, Ground
from rcsa.physics.materials import Material
from rcsa.physics.natural_frequencies import natural_frequencies_hz
from rcsa.physics.sections import composite, tube
from tests.oracles.solid3d.assembly import assemble
from tests.oracles.solid3d.case import CARBIDE, STEEL, Interface, MeshSize
from tests.oracles.solid3d.geometry import Piece, mesh_pieces
from tests.oracles.solid3d.reduction import free_frequencies_hz
from tests.oracles.solid3d.solve import build_body

RTOL_THEORY = 5e-3          # issue 24: the reference within 0.5 % of Timoshenko theory
RC_STEEL = Material(210e9, 0.30, 7850.0)
RC_CARBIDE = Material(600e9, 0.22, 14500.0)


def _free(pieces: tuple[Piece, ...], size_m: float, count: int = 3) -> np.ndarray:
    mesh = mesh_pieces(pieces, MeshSize(size_m, size_m), quarter=True)
    mats = assemble(mesh, (STEEL, CARBIDE), Interface(), "free", max(p.z1_m for p in pieces))
    return free_frequencies_hz(mats, count)


@pytest.mark.reference
@pytest.mark.parametrize(("diameter_m", "length_m", "exact_hz"), [
    (0.020, 0.300, [1011.50, 2732.44, 5209.91]),      # O5
    (0.080, 0.250, [4823.72, 10526.82, 16753.17]),    # O4 (stubby: shear and rotary inertia matter)
])
def test_free_free_solid_rods_match_exact_timoshenko(diameter_m, length_m, exact_hz):
    f = _free((Piece("holder", 0.0, length_m, diameter_m),), 0.25 * diameter_m)
    np.testing.assert_allclose(f, exact_hz, rtol=RTOL_THEORY)


def test_free_free_hollow_rod_matches_rcsa_exact_tube():
    d_o, d_i, length = 0.040, 0.020, 0.300
    f = _free((Piece("holder", 0.0, length, d_o, d_i),), 0.25 * d_o)
    exact = natural_frequencies_hz((Beam(tube(d_o, d_i, RC_STEEL), length),), 100.0, 1.2 * f[-1])[:3]
    np.testing.assert_allclose(f, exact, rtol=RTOL_THEORY)


def _composite_rod(d_o: float, d_i: float, length: float, size_m: float) -> tuple[np.ndarray, np.ndarray]:
    pieces = (Piece("holder", 0.0, length, d_o, d_i), Piece("tool", 0.0, length, d_i))
    f = _free(pieces, size_m)
    section = composite(tube(d_o, d_i, RC_STEEL), tube(d_i, 0.0, RC_CARBIDE))
    return f, natural_frequencies_hz((Beam(section, length),), 100.0, 1.2 * f[-1])[:3]


def test_composite_rod_matches_rcsa_composite_section_where_shear_is_small():
    """Steel tube bonded to a carbide core vs the beam's composite section (EI, κGA, ρA, ρI add).

    Ø20/Ø8 × 300 mm (L/d = 15): +0.09 %, +0.28 %, +0.55 % on modes 1-3; Ø40/Ø16 × 250 mm
    (L/d = 6.25, mesh-converged: 10 and 5 mm meshes agree to 3e-5): +0.38 %, +1.16 %, +2.0 %.
    The bonded solid is stiffer in shear than the summed κ_i G_i A_i (the thick tube keeps its
    own low κ in the sum although, bonded to the core, the section shears as one body): a
    limit of the contract's composite insertion, growing with the mode's shear share, not an
    error of the reference (the solid rods above agree to 0.02-0.14 %).
    """
    f, exact = _composite_rod(0.020, 0.008, 0.300, 0.010)
    ratio = f / exact - 1
    assert np.all(np.abs(ratio[:2]) < RTOL_THEORY), ratio
    assert np.all(ratio > 0) and np.all(np.diff(ratio) > 0), ratio


def test_cantilever_with_a_fixed_base_face_is_slightly_stiffer_than_the_beam_clamp():
    d, length = 0.020, 0.150
    model = build_body((Piece("holder", 0.0, length, d),), (STEEL, STEEL), MeshSize(0.5 * d, 0.5 * d),
                       "clamped", 20000.0)
    f = model.reduced.fixed_base_frequencies_hz[:3]
    rigid = 1e14
    clamp = Ground(rigid, 0.0, rigid, 0.0)
    exact = natural_frequencies_hz((clamp, Beam(tube(d, 0.0, RC_STEEL), length)), 100.0, 1.2 * f[-1])[:3]
    ratio = f / exact - 1
    assert np.all(ratio > -1e-3), ratio           # never softer (beyond discretisation)
    assert np.all(ratio < 2 * RTOL_THEORY), ratio
