"""Truth generator of the withheld-effect benchmark: RA-1 "measurements" from the independent FE oracle.

Every trial is a richer model than the diagnoser's base (``docs/diagnosis.md`` §5.1): the
Timoshenko finite-element assembly of :mod:`tests.oracles.fe_assembly` (it shares no code
with ``rcsa``), with

1. a **nuisance draw** of the nominal parameters inside the tolerances the diagnoser is told
   about (matched: the same distributions as ``rcsa.analysis.diagnosis.discrepancy.DEFAULT_TOLERANCES``):
   carbide E ±3 %, ρ ±1 %, steel E ±2 %, ρ ±1 % (1σ), every loss factor and bearing damper
   ×exp(0.25 N), bearing k ×exp(0.08 N), spindle–holder k_t, k_r ×exp(0.15 N) and dampers
   ×exp(0.25 N); per measurement (re-clamp) holder–tool k_t, k_r ×exp(0.15 N), dampers
   ×exp(0.25 N), stickout + 0.3 mm · N;
2. at most one **hidden effect, realised physically** — never with the candidate's formula:

   ========================  ==============================================================
   effect                    physical realisation in the FE truth
   ========================  ==============================================================
   holder_tool_joint         the tool core is its own beam inside the bore, held by springs
                             per unit length (lateral and rotational) over the whole insertion
                             (``holder_tool_distributed``) instead of a bonded composite plus a
                             lumped joint; softened to 10^U(−1.3, −0.3) × the closest-to-base
                             values in translation, and that × 10^U(−0.3, 0.3) in rotation
   spindle_holder_joint      a BT40-like taper shank (three steps Ø41/35/29 mm over 65 mm)
                             hangs from the holder and sits in a matching bore of the spindle
                             nose, held by springs per unit length over the taper
                             (``spindle_holder_distributed``, calibrated likewise), softened
                             by 10^U(−1.3, −0.3)
   bearings                  front pair ×a, rear pair ×a^β: a = 10^(±U(0.15, 0.5)), β ∈ U(0, 1)
   shear_and_rotary_inertia  the diagnoser's base says Euler–Bernoulli; the truth is the
                             Timoshenko FE (Hutchinson or Cowper κ, at random)
   fluted_section            the flutes get their own cross-section: area a·πD²/4 with
                             a ∈ U(0.50, 0.85), second moment i·πD⁴/64 with i = a²·U(0.45, 1)
                             (solid-circle κ), instead of the 0.8·D equivalent circle
   insertion_depth           the front δ ∈ U(2, 12) mm of the bore does not grip: the tool is
                             free over δ more length, the holder annulus over δ is a free
                             beam branch (not a lumped mass) on the holder
   sensor_mass               a rigid accelerometer of m ∈ U(1, 8) g (cube of density 4000 kg/m³,
                             its own rotary inertia) glued 0–4 mm behind the tip
   joint_damping             hysteretic (frequency-independent) loss η_HT ∈ U(0.05, 0.4),
                             η_SH = η_HT·U(0.5, 1.5) added to both joints (the base joints
                             are viscous)
   spindle_rotational_...    the spindle's rotational receptances at the nose are scaled as
                             an FD estimate would bias them: R_s → diag(1, s) R_s diag(1, s),
                             s ∈ U(1.25, 2.0) (l, n × s; p × s²), applied by a structural
                             modification of the FE assembly at the nose DOFs (the candidate
                             is a frequency-independent residual compliance, not this scaling)
   ========================  ==============================================================
3. **measurement noise**: complex Gaussian, 1 % of |H| plus a floor at −50 dB of the peak,
   per real and imaginary part; the coherence passed to the diagnoser is the one this noise
   implies for 5 averages, γ² = 1 / (1 + 2·5·(σ/|H|)²) (Bendat & Piersol).

Discretisation: 2 mm elements. Against the exact RA-1 model the FE tool-point FRF differs by
at most 0.3 % of the local |H| (at the 50 mm stickout's deepest antiresonance; ≤ 0.06 % at
the others, median 0.005 %) on 50–8000 Hz, well below the 1 % noise
(``benchmarks/bench_diagnosis.py --check-mesh`` measures it).
"""

