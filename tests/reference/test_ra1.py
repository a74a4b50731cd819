"""RA-1, the project's verified reference assembly (``docs/physics.md`` §1.4–1.5, §6 O10–O12, O16).

RA-1: BT40-class spindle (9 segments, 4 bearings), shrink-fit holder with the Ø12.7 mm
carbide shank inside (composite sections), 74 mm stickout, the seed paper's Table 2 joint
values. The reference values were produced by an exact RCSA prototype cross-checked against a
Timoshenko FE model (<0.01 %); the damped tool-point h is in ``tests/data/ra1``.
"""

from __future__ import annotations

import numpy as np
import pytest

import rcsa
from rcsa.model.assembly import build_model
from rcsa.model.contract import parse_assembly
from rcsa.reference import ra1
from tests.helpers import REPO

pytestmark = pytest.mark.reference

# docs/physics.md §1.5, undamped natural frequencies (Hz) of RA-1 and its variants, printed to
# 0.01 Hz. The issue asked for 0.01 % (1e-4 relative); they agree to <= 1e-5 (worst: the
# rigid-joint variant, 7.2e-6; RA-1 itself 4.5e-6, its print rounding), so 2e-5 is asserted.
EXACT = [599.85, 921.69, 1115.51, 1383.61, 1444.68, 3115.94, 4025.97, 5102.79, 6080.83, 7717.51]
VARIANTS = {
    "euler_bernoulli": [607.77, 938.08, 1136.65, 1393.84, 1530.86, 3551.80, 4091.62, 6330.50, 7415.28],
    "rigid_joints": [752.95, 944.85, 1250.06, 2054.69, 2946.13, 4749.97, 6285.50, 7806.82, 9868.78],
    "cowper": [599.56, 920.97, 1114.61, 1383.14, 1442.45, 3106.73, 4025.10, 5074.74, 6050.82, 7652.83],
    "flutes_equal_d": [590.33, 921.41, 1102.03, 1284.08, 1444.53, 3115.79, 3711.57, 5099.47, 6075.12, 7717.04],
}
RTOL_MODES = 2e-5
#: max |h - h_csv| / max |h_csv| over 5-9999 Hz (measured 2.0e-8)
RTOL_CSV_OF_PEAK = 5e-8


def variant(name: str) -> dict:
    doc = ra1({"start_hz": 5.0, "stop_hz": 10000.0, "step_hz": 5.0})
    if name == "euler_bernoulli":
        doc["beam_theory"] = "euler_bernoulli"
    elif name == "rigid_joints":
        del doc["joints"]
    elif name == "cowper":
        doc["shear_coefficient"] = "cowper"
    elif name == "flutes_equal_d":
        doc["tool"]["fluted_diameter_ratio"] = 1.0
    return doc


def test_o10_natural_frequencies():
    result = rcsa.predict(variant("exact"))
    np.testing.assert_allclose(result.natural_frequencies_hz, EXACT, rtol=RTOL_MODES,
                               err_msg="RA-1 undamped natural frequencies vs docs/physics.md §1.5")


@pytest.mark.parametrize("name", list(VARIANTS))
def test_o11_variants(name):
    found = rcsa.predict(variant(name)).natural_frequencies_hz
    expected = VARIANTS[name]
    # The EB column lists 9 of the modes below 10 kHz (its 10th mode is 10905 Hz, out of band).
    np.testing.assert_allclose(found[:len(expected)], expected, rtol=RTOL_MODES,
                               err_msg=f"RA-1 variant {name} vs docs/physics.md §1.5")


# docs/physics.md §1.5 regression table: damped tool-point 2×2 at seven frequencies, printed to
# 5 significant digits → compared at 2e-4 relative (the table's own rounding is ≤5e-5).
REGRESSION = [  # f_hz, H, L (= N), P
    (100, 4.1901e-7 - 1.3918e-9j, 4.9194e-6 - 1.2373e-8j, 1.5062e-4 - 3.2210e-7j),
    (500, 7.6894e-7 - 3.9965e-8j, 6.4028e-6 - 1.4069e-7j, 1.5856e-4 - 8.1761e-7j),
    (1000, 4.8579e-7 - 4.7262e-8j, 6.7847e-6 - 3.1370e-7j, 1.7470e-4 - 2.4756e-6j),
    (1383, 7.1710e-7 - 5.7292e-6j, 9.4734e-6 - 5.4746e-5j, 2.0866e-4 - 5.2362e-4j),
    (2000, -1.0935e-7 - 1.0885e-8j, 1.3460e-6 - 1.6660e-7j, 1.3504e-4 - 2.8931e-6j),
    (4026, 2.5718e-7 - 2.0264e-6j, 9.9889e-6 - 6.6740e-5j, 4.0031e-4 - 2.1983e-3j),
    (6000, -5.1646e-8 - 2.7496e-9j, -1.0082e-6 - 1.0272e-7j, 2.1932e-5 - 3.9562e-6j),
]


@pytest.fixture(scope="module")
def regression_result():
    doc = ra1({"values_hz": [row[0] for row in REGRESSION]})
    return rcsa.predict(doc)


