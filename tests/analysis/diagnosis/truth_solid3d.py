"""Withheld-effect truths from the 3-D reference: tap tests of 3-D holder + tool solids.

The diagnosis is otherwise only ever checked against beam models whose unmodelled effect
comes from its own catalogue. Here the truth is 3-D linear elasticity
(:mod:`tests.oracles.solid3d`: quadratic tetrahedra of the issue's stepped steel holder —
flange Ø63 × 24, body Ø40 × 30, nose Ø26 × 40 mm, Ø10 bore through — with a Ø10 carbide end
mill, OAL 75 mm, flutes 25 mm) coupled exactly at the holder's base face to RA-1's spindle and
spindle–holder joint. Tap tests at three stickouts (30, 40, 50 mm: inserted 45, 35, 25 mm)
of one variant:

=====================  =========================================================  ==================
variant                the 3-D truth                                              class
=====================  =========================================================  ==================
bonded                 shank bonded to the bore over the whole insertion          bonded
layer_k1e13/k3e13      a spring layer k_n = k_t = 1e13 / 3e13 N/m³ over it        soft_layer
front_lost_6/12mm      contact lost over the front 6 / 12 mm of the bore          front_contact_lost
flutes_2 / flutes_4    a real 2- / 4-flute cross-section (straight flutes)        fluted
=====================  =========================================================  ==================

**Cached data.** A 3-D model takes minutes to mesh and reduce, so each (variant, stickout) is
stored as its Craig–Bampton reduced model (``tests/data/diagnosis_solid3d/*.npz``: a dozen
DOFs — per-part stiffness matrices with their loss factors, the mass, the tip loads), from
which the tool-point FRF on *any* base receptance and grid is exact and instant
(:func:`tests.oracles.solid3d.reduction.tip_receptance`). Regenerate with::

    .venv/bin/python benchmarks/bench_diagnosis.py --solid3d-write-data

**Nuisance** (per trial, the diagnoser's tolerances times ``tolerance_scale``): the spindle
side is rcsa's RA-1 spindle with its bearing stiffnesses and dampers, and the spindle–holder
joint's stiffnesses and dampers drawn (the base receptance at the gauge line is then exact);
the holder's and the tool's Young's moduli scale their own stiffness parts of the reduced
model (a Ritz estimate on the nominal basis: second order in the ±2–3 % change), every loss
factor scales, the masses scale with one common density factor, and a layer's stiffness is
re-drawn per measurement (re-clamp). **Not drawn**: the stickout setting (the mesh is fixed;
the diagnoser is still told ±0.3 mm) and separate holder/tool densities. Noise as in
:mod:`tests.analysis.diagnosis.truth` (1 % + floor at −50 dB of the peak, 5 averages).
"""

from __future__ import annotations

import copy
import json
import math
import time
from collections.abc import Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np

from tests.analysis.diagnosis.truth import N_AVERAGES, measure
from tests.oracles.solid3d.case import (
    Flutes,
    HolderSegment,
    Interface,
    MeshSize,
    SolidCase,
    ToolGeometry,
)
from tests.oracles.solid3d.reduction import ReducedModel, tip_receptance

__all__ = ["CLASSES", "DATA_DIR", "FREQUENCY_HZ", "STICKOUTS_M", "VARIANTS", "DatasetTrial", "SolidTrial",
           "base_document", "dataset_base_document", "dataset_cases_outside_calibration", "load_reduced",
           "make_dataset_trial", "make_solid_trial", "nuisance_knobs", "solid_case", "truth_h", "write_data"]

DATA_DIR = Path(__file__).resolve().parents[2] / "data" / "diagnosis_solid3d"
STICKOUTS_M = (0.030, 0.040, 0.050)
FREQUENCY_HZ = np.arange(100.0, 6000.0 + 1e-9, 2.0)
DIAMETER_M = 0.010
OVERALL_LENGTH_M = 0.075
FLUTE_LENGTH_M = 0.025
HOLDER = (HolderSegment(0.024, 0.063, DIAMETER_M), HolderSegment(0.030, 0.040, DIAMETER_M),
          HolderSegment(0.040, 0.026, DIAMETER_M))