from __future__ import annotations

import copy
import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from rcsa.reference import ra1
from tests.oracles.fe_assembly import build_assembly_model
from tests.oracles.timoshenko_fe import (
    BeamModel,
    circular_section,
    harmonic_receptance,
    hutchinson_shear_coefficient,
    solid_circle_section_properties,
)

__all__ = ["EFFECTS", "FREQUENCY_HZ", "STICKOUTS_M", "Trial", "base_document", "make_trial"]

STICKOUTS_M = (0.050, 0.058, 0.066, 0.074, 0.082)
FREQUENCY_HZ = np.arange(50.0, 8000.0 + 1e-9, 2.0)
MESH_M = 0.002
EFFECTS = ("none", "holder_tool_joint", "spindle_holder_joint", "bearings", "shear_and_rotary_inertia",
           "fluted_section", "insertion_depth", "sensor_mass", "joint_damping", "spindle_rotational_receptance")
NOISE_REL = 0.01
NOISE_FLOOR_DB = -50.0
N_AVERAGES = 5

# Distributed contacts closest to RA-1's point joints (per unit length over the contact):
# fitted once by least squares on the features at the five stickouts (Nelder-Mead, 400 FE
# evaluations; `benchmarks/bench_diagnosis.py --calibrate`). No uniform contact reproduces
# the base's lumped joints: at these values the holder-tool truth still differs from the
# base by 15-30 % in static compliance (its compliance grows differently with the stickout)
# and the spindle-holder truth by ~1.3 dB RMS. Scale 1 is therefore already a (form) effect.
HT_DISTRIBUTED = {"translational_stiffness_n_m2": 9.31e8, "rotational_stiffness_nm_rad_m": 1.52e6,
                  "translational_damping_ns_m2": 459.0, "rotational_damping_nms_rad_m": 14.0}
SH_DISTRIBUTED = {"translational_stiffness_n_m2": 7.54e8, "rotational_stiffness_nm_rad_m": 1.79e4,
                  "translational_damping_ns_m2": 504.0, "rotational_damping_nms_rad_m": 4.18e4}
TAPER_SHANK = [{"length_m": 0.022, "outer_diameter_m": 0.041, "material": "steel"},
               {"length_m": 0.022, "outer_diameter_m": 0.035, "material": "steel"},
               {"length_m": 0.021, "outer_diameter_m": 0.029, "material": "steel"}]


def base_document(beam_theory: str = "timoshenko") -> dict[str, Any]:
    """RA-1 as the diagnoser's base model (no frequency grid)."""
    doc = ra1()
    del doc["frequency"]
    doc["beam_theory"] = beam_theory
    return doc


# ---------------------------------------------------------------------------------- nuisance
@dataclass
class Nuisance:
    """One draw of the nominal parameters inside their tolerances."""

    shared: dict[str, float]
    per_config: list[dict[str, float]]


def draw_nuisance(rng: np.random.Generator, n_configs: int, scale: float = 1.0) -> Nuisance:
    """Draw shared and per-measurement deviations (``scale`` widens every tolerance)."""
    n = rng.standard_normal
    s = scale
    shared = {"tool_e": 1 + 0.03 * s * n(), "tool_rho": 1 + 0.01 * s * n(), "steel_e": 1 + 0.02 * s * n(),
              "steel_rho": 1 + 0.01 * s * n(), "loss": math.exp(0.25 * s * n()),
              "bearing_k": math.exp(0.08 * s * n()), "bearing_c": math.exp(0.25 * s * n()),
              "sh_kt": math.exp(0.15 * s * n()), "sh_kr": math.exp(0.15 * s * n()), "sh_c": math.exp(0.25 * s * n())}
    per = [{"ht_kt": math.exp(0.15 * s * n()), "ht_kr": math.exp(0.15 * s * n()), "ht_c": math.exp(0.25 * s * n()),
            "stickout_dm": 0.0003 * s * n()} for _ in range(n_configs)]
    return Nuisance(shared, per)


