"""The small chatter-safe pocket case the backend tests compute here and elsewhere (a cluster,
worker processes) and compare."""

from __future__ import annotations

import rcsa
from rcsa.analysis.lobes.tool_pockets import CutSettings, ToolCut
from rcsa.reference import ra1


def pocket_case(n_tools: int) -> tuple[list[ToolCut], CutSettings]:
    """``n_tools`` tools on RA-1's tool point (compliance scaled by 1.2, 1.4, ..., one and two
    teeth in turn) and a finishing cut in aluminium solved by 40 semi-discretization speeds."""
    p = rcsa.predict(ra1({"start_hz": 200.0, "stop_hz": 3000.0, "step_hz": 2.0}))
    cuts = [ToolCut(f"t{i}", p.frequency_hz, p.tool_point.h * (1 + 0.2 * i), 1 + i % 2, 0.02, 21000.0, 24000.0)
            for i in range(n_tools)]
    return cuts, CutSettings(1319.41e6, 0.5979, 0.05, "down", method="semi_discretization", sdm_speed_count=40)
