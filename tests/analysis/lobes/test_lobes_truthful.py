"""Lobe responses and pictures that tell the truth (issue 20, item 7): the flute length, the
notes (under-resolved speeds, an FRF grid too coarse for zero-order lobes), the method auto
chose and why, and no-limit speeds of the semi-discretization drawn as stable."""

from __future__ import annotations

import numpy as np
import pytest

from rcsa.analysis.lobes.options import parse_method
from rcsa.analysis.lobes.zoa import MIN_LINES_PER_HALF_POWER_BAND, frf_grid_notes
from rcsa.app.analyses import stability_lobes, stability_lobes_answer
from rcsa.app.figures import robust_lobes_figure
from rcsa.errors import InputError
from rcsa.reference import ra1

CUT = {"teeth": 1, "tangential_coefficient_n_m2": 1.31941e9, "radial_ratio": 0.5979, "milling": "down"}


def _mode(f: np.ndarray, zeta: float = 0.02) -> np.ndarray:
    return 1.0 / (1e7 * (1 - (f / 800.0) ** 2 + 2j * zeta * f / 800.0))


@pytest.mark.parametrize(("step", "warned"), [(20.0, True), (8.0, True), (2.0, False)])
def test_a_grid_too_coarse_for_the_dominant_mode_is_said(step, warned):
    """The half-power band of a 2 % mode at 800 Hz is 32 Hz wide: 1–2 lines at 20 Hz, 4 at 8 Hz."""
    f = np.arange(100.0, 2000.0, step)
    notes = frf_grid_notes(f, _mode(f))
    assert bool(notes) == warned
    if warned:
        lines = int(notes[0].split(" has ")[1].split(" line")[0])
        assert lines < MIN_LINES_PER_HALF_POWER_BAND and " Hz: the zero-order" in notes[0] and "kinked" in notes[0]


def test_the_response_carries_the_flute_length_and_the_grid_note():
    coarse = stability_lobes({"assembly": ra1({"start_hz": 5.0, "stop_hz": 5000.0, "step_hz": 20.0}), **CUT,
                              "radial_immersion": 0.5, "method": "zoa", "spindle_speed_rpm": {"start": 4000, "stop": 24000, "count": 50}})
    assert coarse["flute_length_m"] == pytest.approx(ra1()["tool"]["flute_length_m"])
    assert any("FRF grid" in n for n in coarse["notes"])
    fine = stability_lobes({"assembly": ra1({"start_hz": 5.0, "stop_hz": 5000.0, "step_hz": 1.0}), **CUT,
                            "radial_immersion": 0.5, "method": "zoa", "spindle_speed_rpm": {"start": 4000, "stop": 24000, "count": 50}})
    assert fine["notes"] == []


def test_auto_says_which_method_and_why():
    assert parse_method({"method": "auto"}, teeth=4, radial_immersion=1.0).name == "zoa"  # exact there
    assert parse_method({"method": "auto"}, teeth=4, radial_immersion=0.5).name == "semi_discretization"
    with pytest.raises(InputError) as err:
        parse_method({"method": "auto"})
    assert err.value.field == "method"
    response = stability_lobes({"assembly": ra1({"start_hz": 200.0, "stop_hz": 3000.0, "step_hz": 2.0}), **CUT,
                                "radial_immersion": 0.05, "method": "auto",
                                "spindle_speed_rpm": {"start": 20000, "stop": 24000, "count": 8}})
    assert response["method"] == "semi_discretization" and "teeth in the cut" in response["method_reason"]


def test_the_picture_draws_the_flute_length_the_notes_and_no_limit_speeds_as_stable():
    answer = stability_lobes_answer({"assembly": ra1({"start_hz": 200.0, "stop_hz": 3000.0, "step_hz": 2.0}),
                                     **CUT, "radial_immersion": 0.05, "method": "semi_discretization",
                                     "steps_per_period": 20,
                                     "spindle_speed_rpm": {"start": 6000, "stop": 24000, "count": 40}})
    extras = answer.extras()
    assert extras["notes"] and "not resolved" in extras["notes"][0]  # 20 steps over the period: too few
    fig = robust_lobes_figure(answer.nominal, extras)
    ax = fig.axes[0]
    gids = {a.get_gid() for a in [*ax.lines, *fig.texts]}
    assert {"flute-length", "notes", "envelope"} <= gids
    flute = next(line for line in ax.lines if line.get_gid() == "flute-length")
    assert flute.get_ydata()[0] == pytest.approx(ra1()["tool"]["flute_length_m"] * 1e3)
    assert ax.get_ylim()[1] <= 1.15 * flute.get_ydata()[0] + 1e-9 or np.nanmax(answer.nominal.depth_limit_m) * 1e3 \
        <= flute.get_ydata()[0]
    if np.any(np.isnan(answer.nominal.depth_limit_m)):  # stable to the search depth: shaded, not blank
        fill = ax.collections[0].get_paths()[0].vertices
        assert fill[:, 1].max() > 0