def config_documents(base: dict[str, Any], nz: Nuisance, stickouts_m: Sequence[float]) -> list[dict[str, Any]]:
    """FE assembly dicts of every measurement with the nuisance applied (true nominal values)."""
    s = nz.shared
    out = []
    for stickout, per in zip(stickouts_m, nz.per_config, strict=True):
        d = copy.deepcopy(base)
        d["materials"] = {
            "carbide": {"youngs_modulus_pa": 600e9 * s["tool_e"], "poisson_ratio": 0.22,
                        "density_kg_m3": 14500.0 * s["tool_rho"], "loss_factor": 0.002 * s["loss"]},
            "steel": {"youngs_modulus_pa": 210e9 * s["steel_e"], "poisson_ratio": 0.30,
                      "density_kg_m3": 7850.0 * s["steel_rho"], "loss_factor": 0.002 * s["loss"]}}
        for b in d["spindle"]["bearings"]:
            b["stiffness_n_m"] *= s["bearing_k"]
            b["damping_ns_m"] *= s["bearing_c"]
        sh, ht = d["joints"]["spindle_holder"], d["joints"]["holder_tool"]
        sh["stiffness_n_m"] *= s["sh_kt"]
        sh["rotational_stiffness_nm_rad"] *= s["sh_kr"]
        sh["damping_ns_m"] *= s["sh_c"]
        sh["rotational_damping_nms_rad"] *= s["sh_c"]
        ht["stiffness_n_m"] *= per["ht_kt"]
        ht["rotational_stiffness_nm_rad"] *= per["ht_kr"]
        ht["damping_ns_m"] *= per["ht_c"]
        ht["rotational_damping_nms_rad"] *= per["ht_c"]
        d["tool"]["stickout_m"] = stickout + per["stickout_dm"]
        d["_per"] = per  # read by the effects below; removed before the FE sees the dict
        d["_shared"] = s
        out.append(d)
    return out


# ---------------------------------------------------------------------------------- FE solves
def _clean(doc: dict[str, Any]) -> dict[str, Any]:
    return {k: v for k, v in doc.items() if not k.startswith("_")}


def _tip(built) -> list[int]:
    return list(built.model.node_dofs[built.tip_node])


def _solve(doc: dict[str, Any], f: np.ndarray, effects: dict | None = None, modify=None) -> np.ndarray:
    built = build_assembly_model(_clean(doc), effects=effects, max_element_length_m=MESH_M)
    if modify is not None:
        modify(built, doc)
    tip = _tip(built)[:1]
    return harmonic_receptance(built.model, f, tip, tip)[:, 0, 0]


def _distributed(doc: dict[str, Any], nominal: dict[str, float], kt: float, kr: float, c: float) -> dict:
    return {"translational_stiffness_n_m2": nominal["translational_stiffness_n_m2"] * kt,
            "rotational_stiffness_nm_rad_m": nominal["rotational_stiffness_nm_rad_m"] * kr,
            "translational_damping_ns_m2": nominal["translational_damping_ns_m2"] * c,
            "rotational_damping_nms_rad_m": nominal["rotational_damping_nms_rad_m"] * c}


def _taper_spindle(doc: dict[str, Any]) -> dict[str, Any]:
    """Spindle nose bored out where the taper shank sits (the shank's mass moves to the holder)."""
    d = copy.deepcopy(doc)
    s1 = d["spindle"]["segments"][0]
    bore = [dict(s1, length_m=p["length_m"], inner_diameter_m=p["outer_diameter_m"]) for p in TAPER_SHANK]
    rest = s1["length_m"] - sum(p["length_m"] for p in TAPER_SHANK)
    d["spindle"]["segments"] = bore + [dict(s1, length_m=rest)] + d["spindle"]["segments"][1:]
    return d


def _spindle_nose_receptance(doc: dict[str, Any], f: np.ndarray) -> np.ndarray:
    """FE receptance [[h, l], [n, p]] of the spindle alone (bearings, no holder) at its nose."""
    model, nose = spindle_model(doc)
    dofs = list(model.node_dofs[nose])
    return harmonic_receptance(model, f, dofs, dofs)


