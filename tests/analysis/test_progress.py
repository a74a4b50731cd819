"""Long analyses report progress(done, total) at their step boundaries."""

from __future__ import annotations

from rcsa.analysis.effects.sensitivities import effects
from rcsa.reference import ra1


def test_effect_analysis_reports_each_parameter_and_ends_at_total():
    calls: list[tuple[int, int]] = []
    effects({"assembly": ra1({"start_hz": 500.0, "stop_hz": 1500.0, "step_hz": 10.0}),
             "parameters": ["holder_tool.stiffness_n_m", "tool.stickout_m"]},
            progress=lambda done, total: calls.append((done, total)))
    assert calls == [(1, 3), (2, 3), (3, 3)]
