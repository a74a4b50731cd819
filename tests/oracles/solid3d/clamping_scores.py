"""rcsa's clamping models on the cases of the 3-D data set, and how far they are from it.

Shared by ``benchmarks/calibrate_clamping.py`` (the fit and the full table) and
``tests/model/test_clamping_vs_solid3d.py`` (held-out cases in the suite).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from rcsa.model.assembly import build_model
from rcsa.model.contract import parse_assembly
from rcsa.physics.chain import Ground
from rcsa.physics.elimination import tip_receptance
from tests.oracles.solid3d import dataset

__all__ = ["CALIBRATION_CASES", "INFORMATION", "holder_tool", "load", "rcsa_h", "scores"]

#: The cases the clamping coefficients are fitted on; every other bonded case is held out.
CALIBRATION_CASES = ("base_d10", "diameter_d6", "diameter_d16", "nose_od1.6d", "nose_od3.2d", "insertion_2d",
               "insertion_5d", "stickout_3d", "stickout_6d")
#: Cases the clamping models do not describe (reported, not scored).
INFORMATION = ("flutes_2", "flutes_4", "rigid_holder")
_CLAMP = (Ground(1e15, 0.0, 1e15, 0.0),)


def load(name: str, directory: Path = dataset.DATA_DIR) -> dict[str, Any]:
    """A case of the 3-D data set (:func:`tests.oracles.solid3d.dataset.load_case`)."""
    return dataset.load_case(name, directory)


def holder_tool(case: dict[str, Any]) -> dict[str, Any]:
    """The case's interface as a contract ``joints.holder_tool`` (bonded, or contact with its layer)."""
    face = case["interface"]
    out: dict[str, Any] = {"model": "bonded"}
    if face["model"] == "layer":
        out = {"model": "contact", "interface_stiffness_n_m3": face["interface_stiffness_n_m3"],
               "interface_tangential_ratio": face["tangential_ratio"], "interface_loss_factor": face["loss_factor"]}
    if face["contact_start_m"] > 0:
        out["front_gap_length_m"] = face["contact_start_m"]
    if face["contact_stop_m"] is not None:
        out["contact_length_m"] = face["contact_stop_m"] - face["contact_start_m"]
    return out


def rcsa_h(name: str, model: str, base: str, frequency_hz: np.ndarray, directory: Path = dataset.DATA_DIR
           ) -> np.ndarray:
    """rcsa's tool-point h of a data-set case: ``model`` ``"point"`` (the contract's beam model) or
    ``"clamping"`` (the case's interface as a clamping); ``base`` ``"clamped"`` or ``"spindle"``."""
    case = load(name, directory)["case"]
    doc = dataset.beam_document(dataset.reference_cases()[name][0], frequency_hz)
    if model != "point":
        doc["joints"]["holder_tool"] = holder_tool(case)
    m = build_model(parse_assembly(doc))
    chain = (_CLAMP + m.holder + m.tool_side()) if base == "clamped" else m.chain()
    return tip_receptance(chain, 2 * np.pi * frequency_hz)[:, 0, 0]


def scores(frequency_hz: np.ndarray, h: np.ndarray, truth: np.ndarray) -> dict[str, float]:
    """Mean |dB| over the band and the largest peak's frequency and height errors (relative)."""
    i, j = int(np.argmax(np.abs(truth))), int(np.argmax(np.abs(h)))
    return {"mean_abs_db": float(np.mean(np.abs(20 * np.log10(np.abs(h) / np.abs(truth))))),
            "peak_frequency_error": float(frequency_hz[j] / frequency_hz[i] - 1.0),
            "peak_height_error": float(abs(h[j]) / abs(truth[i]) - 1.0),
            "peak_hz": float(frequency_hz[i])}
