"""Finite-element model of a spindle-holder-tool assembly given as a contract dict.

Parses the assembly JSON of ``docs/contract.md`` itself (no code shared with ``rcsa``) and builds a
:class:`~tests.oracles.timoshenko_fe.BeamModel`. Geometry, with x = 0 at the gauge line
(spindle nose face) and x growing toward the tool tip (``docs/physics.md`` §2.1):

* spindle segments listed nose -> rear occupy ``[-L_spindle, 0]``; bearings at
  ``x = -position_m`` are spring-dampers to ground (translational, and rotational if given);
* holder segments listed from the gauge line occupy ``[0, L_holder]``;
* the tool overhang occupies ``[L_holder, L_holder + stickout]``: a shank piece of length
  ``stickout - flute_length`` at the shank diameter, then the fluted piece at
  ``fluted_diameter_ratio * diameter`` (default 0.8; if ``flute_length > stickout`` the whole
  overhang is fluted). The inserted length ``OAL - stickout`` (capped at ``L_holder``) fills
  the holder bore from the holder's tool end: there each holder section is the composite of
  the annulus and a solid tool core of the shank diameter;
* joints ``spindle_holder`` and ``holder_tool`` are two-node springs
  ``diag(k_t + i omega c_t, k_r + i omega c_r)``; a joint left out, or a stiffness left
  out, is rigid (the DOF is shared).

Physical "effects" for the withheld-effect benchmark (``docs/diagnosis.md`` §2, §5) are switched
on by the ``effects`` mapping; every key is optional:

``"beam_theory"``: ``{"spindle" | "holder" | "tool": "timoshenko" | "euler_bernoulli"}``
    per-component override of the assembly's ``beam_theory``.
``"tip_mass"``: ``{"mass_kg", "rotary_inertia_kg_m2": 0, "distance_from_tip_m": 0, "offset_m": 0}``
    a rigid sensor on the tool node at ``distance_from_tip_m`` from the tip, its centre a
    further ``offset_m`` along +x (rigid lever).
``"holder_tool_distributed"``: ``{"translational_stiffness_n_m2", "translational_damping_ns_m2": 0,
    "rotational_stiffness_nm_rad_m": 0, "rotational_damping_nms_rad_m": 0, "loss_factor": 0}``
    the inserted tool core becomes a separate beam (part of the tool) joined to the holder
    annulus by springs per unit length over the insertion; the holder sections there are the
    bare annulus, and ``joints.holder_tool`` is not used.
``"spindle_holder_distributed"``: ``{"shank_segments": [{"length_m", "outer_diameter_m",
    "inner_diameter_m", "material"}], "contact_length_m", "translational_stiffness_n_m2", ...}``
    (same spring keys as above) a holder taper-shank beam, listed from the gauge line toward
    the rear, hangs from the holder base and is joined to the spindle by distributed springs
    over ``contact_length_m`` (default: the whole shank) from the gauge line; the spindle
    segments are used as given (hollow the nose in the dict if the shank displaces material),
    and ``joints.spindle_holder`` is not used.
``"fluted_section"``: ``{"area_m2", "second_moment_m4"}``
    the fluted piece gets this area (mass) and second moment (stiffness, rotary inertia),
    with the solid-circle shear coefficient, instead of the diameter ratio.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import scipy.linalg

from .timoshenko_fe import (
    BEAM_THEORIES,
    BeamModel,
    Section,
    circular_section,
    cowper_shear_coefficient,
    harmonic_receptance,
    hutchinson_shear_coefficient,
    solid_circle_section_properties,
    undamped_natural_frequencies_hz,
)

__all__ = [
    "BUILTIN_MATERIALS",
    "DEFAULT_MAX_ELEMENT_LENGTH_M",
    "EFFECT_KEYS",
    "AssemblyModel",
    "build_assembly_model",
    "frequency_grid_hz",
    "natural_frequencies_hz",
    "receptance_at",
    "static_tool_point_compliance_m_n",
    "tool_point_receptance",
]

DEFAULT_MAX_ELEMENT_LENGTH_M = 0.002
BUILTIN_MATERIALS: dict[str, dict[str, float]] = {
    "steel": {"youngs_modulus_pa": 210e9, "poisson_ratio": 0.30, "density_kg_m3": 7850.0,
              "loss_factor": 0.002},
    "carbide": {"youngs_modulus_pa": 600e9, "poisson_ratio": 0.22, "density_kg_m3": 14500.0,
                "loss_factor": 0.002},
}
EFFECT_KEYS = ("beam_theory", "tip_mass", "holder_tool_distributed",
               "spindle_holder_distributed", "fluted_section")
_COMPONENTS = ("spindle", "holder", "tool")
_DISTRIBUTED_KEYS = {"translational_stiffness_n_m2", "translational_damping_ns_m2",
                     "rotational_stiffness_nm_rad_m", "rotational_damping_nms_rad_m", "loss_factor"}
_X_TOL_M = 1e-9


# ---------------------------------------------------------------------------------------
# Parsing helpers
# ---------------------------------------------------------------------------------------


def _get(mapping: Mapping[str, Any], key: str, where: str) -> Any:
    if key not in mapping:
        raise ValueError(f"{where}: missing field {key!r}")
    return mapping[key]


def _check_keys(mapping: Mapping[str, Any], allowed: set[str], where: str) -> None:
    unknown = set(mapping) - allowed
    if unknown:
        raise ValueError(f"{where}: unknown field(s) {sorted(unknown)}; allowed {sorted(allowed)}")


def frequency_grid_hz(assembly: Mapping[str, Any]) -> np.ndarray:
    """Frequency lines of ``assembly["frequency"]`` (start/stop/step with stop included, or values).

    Returns
    -------
    numpy.ndarray, shape (nfreq,)
    """
    spec = _get(assembly, "frequency", "assembly")
    if "values_hz" in spec:
        values = np.asarray(spec["values_hz"], dtype=float)
    else:
        start, stop, step = (float(_get(spec, k, "frequency")) for k in ("start_hz", "stop_hz", "step_hz"))
        if step <= 0 or stop < start:
            raise ValueError("frequency: need step_hz > 0 and stop_hz >= start_hz")
        count = int(math.floor((stop - start) / step + 1e-9)) + 1
        values = start + step * np.arange(count)
    if values.ndim != 1 or values.size == 0 or np.any(values <= 0):
        raise ValueError("frequency: all values must be > 0 Hz (0 Hz is singular)")
    return values


@dataclass(frozen=True)
class _Material:
    youngs_modulus_pa: float
    poisson_ratio: float
    density_kg_m3: float
    loss_factor: float


def _materials(assembly: Mapping[str, Any]) -> dict[str, _Material]:
    table = {name: dict(values) for name, values in BUILTIN_MATERIALS.items()}
    for name, values in assembly.get("materials", {}).items():
        table[name] = {**table.get(name, {}), **values}
    out = {}
    for name, values in table.items():
        fields = ("youngs_modulus_pa", "poisson_ratio", "density_kg_m3")
        out[name] = _Material(*(float(_get(values, f, f"materials.{name}")) for f in fields),
                              float(values.get("loss_factor", 0.0)))
    return out


class _SectionFactory:
    """Builds sections from materials, the shear-coefficient rule and the damping switch."""

    def __init__(self, assembly: Mapping[str, Any], damped: bool) -> None:
        self.materials = _materials(assembly)
        self.rule = assembly.get("shear_coefficient", "hutchinson")
        if not isinstance(self.rule, int | float) and self.rule not in ("hutchinson", "cowper"):
            raise ValueError(f"shear_coefficient must be 'hutchinson', 'cowper' or a number, got {self.rule!r}")
        self.damped = damped

    def material(self, name: str) -> _Material:
        if name not in self.materials:
            raise ValueError(f"unknown material {name!r}; known: {sorted(self.materials)}")
        return self.materials[name]

    def kappa(self, poisson_ratio: float, diameter_ratio: float) -> float:
        if self.rule == "hutchinson":
            return hutchinson_shear_coefficient(poisson_ratio, diameter_ratio)
        if self.rule == "cowper":
            return cowper_shear_coefficient(poisson_ratio, diameter_ratio)
        return float(self.rule)

    def custom(self, material: str, area_m2: float, second_moment_m4: float,
               diameter_ratio: float = 0.0) -> Section:
        mat = self.material(material)
        return circular_section(
            mat.youngs_modulus_pa, mat.poisson_ratio, mat.density_kg_m3, area_m2=area_m2,
            second_moment_m4=second_moment_m4,
            shear_coefficient=self.kappa(mat.poisson_ratio, diameter_ratio),
            loss_factor=mat.loss_factor if self.damped else 0.0)

    def tube(self, material: str, outer_diameter_m: float, inner_diameter_m: float = 0.0) -> Section:
        if not 0.0 <= inner_diameter_m < outer_diameter_m:
            raise ValueError(f"need 0 <= inner < outer diameter, got {inner_diameter_m}, {outer_diameter_m}")
        area, second_moment = solid_circle_section_properties(outer_diameter_m, inner_diameter_m)
        return self.custom(material, area, second_moment, inner_diameter_m / outer_diameter_m)


# ---------------------------------------------------------------------------------------
# Geometry: components as lists of pieces (x_start, x_end, section, theory)
# ---------------------------------------------------------------------------------------


@dataclass(frozen=True)
class _Piece:
    x_start_m: float
    x_end_m: float
    section: Section
    theory: str


def _segment_pieces(segments: Sequence[Mapping[str, Any]], x0_m: float, direction: int,
                    section_of, where: str) -> list[_Piece]:
    """Pieces of a segment list starting at ``x0_m`` and running toward ``direction`` (+1/-1)."""
    pieces, x = [], x0_m
    for i, seg in enumerate(segments):
        length = float(_get(seg, "length_m", f"{where}[{i}]"))
        if length <= 0:
            raise ValueError(f"{where}[{i}].length_m must be > 0")
        x_next = x + direction * length
        pieces.append((min(x, x_next), max(x, x_next), seg))
        x = x_next
    return [_Piece(a, b, *section_of(seg, a, b)) for a, b, seg in sorted(pieces, key=lambda p: p[0])]


def _split(pieces: list[_Piece], x_m: float) -> list[_Piece]:
    out = []
    for p in pieces:
        if p.x_start_m + _X_TOL_M < x_m < p.x_end_m - _X_TOL_M:
            out += [_Piece(p.x_start_m, x_m, p.section, p.theory), _Piece(x_m, p.x_end_m, p.section, p.theory)]
        else:
            out.append(p)
    return out


def _mesh(model: BeamModel, pieces: list[_Piece], breakpoints: Sequence[float], h_max_m: float,
          *, start_node: int | None = None, end_node: int | None = None) -> tuple[list[int], np.ndarray]:
    """Mesh contiguous pieces (ascending x) into equal elements <= ``h_max_m`` per interval.

    Intervals are bounded by the piece ends and the given breakpoints, so two beams meshed
    with the same breakpoints over an x range get nodes at identical positions there.
    """
    for x in breakpoints:
        pieces = _split(pieces, x)
    node = model.add_node(pieces[0].x_start_m) if start_node is None else start_node
    nodes = [node]
    for i, p in enumerate(pieces):
        length = p.x_end_m - p.x_start_m
        n_el = max(1, math.ceil(length / h_max_m - 1e-9))
        last = end_node if (end_node is not None and i == len(pieces) - 1) else None
        nodes += model.add_beam(nodes[-1], length, p.section, p.theory, n_elements=n_el, end_node=last)[1:]
    return nodes, np.array([model.node_x_m[n] for n in nodes])


def _nodes_between(nodes: list[int], xs: np.ndarray, a_m: float, b_m: float) -> list[int]:
    return [n for n, x in zip(nodes, xs, strict=True) if a_m - _X_TOL_M <= x <= b_m + _X_TOL_M]


def _node_at(nodes: list[int], xs: np.ndarray, x_m: float, where: str) -> int:
    hits = np.flatnonzero(np.abs(xs - x_m) <= 1e-7)
    if hits.size == 0:
        raise ValueError(f"no {where} node at x = {x_m:.6g} m")
    return nodes[int(hits[-1])]


def _connect(model: BeamModel, node_a: int, x_m: float, joint: Mapping[str, Any] | None,
             damped: bool) -> int:
    """New node at ``x_m`` joined to ``node_a`` by a joint (missing stiffness = rigid DOF)."""
    if joint is None:
        return node_a
    k_t, k_r = joint.get("stiffness_n_m"), joint.get("rotational_stiffness_nm_rad")
    if k_t is None and k_r is None:
        return node_a
    node_b = model.add_node(x_m, share_w_with=node_a if k_t is None else None,
                            share_psi_with=node_a if k_r is None else None)
    scale = 1.0 if damped else 0.0
    model.add_spring(node_a, node_b, translational_n_m=float(k_t or 0.0),
                     translational_ns_m=scale * float(joint.get("damping_ns_m", 0.0)),
                     rotational_nm_rad=float(k_r or 0.0),
                     rotational_nms_rad=scale * float(joint.get("rotational_damping_nms_rad", 0.0)))
    return node_b


def _distributed(model: BeamModel, nodes_a: list[int], nodes_b: list[int],
                 spec: Mapping[str, Any], damped: bool, where: str) -> None:
    _check_keys(spec, _DISTRIBUTED_KEYS | {"shank_segments", "contact_length_m"}, where)
    scale, eta = (1.0, float(spec.get("loss_factor", 0.0))) if damped else (0.0, 0.0)
    model.add_distributed_springs(
        nodes_a, nodes_b,
        translational_n_m2=float(_get(spec, "translational_stiffness_n_m2", where)) * (1 + 1j * eta),
        translational_ns_m2=scale * float(spec.get("translational_damping_ns_m2", 0.0)),
        rotational_nm_rad_m=float(spec.get("rotational_stiffness_nm_rad_m", 0.0)) * (1 + 1j * eta),
        rotational_nms_rad_m=scale * float(spec.get("rotational_damping_nms_rad_m", 0.0)))


@dataclass
class AssemblyModel:
    """An assembled FE model with the nodes needed to read receptances.

    Attributes
    ----------
    model : BeamModel
        The FE model.
    tip_node : int
        Tool-tip node.
    tip_x_m : float
        Tool-tip x (gauge line at x = 0).
    holder_length_m : float
        Holder length (the holder's tool-end face is at ``x = holder_length_m``).
    outer_nodes : dict
        Per component ``(nodes, x_m)`` of the beam one can touch from outside (spindle,
        holder annulus or composite, tool).
    """

    model: BeamModel
    tip_node: int
    tip_x_m: float
    holder_length_m: float
    outer_nodes: dict[str, tuple[list[int], np.ndarray]]

    def node_from_tip(self, distance_m: float) -> int:
        """Outer-surface node at ``distance_m`` from the tool tip toward the spindle.

        Points at or beyond the holder face belong to the tool, points inside the holder
        length to the holder, points behind the gauge line to the spindle.
        """
        x = self.tip_x_m - distance_m
        if x >= self.holder_length_m - _X_TOL_M:
            component = "tool"
        elif x >= -_X_TOL_M:
            component = "holder"
        else:
            component = "spindle"
        return _node_at(*self.outer_nodes[component], x, component)


def build_assembly_model(assembly: Mapping[str, Any], *, damped: bool = True,
                         effects: Mapping[str, Any] | None = None,
                         max_element_length_m: float = DEFAULT_MAX_ELEMENT_LENGTH_M,
                         points_from_tip_m: Sequence[float] = ()) -> AssemblyModel:
    """Build the FE model of a contract assembly dict.

    Parameters
    ----------
    assembly : mapping
        Assembly in the contract format (``docs/contract.md``, "Assembly").
    damped : bool
        False sets every loss factor and damper to zero (for natural frequencies).
    effects : mapping, optional
        Physical effects (see the module docstring).
    max_element_length_m : float
        Maximum element length; each interval between breakpoints is split into equal
        elements no longer than this.
    points_from_tip_m : sequence of float
        Extra mesh nodes at these distances from the tool tip (measurement points).

    Returns
    -------
    AssemblyModel
    """
    effects = dict(effects or {})
    _check_keys(effects, set(EFFECT_KEYS), "effects")
    factory = _SectionFactory(assembly, damped)
    theory = {c: assembly.get("beam_theory", "timoshenko") for c in _COMPONENTS}
    theory.update(effects.get("beam_theory", {}))
    if set(theory) != set(_COMPONENTS) or any(t not in BEAM_THEORIES for t in theory.values()):
        raise ValueError(f"beam theory per component must be one of {BEAM_THEORIES}: {theory}")
    model = BeamModel()
    joints = assembly.get("joints", {}) or {}

    # -- spindle --------------------------------------------------------------------
    spindle = _get(assembly, "spindle", "assembly")
    if "measurement_id" in spindle:
        raise ValueError("the FE oracle needs a modelled spindle (segments), not a measurement_id")
    spindle_pieces = _segment_pieces(
        _get(spindle, "segments", "spindle"), 0.0, -1,
        lambda s, a, b: (factory.tube(_get(s, "material", "spindle segment"), float(s["outer_diameter_m"]),
                                      float(s.get("inner_diameter_m", 0.0))), theory["spindle"]),
        "spindle.segments")
    spindle_length = -spindle_pieces[0].x_start_m
    bearings = spindle.get("bearings", [])
    bearing_x = [-float(_get(b, "position_m", "bearing")) for b in bearings]
    if any(not -spindle_length - _X_TOL_M <= x <= _X_TOL_M for x in bearing_x):
        raise ValueError("bearing position_m must lie within the spindle length")

    # -- holder and tool geometry -----------------------------------------------------
    holder_segments = _get(_get(assembly, "holder", "assembly"), "segments", "holder")
    tool = _get(assembly, "tool", "assembly")
    tool_material = _get(tool, "material", "tool")
    shank_d = float(_get(tool, "shank_diameter_m", "tool"))
    stickout = float(_get(tool, "stickout_m", "tool"))
    flute_length = float(_get(tool, "flute_length_m", "tool"))
    inserted = float(_get(tool, "overall_length_m", "tool")) - stickout
    ht_spec = effects.get("holder_tool_distributed")
    core = factory.tube(tool_material, shank_d)
    holder_pieces = _segment_pieces(
        holder_segments, 0.0, +1,
        lambda s, a, b: (factory.tube(_get(s, "material", "holder segment"), float(s["outer_diameter_m"]),
                                      float(s.get("inner_diameter_m", 0.0))), theory["holder"]),
        "holder.segments")
    holder_length = holder_pieces[-1].x_end_m
    insert_start = holder_length - min(max(inserted, 0.0), holder_length)
    holder_pieces = _split(holder_pieces, insert_start)
    if ht_spec is None:  # composite annulus + solid tool core over the insertion
        holder_pieces = [_Piece(p.x_start_m, p.x_end_m, p.section + core, p.theory)
                         if p.x_start_m >= insert_start - _X_TOL_M else p for p in holder_pieces]
    tip_x = holder_length + stickout
    fluted_length = min(flute_length, stickout)
    if "fluted_section" in effects:
        spec = effects["fluted_section"]
        _check_keys(spec, {"area_m2", "second_moment_m4"}, "effects.fluted_section")
        fluted = factory.custom(tool_material, float(_get(spec, "area_m2", "fluted_section")),
                                float(_get(spec, "second_moment_m4", "fluted_section")))
    else:
        fluted = factory.tube(tool_material, float(tool.get("fluted_diameter_ratio", 0.8))
                              * float(_get(tool, "diameter_m", "tool")))
    tool_pieces = [_Piece(holder_length, tip_x - fluted_length, factory.tube(tool_material, shank_d), theory["tool"]),
                   _Piece(tip_x - fluted_length, tip_x, fluted, theory["tool"])]
    tool_pieces = [p for p in tool_pieces if p.x_end_m - p.x_start_m > _X_TOL_M]
    if not tool_pieces:
        raise ValueError("tool stickout_m must be > 0")
    if ht_spec is not None:
        if inserted <= 0:
            raise ValueError("holder_tool_distributed needs an inserted length OAL - stickout > 0")
        tool_pieces = [_Piece(insert_start, holder_length, core, theory["tool"])] + tool_pieces

    # -- breakpoints shared by the components ------------------------------------------
    tip_spec = dict(effects.get("tip_mass", {}))
    _check_keys(tip_spec, {"mass_kg", "rotary_inertia_kg_m2", "distance_from_tip_m", "offset_m"}, "effects.tip_mass")
    extra_x = [tip_x - float(d) for d in points_from_tip_m]
    extra_x.append(tip_x - float(tip_spec.get("distance_from_tip_m", 0.0)))
    if any(x < -spindle_length - _X_TOL_M or x > tip_x + _X_TOL_M for x in extra_x):
        raise ValueError("points must lie between the spindle rear and the tool tip")
    ends = {p.x_start_m for p in spindle_pieces + holder_pieces + tool_pieces} | {tip_x}
    breakpoints = sorted(set(extra_x) | set(bearing_x) | ends | {insert_start})

    sh_spec = effects.get("spindle_holder_distributed")
    shank_pieces: list[_Piece] = []
    if sh_spec is not None:
        shank_pieces = _segment_pieces(
            _get(sh_spec, "shank_segments", "spindle_holder_distributed"), 0.0, -1,
            lambda s, a, b: (factory.tube(_get(s, "material", "shank segment"), float(s["outer_diameter_m"]),
                                          float(s.get("inner_diameter_m", 0.0))), theory["holder"]),
            "effects.spindle_holder_distributed.shank_segments")
        contact = float(sh_spec.get("contact_length_m", -shank_pieces[0].x_start_m))
        if not 0 < contact <= min(-shank_pieces[0].x_start_m, spindle_length) + _X_TOL_M:
            raise ValueError("contact_length_m must be > 0 and within the shank and spindle lengths")
        breakpoints = sorted(set(breakpoints) | {p.x_start_m for p in shank_pieces} | {-contact})

    # -- mesh and connect -------------------------------------------------------------
    h = max_element_length_m
    spindle_nodes, spindle_xs = _mesh(model, spindle_pieces, breakpoints, h)
    for b, x in zip(bearings, bearing_x, strict=True):
        scale = 1.0 if damped else 0.0
        model.add_spring(_node_at(spindle_nodes, spindle_xs, x, "spindle"), None,
                         translational_n_m=float(_get(b, "stiffness_n_m", "bearing")),
                         translational_ns_m=scale * float(b.get("damping_ns_m", 0.0)),
                         rotational_nm_rad=float(b.get("rotational_stiffness_nm_rad", 0.0)),
                         rotational_nms_rad=scale * float(b.get("rotational_damping_nms_rad", 0.0)))
    nose = spindle_nodes[-1]
    if sh_spec is None:
        holder_base = _connect(model, nose, 0.0, joints.get("spindle_holder"), damped)
    else:
        holder_base = model.add_node(0.0)
        shank_nodes, shank_xs = _mesh(model, shank_pieces, breakpoints, h, end_node=holder_base)
        _distributed(model, _nodes_between(spindle_nodes, spindle_xs, -contact, 0.0),
                     _nodes_between(shank_nodes, shank_xs, -contact, 0.0), sh_spec, damped,
                     "effects.spindle_holder_distributed")
    holder_nodes, holder_xs = _mesh(model, holder_pieces, breakpoints, h, start_node=holder_base)
    if ht_spec is None:
        tool_base = _connect(model, holder_nodes[-1], holder_length, joints.get("holder_tool"), damped)
        tool_nodes, tool_xs = _mesh(model, tool_pieces, breakpoints, h, start_node=tool_base)
    else:
        tool_nodes, tool_xs = _mesh(model, tool_pieces, breakpoints, h)
        _distributed(model, _nodes_between(holder_nodes, holder_xs, insert_start, holder_length),
                     _nodes_between(tool_nodes, tool_xs, insert_start, holder_length), ht_spec, damped,
                     "effects.holder_tool_distributed")
    result = AssemblyModel(model, tool_nodes[-1], tip_x, holder_length,
                           {"spindle": (spindle_nodes, spindle_xs), "holder": (holder_nodes, holder_xs),
                            "tool": (tool_nodes, tool_xs)})
    if tip_spec:
        node = _node_at(tool_nodes, tool_xs, extra_x[-1], "tool")
        model.add_lumped_mass(node, float(_get(tip_spec, "mass_kg", "effects.tip_mass")),
                              float(tip_spec.get("rotary_inertia_kg_m2", 0.0)),
                              float(tip_spec.get("offset_m", 0.0)))
    return result


# ---------------------------------------------------------------------------------------
# Public results
# ---------------------------------------------------------------------------------------


def tool_point_receptance(assembly: Mapping[str, Any], frequency_hz: np.ndarray | None = None, *,
                          effects: Mapping[str, Any] | None = None,
                          max_element_length_m: float = DEFAULT_MAX_ELEMENT_LENGTH_M) -> np.ndarray:
    """Damped tool-point receptance ``[[h, l], [n, p]]``.

    Parameters
    ----------
    assembly : mapping
        Contract assembly dict.
    frequency_hz : array_like, shape (nfreq,), optional
        Frequencies (> 0 Hz); default: the assembly's ``frequency`` grid.
    effects : mapping, optional
        Physical effects (module docstring).
    max_element_length_m : float
        Maximum element length.

    Returns
    -------
    numpy.ndarray, shape (nfreq, 2, 2), complex
        ``h = w/F`` (m/N), ``l = w/M`` (1/N), ``n = psi/F`` (rad/N), ``p = psi/M`` (rad/(N·m)).
    """
    f = frequency_grid_hz(assembly) if frequency_hz is None else np.asarray(frequency_hz, dtype=float)
    built = build_assembly_model(assembly, effects=effects, max_element_length_m=max_element_length_m)
    tip = list(built.model.node_dofs[built.tip_node])
    return harmonic_receptance(built.model, f, tip, tip)


def receptance_at(assembly: Mapping[str, Any], frequency_hz: np.ndarray,
                  response_from_tip_m: Sequence[float], excitation_from_tip_m: Sequence[float], *,
                  rotations: bool = False, effects: Mapping[str, Any] | None = None,
                  max_element_length_m: float = DEFAULT_MAX_ELEMENT_LENGTH_M) -> np.ndarray:
    """Damped receptances between points given by their distance from the tool tip.

    Parameters
    ----------
    assembly : mapping
        Contract assembly dict.
    frequency_hz : array_like, shape (nfreq,)
        Frequencies (> 0 Hz).
    response_from_tip_m, excitation_from_tip_m : sequence of float
        Distances from the tool tip toward the spindle (e.g. ``[0.0, 0.015]`` for the h11,
        h21, h22 of an artifact test). See :meth:`AssemblyModel.node_from_tip`.
    rotations : bool
        False: translational receptances only, shape ``(nfreq, nresp, nexc)``.
        True: ``(w, psi)`` per point, shape ``(nfreq, 2 nresp, 2 nexc)`` ordered
        ``(w_1, psi_1, w_2, psi_2, ...)`` against ``(F_1, M_1, F_2, M_2, ...)``.
    effects : mapping, optional
        Physical effects (module docstring).
    max_element_length_m : float
        Maximum element length.

    Returns
    -------
    numpy.ndarray, complex
        ``out[k, i, j]`` = response i per unit load j at ``frequency_hz[k]``.
    """
    built = build_assembly_model(assembly, effects=effects, max_element_length_m=max_element_length_m,
                                 points_from_tip_m=[*response_from_tip_m, *excitation_from_tip_m])
    dofs = built.model.dofs_of
    response = dofs([built.node_from_tip(d) for d in response_from_tip_m])
    excitation = dofs([built.node_from_tip(d) for d in excitation_from_tip_m])
    if not rotations:
        response, excitation = response[::2], excitation[::2]
    return harmonic_receptance(built.model, np.asarray(frequency_hz, dtype=float), response, excitation)


def natural_frequencies_hz(assembly: Mapping[str, Any], fmax_hz: float | None = None, *,
                           effects: Mapping[str, Any] | None = None,
                           max_element_length_m: float = DEFAULT_MAX_ELEMENT_LENGTH_M) -> np.ndarray:
    """Undamped natural frequencies (all loss factors and dampers set to zero) up to ``fmax_hz``.

    Parameters
    ----------
    assembly : mapping
        Contract assembly dict.
    fmax_hz : float, optional
        Upper limit; default: the top of the assembly's frequency grid.
    effects : mapping, optional
        Physical effects (module docstring).
    max_element_length_m : float
        Maximum element length.

    Returns
    -------
    numpy.ndarray, shape (nmodes,), ascending
    """
    fmax = float(frequency_grid_hz(assembly)[-1]) if fmax_hz is None else float(fmax_hz)
    built = build_assembly_model(assembly, damped=False, effects=effects,
                                 max_element_length_m=max_element_length_m)
    return undamped_natural_frequencies_hz(built.model, fmax)


def static_tool_point_compliance_m_n(assembly: Mapping[str, Any], *,
                                     effects: Mapping[str, Any] | None = None,
                                     max_element_length_m: float = DEFAULT_MAX_ELEMENT_LENGTH_M) -> float:
    """Undamped static tool-point compliance ``w/F`` (m/N) from ``K u = f`` (needs bearings)."""
    built = build_assembly_model(assembly, damped=False, effects=effects,
                                 max_element_length_m=max_element_length_m)
    k, _, _ = built.model.matrices()
    free = built.model.free_dofs_in_x_order()
    tip_w = built.model.node_dofs[built.tip_node][0]
    rhs = (free == tip_w).astype(float)
    u = scipy.linalg.solve(k.real[np.ix_(free, free)], rhs, assume_a="pos")
    return float(u[np.flatnonzero(free == tip_w)[0]])
