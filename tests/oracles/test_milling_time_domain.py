"""The time-domain milling oracle, and chatter-safe presets confirmed by it (issue 20, item 6).

The oracle (``milling_time_domain``) shares no code with ``rcsa``. It is checked first on
its own (free decay, and the published flip limit of Insperger & Stépán's benchmark), then
used to judge presets that ``rcsa`` chose by semi-discretization on a single-flute tool at
``a_e/D`` = 0.05 and 0.5: the preset (its speed, its stepdown) must not chatter, and the next
step up — 1.25 × the window's depth limit, at the window's weakest speed — must.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from rcsa.analysis.lobes.pockets import PocketRule
from rcsa.analysis.lobes.tool_pockets import CutSettings, ToolCut, tool_pockets
from rcsa.reference import ra1
from tests.oracles.milling_time_domain import Cut, Mode, resolving_steps, simulate

BENCHMARK = [Mode(922.0, 0.011, 0.03993, 0)]  # Insperger & Stépán (2004): m 0.03993 kg, 922 Hz, ζ 0.011, in x
AL7075 = {"kt": 1319.41e6, "kr": 788.83 / 1319.41}  # the manual's aluminium 7075 row


def test_free_decay_per_tooth_period_is_that_of_the_mode():
    """Zero depth: the kicked mode decays by e^{−ζωT} per tooth period (exact one-step maps)."""
    out = simulate(BENCHMARK, [Cut(9000.0, 0.0, 4, 6e8, 1 / 3, 0.5, "down")], periods=80, ramp=0.25)
    decay_per_period = math.exp(-0.011 * 2 * math.pi * 922.0 * 60.0 / (9000.0 * 4))
    expected = decay_per_period ** 60  # the last fifth ends 60 periods after the kick ... roughly
    assert out.ratio[0] < 10 * expected and out.stable[0]


@pytest.mark.slow
def test_the_published_flip_limit_of_the_benchmark():
    """18 000 rpm, 2 teeth, a/D = 0.05 down milling: the paper's limit is 1.31 mm (period doubling)."""
    out = simulate(BENCHMARK, [Cut(18000.0, d, 2, 6e8, 1 / 3, 0.05, "down", 5e-5) for d in (1.05e-3, 1.64e-3)],
                   periods=240, steps_per_period=96)  # 1.5 chatter cycles per tooth period: 64 steps a cycle
    assert out.stable[0] and out.chatter[1], out.ratio


@pytest.fixture(scope="module")
def tool():
    import rcsa

    p = rcsa.predict(ra1({"start_hz": 200.0, "stop_hz": 5000.0, "step_hz": 1.0}))
    return p.frequency_hz, p.tool_point.h


@pytest.mark.slow
@pytest.mark.parametrize("immersion", [0.05, 0.5])
def test_a_semi_discretization_preset_is_stable_and_the_next_step_up_chatters(tool, immersion):
    f, h = tool
    cut = ToolCut("ra1-single-flute", f, h, 1, 0.04, 18000.0, 24000.0)
    settings = CutSettings(AL7075["kt"], AL7075["kr"], immersion, "down", PocketRule(), method="semi_discretization")
    found = tool_pockets([cut], settings)[0]
    pocket, lobes = found.pocket, found.lobes
    assert pocket is not None and pocket.limited_by == "stability" and lobes is not None
    n, tol = pocket.spindle_speed_rpm, settings.rule.speed_tolerance
    window = (lobes.spindle_speed_rpm >= n * (1 - tol)) & (lobes.spindle_speed_rpm <= n * (1 + tol))
    weakest = lobes.spindle_speed_rpm[window][np.nanargmin(lobes.depth_limit_m[window])]
    model = lobes.modal_model
    modes = [Mode(float(fr), float(z), 1.0 / float(r), int(d)) for fr, z, r, d in
             zip(model.frequency_hz, model.damping_ratio, model.residue_1_kg, model.direction, strict=True)]
    cuts = [Cut(n, pocket.stepdown_m, 1, AL7075["kt"], AL7075["kr"], immersion, "down", 5e-5),
            Cut(float(weakest), 1.25 * pocket.depth_limit_m, 1, AL7075["kt"], AL7075["kr"], immersion, "down", 5e-5)]
    out = simulate(modes, cuts, steps_per_period=resolving_steps(modes, cuts))
    assert out.stable[0], ("the preset chatters", n, pocket.stepdown_m, out.ratio)
    assert out.chatter[1], ("1.25 x the window limit does not chatter", weakest, pocket.depth_limit_m, out.ratio)


@pytest.mark.slow
def test_a_pocket_governed_by_a_weak_high_mode_is_confirmed():
    """One flute at half immersion whose 6.2 kHz tool mode (0.6 × the largest peak) governs the
    pockets of its 635 Hz mode (``tests/analysis/lobes/test_sdm_weak_high_mode.py``): the preset
    found on the FRF of those three modes must not chatter in the time domain, and 1.25 × its
    window's limit must. Steps resolving only the largest peak wrote 9.7 mm here, which chatters."""
    from tests.analysis.lobes.test_sdm_weak_high_mode import MODES

    f = np.arange(5.0, 8000.0, 2.0)  # the 6.2 kHz peak inside the grid
    w = 2 * np.pi * f
    h = sum(1.0 / (m * ((2 * np.pi * fn) ** 2 - w**2 + 2j * z * (2 * np.pi * fn) * w)) for fn, z, m in MODES)
    cut = ToolCut("single-flute-0506", f, h, 1, 0.0254, 18000.0, 20500.0)
    settings = CutSettings(AL7075["kt"], AL7075["kr"], 0.5, "down", PocketRule(), method="semi_discretization")
    found = tool_pockets([cut], settings)[0]
    pocket, lobes = found.pocket, found.lobes
    assert pocket is not None and pocket.limited_by == "stability" and lobes is not None
    assert pocket.stepdown_m < 0.0045  # the converged window limit is ~4.1 mm (/ 1.25)
    n, tol = pocket.spindle_speed_rpm, settings.rule.speed_tolerance
    window = (lobes.spindle_speed_rpm >= n * (1 - tol)) & (lobes.spindle_speed_rpm <= n * (1 + tol))
    weakest = lobes.spindle_speed_rpm[window][np.nanargmin(lobes.depth_limit_m[window])]
    modes = [Mode(fn, z, m, d) for d in (0, 1) for fn, z, m in MODES]
    cuts = [Cut(n, pocket.stepdown_m, 1, AL7075["kt"], AL7075["kr"], 0.5, "down", 5e-5),
            Cut(float(weakest), 1.25 * pocket.depth_limit_m, 1, AL7075["kt"], AL7075["kr"], 0.5, "down", 5e-5)]
    out = simulate(modes, cuts, steps_per_period=resolving_steps(modes, cuts))
    assert out.stable[0], ("the preset chatters", n, pocket.stepdown_m, out.ratio)
    assert out.chatter[1], ("1.25 x the window limit does not chatter", weakest, pocket.depth_limit_m, out.ratio)
