"""The seed paper's effect-analysis findings, restated and checked on RA-1.

Source: Ertürk A., Özgüven H.N., Budak E., "Effect analysis of bearing and interface
dynamics on tool point FRF for chatter stability in machine tools by using a new analytical
model for spindle–tool assemblies", Int. J. Machine Tools & Manufacture 47 (2007) 23–32, as
summarised in ``docs/diagnosis.md`` §2 (rows 1, 2, 8, 10) and §3.3: varying one parameter at a
time, (a) the bearing parameters act mainly on the lowest (spindle) modes, (b) the interface
(joint) parameters act on the higher, holder/tool-related modes, (c) the rotational contact
parameters matter far less than the translational ones (which is why the paper holds them at
average values when identifying the joints), and (d) stiffness moves the natural frequencies
while damping moves the peak heights (also Özşahin et al., IJMTM 49 (2009) 25–35).

In RA-1's terms (``docs/physics.md`` §1.4–1.5; modes 599.85, 921.69, 1115.51, 1383.61, 1444.68,
3115.94, 4025.97, … Hz; tip residues 2.02, 0.032, 1.28, 13.6, 0.063, 0.0035, 36.0 1/kg) the
normalised sensitivities S = d ln(feature)/d ln(parameter) of :mod:`rcsa.analysis.effects.sensitivities` show:

1. **Bearings → lowest spindle modes.** Every bearing stiffness moves a mode below 1.2 kHz
   most: the front pair (85, 115 mm) the 1115.5 Hz mode (S = 0.15, 0.14), the rear pair
   (355, 395 mm) the 921.7 Hz mode (S = 0.17, 0.23); on the two tool modes (1383.6 and
   4026.0 Hz) no bearing reaches |S| = 0.003. Bearing dampings act on the peaks of the
   599 and 1103 Hz modes only.
2. **Spindle–holder k_t → the first mode**, 599.85 Hz (S = 0.22; next 0.13 on the hidden
   1444.7 Hz mode), i.e. the spindle-on-taper mode the paper attributes to the interface.
3. **Holder–tool k_t → the dominant tool mode 1383.6 Hz** (S = 0.27, the largest of all
   joint and bearing parameters there), and also the second tool mode 4026.0 Hz
   (S = 0.14), while it barely moves the spindle modes (|S| ≤ 0.022).
4. **Rotational stiffnesses matter little** on the modes seen at the tool point up to
   5 kHz (tip participation ≥ 1 %: 599.9, 1115.5, 1383.6, 4026.0 Hz): their largest
   |S_f| is 0.012 (spindle–holder) and 0.004 (holder–tool) against 0.22 and 0.27 for the
   translational stiffnesses — more than an order of magnitude. Caveat beyond the paper's
   band: the weak 6080.8 Hz mode (participation 1.8 %) is controlled by the spindle–holder
   k_r (S = 0.17).
5. **Stiffness moves frequencies, damping moves peaks.** A joint's damping leaves every
   natural frequency unchanged (S = 0 by definition of the undamped frequency) and shifts
   the damped peak frequencies by |S| < 0.005, while its stiffness moves its controlled
   mode by S ≥ 0.2; the damping lowers its controlled peak strongly — spindle–holder c_t
   the 599 Hz peak (S = −0.58), holder–tool c_t the 4034 Hz peak (S = −0.77) and the
   1386 Hz peak (S = −0.46).
"""

from __future__ import annotations

import numpy as np
import pytest

from rcsa.analysis.effects.sensitivities import effect_analysis
from rcsa.reference import ra1

pytestmark = pytest.mark.reference

SOURCE = "Ertürk, Özgüven, Budak, IJMTM 47 (2007) 23–32, on RA-1"
#: RA-1 modes (Hz) by role, rounded; the test looks each up to 0.1 Hz.
SPINDLE_MODES_HZ = (599.85, 921.69, 1115.51)
TOOL_MODES_HZ = (1383.61, 4025.97)
#: Modes seen at the tool point up to 5 kHz (tip participation ≥ 1 % of the largest).
VISIBLE_BELOW_5KHZ = (599.85, 1115.51, 1383.61, 4025.97)


@pytest.fixture(scope="module")
def report():
    return effect_analysis(ra1({"start_hz": 300.0, "stop_hz": 6500.0, "step_hz": 1.0}))


def mode(report, f_hz: float) -> int:
    i = int(np.argmin(np.abs(report.frequency_hz - f_hz)))
    assert abs(report.frequency_hz[i] - f_hz) < 0.1, f"RA-1 mode {f_hz} Hz not found ({SOURCE})"
    return i


def test_the_modes_analysed_are_ra1s(report):
    np.testing.assert_allclose(report.frequency_hz,
                               [599.85, 921.69, 1115.51, 1383.61, 1444.68, 3115.94, 4025.97, 5102.79, 6080.83],
                               atol=0.01, err_msg=f"natural frequencies ({SOURCE})")
    # the two tool modes dominate the tool point (docs/physics.md §1.5 tip residues 13.6 and 36.0)
    np.testing.assert_allclose(report.modes.tip_residue_1_kg[[mode(report, f) for f in TOOL_MODES_HZ]],
                               [13.6, 36.0], rtol=0.01)


