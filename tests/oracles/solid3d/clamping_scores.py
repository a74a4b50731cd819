"""rcsa's clamping models on the cases of the 3-D data set, and how far they are from it.

Shared by ``benchmarks/calibrate_clamping.py`` (the fit, the leave-one-family-out folds and the
full table) and ``tests/model/test_clamping_vs_solid3d.py`` (every held-out row in the suite).

What is compared, per case and base (the holder's base face clamped, or RA-1's spindle):

* every **peak** of the 3-D tool-point |h| in the band (a local maximum standing at least
  :data:`PEAK_PROMINENCE_DB` above its surroundings): its frequency and height against rcsa's
  nearest peak's, both refined on a fine grid around the peak (the 3-D one from its stored
  Craig–Bampton model, so a lightly damped peak is not cut by the 1 Hz grid; a peak, not the
  undamped natural frequency under it: the spindle's modes are heavily damped);
* the mean |dB| of rcsa's h against the 3-D h over the band, and the static compliance.
"""

from __future__ import annotations

import functools
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np
from scipy.signal import find_peaks

from rcsa.model.assembly import build_model
from rcsa.model.contract import parse_assembly
from rcsa.physics.chain import Chain, Ground
from rcsa.physics.elimination import tip_receptance
from tests.oracles.solid3d import dataset
from tests.oracles.solid3d.reduction import tip_receptance as solid_tip_receptance

__all__ = ["CALIBRATION_CASES", "GEOMETRY_KEYS", "INFORMATION", "PEAK_PROMINENCE_DB", "case_geometry",
           "extrapolation_notes", "geometry_ranges", "holder_tool", "load", "outside",
           "model_chain", "model_peaks", "peak_scores", "rcsa_h", "refine_peaks", "role", "score_row", "scores",
           "truth_h", "truth_peaks"]

#: The cases the clamping coefficients are fitted on (both bases). One per holder family other than
#: the issue-24 holder's; the issue-24 holder's own case (``base_d10``, also the diagnosis's 40 mm
#: bonded truth) is held out. Every other case is held out, except :data:`INFORMATION`.
CALIBRATION_CASES = ("diameter_d6", "diameter_d16", "nose_od1.6d", "nose_od3.2d", "insertion_2d", "insertion_5d",
               "stickout_3d", "stickout_6d", "shrink_slender_d6", "hydraulic_d20", "collet_d16", "sidelock_d16")
#: Cases the clamping models do not describe (reported, not scored): real flute sections (the
#: ``fluted_section`` effect), a rigid holder.
INFORMATION = ("flutes_2", "flutes_4", "rigid_holder")

#: A local maximum of the 3-D |h| this far above its surroundings (dB) is a peak to be met.
PEAK_PROMINENCE_DB = 1.0
#: Points of the fine grid around a peak, over ± :data:`_FINE_SPAN` half-power bandwidths.
_FINE_POINTS, _FINE_SPAN = 121, 3.0
_CLAMP = (Ground(1e15, 0.0, 1e15, 0.0),)


def role(name: str) -> str:
    """``"calibration"``, ``"information"`` or ``"held-out"``."""
    return "calibration" if name in CALIBRATION_CASES else "information" if name in INFORMATION else "held-out"


#: The geometry a calibration covers, as rcsa sees a case (:func:`case_geometry`); the keys of
#: :data:`rcsa.model.clamping.CALIBRATED_GEOMETRY_RANGES`.
GEOMETRY_KEYS = ("wall_ratio", "shank_diameter_m", "insertion_diameters")


def case_geometry(name: str) -> dict[str, float]:
    """A case's geometry as rcsa's clamping notes read it (the holder as its outline, a cone stepped):
    the nose's outer diameter over the shank's, the shank diameter (m), the inserted length in
    shank diameters."""
    doc = dataset.beam_document(dataset.reference_cases()[name][0], dataset.FREQUENCY_HZ[:2])
    d = float(doc["tool"]["shank_diameter_m"])
    return {"wall_ratio": doc["holder"]["segments"][-1]["outer_diameter_m"] / d, "shank_diameter_m": d,
            "insertion_diameters": (doc["tool"]["overall_length_m"] - doc["tool"]["stickout_m"]) / d}


def geometry_ranges(names: Sequence[str]) -> dict[str, tuple[float, float]]:
    """The span (lowest, highest) of each of :data:`GEOMETRY_KEYS` over the cases ``names``."""
    found = [case_geometry(n) for n in names]
    return {k: (min(g[k] for g in found), max(g[k] for g in found)) for k in GEOMETRY_KEYS}


def outside(name: str, ranges: Mapping[str, tuple[float, float]]) -> list[str]:
    """The keys of :data:`GEOMETRY_KEYS` in which the case ``name`` lies outside ``ranges`` (extrapolated)."""
    g = case_geometry(name)
    return [k for k in GEOMETRY_KEYS if not ranges[k][0] * (1 - 1e-9) <= g[k] <= ranges[k][1] * (1 + 1e-9)]


