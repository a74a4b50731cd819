"""The catalogue of candidate unmodelled effects: bounded add-ons to the base model.

Each candidate has one or two physically bounded parameters with a uniform prior, a null
value at which the model *is* the base model, and a pure ``apply(knobs, values) -> knobs``.
Parameters are shared by all measurements (a joint stiffness does not change with the
stickout). Bounds follow ``docs/diagnosis.md`` §2:

================================  =========================================  ==============
effect                            parameters (prior range)                   null
================================  =========================================  ==============
holder_tool_joint                 log10 k_t/k_t0, log10 k_r/k_r0 ∈ [lo, 0.5]  0, 0
                                  (point joint; lo = min(−2, a decade below
                                  the shank's own stiffness over one
                                  diameter: :func:`shank_joint_reference`);
                                  on a clamping (bonded/contact): log10 of
                                  the interface stiffness scale ∈ [−3, 0.5]
spindle_holder_joint              log10 k_t/k_t0, log10 k_r/k_r0 ∈ [−2, 0.5]  0, 0
bearings                          log10 of all bearing stiffnesses, [−1, 0.5]  0
shear_and_rotary_inertia          shear/rotary-inertia scale s ∈ [0, 1.5]     0 (EB) / 1
fluted_section                    D_I/DC, D_A/DC ∈ [0.6, 1.0]                 base ratios
insertion_depth                   clamping point δ inside the holder,         0
                                  [0, 0.3 · inserted length]; on a clamping
                                  contact lost over δ at the front of the
                                  bore, [0, 0.6 · inserted length]
sensor_mass                       mass m ∈ [0, m_max], d ∈ [0, 6 mm] behind   0, 0
                                  the tip
joint_damping                     log10 scale of all joint dampers, [−1, 1.2]  0
                                  (on a clamping also a loss factor added
                                  to its interface, [0, 0.3])                  (0, 0)
spindle_rotational_receptance     residual compliance added to the spindle's   0, 0
                                  nose receptance: c_wψ = a·l₀, c_ψψ = b·p₀
                                  (l₀, p₀ its own static values),
                                  a ∈ [−0.5, 1.5], b ∈ [−0.5, 4]
================================  =========================================  ==============

**Model form** (an extension of the contract's effects; ``docs/diagnosis.md`` §4.9): two more
candidates change the form of the base's holder–tool model instead of adding to it —

================================  =========================================  ==============
clamping_model                    every form the base lacks: ``point``        the base's
                                  (rigid joint, no parameter), ``bonded``     form
                                  (none), ``contact`` (log10 k_n ∈ [11, 15]
                                  N/m³); evidence: the mean over the forms
interface_scale                   a clamping's interface per length,          0, 0
                                  log10 of translation and of rotation
                                  factors ∈ [−2, 1] (clamping bases)
================================  =========================================  ==============

``m_max`` is 1.5 × the largest declared ``sensor_mass_kg`` of the measurements, or 20 g.
Speed-dependent effects are listed in :data:`NOT_OBSERVABLE_AT_STANDSTILL`; they are never
candidates for a standstill tap test.

On a **measured spindle** (hybrid, ``docs/physics.md`` §4) the catalogue changes where the
physics does (:func:`not_applicable` gives each excluded effect its reason):

* ``bearings`` is not applicable: the bearings are inside the measured receptance;
* ``spindle_holder_joint`` is not applicable on a ``holder_tip`` measurement (the joint is
  inside it), and so is the holder's part of ``insertion_depth`` (only the tool's free
  length grows);
* ``spindle_rotational_receptance`` acts on the measured receptance at its plane. For a
  ``direct_frf`` spindle, whose rotations are an equivalent-cantilever estimate of length L
  (:func:`rcsa.measured.hybrid.cantilever_rotations`), its parameter is the effective length
  ``L·2^u``, u ∈ [−2, 2] (l, n scale as 1/L, p as 1/L²); for a ``point_receptance`` or
  ``artifact_frfs`` spindle it is the residual compliance above with l₀, p₀ read from the
  measurement at its lowest analysis line, a ∈ [−0.6, 1.5], b ∈ [−0.8, 4] (a measured
  rotation may be too large as well as too small).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING

import numpy as np

from rcsa.analysis.diagnosis.perturbed_model import (
    RIGID_POINT,
    Knobs,
    Solver,
    config_parts,
    null_shear_scale,
)
from rcsa.model.contract import AssemblySpec, ClampingSpec, JointSpec, ToolSpec
from rcsa.physics.algebra2x2 import inv2

if TYPE_CHECKING:  # types only: the measured spindle's module loads with a measured spindle
    from rcsa.model.spindle_side import MeasuredBase

__all__ = ["CANDIDATE_NAMES", "EFFECT_NAMES", "MODEL_FORM_NAMES", "NOT_OBSERVABLE_AT_STANDSTILL",
           "STANDSTILL_SENTENCE", "Candidate", "Parameter", "catalogue", "model_form_of", "not_applicable",
           "shank_joint_reference"]

EFFECT_NAMES = ("holder_tool_joint", "spindle_holder_joint", "bearings", "shear_and_rotary_inertia",
                "fluted_section", "insertion_depth", "sensor_mass", "joint_damping",
                "spindle_rotational_receptance")
#: Model-form candidates (an extension of the contract's effects): another form of the base's
#: holder–tool model, not an effect inside it (module docstring, "Model form").
MODEL_FORM_NAMES = ("clamping_model", "interface_scale")
CANDIDATE_NAMES = EFFECT_NAMES + MODEL_FORM_NAMES
NOT_OBSERVABLE_AT_STANDSTILL = ("gyroscopic_coupling", "centrifugal_bearing_softening",
                                "centrifugal_taper_expansion")
STANDSTILL_SENTENCE = ("Speed-dependent effects (gyroscopic coupling, centrifugal softening of the bearings, "
                       "centrifugal expansion of the spindle taper) do not act in a standstill tap test; "
                       "these measurements carry no information about them, so none of them is blamed "
                       "or ruled out.")
DEFAULT_SENSOR_MASS_MAX_KG = 0.020
# An accelerometer glued near the tip has its centre a few mm behind it (6 mm: half a 12 mm cube).
SENSOR_DISTANCE_MAX_M = 0.006


@dataclass(frozen=True, slots=True)
class Parameter:
    """One bounded effect parameter with a uniform prior on ``[lo, hi]``."""

    name: str
    lo: float
    hi: float
    null: float
    unit: str


@dataclass(frozen=True)
class Candidate:
    """A candidate effect: name, parameters and the add-on it makes to the base model.

    A model-form candidate (``model_form``) proposes another form of the holder–tool model;
    ``variant`` names the form it proposes (``point``, ``bonded``, ``contact``), and
    ``forms`` holds the alternatives of a candidate that chooses among several (its evidence
    is their average: :func:`rcsa.analysis.diagnosis.attribution.fit_candidate`).
    """

    name: str
    parameters: tuple[Parameter, ...]
    apply: Callable[[Knobs, np.ndarray], Knobs]
    meaning: Callable[[np.ndarray], dict[str, float]]
    variant: str = ""
    model_form: bool = False
    forms: tuple[Candidate, ...] = ()

    @property
    def key(self) -> str:
        """Name and variant: what the model's features are cached under."""
        return f"{self.name}:{self.variant}" if self.variant else self.name

    @property
    def null(self) -> np.ndarray:
        """Parameter values that reproduce the base model."""
        return np.array([p.null for p in self.parameters])

    @property
    def lo(self) -> np.ndarray:
        """Lower bounds."""
        return np.array([p.lo for p in self.parameters])

    @property
    def hi(self) -> np.ndarray:
        """Upper bounds."""
        return np.array([p.hi for p in self.parameters])