MESH = MeshSize(0.15 * DIAMETER_M, 0.008, 0.3)  # the 3-D data set's mesh (tests/oracles/solid3d/dataset.py)
CUTOFF_HZ = 2.5 * 6000.0

#: variant → (class, interface, flutes)
VARIANTS: dict[str, tuple[str, Interface, Flutes | None]] = {
    "bonded": ("bonded", Interface(), None),
    "layer_k1e13": ("soft_layer", Interface("layer", 1e13), None),
    "layer_k3e13": ("soft_layer", Interface("layer", 3e13), None),
    "front_lost_6mm": ("front_contact_lost", Interface(contact_start_m=0.006), None),
    "front_lost_12mm": ("front_contact_lost", Interface(contact_start_m=0.012), None),
    "flutes_2": ("fluted", Interface(), Flutes(2, 0.5 * DIAMETER_M, 0.27 * DIAMETER_M)),
    "flutes_4": ("fluted", Interface(), Flutes(4, 0.6 * DIAMETER_M, 0.16 * DIAMETER_M)),
}
CLASSES = ("bonded", "soft_layer", "front_contact_lost", "fluted")
#: what a right verdict names per class, on the bonded base (the class's own effect; "none" for bonded)
EXPECTED_ON_BONDED = {"bonded": "none", "soft_layer": "holder_tool_joint", "front_contact_lost": "insertion_depth",
                      "fluted": "fluted_section"}


def solid_case(variant: str, stickout_m: float) -> SolidCase:
    """The 3-D case of one variant at one stickout."""
    _, interface, flutes = VARIANTS[variant]
    tool = ToolGeometry(diameter_m=DIAMETER_M, shank_diameter_m=DIAMETER_M, overall_length_m=OVERALL_LENGTH_M,
                        flute_length_m=FLUTE_LENGTH_M, stickout_m=stickout_m, flutes=flutes)
    return SolidCase(HOLDER, tool, interface=interface, mesh=MESH)


def _path(variant: str, stickout_m: float, directory: Path) -> Path:
    return directory / f"{variant}_{round(stickout_m * 1e3):d}mm.npz"


def write_data(variants: Sequence[str] | None = None, directory: Path = DATA_DIR) -> None:
    """Build, reduce and store every (variant, stickout) that is not stored yet (minutes each)."""
    from tests.oracles.solid3d.solve import build

    directory.mkdir(parents=True, exist_ok=True)
    index_path = directory / "index.json"
    index = json.loads(index_path.read_text()) if index_path.exists() else {}
    for variant in variants or list(VARIANTS):
        for s in STICKOUTS_M:
            path = _path(variant, s, directory)
            if path.exists():
                continue
            t0 = time.perf_counter()
            model = build(solid_case(variant, s), "elastic", CUTOFF_HZ)
            red = model.reduced
            arrays = {f"stiffness_{i}": a for i, (a, _) in enumerate(red.stiffness)}
            np.savez_compressed(path, **arrays, loss_factors=np.array([eta for _, eta in red.stiffness]),
                                mass=red.mass, tip_loads=red.tip_loads,
                                fixed_base_frequencies_hz=red.fixed_base_frequencies_hz,
                                meta=np.array([red.n_boundary, red.multiplicity, red.cutoff_hz]))
            index[path.stem] = {"variant": variant, "stickout_m": s, "n_dof": model.matrices.n_dof,
                                "n_elements": int(model.mesh.tets.shape[1]), "n_reduced": int(red.mass.shape[0]),
                                "wall_time_s": round(time.perf_counter() - t0, 1)}
            index_path.write_text(json.dumps(index, indent=1, sort_keys=True))
            print(f"{path.name}: {index[path.stem]}", flush=True)


