"""Hybrid truth of the withheld-effect benchmark: tap tests *and* the measured spindle from the FE truth.

A shop measures its spindle once and couples analytical holders and tools to it. Each trial
here is one such shop (``truth.py`` §1-3 for the tap tests) plus the spindle measurement it
stored, taken on the same physical spindle — the FE spindle of that trial, with its nuisance
(bearing stiffness, steel modulus, …) inside the measurement:

* ``point_receptance`` — h, l, n, p of the FE spindle at its nose, each with 0.3 % complex
  noise (the coherence stored with them implies it for 5 averages);
* ``direct_frf`` — h alone (0.3 %); the request estimates the rotations with an equivalent
  cantilever whose length is the FE spindle's own (1.5 h/n at the lowest line, ≈ 0.23 m)
  scattered by the tolerance the diagnoser assumes (ln-sd 0.35);
* ``artifact_frfs`` — a Ø40 × 80 mm steel test arbor bolted to the nose (rigid), tapped at
  its tip and 25 mm inward (h11, h21, h22, each 0.3 % noise): FE of spindle + arbor,
  identified by the diagnoser with the exact three-FRF method.

Plane: ``spindle_nose`` (the holder and its joint are modelled). The hidden effects are
realised as in ``truth.py`` — except ``bearings``, which cannot be a cause here (the measured
spindle contains its bearings), and ``spindle_rotational_receptance``, which now lives in the
stored measurement, not in the machine, realised per kind as the error that really occurs:

========================  ====================================================================
kind                      rotational error of the stored spindle
========================  ====================================================================
point_receptance          rotations from an earlier (e.g. finite-difference) identification:
                          l, n × s and p × s², s = U(1.25, 2)^(±1)
direct_frf                the cantilever length of the estimate is off: L = L_true · 2^(±U(1.25, 2))
                          (2.4-4 × too long or too short, beyond the L/2-2L the estimate claims)
artifact_frfs             point 2 sits δ = U(3, 7) mm from where it is declared (toward or away
                          from the tip): the exact identification reads the rotations wrongly
========================  ====================================================================
"""

from __future__ import annotations

import copy
import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from rcsa.measured.store import Measurement, MeasurementMeta
from tests.analysis.diagnosis import truth as T
from tests.oracles.timoshenko_fe import (
    circular_section,
    harmonic_receptance,
    hutchinson_shear_coefficient,
    solid_circle_section_properties,
)

__all__ = ["HYBRID_EFFECTS", "KINDS", "STICKOUTS_M", "HybridTrial", "MemorySource", "make_hybrid_trial"]

KINDS = ("point_receptance", "direct_frf", "artifact_frfs")
HYBRID_EFFECTS = ("none", "holder_tool_joint", "spindle_holder_joint", "shear_and_rotary_inertia", "fluted_section",
                  "insertion_depth", "sensor_mass", "joint_damping", "spindle_rotational_receptance")
STICKOUTS_M = (0.050, 0.066, 0.082)
SPINDLE_NOISE_REL = 0.003
LENGTH_LOG_SD = 0.35  # the diagnoser's default spindle_effective_length_log
ARBOR = {"diameter_m": 0.040, "stickout_m": 0.080, "material": "steel"}
ARBOR_POINTS_M = (0.0, 0.025)


class MemorySource(dict):
    """Stored measurements by id (what :func:`rcsa.measured.hybrid.base_resolver` reads)."""

    def get(self, measurement_id: str) -> Measurement:  # type: ignore[override]
        """The measurement (KeyError if absent)."""
        return self[measurement_id]