#: How far a point joint's prior reaches below a stiff given joint: a decade below the
#: shank's own stiffness over one shank diameter (:func:`shank_joint_reference`), or 1/100 of
#: the given joint, whichever is softer.
JOINT_REACH_BELOW_SHANK = 1.0
JOINT_MIN_DECADES = 2.0
#: insertion_depth on a point joint: the clamping point up to this fraction of the shortest
#: insertion inside the holder; on a clamping, the contact lost at the front up to this one.
CLAMPING_POINT_MAX_FRACTION = 0.3
FRONT_GAP_MAX_FRACTION = 0.6
#: Largest loss factor joint_damping adds to a clamping's interface (micro-slip damping of
#: shrink-fit and collet clamps: a few percent to tens of percent).
INTERFACE_LOSS_MAX = 0.3
#: log10 of a ``contact`` clamping's normal interface stiffness per area (N/m³) that
#: ``clamping_model`` may propose: from a compliant sleeve (1e11) to a layer too stiff to
#: tell from ``bonded`` (1e15: the 3-D reference's layer of 1e15 N/m³ is within 0.2 dB of bonded).
CONTACT_LOG10_N_M3 = (11.0, 15.0)
#: log10 of ``interface_scale``'s factors on a clamping's translational and rotational
#: interface stiffness per length.
INTERFACE_SCALE_LOG10 = (-2.0, 1.0)