def spindle_model(doc: dict[str, Any]) -> tuple[BeamModel, int]:
    """FE of the spindle alone (bearings, no holder): the model and its nose node (x = 0, rear toward −x)."""
    mats = doc["materials"]
    model = BeamModel()
    nose = model.add_node(0.0)
    segs = doc["spindle"]["segments"]
    stations = np.round(np.cumsum([0.0] + [s["length_m"] for s in segs]), 9)
    cuts = sorted({*stations.tolist(), *(round(b["position_m"], 9) for b in doc["spindle"]["bearings"])})
    node, nodes_at = nose, {0.0: nose}
    for a, b in zip(cuts[:-1], cuts[1:], strict=True):  # distances from the nose; x = -distance
        seg = segs[int(np.searchsorted(stations, a, side="right")) - 1]
        m = mats[seg["material"]]
        di = seg.get("inner_diameter_m", 0.0)
        area, inertia = solid_circle_section_properties(seg["outer_diameter_m"], di)
        kappa = hutchinson_shear_coefficient(m["poisson_ratio"], di / seg["outer_diameter_m"])
        sec = circular_section(m["youngs_modulus_pa"], m["poisson_ratio"], m["density_kg_m3"], area_m2=area,
                               second_moment_m4=inertia, shear_coefficient=kappa, loss_factor=m["loss_factor"])
        start = model.add_node(-b)
        model.add_beam(start, b - a, sec, "timoshenko", n_elements=max(1, math.ceil((b - a) / MESH_M - 1e-9)),
                       end_node=node)
        node = nodes_at[b] = start
    for bg in doc["spindle"]["bearings"]:
        model.add_spring(nodes_at[round(bg["position_m"], 9)], None, translational_n_m=bg["stiffness_n_m"],
                         translational_ns_m=bg.get("damping_ns_m", 0.0),
                         rotational_nm_rad=bg.get("rotational_stiffness_nm_rad", 0.0),
                         rotational_nms_rad=bg.get("rotational_damping_nms_rad", 0.0))
    return model, nose


# ---------------------------------------------------------------------------------- effects
def draw_effect(rng: np.random.Generator, name: str) -> dict[str, float]:
    """Truth parameters of one hidden effect (ranges chosen so the SNR spans ~2–40)."""
    u = rng.uniform
    if name == "holder_tool_joint":
        a = 10 ** u(-1.3, -0.3)
        return {"translational_scale": a, "rotational_scale": a * 10 ** u(-0.3, 0.3)}
    if name == "spindle_holder_joint":
        return {"scale": 10 ** u(-1.3, -0.3)}
    if name == "bearings":
        return {"front_scale": 10 ** (rng.choice([-1.0, 1.0]) * u(0.15, 0.5)), "rear_exponent": u(0.0, 1.0)}
    if name == "shear_and_rotary_inertia":
        return {"cowper": float(rng.integers(0, 2))}
    if name == "fluted_section":
        a = u(0.50, 0.85)
        return {"area_ratio": a, "inertia_ratio": a * a * u(0.45, 1.0)}
    if name == "insertion_depth":
        return {"free_length_m": u(0.002, 0.012)}
    if name == "sensor_mass":
        return {"mass_kg": u(0.001, 0.008), "distance_from_tip_m": u(0.0, 0.004)}
    if name == "joint_damping":
        eta = u(0.05, 0.4)
        return {"eta_holder_tool": eta, "eta_spindle_holder": eta * u(0.5, 1.5)}
    if name == "spindle_rotational_receptance":
        return {"rotation_scale": u(1.25, 2.0)}
    if name == "none":
        return {}
    raise ValueError(f"unknown effect {name!r}")


