"""The clamping models against 3-D elasticity, on every case held out of their calibration.

The truth is ``tests/data/solid3d`` (quadratic tetrahedra of holder and tool, the holder's base
face clamped, or coupled to RA-1's spindle; ``benchmarks/bench_solid3d.py --write-data``
regenerates it), a model family outside rcsa's beams: five holder families (the issue-24
stepped holder, a slim shrink-fit, a hydraulic chuck, an ER collet chuck with its nut, a
Weldon side-lock). ``benchmarks/calibrate_clamping.py --fit`` fits
:data:`rcsa.model.clamping.BULK_COEFFICIENTS` on the cases of
:data:`~tests.oracles.solid3d.clamping_scores.CALIBRATION_CASES`; every other case but the three
for information is held out and checked here, on both bases. Targets (issue 31): every peak
of 100–8000 Hz within 1.5 % in frequency and 15 % in height; the contract's point model
(composite insertion, rigid point joint) misses them by far, which the last tests pin so that
the comparison cannot pass by accident.
"""

from __future__ import annotations

import pytest

from rcsa.model.clamping import CALIBRATED_GEOMETRY_RANGES
from tests.oracles.solid3d.clamping_scores import (
    CALIBRATION_CASES,
    GEOMETRY_KEYS,
    INFORMATION,
    extrapolation_notes,
    geometry_ranges,
    outside,
    role,
    score_row,
)
from tests.oracles.solid3d.dataset import BASES, FAMILIES, case_family, reference_cases

HELD_OUT = tuple(n for n in reference_cases() if role(n) == "held-out")


@pytest.mark.parametrize("base", BASES)
@pytest.mark.parametrize("name", HELD_OUT)
def test_every_peak_of_a_held_out_case_is_met(name, base):
    s = score_row(name, base, "clamping")
    assert s["peaks"], "a case without a peak in the band"
    assert s["max_frequency_error"] <= 0.015, s["peaks"]
    assert s["max_height_error"] <= 0.15, s["peaks"]


def test_the_point_model_does_not():
    """The same geometry with the contract's point model: its tool mode 5–16 % too high, 4–8.5 dB off."""
    s = score_row("diameter_d8", "clamped", "point")
    assert s["mean_abs_db"] > 4.0 and s["max_frequency_error"] > 0.05, s


def test_every_family_is_both_calibrated_and_held_out_and_no_truth_is_shared():
    assert set(CALIBRATION_CASES).isdisjoint(HELD_OUT) and set(INFORMATION).isdisjoint(HELD_OUT + CALIBRATION_CASES)
    for family in FAMILIES:
        assert any(case_family(n) == family for n in CALIBRATION_CASES), family
        assert any(case_family(n) == family for n in HELD_OUT), family
    # the diagnosis's 40 mm bonded 3-D truth (tests/analysis/diagnosis/truth_solid3d.py) is base_d10's geometry
    assert "base_d10" in HELD_OUT


def test_the_calibrated_range_is_the_span_of_the_calibration_cases():
    """What the prediction notes as extrapolated (rcsa.model.clamping.CALIBRATED_GEOMETRY_RANGES) is where no
    calibration case is (rcsa's view of each case: the holder as its outline, a cone stepped)."""
    ranges = geometry_ranges(CALIBRATION_CASES)
    for key in GEOMETRY_KEYS:
        assert CALIBRATED_GEOMETRY_RANGES[key] == pytest.approx(ranges[key], rel=1e-6), key
    # and a held-out case outside that span is named by rcsa's own notes, one inside is not
    for name in HELD_OUT:
        assert bool(outside(name, ranges)) == bool(extrapolation_notes(name)), name