def shank_joint_reference(spec: AssemblySpec, tools: Sequence[ToolSpec]) -> tuple[float, float]:
    """Stiffnesses of one shank diameter of the tool's own shank, as a cantilever: ``(3EI/d³, EI/d)``.

    A real clamping's compliance is of the order of the shank's over a diameter or so (the
    tool pivots inside the bore); a prior that stops at 1/100 of a stiff given joint cannot
    reach it (issue 24). N/m, N·m/rad; the thinnest shank of the measurements.

    Parameters
    ----------
    spec : AssemblySpec
    tools : sequence of ToolSpec

    Returns
    -------
    (float, float)
    """
    d = min(t.shank_diameter_m for t in tools)
    e = spec.materials[spec.tool.material].youngs_modulus_pa
    ei = e * np.pi * d**4 / 64.0
    return 3.0 * ei / d**3, ei / d


def _joint_lower_bound(given: float, reference: float) -> float:
    """log10 of the softest scale: 1/100 of the given joint, or a decade below the shank's reference."""
    return float(min(-JOINT_MIN_DECADES, np.log10(reference / given) - JOINT_REACH_BELOW_SHANK))


def _mul(k: Knobs, **scales: float) -> Knobs:
    return replace(k, **{name: getattr(k, name) * s for name, s in scales.items()})


def _static_nose_rotational_receptance(spec: AssemblySpec, solver: Solver) -> tuple[float, float]:
    """The spindle's own ``l`` (rad/N) and ``p`` (rad/(N·m)) at the nose, at the lowest analysis line."""
    k = solver.nose_stiffness(config_parts(spec, spec.tool, Knobs()))
    r = inv2(k[:1])[0].real
    return float(r[0, 1]), float(r[1, 1])


def _rotational_candidate(spec: AssemblySpec, solver: Solver, measured: MeasuredBase | None) -> Candidate:
    """``spindle_rotational_receptance``: effective length of estimated rotations, else a residual compliance."""
    name = "spindle_rotational_receptance"
    if measured is not None and measured.effective_length_m is not None:
        length = measured.effective_length_m
        return Candidate(
            name, (Parameter("log2_effective_length_scale", -2.0, 2.0, 0.0, "1"),),
            lambda k, v: replace(k, base_rotation_scale=k.base_rotation_scale * float(2.0 ** -v[0])),
            lambda v: {"effective_length_m": length * float(2.0 ** v[0]), "estimate_effective_length_m": length})
    if measured is None:
        l0, p0 = _static_nose_rotational_receptance(spec, solver)
        a_lo, b_lo = -0.5, -0.5
    else:
        r = measured.receptance[0].real
        l0, p0 = float(0.5 * (r[0, 1] + r[1, 0])), float(r[1, 1])
        a_lo, b_lo = -0.6, -0.8
    return Candidate(
        name,
        (Parameter("cross_residual_over_static_l", a_lo, 1.5, 0.0, "1"),
         Parameter("rotational_residual_over_static_p", b_lo, 4.0, 0.0, "1")),
        lambda k, v: replace(k, nose_cross_compliance_rad_n=float(v[0]) * l0,
                             nose_rotational_residual_rad_nm=float(v[1]) * p0),
        lambda v: {"added_cross_compliance_rad_n": float(v[0]) * l0,
                   "added_rotational_compliance_rad_nm": float(v[1]) * p0,
                   "spindle_static_l_rad_n": l0, "spindle_static_p_rad_nm": p0})