def extrapolation_notes(name: str, directory: Path = dataset.DATA_DIR) -> list[str]:
    """What rcsa notes of a case's clamping as outside the range its calibration covers."""
    import json

    from rcsa.model.assembly import assembly_notes

    notes = assembly_notes(parse_assembly(json.loads(_document(name, directory))))
    return [n for n in notes if "extrapolated" in n]


def load(name: str, directory: Path = dataset.DATA_DIR) -> dict[str, Any]:
    """A case of the 3-D data set (:func:`tests.oracles.solid3d.dataset.load_case`)."""
    return dataset.load_case(name, directory)


def holder_tool(case: dict[str, Any]) -> dict[str, Any]:
    """The case's interface as a contract ``joints.holder_tool`` (bonded, or contact with its layer).

    The contact region (front gap and length), its arc (``contact_arc_deg``, a side-lock's
    contact at the back of the bore) and a side-lock screw (``screw_diameter_m``) are carried.
    """
    face = case["interface"]
    out: dict[str, Any] = {"model": "bonded"}
    if face["model"] == "layer":
        out = {"model": "contact", "interface_stiffness_n_m3": face["interface_stiffness_n_m3"],
               "interface_tangential_ratio": face["tangential_ratio"], "interface_loss_factor": face["loss_factor"]}
    if face["contact_start_m"] > 0:
        out["front_gap_length_m"] = face["contact_start_m"]
    if face["contact_stop_m"] is not None:
        out["contact_length_m"] = face["contact_stop_m"] - face["contact_start_m"]
    if face.get("arc_deg", 360.0) < 360.0:
        out["contact_arc_deg"] = face["arc_deg"]
    flat = case["tool"].get("flat")
    if flat is not None:
        out["screw_diameter_m"] = flat["screw_diameter_m"]
    return out


@functools.lru_cache(maxsize=256)
def _document(name: str, directory: Path) -> str:
    import json

    case = load(name, directory)["case"]
    doc = dataset.beam_document(dataset.reference_cases()[name][0], dataset.FREQUENCY_HZ[:2])
    doc["joints"]["holder_tool"] = holder_tool(case)
    return json.dumps(doc)


def model_chain(name: str, model: str, base: str, directory: Path = dataset.DATA_DIR) -> Chain:
    """rcsa's chain of a data-set case: ``model`` ``"point"`` (the contract's beam model) or
    ``"clamping"`` (the case's interface as a clamping); ``base`` ``"clamped"`` or ``"spindle"``.
    Built with the current :data:`rcsa.model.clamping.BULK_COEFFICIENTS`."""
    import json

    doc = json.loads(_document(name, directory))
    if model == "point":
        doc["joints"].pop("holder_tool")
    m = build_model(parse_assembly(doc))
    return (_CLAMP + m.holder + m.tool_side()) if base == "clamped" else m.chain()


def rcsa_h(name: str, model: str, base: str, frequency_hz: np.ndarray, directory: Path = dataset.DATA_DIR
           ) -> np.ndarray:
    """rcsa's tool-point h of a data-set case (:func:`model_chain`), shape (nfreq,)."""
    return tip_receptance(model_chain(name, model, base, directory), 2 * np.pi * np.asarray(frequency_hz))[:, 0, 0]


def truth_h(name: str, base: str, frequency_hz: np.ndarray, directory: Path = dataset.DATA_DIR) -> np.ndarray:
    """The 3-D tool-point h of a case at any frequencies (its stored Craig–Bampton model), shape (nfreq,)."""
    f = np.asarray(frequency_hz, dtype=float)
    red = dataset.load_reduced(name, directory)
    stiffness = None
    if base == "spindle":
        damped, _ = dataset.spindle_base_receptance(f)
        stiffness = np.linalg.inv(damped)
    return solid_tip_receptance(red, 2 * np.pi * f, stiffness)[:, 0, 0]


def scores(frequency_hz: np.ndarray, h: np.ndarray, truth: np.ndarray) -> dict[str, float]:
    """Mean |dB| over the band and the largest peak's frequency and height errors (relative)."""
    i, j = int(np.argmax(np.abs(truth))), int(np.argmax(np.abs(h)))
    return {"mean_abs_db": float(np.mean(np.abs(20 * np.log10(np.abs(h) / np.abs(truth))))),
            "peak_frequency_error": float(frequency_hz[j] / frequency_hz[i] - 1.0),
            "peak_height_error": float(abs(h[j]) / abs(truth[i]) - 1.0),
            "peak_hz": float(frequency_hz[i])}