def arbor_frfs(doc: dict[str, Any], f: np.ndarray, points_m: Sequence[float] = ARBOR_POINTS_M
               ) -> dict[str, np.ndarray]:
    """h11, h21, h22 of the test arbor bolted (rigidly) to the FE spindle's nose; points from the tip."""
    model, nose = T.spindle_model(doc)
    m = doc["materials"][ARBOR["material"]]
    area, inertia = solid_circle_section_properties(ARBOR["diameter_m"], 0.0)
    sec = circular_section(m["youngs_modulus_pa"], m["poisson_ratio"], m["density_kg_m3"], area_m2=area,
                           second_moment_m4=inertia, shear_coefficient=hutchinson_shear_coefficient(m["poisson_ratio"]),
                           loss_factor=m["loss_factor"])
    length = ARBOR["stickout_m"]
    inner = length - points_m[1]
    p2 = model.add_beam(nose, inner, sec, n_elements=max(1, math.ceil(inner / T.MESH_M - 1e-9)))[-1]
    tip = model.add_beam(p2, points_m[1], sec, n_elements=max(1, math.ceil(points_m[1] / T.MESH_M - 1e-9)))[-1]
    dofs = [model.node_dofs[tip][0], model.node_dofs[p2][0]]
    g = harmonic_receptance(model, f, dofs, dofs)
    return {"h11": g[:, 0, 0], "h21": g[:, 1, 0], "h22": g[:, 1, 1]}