def not_applicable(spec: AssemblySpec, tools: Sequence[ToolSpec], measured: MeasuredBase | None = None
                   ) -> dict[str, tuple[str, bool]]:
    """Effects that are no candidate for this base model, with the reason.

    Parameters
    ----------
    spec : AssemblySpec
    tools : sequence of ToolSpec
        The measurements' tools.
    measured : MeasuredBase, optional
        The measured spindle (hybrid).

    Returns
    -------
    dict
        ``{effect: (reason, cannot_exist)}``; ``cannot_exist`` is True when the effect cannot
        exist for this spindle at all (asking for it is refused), False when only the base
        model leaves it out (e.g. a rigid joint, which a finite stiffness would make testable).
    """
    out: dict[str, tuple[str, bool]] = {}
    plane = None if measured is None else measured.plane
    if measured is not None:
        out["bearings"] = ("the spindle is measured: its bearings are inside the measured receptance, so no bearing "
                           "deviation can be added to it (nor blamed on a stand-in)", True)
    if plane == "holder_tip":
        out["spindle_holder_joint"] = ("the spindle was measured at the holder tip: the spindle-holder joint is inside "
                                       "the measurement", True)
    ht, sh = spec.holder_tool, spec.spindle_holder
    if ht is None or (isinstance(ht, JointSpec) and ht.rotational_stiffness_nm_rad is None):
        out["holder_tool_joint"] = ("the base model's holder-tool joint (or its rotational stiffness) is rigid; give "
                                    "finite stiffnesses to test it" + (" (at a holder_tip plane the clamping of the "
                                                                       "measured artifact is inside the measurement)"
                                                                       if plane == "holder_tip" else ""), False)
    if sh is None and "spindle_holder_joint" not in out:
        out["spindle_holder_joint"] = ("the base model's spindle-holder joint is rigid; give finite stiffnesses to "
                                       "test it", False)
    if plane == "holder_tip" and ht is None:
        out["joint_damping"] = ("no joint is modelled (the spindle was measured at the holder tip and the holder-tool "
                                "joint is rigid)", False)
    holder_len = spec.holder.length_m if spec.holder is not None else float("inf")
    if min(min(t.inserted_length_m for t in tools), holder_len) <= 0.0:
        out["insertion_depth"] = ("no tool shank is inserted in the holder", False)
        out["clamping_model"] = ("no tool shank is inserted in the holder: there is no clamping along an insertion",
                                 False)
    if plane == "holder_tip":
        out["clamping_model"] = ("the spindle was measured at the holder tip: the holder and the tool's clamping in "
                                 "it are not modelled", True)
    if "clamping_model" in out or not isinstance(ht, ClampingSpec):
        out["interface_scale"] = out.get("clamping_model", (
            "the base model's holder-tool joint is a point joint: there is no clamping interface to scale "
            "(clamping_model proposes a clamping instead)", False))
    return out


def model_form_of(joint: JointSpec | ClampingSpec | None) -> str:
    """The model form of a holder–tool joint: ``point``, ``bonded`` or ``contact``.

    Parameters
    ----------
    joint : JointSpec, ClampingSpec or None

    Returns
    -------
    str
    """
    return joint.model if isinstance(joint, ClampingSpec) else "point"


