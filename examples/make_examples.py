"""Write the synthetic examples of this folder (``python examples/make_examples.py [DIR]``).

Everything here is invented from RA-1 (``rcsa.reference.ra1``) with fixed seeds, so the
files are the same on every run (to rounding):

* ``diagnosis.json`` — tap tests of RA-1 at three stickouts (60, 74 and 90 mm) whose
  holder–tool joint is half as stiff as the base model says (a badly clamped tool), with 1 %
  measurement noise and the coherence it implies; the base model is RA-1 as designed. The
  diagnosis should name ``holder_tool_joint``.
* ``identification.json`` — the same tap tests, asking for the joints' stiffness and
  damping; the holder–tool stiffness should come out near 5.7e6 N/m (RA-1: 11.4e6).
* ``measurement.json`` and ``measurement.csv`` — one invented spindle-nose receptance
  (``direct_frf``, two modes) as the contract's measurement JSON and as a CSV table with a
  header naming the columns and units, for ``rcsa store import`` and ``POST /v1/measurements``.
* ``lobes-frf.json`` — a stability-lobes request with an inline tool-point FRF (RA-1's,
  predicted on a coarse grid); ``lobes-assembly.json`` — the same cut on RA-1 given as an
  assembly (predicted first).
* ``batch.json`` — three tools on RA-1's spindle (``POST /v1/tool-point-frf/batch``).
* ``effects.json`` — an effect analysis of RA-1: four joint, bearing and tool parameters,
  modes between 300 and 1500 Hz.
* ``ra1-uncertainty.json`` — RA-1 with an uncertainty band (``"uncertainty"``: 50 drawn
  assemblies under the default tolerances); ``lobes-robust.json`` — the lobes of
  ``lobes-assembly.json`` with robust limits over 50 draws; ``lobes-sdm.json`` — a thin
  finishing cut (2 teeth, a/D = 0.05) by semi-discretization.

``tests/test_examples.py`` runs this script and compares what it writes with the committed
files.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np

import rcsa
from rcsa.reference import ra1

HERE = Path(__file__).resolve().parent
#: The tap tests' frequency lines, Hz (a typical impact-hammer band for this tool).
TAP_GRID = {"start_hz": 200.0, "stop_hz": 3000.0, "step_hz": 5.0}
STICKOUTS_M = (0.060, 0.074, 0.090)
#: The truth the taps come from: the holder–tool joint at half its design stiffness.
SOFT_CLAMP = 0.5
NOISE_REL = 0.01
#: The grid of the other examples (predictions of RA-1 for lobes, batches, effects), Hz.
GRID = {"start_hz": 100.0, "stop_hz": 5000.0, "step_hz": 5.0}
CUTTING = {"teeth": 4, "tangential_coefficient_n_m2": 6.0e8, "radial_ratio": 0.3, "radial_immersion": 0.5,
           "milling": "down"}


def _wire(h: np.ndarray) -> dict[str, list[float]]:
    return {"real": [float(f"{x:.6e}") for x in h.real], "imag": [float(f"{x:.6e}") for x in h.imag]}


def tap_tests(seed: int = 7) -> list[dict]:
    """RA-1 with a soft holder–tool clamp, measured at each stickout with 1 % noise."""
    rng = np.random.default_rng(seed)
    out = []
    for stickout in STICKOUTS_M:
        truth = ra1(TAP_GRID)
        truth["tool"]["stickout_m"] = stickout
        truth["joints"]["holder_tool"]["stiffness_n_m"] *= SOFT_CLAMP
        p = rcsa.predict(truth)
        noise = NOISE_REL * np.abs(p.tool_point.h) * (rng.standard_normal(p.frequency_hz.size)
                                                     + 1j * rng.standard_normal(p.frequency_hz.size)) / np.sqrt(2)
        # the coherence that goes with a 1 % error over 5 averaged impacts: 1 - 2 n ε² (Bendat & Piersol)
        coherence = round(1.0 - 2 * 5 * NOISE_REL**2, 6)
        out.append({"tool": {"stickout_m": stickout}, "frequency_hz": p.frequency_hz.tolist(),
                    "h": _wire(p.tool_point.h + noise), "coherence": [coherence] * p.frequency_hz.size})
    return out


def diagnosis(taps: list[dict]) -> dict:
    """The diagnosis request: RA-1 as designed, the taps labelled by stickout, modest effort."""
    base = ra1(TAP_GRID)
    del base["frequency"]  # each measurement brings its own lines
    measurements = [{**t, "label": f"{1000 * t['tool']['stickout_m']:.0f} mm", "n_averages": 5} for t in taps]
    return {"assembly": base, "measurements": measurements,
            "options": {"monte_carlo_draws": 100, "max_lines": 400, "seed": 1}}


def identification(taps: list[dict]) -> dict:
    """The joint-identification request: RA-1's joints are the starting guess."""
    return {"assembly": ra1(TAP_GRID), "measurements": taps}


def spindle_measurement() -> tuple[dict, str]:
    """An invented spindle-nose receptance (two modes) as contract JSON and as CSV text."""
    f = np.arange(50.0, 2001.0, 10.0)
    h = np.zeros(f.size, dtype=complex)
    for fn, zeta, k in ((650.0, 0.035, 6.0e7), (1750.0, 0.045, 1.5e8)):
        r = f / fn
        h += 1.0 / (k * (1 - r**2 + 2j * zeta * r))
    doc = {"spindle_id": "example-mc1", "machine": "example-mill", "direction": "x", "plane": "spindle_nose",
           "kind": "direct_frf", "notes": "invented example (examples/make_examples.py)",
           "frequency_hz": f.tolist(), "h": _wire(h)}
    rows = ["frequency [Hz],real [m/N],imag [m/N]"]
    rows += [f"{fi:g},{hi.real:.6e},{hi.imag:.6e}" for fi, hi in zip(f, h, strict=True)]
    return doc, "\n".join(rows) + "\n"


