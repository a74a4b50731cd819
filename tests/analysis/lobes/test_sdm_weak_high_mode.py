"""A weaker, higher mode that governs a pocket of the strongest one is resolved, or noted.

The tool of ``tests/data/tool-libraries/fusion-single-flute`` (guid ...0506) on RA-1's
spindle, one flute at half immersion, down milling, aluminium 7075, around 19 066 rpm: its
FRF has a 635 Hz mode (the largest peak), a 1 134 Hz mode and a 6.2 kHz tool mode of about
0.6 × the largest peak. In this pocket of the 635 Hz mode the cut chatters at 6.4 kHz,
4.1 mm deep (converged: 480 steps per tooth period). Steps chosen for the largest peak only
(40) saw 12.4 mm there — a discretisation too coarse for a mode damps its instability away
rather than flagging it — and a preset 2.3× too deep was written (``benchmarks/bench_presets.py``
at a_e/D = 0.5, before :func:`resolving_steps` took the highest mode).
"""

from __future__ import annotations

import numpy as np

from rcsa.analysis.lobes.modal_model import ModalModel
from rcsa.analysis.lobes.semi_discretization import (
    MIN_STEPS_PER_CHATTER_CYCLE,
    resolving_steps,
    semi_discretization_lobes_many,
)

KT, KR = 1319.41e6, 788.83 / 1319.41
#: (frequency Hz, damping ratio, modal mass kg = 1 / residue) in x and the same in y
MODES = [(635.2484, 0.0183354, 1.0409145), (1134.1445, 0.0288546, 8.0048949), (6234.5815, 0.0654293, 0.0048973)]
CONVERGED_M = 0.004126  # 480 steps per period, at the window's weakest speed (19 560 rpm)


def _model() -> ModalModel:
    f, z, m = (np.array([x[i] for x in MODES] * 2) for i in range(3))
    return ModalModel.of(f, z, 1.0 / m, np.repeat([0, 1], len(MODES)))


def _window_minimum(steps: np.ndarray | int | None) -> tuple[float, object]:
    speeds = np.geomspace(19066 * 0.97, 19066 * 1.03, 9)
    k = None if steps is None else [np.broadcast_to(np.asarray(steps), speeds.shape).astype(np.int64)]
    r = semi_discretization_lobes_many([_model()], teeth=1, tangential_coefficient_n_m2=KT, radial_ratio=KR,
                                       radial_immersion=0.5, milling="down", spindle_speed_rpm=[speeds],
                                       steps_per_period=k, min_depth_search_max_m=[0.02])[0]
    return float(np.nanmin(r.depth_limit_m)), r


def test_the_resolving_steps_find_the_weak_high_modes_chatter():
    model = _model()
    speeds = np.geomspace(19066 * 0.97, 19066 * 1.03, 9)
    # a quarter of the period in the cut (one flute, half immersion: 90 degrees): 10 steps per cycle of
    # 1.2 x 6.23 kHz over 0.79 ms: 59 -> the band 64
    steps = resolving_steps(model, 1, speeds, radial_immersion=0.5)
    assert steps.min() >= 59
    limit, r = _window_minimum(None)  # the default: those steps, checked at 1/sqrt(2) of them, refined
    assert r.scheme == "cut_window" and r.resolved.all()
    # converged within the 1 % two resolutions agree to (first-order SDM converges from above)
    assert CONVERGED_M * (1 - 0.005) <= limit <= CONVERGED_M * 1.015
    chatter = r.chatter_frequency_hz[np.isfinite(r.depth_limit_m)]
    assert chatter.size == 9 and np.all((chatter > 6000) & (chatter < 6700))  # every speed: the 6.2 kHz mode
    assert r.notes() == []


def test_too_few_steps_for_the_high_mode_are_noted():
    limit, r = _window_minimum(40)
    assert limit > 2.5 * CONVERGED_M  # the instability of the 6.2 kHz mode is not seen at all ...
    assert np.all(r.top_mode_steps_per_cycle < MIN_STEPS_PER_CHATTER_CYCLE)
    notes = [n for n in r.notes() if "highest mode" in n]
    assert len(notes) == 1 and "highest mode (6235 Hz)" in notes[0] and "can be missed" in notes[0]  # ... but said