def load_reduced(variant: str, stickout_m: float, directory: Path = DATA_DIR) -> ReducedModel:
    """The stored reduced model of one (variant, stickout)."""
    with np.load(_path(variant, stickout_m, directory)) as d:
        etas = d["loss_factors"]
        stiff = tuple((d[f"stiffness_{i}"], float(eta)) for i, eta in enumerate(etas))
        nq, mult, cutoff = d["meta"]
        return ReducedModel(stiffness=stiff, mass=d["mass"], tip_loads=d["tip_loads"], n_boundary=int(nq),
                            multiplicity=int(mult), fixed_base_frequencies_hz=d["fixed_base_frequencies_hz"],
                            cutoff_hz=float(cutoff))


def base_document(model: str = "bonded", holder_tool: dict[str, float] | None = None) -> dict[str, Any]:
    """The diagnoser's base model of the same geometry on RA-1's spindle (no frequency grid).

    ``model``: ``"bonded"`` (the clamping along the insertion) or ``"point"`` with the point
    joint ``holder_tool`` (default: RA-1's).
    """
    from rcsa.reference import ra1
    from tests.oracles.solid3d.dataset import beam_document

    doc = beam_document(solid_case("bonded", STICKOUTS_M[1]), FREQUENCY_HZ)
    del doc["frequency"]
    if model == "bonded":
        doc["joints"]["holder_tool"] = {"model": "bonded"}
    else:
        doc["joints"]["holder_tool"] = dict(holder_tool or ra1()["joints"]["holder_tool"])
    return doc


# ---------------------------------------------------------------------------------- nuisance
@dataclass
class SolidNuisance:
    """One draw: shared scales and per-measurement layer scales."""

    shared: dict[str, float]
    layer_scale: list[float]


def draw_nuisance(rng: np.random.Generator, n_configs: int, scale: float = 1.0) -> SolidNuisance:
    """The diagnoser's tolerances (``scale`` times), as far as the cached 3-D models allow (module docstring)."""
    n = rng.standard_normal
    s = scale
    shared = {"tool_e": 1 + 0.03 * s * n(), "rho": 1 + 0.01 * s * n(), "steel_e": 1 + 0.02 * s * n(),
              "loss": math.exp(0.25 * s * n()), "bearing_k": math.exp(0.08 * s * n()),
              "bearing_c": math.exp(0.25 * s * n()), "sh_kt": math.exp(0.15 * s * n()),
              "sh_kr": math.exp(0.15 * s * n()), "sh_c": math.exp(0.25 * s * n())}
    return SolidNuisance(shared, [math.exp(0.15 * s * n()) for _ in range(n_configs)])


def spindle_receptance(shared: dict[str, float], frequency_hz: np.ndarray) -> np.ndarray:
    """RA-1's spindle + spindle–holder joint under the draw, as a receptance at the gauge line (nfreq, 2, 2)."""
    from rcsa.model.assembly import build_model
    from rcsa.model.contract import parse_assembly
    from rcsa.physics.elimination import tip_receptance as beam_tip
    from rcsa.reference import ra1

    doc = ra1({"values_hz": [float(x) for x in frequency_hz]})
    steel = {"youngs_modulus_pa": 210e9 * shared["steel_e"], "poisson_ratio": 0.30,
             "density_kg_m3": 7850.0 * shared["rho"], "loss_factor": 0.002 * shared["loss"]}
    doc["materials"] = {"steel": steel}
    for b in doc["spindle"]["bearings"]:
        b["stiffness_n_m"] *= shared["bearing_k"]
        b["damping_ns_m"] *= shared["bearing_c"]
    sh = doc["joints"]["spindle_holder"]
    sh["stiffness_n_m"] *= shared["sh_kt"]
    sh["rotational_stiffness_nm_rad"] *= shared["sh_kr"]
    sh["damping_ns_m"] *= shared["sh_c"]
    sh["rotational_damping_nms_rad"] *= shared["sh_c"]
    chain = build_model(parse_assembly(doc)).spindle_side()
    return beam_tip(chain, 2 * np.pi * np.asarray(frequency_hz, dtype=float))