@pytest.mark.parametrize("bearing, controlled_hz", [(0, 1115.51), (1, 1115.51), (2, 921.69), (3, 921.69)],
                         ids=["B1 front", "B2 front", "B3 rear", "B4 rear"])
def test_bearing_stiffness_controls_a_lowest_spindle_mode(report, bearing, controlled_hz):
    name = f"bearings[{bearing}].stiffness_n_m"
    assert report.controls(name) == pytest.approx(controlled_hz, abs=0.1), f"finding 1 ({SOURCE}): {name}"
    assert report.controls(name) < 1200.0
    s = report.column(name)
    assert s[mode(report, controlled_hz)] > 0.1
    for f in TOOL_MODES_HZ:
        assert abs(s[mode(report, f)]) < 0.003, f"finding 1 ({SOURCE}): {name} on the {f} Hz tool mode"


@pytest.mark.parametrize("bearing", range(4))
def test_bearing_damping_acts_on_lowest_peaks(report, bearing):
    name = f"bearings[{bearing}].damping_ns_m"
    assert min(abs(report.controls(name) - f) for f in SPINDLE_MODES_HZ) < 0.1, f"finding 1 ({SOURCE}): {name}"
    assert np.all(report.column(name) == 0.0), "damping never moves an undamped natural frequency"


def test_spindle_holder_stiffness_controls_the_first_mode(report):
    name = "spindle_holder.stiffness_n_m"
    assert report.controls(name) == pytest.approx(599.85, abs=0.1), f"finding 2 ({SOURCE})"
    assert report.column(name)[mode(report, 599.85)] == pytest.approx(0.22, abs=0.01)


def test_holder_tool_stiffness_controls_the_dominant_tool_mode(report):
    name = "holder_tool.stiffness_n_m"
    s = report.column(name)
    assert report.controls(name) == pytest.approx(1383.61, abs=0.1), f"finding 3 ({SOURCE})"
    assert s[mode(report, 1383.61)] == pytest.approx(0.27, abs=0.01)
    assert s[mode(report, 4025.97)] == pytest.approx(0.14, abs=0.01)
    interfaces = [p for p in report.parameters if not p.startswith("tool.")]
    assert report.controlled_by(mode(report, 1383.61), among=interfaces) == name
    assert report.controlled_by(mode(report, 4025.97), among=interfaces) == name
    for f in SPINDLE_MODES_HZ:
        assert abs(s[mode(report, f)]) < 0.025, f"finding 3 ({SOURCE}): {name} on the {f} Hz spindle mode"


@pytest.mark.parametrize("joint", ["spindle_holder", "holder_tool"])
def test_rotational_stiffness_matters_an_order_of_magnitude_less(report, joint):
    visible = [mode(report, f) for f in VISIBLE_BELOW_5KHZ]
    assert np.all(report.tip_participation[visible] >= 0.01)
    rot = np.max(np.abs(report.column(f"{joint}.rotational_stiffness_nm_rad")[visible]))
    trans = np.max(np.abs(report.column(f"{joint}.stiffness_n_m")[visible]))
    assert trans >= 0.2
    assert rot < 0.1 * trans, f"finding 4 ({SOURCE}): {joint} k_r {rot:.3g} vs k_t {trans:.3g}"
    # the manual's figure: |S| <= 0.012 for either rotational stiffness on the visible modes
    assert rot <= 0.024, f"{joint} k_r {rot:.3g} (manual: <= 0.012)"


def test_caveat_the_6081_hz_mode_is_a_rotational_one(report):
    i = mode(report, 6080.83)
    assert report.controlled_by(i, among=[p for p in report.parameters if not p.startswith("tool.")]) \
        == "spindle_holder.rotational_stiffness_nm_rad"
    assert report.column("spindle_holder.rotational_stiffness_nm_rad")[i] == pytest.approx(0.17, abs=0.01)


@pytest.mark.parametrize("joint, peak_hz, s_peak", [
    ("spindle_holder", 599.85, -0.58),
    ("holder_tool", 4025.97, -0.77),
], ids=["spindle_holder", "holder_tool"])
def test_stiffness_moves_frequencies_damping_moves_peaks(report, joint, peak_hz, s_peak):
    k, c = f"{joint}.stiffness_n_m", f"{joint}.damping_ns_m"
    controlled = report.controlled_mode(k)
    assert report.column(k)[controlled] >= 0.2, f"finding 5 ({SOURCE}): {k} moves its mode"
    assert np.all(report.column(c) == 0.0)
    with_peak = np.isfinite(report.modes.peak_frequency_hz)
    assert np.all(np.abs(report.column(c, "peak_frequency_hz")[with_peak]) < 0.005), \
        f"finding 5 ({SOURCE}): {c} barely moves any peak frequency"
    assert report.controls(c) == pytest.approx(peak_hz, abs=0.1)
    assert report.column(c, "peak_magnitude_m_n")[report.controlled_mode(c)] == pytest.approx(s_peak, abs=0.02)


def test_holder_tool_damping_also_lowers_the_1386_hz_peak(report):
    s = report.column("holder_tool.damping_ns_m", "peak_magnitude_m_n")[mode(report, 1383.61)]
    assert s == pytest.approx(-0.46, abs=0.02)
