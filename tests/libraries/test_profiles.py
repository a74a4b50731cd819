"""Stepped cones converge to the cone, and the default step count is within 0.5 % of it.

A cone clamped at its thick end (a tapered tool neck, a holder nose as a cantilever) is
built from :func:`cone_cylinders` with n steps; its tip static compliance and first natural
frequency are compared with the fine-step limit (64 and 128 steps extrapolated). Checked: the error
falls monotonically and as 1/n² (halving the step quarters it), the default
:func:`cone_steps` count keeps both within :data:`CONE_STEP_TOLERANCE` (0.5 %), and the
mid-length diameter is closer than the uniform-moment "stiffness-equivalent" diameter.
Measured (for the record): 6→10 mm over 30 mm, n = 1, 2, 4, 8, 16, 32 → tip compliance
+43.7, +10.6, +2.54, +0.62, +0.16, +0.04 %, first mode −33.8, −10.5, −2.81, −0.71, −0.18,
−0.04 %; the default n = 12 gives +0.28 % / −0.32 %.
"""

from __future__ import annotations

import math

import pytest

from rcsa.libraries.profiles import CONE_STEP_TOLERANCE, cone_cylinders, cone_steps
from rcsa.model.assembly import tool_chain
from rcsa.model.contract import parse_tool
from rcsa.physics.chain import Beam, Ground
from rcsa.physics.elimination import static_tip_receptance
from rcsa.physics.materials import BUILTIN_MATERIALS
from rcsa.physics.natural_frequencies import natural_frequencies_hz
from rcsa.physics.sections import tube

CARBIDE = BUILTIN_MATERIALS["carbide"]
CLAMP = Ground(1e18, 0.0, 1e18, 0.0)
# (length m, tip diameter, clamped diameter): a tapered neck, a gentle taper, a steep one
CONES = [(0.030, 0.006, 0.010), (0.030, 0.008, 0.0084), (0.050, 0.003, 0.012)]


def cantilever(length: float, tip: float, root: float, pieces: list[tuple[float, float]]) -> tuple[float, float]:
    """Tip static compliance (m/N) and first natural frequency (Hz) of the stepped cone."""
    del length, tip, root
    chain = (CLAMP, *(Beam(tube(d, 0.0, CARBIDE), h) for h, d in reversed(pieces)))
    return float(static_tip_receptance(chain)[0, 0]), float(natural_frequencies_hz(chain, 10.0, 1e5)[0])


def errors(cone: tuple[float, float, float], n: int, reference: tuple[float, float]) -> tuple[float, float]:
    length, tip, root = cone
    s, f = cantilever(*cone, cone_cylinders(length, tip, root, n))
    return s / reference[0] - 1.0, f / reference[1] - 1.0


@pytest.fixture(scope="module")
def references() -> dict[tuple[float, float, float], tuple[float, float]]:
    """The fine-step limit: Richardson extrapolation of 64 and 128 steps (the error is ∝ 1/n²)."""
    out = {}
    for cone in CONES:
        (s1, f1), (s2, f2) = (cantilever(*cone, cone_cylinders(cone[0], cone[1], cone[2], n)) for n in (64, 128))
        out[cone] = ((4 * s2 - s1) / 3, (4 * f2 - f1) / 3)
    return out


@pytest.mark.parametrize("cone", CONES, ids=["neck-6-10", "gentle-8-8.4", "steep-3-12"])
def test_stepped_cone_converges_as_one_over_n_squared(cone, references):
    ref = references[cone]
    errs = [errors(cone, n, ref) for n in (2, 4, 8, 16, 32)]
    for k, ((s_coarse, f_coarse), (s_fine, f_fine)) in enumerate(zip(errs, errs[1:], strict=False)):
        assert 0 < s_fine < s_coarse and f_coarse < f_fine < 0  # too soft, too low, less so each time
        if k >= 1:  # from n = 4 on, halving the step quarters the error
            assert s_coarse / s_fine == pytest.approx(4.0, rel=0.15)
            assert f_coarse / f_fine == pytest.approx(4.0, rel=0.15)


@pytest.mark.parametrize("cone", CONES, ids=["neck-6-10", "gentle-8-8.4", "steep-3-12"])
def test_default_step_count_is_within_the_stated_tolerance(cone, references):
    length, tip, root = cone
    n = cone_steps(tip, root)
    assert n == math.ceil(math.sqrt(abs(root - tip) / min(tip, root) / CONE_STEP_TOLERANCE))
    s_err, f_err = errors(cone, n, references[cone])
    assert abs(s_err) <= CONE_STEP_TOLERANCE and abs(f_err) <= CONE_STEP_TOLERANCE, (n, s_err, f_err)
    # and one step fewer is not always enough: the rule is not generous by a wide margin
    assert max(abs(e) for e in errors(cone, max(1, n // 2), references[cone])) > CONE_STEP_TOLERANCE


def test_middle_diameter_beats_the_uniform_moment_equivalent_diameter(references):
    cone = CONES[0]
    length, tip, root = cone
    n = 4
    h = length / n

    def uniform_moment(a: float, b: float) -> float:  # d⁴ = harmonic mean of d⁴ along the step
        return (3 * a**3 * b**3 / (a * a + a * b + b * b)) ** 0.25

    ends = [tip + (root - tip) * k / n for k in range(n + 1)]
    equivalent = [(h, uniform_moment(a, b)) for a, b in zip(ends, ends[1:], strict=False)]
    s_eq = cantilever(*cone, equivalent)[0] / references[cone][0] - 1
    s_mid, _ = errors(cone, n, references[cone])
    assert 0 < s_mid < s_eq


def test_cone_steps_rule_examples():
    assert cone_steps(50.0, 50.0) == 1
    assert (cone_steps(42.0, 46.0), cone_steps(46.0, 42.0)) == (5, 5)  # symmetric
    assert cone_steps(8.0, 8.01) == 1 + 0  # a 0.1 % taper: ⌈√0.25⌉ = 1
    assert cone_steps(1.0, 100.0) == 50  # capped


def test_a_stepped_neck_through_the_tool_model_converges_too():
    """The contract's neck_segments, solved by the tool chain, clamped at the holder face."""
    base = {"material": "carbide", "diameter_m": 0.006, "shank_diameter_m": 0.010, "overall_length_m": 0.090,
            "flute_length_m": 0.012, "stickout_m": 0.052}

    def tip_compliance(n: int) -> float:
        steps = cone_cylinders(0.030, 0.006, 0.010, n)  # from the flute end (thin) to the shank
        tool = parse_tool({**base, "neck_segments": [{"length_m": h, "diameter_m": d} for h, d in steps]},
                          BUILTIN_MATERIALS)
        return float(static_tip_receptance((CLAMP, *tool_chain(tool, BUILTIN_MATERIALS)))[0, 0])

    ref = tip_compliance(200)
    assert abs(tip_compliance(cone_steps(0.006, 0.010)) / ref - 1) <= CONE_STEP_TOLERANCE
    assert tip_compliance(1) / ref - 1 > 0.05  # one mean-diameter cylinder: several % too soft