def _clamping_form(name: str, form: ClampingSpec | str, params: tuple[Parameter, ...],
                   make: Callable[[np.ndarray], ClampingSpec | str],
                   meaning: Callable[[np.ndarray], dict[str, float]]) -> Candidate:
    return Candidate(name, params, lambda k, v: replace(k, ht_form=make(v)), meaning,
                     variant=form if isinstance(form, str) else form.model, model_form=True)


def _model_form_candidates(spec: AssemblySpec, excluded: dict[str, tuple[str, bool]]) -> list[Candidate]:
    """``clamping_model`` (the other forms of the holder–tool model) and ``interface_scale``.

    ``clamping_model`` offers every form the base does not have: ``point`` (the contract's
    point model, composite insertion and a rigid joint at the face), ``bonded`` (the
    clamping as calibrated, no parameter) and ``contact`` (the same with an interface layer
    of stiffness ``k_n`` per area in series, log10 k_n ∈ :data:`CONTACT_LOG10_N_M3`). A
    clamping base keeps its front gap, contact length and loss factor in the other clamping
    form. ``interface_scale`` (a clamping base) scales the interface's translational and
    rotational stiffness per length separately, log10 each ∈ :data:`INTERFACE_SCALE_LOG10`:
    how the interface is distributed between the two, which one common factor
    (``holder_tool_joint``) cannot change.
    """
    out: list[Candidate] = []
    ht = spec.holder_tool
    base = model_form_of(ht)
    keep = ht if isinstance(ht, ClampingSpec) else ClampingSpec("bonded")
    if "clamping_model" not in excluded:
        forms: list[Candidate] = []
        if base != "bonded":
            bonded = replace(keep, model="bonded", interface_stiffness_n_m3=None, interface_tangential_ratio=1.0,
                             contact_pressure_pa=None, surface_roughness_m=None)
            forms.append(_clamping_form("clamping_model", bonded, (), lambda v: bonded, lambda v: {}))
        if base != "contact":
            def contact(v: np.ndarray) -> ClampingSpec:
                return replace(keep, model="contact", interface_stiffness_n_m3=float(10 ** v[0]),
                               contact_pressure_pa=None, surface_roughness_m=None)
            forms.append(_clamping_form(
                "clamping_model", "contact",
                (Parameter("log10_interface_stiffness_n_m3", *CONTACT_LOG10_N_M3, CONTACT_LOG10_N_M3[1], "1"),),
                contact, lambda v: {"holder_tool.interface_stiffness_n_m3": float(10 ** v[0])}))
        if base != "point":
            forms.append(replace(_clamping_form("clamping_model", RIGID_POINT, (), lambda v: RIGID_POINT,
                                                lambda v: {}), variant="point"))
        out.append(Candidate("clamping_model", (), lambda k, v: k, lambda v: {}, model_form=True, forms=tuple(forms)))
    if "interface_scale" not in excluded and isinstance(ht, ClampingSpec):
        scale0 = ht.interface_stiffness_scale
        out.append(Candidate(
            "interface_scale",
            (Parameter("log10_translational_interface_scale", *INTERFACE_SCALE_LOG10, 0.0, "1"),
             Parameter("log10_rotational_interface_scale", *INTERFACE_SCALE_LOG10, 0.0, "1")),
            lambda k, v: replace(k, ht_translational_scale=k.ht_translational_scale * 10 ** v[0],
                                 ht_rotational_interface_scale=k.ht_rotational_interface_scale * 10 ** (v[1] - v[0])),
            lambda v: {"holder_tool.interface_stiffness_scale": scale0 * float(10 ** v[0]),
                       "rotational_interface_scale": float(10 ** v[1])},
            variant=base, model_form=True))
    return out