def refine_peaks(frequency_hz: np.ndarray, h_of: Any, loss: float = 0.002) -> tuple[np.ndarray, np.ndarray]:
    """The maxima of |h| near each frequency: on a fine grid over ± a few half-power widths (at
    least ± 2 Hz), refined by a parabola through the three highest points.

    Parameters
    ----------
    frequency_hz : numpy.ndarray, shape (npeaks,)
        Where the peaks are, to a line of the data set's grid, Hz.
    h_of : callable
        ``h_of(f)`` → h at frequencies ``f`` (any shape, flattened), complex.
    loss : float
        The structure's loss factor (sets the half-power width η f).

    Returns
    -------
    (numpy.ndarray, numpy.ndarray)
        The peaks' frequencies, Hz, and their |h|.
    """
    f0 = np.asarray(frequency_hz, dtype=float)
    if f0.size == 0:
        return np.zeros(0), np.zeros(0)
    span = np.maximum(_FINE_SPAN * loss * f0, 2.0)
    steps = np.linspace(-1.0, 1.0, _FINE_POINTS)
    grid = f0[:, None] + span[:, None] * steps[None, :]
    a = np.abs(h_of(grid.ravel())).reshape(grid.shape)
    j = np.clip(np.argmax(a, axis=1), 1, _FINE_POINTS - 2)
    rows = np.arange(f0.size)
    y0, y1, y2 = a[rows, j - 1], a[rows, j], a[rows, j + 1]
    den = y0 - 2 * y1 + y2
    d = np.where(den < 0, 0.5 * (y0 - y2) / np.where(den < 0, den, -1.0), 0.0)
    return grid[rows, j] + d * (grid[rows, 1] - grid[rows, 0]), y1 - 0.25 * (y0 - y2) * d


def truth_peaks(name: str, base: str, directory: Path = dataset.DATA_DIR) -> np.ndarray:
    """The 3-D case's peaks in the band, to a line of its grid, Hz (:data:`PEAK_PROMINENCE_DB`)."""
    data = load(name, directory)
    f, h = data["frequency_hz"], data[f"h_{base}"]
    idx, _ = find_peaks(20 * np.log10(np.abs(h)), prominence=PEAK_PROMINENCE_DB)
    return np.asarray(f[idx], dtype=float)


def model_peaks(chain: Chain, frequency_hz: np.ndarray, near_hz: np.ndarray, loss: float = 0.002,
                h_grid: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """rcsa's peaks nearest to ``near_hz``: its local maxima of |h| on the grid (``h_grid`` if
    already computed), refined (:func:`refine_peaks`)."""
    h = np.abs(tip_receptance(chain, 2 * np.pi * frequency_hz)[:, 0, 0] if h_grid is None else h_grid)
    idx, _ = find_peaks(h)
    if idx.size == 0 or near_hz.size == 0:
        return np.full(near_hz.size, np.nan), np.full(near_hz.size, np.nan)
    found = frequency_hz[idx]
    nearest = found[np.argmin(np.abs(found[:, None] - near_hz[None, :]), axis=0)]
    return refine_peaks(nearest, lambda f: tip_receptance(chain, 2 * np.pi * f)[:, 0, 0], loss)


def peak_scores(name: str, base: str, chain: Chain, directory: Path = dataset.DATA_DIR, loss: float = 0.002,
                h_grid: np.ndarray | None = None) -> list[dict[str, float]]:
    """Every 3-D peak of a case and base against rcsa's ``chain``: frequency and height errors.

    Parameters
    ----------
    name, base : str
    chain : Chain
        rcsa's model of the case on that base (:func:`model_chain`).
    directory : pathlib.Path
    loss : float
        The structure's loss factor (sets the fine grid's width around each peak).
    h_grid : numpy.ndarray, optional
        rcsa's h on the data set's grid, if already computed.

    Returns
    -------
    list of dict
        Per peak: ``frequency_hz`` (3-D), ``model_hz``, ``frequency_error`` and ``height_error``
        (relative), ``height_m_n`` (3-D).
    """
    found = truth_peaks(name, base, directory)
    if found.size == 0:
        return []
    truth_f, truth_height = refine_peaks(found, lambda f: truth_h(name, base, f, directory), loss)
    model_f, model_height = model_peaks(chain, load(name, directory)["frequency_hz"], truth_f, loss, h_grid)
    return [{"frequency_hz": float(a), "model_hz": float(b), "frequency_error": float(b / a - 1.0),
             "height_error": float(hb / ha - 1.0), "height_m_n": float(ha)}
            for a, b, ha, hb in zip(truth_f, model_f, truth_height, model_height, strict=True)]


def score_row(name: str, base: str, model: str, directory: Path = dataset.DATA_DIR) -> dict[str, Any]:
    """Everything compared for one case, base and model (module docstring).

    Returns
    -------
    dict
        ``peaks`` (:func:`peak_scores`), ``max_frequency_error``, ``max_height_error`` (largest
        absolute relative errors over the peaks), ``mean_abs_db``, ``static_error`` (relative, at
        the grid's first line), and the largest-peak figures of :func:`scores`.
    """
    data = load(name, directory)
    f, truth = data["frequency_hz"], data[f"h_{base}"]
    chain = model_chain(name, model, base, directory)
    h = tip_receptance(chain, 2 * np.pi * f)[:, 0, 0]
    peaks = peak_scores(name, base, chain, directory, h_grid=h)
    out: dict[str, Any] = dict(scores(f, h, truth))
    out.update({"peaks": peaks,
                "max_frequency_error": max((abs(p["frequency_error"]) for p in peaks), default=0.0),
                "max_height_error": max((abs(p["height_error"]) for p in peaks), default=0.0),
                "static_error": float(abs(h[0]) / abs(truth[0]) - 1.0)})
    return out
