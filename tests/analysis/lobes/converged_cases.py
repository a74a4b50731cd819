"""Cuts with converged stability limits that the product did not make (issue 29).

Each case is a modal table per direction, a cut and a few spindle speeds. Their converged depth
limits come from the spectral-element collocation oracle (``tests/oracles/milling_collocation.py``,
a method of another family than the product's semi-discretization, converging exponentially) at
two resolutions; ``benchmarks/sdm_references.py --write`` computes them into
``tests/data/lobes/converged_limits.json`` and ``tests/analysis/lobes/test_sdm_converged.py``
judges the product's default answers against them.

* ``single_flute_*``: a small single-flute O-flute carbide tool on a spindle: a 1.15 kHz
  spindle-holder mode and a 3.4 kHz tool mode, the two flexible; aluminium 7075 at a_e/D = 0.05
  down and up milling, low speeds where a tooth period holds tens of cycles of the tool mode
  (the presets of issue 29 were fifty times too deep there).
* ``ji2024_35mm``: the published five-mode table (x and y differ; modes of comparable peak),
  three flutes, a_e = 1 mm of a 6 mm tool (a_e/D = 1/6), down milling (Ji & Liu 2024, CC BY 4.0:
  ``tests/data/lobes/ji2024/SOURCE.md``).
* ``strong_high_mode``: two flutes at a_e/D = 0.05, a 700 Hz mode and a 5.2 kHz mode half as
  stiff in peak, different in x and y.
* ``four_flutes_up``: four flutes at a_e/D = 0.2, up milling, the same two modes.
"""

from __future__ import annotations

import csv
from pathlib import Path

from tests.helpers import REPO

AL7075 = (1319.41e6, 788.83 / 1319.41)  # K_t (N/m²), K_r = K_n/K_t: rcsa.analysis.lobes.workpiece_materials
JI2024 = REPO / "tests" / "data" / "lobes" / "ji2024" / "measured_frf.csv"
LIMITS = REPO / "tests" / "data" / "lobes" / "converged_limits.json"


def ji2024_table(overhang_mm: int = 35) -> dict[str, list[dict[str, float]]]:
    """The published table of one overhang: ``{"modal_x": [...], "modal_y": [...]}`` (request form)."""
    out: dict[str, list[dict[str, float]]] = {"modal_x": [], "modal_y": []}
    with Path(JI2024).open(newline="") as fh:
        for row in csv.DictReader(fh):
            if int(row["overhang_mm"]) == overhang_mm:
                out[f"modal_{row['axis']}"].append({"frequency_hz": float(row["freq_hz"]),
                                                    "damping_ratio": float(row["damping_ratio"]),
                                                    "modal_mass_kg": float(row["modal_mass_kg"])})
    return out


def _same(modes: list[tuple[float, float, float]]) -> dict[str, list[dict[str, float]] | None]:
    return {"modal_x": [{"frequency_hz": f, "damping_ratio": z, "modal_mass_kg": m} for f, z, m in modes],
            "modal_y": None}


SINGLE_FLUTE = [(1150.0, 0.035, 0.9), (3400.0, 0.012, 0.0125)]
HIGH_X = [(700.0, 0.03, 0.5), (5200.0, 0.015, 0.02)]
HIGH_Y = [(760.0, 0.03, 0.45), (5000.0, 0.015, 0.022)]

CASES: dict[str, dict] = {
    "single_flute_down": {**_same(SINGLE_FLUTE), "teeth": 1, "radial_immersion": 0.05, "milling": "down",
                          "speeds": [1061.0, 2330.0, 3000.0, 4500.0, 6500.0, 9455.0, 14000.0, 20000.0]},
    "single_flute_up": {**_same(SINGLE_FLUTE), "teeth": 1, "radial_immersion": 0.05, "milling": "up",
                        "speeds": [1500.0, 3000.0, 6000.0, 12000.0, 20000.0, 24000.0]},
    "ji2024_35mm": {**ji2024_table(35), "teeth": 3, "radial_immersion": 1.0 / 6.0, "milling": "down",
                    "speeds": [3000.0, 5000.0, 7000.0, 10000.0, 12000.0, 15000.0, 18000.0]},
    "strong_high_mode": {"modal_x": _same(HIGH_X)["modal_x"], "modal_y": _same(HIGH_Y)["modal_x"], "teeth": 2,
                         "radial_immersion": 0.05, "milling": "down",
                         "speeds": [2000.0, 4000.0, 8000.0, 12000.0, 16000.0, 24000.0, 30000.0]},
    "four_flutes_up": {"modal_x": _same(HIGH_X)["modal_x"], "modal_y": _same(HIGH_Y)["modal_x"], "teeth": 4,
                       "radial_immersion": 0.2, "milling": "up",
                       "speeds": [3000.0, 6000.0, 10000.0, 15000.0, 20000.0, 25000.0]},
}


def request(name: str) -> dict:
    """The case as a stability-lobes request with only the cut in it (no method: the defaults)."""
    case = CASES[name]
    body = {k: case[k] for k in ("modal_x", "modal_y", "teeth", "radial_immersion", "milling")}
    return {**body, "tangential_coefficient_n_m2": AL7075[0], "radial_ratio": AL7075[1],
            "spindle_speed_rpm": list(case["speeds"])}