def perturbed(red: ReducedModel, shared: dict[str, float], layer_scale: float = 1.0) -> ReducedModel:
    """The reduced model with the draw's moduli, loss factors and density (parts: holder, tool, interface)."""
    scales = [shared["steel_e"], shared["tool_e"], layer_scale]
    stiff = tuple((a * scales[min(i, 2)], eta * shared["loss"]) for i, (a, eta) in enumerate(red.stiffness))
    return replace(red, stiffness=stiff, mass=red.mass * shared["rho"])


def truth_h(variant: str, stickout_m: float, base: np.ndarray, frequency_hz: np.ndarray,
            shared: dict[str, float] | None = None, layer_scale: float = 1.0) -> np.ndarray:
    """Noise-free 3-D tool-point h of one (variant, stickout) on a base receptance (nfreq, 2, 2)."""
    red = load_reduced(variant, stickout_m)
    if shared is not None:
        red = perturbed(red, shared, layer_scale)
    omega = 2 * np.pi * np.asarray(frequency_hz, dtype=float)
    return tip_receptance(red, omega, np.linalg.inv(base))[:, 0, 0]


@dataclass
class SolidTrial:
    """One 3-D withheld-effect trial."""

    variant: str
    klass: str
    request: dict[str, Any]
    clean: list[np.ndarray]        # the 3-D truth, no noise, per measurement
    clean_null: list[np.ndarray]   # the bonded 3-D truth under the same draw (SNR reference)
    nuisance: SolidNuisance | None = None


def make_solid_trial(rng: np.random.Generator, variant: str, *, model: str = "bonded",
                     holder_tool: dict[str, float] | None = None, tolerance_scale: float = 1.0,
                     frequency_hz: np.ndarray = FREQUENCY_HZ, options: dict | None = None) -> SolidTrial:
    """Draw nuisance and noise for one variant; the request against the ``model`` base."""
    nz = draw_nuisance(rng, len(STICKOUTS_M), tolerance_scale)
    base = spindle_receptance(nz.shared, frequency_hz)
    layered = VARIANTS[variant][1].model == "layer"
    clean = [truth_h(variant, s, base, frequency_hz, nz.shared, nz.layer_scale[i] if layered else 1.0)
             for i, s in enumerate(STICKOUTS_M)]
    null = clean if variant == "bonded" else [truth_h("bonded", s, base, frequency_hz, nz.shared)
                                              for s in STICKOUTS_M]
    measurements = []
    for s, h in zip(STICKOUTS_M, clean, strict=True):
        noisy, coherence = measure(h, rng)
        measurements.append({"tool": {"stickout_m": s}, "frequency_hz": frequency_hz.tolist(),
                             "h": {"real": noisy.real.tolist(), "imag": noisy.imag.tolist()},
                             "coherence": coherence.tolist(), "n_averages": N_AVERAGES,
                             "label": f"{s * 1e3:.0f} mm"})
    request: dict[str, Any] = {"assembly": copy.deepcopy(base_document(model, holder_tool)),
                               "measurements": measurements}
    if options:
        request["options"] = options
    return SolidTrial(variant, VARIANTS[variant][0], request, clean, null, nz)


def nuisance_knobs(nz: SolidNuisance) -> Any:
    """The draw as the diagnosis's knobs (all but the per-measurement layer scale, which no base has)."""
    from rcsa.analysis.diagnosis.perturbed_model import Knobs

    s = nz.shared
    return Knobs(tool_youngs_scale=s["tool_e"], tool_density_scale=s["rho"], structure_youngs_scale=s["steel_e"],
                 structure_density_scale=s["rho"], loss_factor_scale=s["loss"], bearing_stiffness_scale=s["bearing_k"],
                 bearing_damping_scale=s["bearing_c"], sh_translational_scale=s["sh_kt"],
                 sh_rotational_scale=s["sh_kr"], sh_damping_scale=s["sh_c"])