def lobes_with_inline_frf() -> dict:
    """Stability lobes of RA-1's tool point, its FRF given inline (frf_y null: the same in y)."""
    p = rcsa.predict(ra1(GRID))
    return {"frf_x": {"frequency_hz": p.frequency_hz.tolist(), "h": _wire(p.tool_point.h)}, "frf_y": None,
            **CUTTING, "spindle_speed_rpm": {"start": 2000, "stop": 30000, "count": 150}}


def lobes_with_assembly() -> dict:
    """The same cut, RA-1 given as an assembly (its tool-point FRF is predicted first)."""
    return {"assembly": ra1(GRID), **CUTTING, "spindle_speed_rpm": {"start": 2000, "stop": 30000, "count": 150}}


def batch() -> dict:
    """Three tools on RA-1's spindle and holder: two stickouts of RA-1's end mill and a 10 mm one."""
    a = ra1(GRID)
    small = {**a["tool"], "diameter_m": 0.010, "shank_diameter_m": 0.010, "overall_length_m": 0.1,
             "flute_length_m": 0.022, "stickout_m": 0.045}
    combos = [{"id": "T1-ra1-74mm", "holder": a["holder"], "tool": a["tool"], "joints": a["joints"]},
              {"id": "T1-ra1-50mm", "holder": a["holder"], "tool": {**a["tool"], "stickout_m": 0.05},
               "joints": a["joints"]},
              {"id": "T7-d10", "holder": a["holder"], "tool": small, "joints": a["joints"]}]
    return {"frequency": GRID, "spindle": a["spindle"], "combinations": combos}


def effects() -> dict:
    """Effect analysis of RA-1: which of four parameters moves which mode between 300 and 1500 Hz."""
    return {"assembly": ra1(GRID), "band_hz": [300.0, 1500.0],
            "parameters": ["bearings[0].stiffness_n_m", "spindle_holder.stiffness_n_m", "holder_tool.stiffness_n_m",
                           "tool.stickout_m"]}


def ra1_with_uncertainty() -> dict:
    """RA-1 with an uncertainty band: 50 drawn assemblies under the default tolerances."""
    return {**ra1(GRID), "uncertainty": {"draws": 50, "seed": 1}}


def ra1_bonded() -> dict:
    """RA-1 with its tool bonded along the insertion (``joints.holder_tool.model``) instead of the point joint."""
    doc = ra1(GRID)
    doc["joints"]["holder_tool"] = {"model": "bonded"}
    return doc


def lobes_robust() -> dict:
    """The cut of :func:`lobes_with_assembly` with robust limits at 95 % over 50 drawn assemblies."""
    return {**lobes_with_assembly(), "spindle_speed_rpm": {"start": 2000, "stop": 30000, "count": 40},
            "uncertainty": {"draws": 50, "seed": 1}, "robust": {"confidence": 0.95}}


def lobes_semi_discretization() -> dict:
    """A thin finishing cut (2 teeth, a/D = 0.05) where the zero-order solution is wrong: SDM."""
    return {"assembly": ra1(GRID), "teeth": 2, "tangential_coefficient_n_m2": 6.0e8, "radial_ratio": 0.3,
            "radial_immersion": 0.05, "milling": "down", "spindle_speed_rpm": {"start": 6000, "stop": 24000,
                                                                                 "count": 120},
            "method": "semi_discretization", "steps_per_period": 24, "modes_per_direction": 2}


def lobes_of_a_stored_tool() -> dict:
    """The cut of :func:`lobes_with_assembly` on a tool of the stored library ``fusion-library`` (synced
    from ``fusion-library.json``), by reference: its assembly is rebuilt from the sync, its teeth too."""
    return {"library_tool": {"library_id": "fusion-library", "tool_id": "00000000-0000-4000-8000-000000000101"},
            **{k: v for k, v in CUTTING.items() if k != "teeth"},
            "spindle_speed_rpm": {"start": 2000, "stop": 30000, "count": 150}}


def presets_by_reference() -> dict:
    """The options of chatter-safe presets written into the Fusion file a sync of the library kept."""
    return {"material": "aluminium-7075", "max_rpm": 24000, "method": "zoa"}


def write(folder: Path) -> list[Path]:
    """Write every generated example into ``folder``; returns the paths."""
    folder.mkdir(parents=True, exist_ok=True)
    taps = tap_tests()
    measurement, csv_text = spindle_measurement()
    files = {"diagnosis.json": diagnosis(taps), "identification.json": identification(taps),
             "measurement.json": measurement, "lobes-frf.json": lobes_with_inline_frf(),
             "lobes-assembly.json": lobes_with_assembly(), "batch.json": batch(), "effects.json": effects(),
             "ra1-uncertainty.json": ra1_with_uncertainty(), "ra1-bonded.json": ra1_bonded(),
             "lobes-robust.json": lobes_robust(),
             "lobes-sdm.json": lobes_semi_discretization(), "lobes-library-tool.json": lobes_of_a_stored_tool(),
             "presets-options.json": presets_by_reference()}
    paths = []
    for name, doc in files.items():
        path = folder / name
        path.write_text(json.dumps(doc, indent=1) + "\n", encoding="utf-8")
        paths.append(path)
    path = folder / "measurement.csv"
    path.write_text(csv_text, encoding="utf-8")
    paths.append(path)
    return paths


if __name__ == "__main__":
    for written in write(Path(sys.argv[1]) if len(sys.argv) > 1 else HERE):
        sys.stdout.write(f"{written}\n")