def _noisy(x: np.ndarray, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """``x`` with complex relative noise (per real and imaginary part) and the coherence it implies."""
    noisy = x * (1.0 + SPINDLE_NOISE_REL * (rng.standard_normal(x.size) + 1j * rng.standard_normal(x.size)))
    return noisy, np.full(x.size, 1.0 / (1.0 + 2 * T.N_AVERAGES * SPINDLE_NOISE_REL**2))


def effective_length_m(s: np.ndarray) -> float:
    """The equivalent-cantilever length of a spindle receptance: 1.5 h/n at its lowest line, m."""
    return float(1.5 * (s[0, 0, 0] / s[0, 0, 1]).real)


def spindle_measurement(kind: str, doc: dict[str, Any], f: np.ndarray, rng: np.random.Generator,
                        rotation: dict[str, float] | None = None) -> Measurement:
    """The stored spindle of one trial (``rotation``: the realised error of its rotations, if any)."""
    meta = {"spindle_id": "fe-ra1", "direction": "x", "plane": "spindle_nose", "kind": kind}
    if kind == "artifact_frfs":
        points = ARBOR_POINTS_M
        if rotation:
            points = (0.0, ARBOR_POINTS_M[1] + rotation["point2_offset_m"])  # where point 2 really was
        frfs, coh = {}, {}
        for name, v in arbor_frfs(doc, f, points).items():
            frfs[name], coh[name] = _noisy(v, rng)
        return Measurement(f, frfs, MeasurementMeta(**meta, points_m=ARBOR_POINTS_M, artifact=dict(ARBOR)),
                           coherence=coh, id=f"{kind}-trial")
    s = T._spindle_nose_receptance(doc, f)
    if kind == "direct_frf":
        h, c = _noisy(s[:, 0, 0], rng)
        return Measurement(f, {"h": h}, MeasurementMeta(**meta), coherence={"h": c}, id=f"{kind}-trial")
    if rotation:
        d = rotation["rotation_scale"]
        s = s * np.array([[1.0, d], [d, d * d]])
    frfs, coh = {}, {}
    for name, (i, j) in zip("hlnp", ((0, 0), (0, 1), (1, 0), (1, 1)), strict=True):
        frfs[name], coh[name] = _noisy(s[:, i, j], rng)
    return Measurement(f, frfs, MeasurementMeta(**meta), coherence=coh, id=f"{kind}-trial")


def draw_rotation_error(rng: np.random.Generator, kind: str) -> dict[str, float]:
    """The realised error of the stored rotations (module docstring table)."""
    sign = float(rng.choice([-1.0, 1.0]))
    if kind == "point_receptance":
        return {"rotation_scale": float(rng.uniform(1.25, 2.0) ** sign)}
    if kind == "direct_frf":
        return {"length_factor": float(2.0 ** (sign * rng.uniform(1.25, 2.0)))}
    return {"point2_offset_m": sign * float(rng.uniform(0.003, 0.007))}


@dataclass
class HybridTrial:
    """One hybrid withheld-effect trial: the request, where its spindle is stored, and the truths."""

    effect: str
    kind: str
    params: dict[str, float]
    request: dict[str, Any]
    source: MemorySource
    clean: list[np.ndarray]
    clean_null: list[np.ndarray]
    source_null: MemorySource | None  # the stored spindle without its rotational error (rotation trials)
    length_null_m: float | None       # direct_frf: the estimate's length without the error


def make_hybrid_trial(rng: np.random.Generator, effect: str, kind: str, *,
                      stickouts_m: Sequence[float] = STICKOUTS_M, frequency_hz: np.ndarray = T.FREQUENCY_HZ,
                      with_null: bool = True, options: dict | None = None,
                      length_log_sd: float = LENGTH_LOG_SD) -> HybridTrial:
    """Draw nuisance, effect, tap-test noise and the stored spindle; return the request and its store.

    ``length_log_sd``: how well the shop knows its direct_frf spindle's cantilever length (the
    estimate scatters by it, and the request states it as ``spindle_effective_length_log``).
    """
    if effect not in HYBRID_EFFECTS:
        raise ValueError(f"{effect!r} is no hybrid benchmark class")
    nz = T.draw_nuisance(rng, len(stickouts_m))
    rot = effect == "spindle_rotational_receptance"
    params = draw_rotation_error(rng, kind) if rot else T.draw_effect(rng, effect)
    theory = "euler_bernoulli" if effect == "shear_and_rotary_inertia" else "timoshenko"
    docs = T.config_documents(T.base_document(), nz, stickouts_m)
    tap_effect = "none" if rot else effect
    clean = [T.effect_frf(tap_effect, params, d, frequency_hz) for d in docs]
    if tap_effect == "none" or not with_null:
        null = clean if tap_effect == "none" else []
    elif effect == "shear_and_rotary_inertia":
        null = [T._solve(dict(d, beam_theory="euler_bernoulli"), frequency_hz) for d in docs]
    else:
        null = [T.effect_frf("none", {}, d, frequency_hz) for d in docs]
    spindle_doc = T._clean(docs[0])
    if effect == "spindle_holder_joint":  # the measured spindle is the physical one: bored for the taper
        spindle_doc = T._clean(T._taper_spindle(docs[0]))
    noise_seed = int(rng.integers(2**32))
    spindle = spindle_measurement(kind, spindle_doc, frequency_hz, np.random.default_rng(noise_seed),
                                  params if rot else None)
    source = MemorySource({spindle.id: spindle})
    source_null, length_null = None, None
    spindle_spec: dict[str, Any] = {"measurement_id": spindle.id}
    if kind == "direct_frf":
        length_true = effective_length_m(T._spindle_nose_receptance(spindle_doc, frequency_hz[:1]))
        length_null = length_true * math.exp(length_log_sd * rng.standard_normal())
        spindle_spec["effective_length_m"] = length_true * params["length_factor"] if rot else length_null
        if rot:
            length_null = length_true
    if rot and kind != "direct_frf":
        clean_spindle = spindle_measurement(kind, spindle_doc, frequency_hz, np.random.default_rng(noise_seed))
        source_null = MemorySource({spindle.id: clean_spindle})
    measurements = []
    for stickout, h in zip(stickouts_m, clean, strict=True):
        noisy, coherence = T.measure(h, rng)
        measurements.append({"tool": {"stickout_m": stickout}, "frequency_hz": frequency_hz.tolist(),
                             "h": {"real": noisy.real.tolist(), "imag": noisy.imag.tolist()},
                             "coherence": coherence.tolist(), "n_averages": T.N_AVERAGES,
                             "label": f"{stickout * 1e3:.0f} mm"})
    assembly = copy.deepcopy(T.base_document(theory))
    assembly["spindle"] = spindle_spec
    request: dict[str, Any] = {"assembly": assembly, "measurements": measurements}
    if length_log_sd != LENGTH_LOG_SD:
        request["tolerances"] = {"spindle_effective_length_log": length_log_sd}
    if options:
        request["options"] = options
    return HybridTrial(effect, kind, {k: float(v) for k, v in params.items()}, request, source, clean, null,
                       source_null, length_null)