# ---------------------------------------------------------------------------------- any case of the data set
#: Cases of ``tests/data/solid3d`` that are no holder family for the diagnosis: a holder tied rigid.
NOT_A_HOLDER = ("rigid_holder",)


def dataset_cases_outside_calibration(directory: Path | None = None) -> list[str]:
    """The cases of the 3-D data set the clamping coefficients were not fitted on.

    Every case of ``tests/data/solid3d/cases.json`` but the calibration's
    (:data:`tests.oracles.solid3d.clamping_scores.CALIBRATION_CASES`, read when called: the list
    follows the data set and its calibration) and :data:`NOT_A_HOLDER`.
    """
    from tests.oracles.solid3d import clamping_scores, dataset

    index = json.loads(((directory or dataset.DATA_DIR) / "cases.json").read_text())
    return [n for n in index["cases"] if n not in clamping_scores.CALIBRATION_CASES and n not in NOT_A_HOLDER]


def dataset_base_document(case: dict[str, Any], model: str) -> dict[str, Any]:
    """The diagnoser's base model of a data-set case on RA-1's spindle (no frequency grid).

    The case's holder, tool and materials in the contract's terms as the data set states them
    (only a real flute cross-section, which the contract has no field for, is left out: the
    diagnosis must find what it does), RA-1's spindle and spindle–holder joint (the data set's
    ``spindle`` base), and the
    holder–tool joint of ``model``: ``"point"`` (the contract's default: left out, rigid),
    ``"bonded"``, or ``"point_ra1"`` (RA-1's elastic point joint).
    """
    from rcsa.reference import ra1

    doc = ra1()
    del doc["frequency"]
    doc["holder"] = copy.deepcopy(case["holder"])
    doc["tool"] = {k: v for k, v in case["tool"].items() if k != "flutes"}
    doc["materials"] = {**doc.get("materials", {}), **case["materials"]}
    ht = doc["joints"]["holder_tool"]
    doc["joints"] = {"spindle_holder": doc["joints"]["spindle_holder"]}
    if model == "bonded":
        doc["joints"]["holder_tool"] = {"model": "bonded"}
    elif model == "point_ra1":
        doc["joints"]["holder_tool"] = ht
    elif model != "point":
        raise ValueError(f"unknown base model {model!r}")
    return doc


@dataclass
class DatasetTrial:
    """One tap test of a data-set case: the request and the noise-free truth on its lines."""

    case: str
    request: dict[str, Any]
    clean: list[np.ndarray]


def make_dataset_trial(rng: np.random.Generator, case: str, model: str, step: int = 2,
                       directory: Path | None = None) -> DatasetTrial:
    """A tap test of one case of the 3-D data set, diagnosed against the ``model`` base.

    The truth is the case's tool-point FRF on RA-1's spindle as stored (``h_spindle``, every
    ``step``-th line of 100–6000 Hz), with the benchmark's noise (1 % + floor, 5 averages):
    one stickout, no nuisance scatter (the stored solution is one spindle and one set of
    moduli; the diagnoser is still told its default tolerances).
    """
    from tests.oracles.solid3d import dataset

    data = dataset.load_case(case, directory or dataset.DATA_DIR)
    f = data["frequency_hz"][::step]
    h = data["h_spindle"][::step]
    noisy, coherence = measure(h, rng)
    request = {"assembly": dataset_base_document(data["case"], model),
               "measurements": [{"tool": {}, "frequency_hz": f.tolist(),
                                 "h": {"real": noisy.real.tolist(), "imag": noisy.imag.tolist()},
                                 "coherence": coherence.tolist(), "n_averages": N_AVERAGES, "label": case}]}
    return DatasetTrial(case, request, [h])