@pytest.mark.parametrize("row", REGRESSION, ids=[f"{r[0]}Hz" for r in REGRESSION])
def test_o12_regression_table(regression_result, row):
    i = [r[0] for r in REGRESSION].index(row[0])
    tp = regression_result.tool_point
    for name, value, expected in (("H", tp.h[i], row[1]), ("L", tp.l[i], row[2]),
                                  ("N", tp.n[i], row[2]), ("P", tp.p[i], row[3])):
        # each part rounded to 5 digits: compare complex values at 2e-4 of their modulus
        assert abs(value - expected) <= 2e-4 * abs(expected), f"{name} at {row[0]} Hz vs docs/physics.md §1.5"


@pytest.fixture(scope="module")
def full_band():
    return rcsa.predict(ra1())


def test_tool_point_h_matches_reference_csv(full_band):
    # Issue 2 asked for 2e-4 of the peak magnitude at every line of the reference CSV; the
    # model and the CSV's exact RCSA prototype agree to 2.0e-8 (manual), asserted at 5e-8.
    ref = np.loadtxt(REPO / "tests/data/ra1/ra1_tool_point_h.csv", delimiter=",")
    idx = np.searchsorted(full_band.frequency_hz, ref[:, 0])
    np.testing.assert_array_equal(full_band.frequency_hz[idx], ref[:, 0])
    h_ref = ref[:, 1] + 1j * ref[:, 2]
    err = np.abs(full_band.tool_point.h[idx] - h_ref) / np.abs(h_ref).max()
    assert err.max() < RTOL_CSV_OF_PEAK, f"worst line {ref[np.argmax(err), 0]} Hz: {err.max():.2e} of peak"


def test_peaks_and_stability_quantities(full_band):
    # docs/physics.md §1.5: peaks at 599/1103/1386/4034 Hz (|H| 4.273e-6, 8.27e-7, 5.837e-6, 2.062e-6),
    # most negative Re H −3.007e-6 m/N at 1407 Hz; static stiffness O16.
    peaks = full_band["peaks"]
    assert [p["frequency_hz"] for p in peaks] == [599.0, 1103.0, 1386.0, 4034.0]
    np.testing.assert_allclose([p["magnitude_m_n"] for p in peaks], [4.273e-6, 8.27e-7, 5.837e-6, 2.062e-6],
                               rtol=1e-3)
    assert full_band["min_real_m_n"] == pytest.approx(-3.007e-6, rel=5e-4)
    assert full_band["min_real_frequency_hz"] == 1407.0
    assert full_band["static_stiffness_n_m"] == pytest.approx(1 / 4.13738265e-7, rel=1e-8)


def test_o16_static_compliance_equals_low_frequency_limit():
    # The dynamic-stiffness path at 0.01 Hz is the static FE value to 1e-10 (docs/physics.md §2.7).
    doc = ra1({"values_hz": [0.01]})
    for j in doc["joints"].values():
        j["damping_ns_m"] = j["rotational_damping_nms_rad"] = 0.0
    for b in doc["spindle"]["bearings"]:
        b["damping_ns_m"] = 0.0
    doc["materials"] = {"steel": {"loss_factor": 0.0}, "carbide": {"loss_factor": 0.0}}
    h = rcsa.predict(doc).tool_point.h[0]
    assert h.real == pytest.approx(4.13738265e-7, rel=1e-8)


# docs/physics.md §1.4 section table (real parts, SI), printed to 4 significant digits → 6e-4.
SECTIONS = [  # (chain index in build order, EI, κGA, ρA, ρI)
    ("S1 Ø90", 0.0, 6.763e5, 4.754e8, 49.94, 2.528e-2),
    ("H1 composite", None, 1.629e5, 2.323e8, 25.31, 6.079e-3),
    ("T1 Ø12.7", None, 766.2, 2.829e7, 1.837, 1.852e-5),
    ("T2 Ø10.16", None, 313.8, 1.810e7, 1.176, 7.584e-6),
]


def test_section_table():
    model = build_model(parse_assembly(ra1()))
    spindle_nose_segment = model.spindle[-1].section  # chain runs rear → nose
    sections = {"S1 Ø90": spindle_nose_segment, "H1 composite": model.holder[0].section,
                "T1 Ø12.7": model.tool[0].section, "T2 Ø10.16": model.tool[1].section}
    for name, _, ei, kga, ra, ri in SECTIONS:
        s = sections[name]
        np.testing.assert_allclose([s.ei.real, 1 / s.shear_flexibility.real, s.rho_a, s.rho_i],
                                   [ei, kga, ra, ri], rtol=6e-4, err_msg=f"{name} vs docs/physics.md §1.4")


def test_masses():
    # docs/physics.md §1.4: spindle 14.41 kg, holder incl. tool core 1.073 kg, overhang 0.119 kg.
    model = build_model(parse_assembly(ra1()))

    def mass(chain):
        return sum(b.section.rho_a * b.length_m for b in chain if hasattr(b, "section"))

    np.testing.assert_allclose([mass(model.spindle), mass(model.holder), mass(model.tool)],
                               [14.41, 1.073, 0.119], rtol=5e-3)