def catalogue(spec: AssemblySpec, tools: Sequence[ToolSpec], solver: Solver,
              sensor_mass_max_kg: float | None = None, names: Sequence[str] | None = None,
              measured: MeasuredBase | None = None) -> tuple[list[Candidate], list[str]]:
    """Candidates applicable to this base model, and notes on those left out.

    Parameters
    ----------
    spec : AssemblySpec
        Base assembly.
    tools : sequence of ToolSpec
        The measurements' tools (bounds of ``insertion_depth``).
    solver : Solver
        Used once for an analytical spindle's static nose compliance.
    sensor_mass_max_kg : float, optional
        Upper bound of ``sensor_mass``.
    names : sequence of str, optional
        Restrict the catalogue to these effects.
    measured : MeasuredBase, optional
        The measured spindle of a hybrid diagnosis (its plane, receptance and kind).

    Returns
    -------
    candidates : list of Candidate
    notes : list of str
        One per effect the base model leaves out (effects that cannot exist for a measured
        spindle are not noted here; see :func:`not_applicable`).
    """
    out: list[Candidate] = []
    excluded = not_applicable(spec, tools, measured)
    notes = [f"{name}: not a candidate because {reason}." for name, (reason, cannot) in excluded.items()
             if not cannot]
    ht, sh = spec.holder_tool, spec.spindle_holder

    if "holder_tool_joint" not in excluded and isinstance(ht, ClampingSpec):
        scale0 = ht.interface_stiffness_scale
        out.append(Candidate(  # interface softening over the whole insertion (a soft or worn clamp)
            "holder_tool_joint", (Parameter("log10_interface_stiffness_scale", -3.0, 0.5, 0.0, "1"),),
            lambda k, v: _mul(k, ht_translational_scale=10 ** v[0]),
            lambda v: {"holder_tool.interface_stiffness_scale": scale0 * 10 ** v[0]}))
    elif "holder_tool_joint" not in excluded and isinstance(ht, JointSpec) \
            and ht.rotational_stiffness_nm_rad is not None:
        kr0 = ht.rotational_stiffness_nm_rad
        kt_ref, kr_ref = shank_joint_reference(spec, tools)

        def ht_meaning(v: np.ndarray) -> dict[str, float]:
            assert ht is not None
            return {"holder_tool.stiffness_n_m": ht.stiffness_n_m * 10 ** v[0],
                    "holder_tool.rotational_stiffness_nm_rad": kr0 * 10 ** v[1]}
        out.append(Candidate(
            "holder_tool_joint",
            (Parameter("log10_translational_stiffness_scale", _joint_lower_bound(ht.stiffness_n_m, kt_ref), 0.5,
                       0.0, "1"),
             Parameter("log10_rotational_stiffness_scale", _joint_lower_bound(kr0, kr_ref), 0.5, 0.0, "1")),
            lambda k, v: _mul(k, ht_translational_scale=10 ** v[0], ht_rotational_scale=10 ** v[1]),
            ht_meaning))

    if "spindle_holder_joint" not in excluded and sh is not None:
        rot = sh.rotational_stiffness_nm_rad

        def sh_meaning(v: np.ndarray) -> dict[str, float]:
            assert sh is not None
            out_ = {"spindle_holder.stiffness_n_m": sh.stiffness_n_m * 10 ** v[0]}
            if rot is not None:
                out_["spindle_holder.rotational_stiffness_nm_rad"] = rot * 10 ** v[1]
            return out_
        params = [Parameter("log10_translational_stiffness_scale", -2.0, 0.5, 0.0, "1")]
        if rot is not None:
            params.append(Parameter("log10_rotational_stiffness_scale", -2.0, 0.5, 0.0, "1"))
        out.append(Candidate(
            "spindle_holder_joint", tuple(params),
            lambda k, v: _mul(k, sh_translational_scale=10 ** v[0],
                              sh_rotational_scale=10 ** v[-1] if v.size > 1 else 1.0),
            sh_meaning))

    if "bearings" not in excluded:
        out.append(Candidate(
            "bearings", (Parameter("log10_stiffness_scale", -1.0, 0.5, 0.0, "1"),),
            lambda k, v: _mul(k, bearing_stiffness_scale=10 ** v[0]),
            lambda v: {"bearing_stiffness_scale": float(10 ** v[0])}))

    s0 = null_shear_scale(spec)
    out.append(Candidate(
        "shear_and_rotary_inertia", (Parameter("shear_and_rotary_inertia_scale", 0.0, 1.5, s0, "1"),),
        lambda k, v: replace(k, shear_scale=float(v[0])),
        lambda v: {"shear_and_rotary_inertia_scale": float(v[0])}))

    r_i = spec.tool.fluted_diameter_ratio
    r_a = spec.tool.fluted_mass_diameter_ratio or r_i
    lo_r, hi_r = min(0.6, r_i, r_a), max(1.0, r_i, r_a)
    out.append(Candidate(
        "fluted_section",
        (Parameter("stiffness_diameter_ratio", lo_r, hi_r, r_i, "1"),
         Parameter("mass_diameter_ratio", lo_r, hi_r, r_a, "1")),
        lambda k, v: replace(k, fluted_stiffness_ratio=float(v[0]), fluted_mass_ratio=float(v[1])),
        lambda v: {"fluted_diameter_ratio": float(v[0]), "fluted_mass_diameter_ratio": float(v[1])}))

    if "insertion_depth" not in excluded:
        holder_len = spec.holder.length_m if spec.holder is not None else float("inf")
        inserted = min(min(t.inserted_length_m for t in tools), holder_len)
        # a clamping loses contact at the front: up to 0.6 of the shortest insertion (the rest still grips)
        reach = (FRONT_GAP_MAX_FRACTION if isinstance(ht, ClampingSpec) else CLAMPING_POINT_MAX_FRACTION) * inserted
        out.append(Candidate(
            "insertion_depth", (Parameter("clamping_point_inside_holder_m", 0.0, reach, 0.0, "m"),),
            lambda k, v: replace(k, insertion_offset_m=float(v[0])),
            (lambda v: {"front_gap_length_m": float(v[0])}) if isinstance(ht, ClampingSpec)
            else (lambda v: {"clamping_point_inside_holder_m": float(v[0])})))

    m_max = DEFAULT_SENSOR_MASS_MAX_KG if sensor_mass_max_kg is None else sensor_mass_max_kg
    out.append(Candidate(
        "sensor_mass", (Parameter("tip_mass_kg", 0.0, m_max, 0.0, "kg"),
                        Parameter("distance_from_tip_m", 0.0, SENSOR_DISTANCE_MAX_M, 0.0, "m")),
        lambda k, v: replace(k, tip_mass_kg=float(v[0]), tip_mass_distance_m=float(v[1])),
        lambda v: {"tip_mass_kg": float(v[0]), "distance_from_tip_m": float(v[1])}))

    if "joint_damping" not in excluded and isinstance(ht, ClampingSpec) and spec.holder is not None:
        # a clamping's own loss (micro-slip over the insertion) is a loss factor added to its
        # interface; the point joints' dampers scale as for point joints
        out.append(Candidate(
            "joint_damping", (Parameter("log10_joint_damping_scale", -1.0, 1.2, 0.0, "1"),
                              Parameter("added_interface_loss_factor", 0.0, INTERFACE_LOSS_MAX, 0.0, "1")),
            lambda k, v: replace(_mul(k, sh_damping_scale=10 ** v[0], ht_damping_scale=10 ** v[0]),
                                 ht_interface_loss_added=float(v[1])),
            lambda v: {"joint_damping_scale": float(10 ** v[0]),
                       "holder_tool.interface_loss_factor": ht.interface_loss_factor * float(10 ** v[0])
                       + float(v[1])}))
    elif "joint_damping" not in excluded:
        out.append(Candidate(
            "joint_damping", (Parameter("log10_joint_damping_scale", -1.0, 1.2, 0.0, "1"),),
            lambda k, v: _mul(k, sh_damping_scale=10 ** v[0], ht_damping_scale=10 ** v[0]),
            lambda v: {"joint_damping_scale": float(10 ** v[0])}))

    out.append(_rotational_candidate(spec, solver, measured))
    out.extend(_model_form_candidates(spec, excluded))

    if names is not None:
        out = [c for c in out if c.name in names]
    return out, notes