def effect_frf(name: str, params: dict[str, float], doc: dict[str, Any], f: np.ndarray) -> np.ndarray:
    """Noise-free FE tool-point h of one measurement with the hidden effect realised physically."""
    per, shared = doc["_per"], doc["_shared"]
    if name in ("none", "shear_and_rotary_inertia"):
        d = dict(doc, beam_theory="timoshenko")
        if name == "shear_and_rotary_inertia" and params.get("cowper"):
            d["shear_coefficient"] = "cowper"
        return _solve(d, f)
    if name == "holder_tool_joint":
        spec = _distributed(doc, HT_DISTRIBUTED, params["translational_scale"] * per["ht_kt"],
                            params["rotational_scale"] * per["ht_kr"], per["ht_c"])
        return _solve(doc, f, {"holder_tool_distributed": spec})
    if name == "spindle_holder_joint":
        spec = _distributed(doc, SH_DISTRIBUTED, params["scale"] * shared["sh_kt"], params["scale"] * shared["sh_kr"],
                            shared["sh_c"])
        spec.update(shank_segments=TAPER_SHANK, contact_length_m=sum(p["length_m"] for p in TAPER_SHANK))
        return _solve(_taper_spindle(doc), f, {"spindle_holder_distributed": spec})
    if name == "bearings":
        d = copy.deepcopy(doc)
        a, beta = params["front_scale"], params["rear_exponent"]
        for b in d["spindle"]["bearings"]:
            b["stiffness_n_m"] *= a if b["position_m"] < 0.2 else a**beta
        return _solve(d, f)
    if name == "fluted_section":
        dia = doc["tool"]["diameter_m"]
        fl = {"area_m2": params["area_ratio"] * math.pi * dia**2 / 4,
              "second_moment_m4": params["inertia_ratio"] * math.pi * dia**4 / 64}
        return _solve(doc, f, {"fluted_section": fl})
    if name == "sensor_mass":
        m = params["mass_kg"]
        side = (m / 4000.0) ** (1 / 3)
        tip = {"mass_kg": m, "rotary_inertia_kg_m2": m * side**2 / 6,
               "distance_from_tip_m": params["distance_from_tip_m"], "offset_m": 0.0}
        return _solve(doc, f, {"tip_mass": tip})
    if name == "joint_damping":
        return _solve(doc, f, modify=lambda built, d: _hysteretic_joints(built, d, params))
    if name == "insertion_depth":
        return _insertion(doc, f, params["free_length_m"])
    if name == "spindle_rotational_receptance":
        return _scaled_spindle_rotation(doc, f, params["rotation_scale"])
    raise ValueError(f"unknown effect {name!r}")


def _hysteretic_joints(built, doc: dict[str, Any], params: dict[str, float]) -> None:
    """Add i·η·k in parallel to both joints (structural damping of the contact)."""
    spindle, holder, tool = (built.outer_nodes[c][0] for c in ("spindle", "holder", "tool"))
    for (a, b), joint, eta in (((spindle[-1], holder[0]), doc["joints"]["spindle_holder"], params["eta_spindle_holder"]),
                               ((holder[-1], tool[0]), doc["joints"]["holder_tool"], params["eta_holder_tool"])):
        built.model.add_spring(a, b, translational_n_m=1j * eta * joint["stiffness_n_m"],
                               rotational_nm_rad=1j * eta * joint["rotational_stiffness_nm_rad"])


def _insertion(doc: dict[str, Any], f: np.ndarray, free_m: float) -> np.ndarray:
    """The bore's front ``free_m`` does not grip: shorter holder, longer tool, annulus as a free branch."""
    d = copy.deepcopy(doc)
    last = d["holder"]["segments"][-1]
    ring = dict(last)
    last["length_m"] -= free_m
    d["tool"]["stickout_m"] += free_m

    def add_ring(built, _doc) -> None:
        mat = {**{"steel": {"youngs_modulus_pa": 210e9, "poisson_ratio": 0.3, "density_kg_m3": 7850.0,
                            "loss_factor": 0.002}}, **d.get("materials", {})}[ring["material"]]
        area, inertia = solid_circle_section_properties(ring["outer_diameter_m"], ring["inner_diameter_m"])
        sec = circular_section(mat["youngs_modulus_pa"], mat["poisson_ratio"], mat["density_kg_m3"], area_m2=area,
                               second_moment_m4=inertia,
                               shear_coefficient=hutchinson_shear_coefficient(
                                   mat["poisson_ratio"], ring["inner_diameter_m"] / ring["outer_diameter_m"]),
                               loss_factor=mat["loss_factor"])
        holder_tip = built.outer_nodes["holder"][0][-1]
        built.model.add_beam(holder_tip, free_m, sec, d.get("beam_theory", "timoshenko"),
                             n_elements=max(1, math.ceil(free_m / MESH_M - 1e-9)))

    return _solve(d, f, modify=add_ring)


def _scaled_spindle_rotation(doc: dict[str, Any], f: np.ndarray, s: float) -> np.ndarray:
    """Structural modification at the nose: K_s → D⁻¹ K_s D⁻¹ with D = diag(1, s)."""
    built = build_assembly_model(_clean(doc), max_element_length_m=MESH_M)
    nose = built.outer_nodes["spindle"][0][-1]
    dofs = _tip(built)[:1] + list(built.model.node_dofs[nose])
    g = harmonic_receptance(built.model, f, dofs, dofs)  # (nf, 3, 3): tip w, nose w, nose psi
    k_s = np.linalg.inv(_spindle_nose_receptance(_clean(doc), f))
    d_inv = np.diag([1.0, 1.0 / s])
    dk = d_inv @ k_s @ d_inv - k_s
    gn = g[:, :, 1:]
    corr = gn @ np.linalg.solve(np.eye(2) + dk @ g[:, 1:, 1:], dk @ g[:, 1:, :])
    return (g - corr)[:, 0, 0]


# ---------------------------------------------------------------------------------- trials
def measure(h: np.ndarray, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """Noisy measurement of ``h`` and the coherence it implies (module docstring)."""
    sigma = np.sqrt((NOISE_REL * np.abs(h)) ** 2 + (10 ** (NOISE_FLOOR_DB / 20) * np.abs(h).max()) ** 2)
    noisy = h + sigma * (rng.standard_normal(h.size) + 1j * rng.standard_normal(h.size))
    coherence = 1.0 / (1.0 + 2 * N_AVERAGES * (sigma / np.abs(h)) ** 2)
    return noisy, coherence


@dataclass
class Trial:
    """One withheld-effect trial."""

    effect: str
    params: dict[str, float]
    request: dict[str, Any]
    clean: list[np.ndarray]        # truth with the effect, no noise, per measurement
    clean_null: list[np.ndarray]   # the same truth without the effect (SNR reference)
    nuisance: Nuisance = field(repr=False, default=None)  # type: ignore[assignment]


def make_trial(rng: np.random.Generator, effect: str, *, stickouts_m: Sequence[float] = STICKOUTS_M,
               frequency_hz: np.ndarray = FREQUENCY_HZ, tolerance_scale: float = 1.0,
               with_null: bool = True, options: dict | None = None) -> Trial:
    """Draw nuisance, effect and noise; return the diagnosis request and the clean truths."""
    nz = draw_nuisance(rng, len(stickouts_m), tolerance_scale)
    params = draw_effect(rng, effect)
    theory = "euler_bernoulli" if effect == "shear_and_rotary_inertia" else "timoshenko"
    base = base_document(theory)
    docs = config_documents(base_document(), nz, stickouts_m)
    clean = [effect_frf(effect, params, d, frequency_hz) for d in docs]
    if effect == "none":
        null = clean
    elif effect == "shear_and_rotary_inertia":
        null = [_solve(dict(d, beam_theory="euler_bernoulli"), frequency_hz) for d in docs] if with_null else []
    else:
        null = [effect_frf("none", {}, d, frequency_hz) for d in docs] if with_null else []
    measurements = []
    for stickout, h in zip(stickouts_m, clean, strict=True):
        noisy, coherence = measure(h, rng)
        measurements.append({"tool": {"stickout_m": stickout}, "frequency_hz": frequency_hz.tolist(),
                             "h": {"real": noisy.real.tolist(), "imag": noisy.imag.tolist()},
                             "coherence": coherence.tolist(), "n_averages": N_AVERAGES,
                             "label": f"{stickout * 1e3:.0f} mm"})
    request = {"assembly": base, "measurements": measurements}
    if options:
        request["options"] = options
    return Trial(effect, params, request, clean, null, nz)
