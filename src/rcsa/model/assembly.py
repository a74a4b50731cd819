"""From a validated :class:`~rcsa.model.contract.AssemblySpec` to the beam chain that is solved.

Modelling rules (``docs/contract.md`` "Assembly", ``docs/physics.md`` §1.3, §5):

* Spindle segments are listed nose → rear; the chain runs rear → nose (global axis).
  Bearings are springs/dampers to ground at their position; a segment is split where a
  bearing falls inside it.
* Holder segments are listed from the gauge line toward the tool end. The inserted shank
  (OAL − stickout) fills the bore from the holder's tool end toward the spindle: over that
  length each section is the composite of the holder annulus and a solid tool core of the
  shank diameter; the segment where the insertion starts is split there; inserted length
  beyond the holder is ignored.
* The tool overhang is a shank segment (stickout − flute length, at the shank diameter, or
  up to the shoulder for a necked tool), an optional neck — one diameter
  (``shoulder_*``) or ``neck_segments`` (a stepped or conical neck, listed from the flute
  end) —, and the fluted segment at ``fluted_diameter_ratio · DC`` (stiffness) and
  ``fluted_mass_diameter_ratio · DC`` (mass).
* An insertion shorter than :data:`MIN_INSERTION_DIAMETERS` shank diameters is modelled
  like any other, with a note (:func:`assembly_notes`): the point joint at the holder face
  and the composite section assume a clamped length of a few diameters; a shallow one is
  softer than the model, and how much depends on the clamp.
* Joints are :class:`~rcsa.physics.chain.Spring` items at the gauge line and the holder face.
* A holder–tool clamping (``joints.holder_tool.model`` ``bonded`` or ``contact``) replaces the
  composite section and the point joint: over the inserted length the holder annulus and the
  shank are two beams joined by a distributed interface, one
  :class:`~rcsa.physics.insertion.Insertion` item from where the insertion starts to the
  shank's node in the holder face (:mod:`rcsa.model.clamping`).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from rcsa.errors import InputError
from rcsa.model.clamping import clamped_holder_chain, clamping_notes, face_contact
from rcsa.model.contract import (
    AssemblySpec,
    ClampingSpec,
    HolderSpec,
    JointSpec,
    SpindleSpec,
    ToolSpec,
)
from rcsa.physics.chain import Beam, Chain, Ground, Spring
from rcsa.physics.materials import Material
from rcsa.physics.sections import (
    BeamTheory,
    Section,
    ShearModel,
    composite,
    shear_coefficient,
    tube,
)

__all__ = ["MIN_INSERTION_DIAMETERS", "AssemblyModel", "assembly_notes", "build_model", "holder_chain",
           "joint_spring", "neck_pieces", "shallow_insertion_note", "spindle_chain", "tool_chain"]

_TOL_M = 1e-12

#: Inserted lengths below this many shank diameters are noted as shallow clamping.
MIN_INSERTION_DIAMETERS = 2.0


def shallow_insertion_note(inserted_length_m: float, shank_diameter_m: float) -> str | None:
    """A note when the shank is clamped over less than 2 diameters, else None.

    Parameters
    ----------
    inserted_length_m : float
        Length of the shank inside the holder, m.
    shank_diameter_m : float
        Shank diameter, m.

    Returns
    -------
    str or None

    Examples
    --------
    >>> shallow_insertion_note(0.003, 0.010)[:40]
    'shallow insertion: 3 mm of the 10 mm sha'
    >>> shallow_insertion_note(0.030, 0.010) is None
    True
    """
    if inserted_length_m >= MIN_INSERTION_DIAMETERS * shank_diameter_m:
        return None
    return (f"shallow insertion: {inserted_length_m * 1e3:.4g} mm of the {shank_diameter_m * 1e3:.4g} mm shank is "
            f"clamped, less than {MIN_INSERTION_DIAMETERS:g} shank diameters; the real clamping is softer than "
            "modelled (identify the holder-tool joint, or clamp deeper)")


def assembly_notes(spec: AssemblySpec) -> tuple[str, ...]:
    """Notes on modelling assumptions an assembly stretches (shallow insertion).

    Parameters
    ----------
    spec : AssemblySpec

    Returns
    -------
    tuple of str
    """
    face_mounted = spec.tool.inserted_length_m <= _TOL_M
    note = None if face_mounted else shallow_insertion_note(spec.tool.inserted_length_m, spec.tool.shank_diameter_m)
    notes: tuple[str, ...] = () if note is None else (note,)
    if face_mounted and not isinstance(spec.holder_tool, ClampingSpec):
        notes += ("face-mounted tool (nothing inserted): it sits on the holder's face, joined by "
                  + ("the point joint given" if spec.holder_tool is not None else "a rigid point joint")
                  + " (model contact gives the face contact's stiffness from its area)",)
    if isinstance(spec.holder_tool, ClampingSpec) and spec.holder is not None:
        notes += clamping_notes(spec.holder, spec.tool, spec.holder_tool)
    return notes


@dataclass(frozen=True, slots=True)
class AssemblyModel:
    """The solved chain, kept in its substructures so they can be reused and cached.

    Attributes
    ----------
    spindle : Chain
        Rear → nose, bearings included; empty for a measured spindle.
    spindle_holder : Spring or None
    holder : Chain
        Gauge line → holder tip (composite over the insertion); with a clamping model, gauge
        line → the shank's node in the holder face (the insertion's
        :class:`~rcsa.physics.insertion.Insertion` last). Empty when a measured spindle already
        contains the holder (plane ``holder_tip``).
    holder_tool : Spring or None
        The point joint at the holder face (``None``: rigid, or a clamping along the insertion,
        which is then the last item of ``holder``).
    tool : Chain
        Holder face → tool tip.
    """

    spindle: Chain
    spindle_holder: Spring | None
    holder: Chain
    holder_tool: Spring | None
    tool: Chain

    def to_holder_tip(self) -> Chain:
        """Spindle, spindle–holder joint and holder, as one chain."""
        return self.spindle_side() + self.holder

    def spindle_side(self) -> Chain:
        """Spindle and the spindle–holder joint: what every holder and tool is coupled to."""
        return self.spindle + _opt(self.spindle_holder)

    def tool_side(self) -> Chain:
        """Holder–tool joint and tool overhang: what changes from tool to tool."""
        return _opt(self.holder_tool) + self.tool

    def chain(self) -> Chain:
        """The whole assembly, spindle rear → tool tip."""
        return self.to_holder_tip() + self.tool_side()


def _opt(spring: Spring | None) -> Chain:
    return () if spring is None else (spring,)


def joint_spring(joint: JointSpec | ClampingSpec | None) -> Spring | None:
    """The chain item of an elastic point joint (``None`` = rigid; a clamping has none).

    Parameters
    ----------
    joint : JointSpec, ClampingSpec or None
    """
    if joint is None or isinstance(joint, ClampingSpec):
        return None
    return Spring(joint.stiffness_n_m, joint.damping_ns_m, joint.rotational_stiffness_nm_rad,
                  joint.rotational_damping_nms_rad)


def spindle_chain(spindle: SpindleSpec, materials: Mapping[str, Material],
                  shear: ShearModel | float = "hutchinson", theory: BeamTheory = "timoshenko") -> Chain:
    """Spindle shaft with bearings, from the rear end to the nose.

    Parameters
    ----------
    spindle : SpindleSpec
    materials : mapping of str to Material
        Materials by name (built-ins and the document's own).

    shear : {"hutchinson", "cowper"} or float
        Shear coefficient model, or the coefficient itself.
    theory : {"timoshenko", "euler_bernoulli"}
    """
    total = spindle.length_m
    # Bearing positions along the chain (from the rear), grouped by node.
    stations = sorted({round(total - b.position_m, 12) for b in spindle.bearings})
    grounds = {x: [b for b in spindle.bearings if abs(total - b.position_m - x) < 1e-9] for x in stations}
    items: list[Beam | Spring | Ground] = []
    x0 = 0.0

    def ground_at(x: float) -> None:
        # the bearings of one node are one grounded attachment (their parameters add): one
        # elimination step, and co-located equal bearings give bit-identical results whichever is varied
        here = [b for key in [k for k in grounds if abs(k - x) < 1e-9] for b in grounds.pop(key)]
        if here:
            items.append(Ground(sum(b.stiffness_n_m for b in here), sum(b.damping_ns_m for b in here),
                                sum(b.rotational_stiffness_nm_rad for b in here),
                                sum(b.rotational_damping_nms_rad for b in here)))

    ground_at(0.0)
    for seg in reversed(spindle.segments):
        section = tube(seg.outer_diameter_m, seg.inner_diameter_m, materials[seg.material], shear, theory)
        x1 = x0 + seg.length_m
        cuts = [x for x in sorted(grounds) if x0 + 1e-9 < x < x1 - 1e-9]
        for a, b in zip([x0, *cuts], [*cuts, x1], strict=True):
            items.append(Beam(section, b - a))
            ground_at(b)
        x0 = x1
    ground_at(x0)
    return tuple(items)


def holder_chain(holder: HolderSpec, tool: ToolSpec, materials: Mapping[str, Material],
                 shear: ShearModel | float = "hutchinson", theory: BeamTheory = "timoshenko",
                 clamping: ClampingSpec | None = None) -> Chain:
    """Holder from the gauge line to its tool end, composite with the tool core over the insertion.

    With a ``clamping``, the insertion is instead one :class:`~rcsa.physics.insertion.Insertion`
    item (holder annulus and shank joined by the interface) and the chain ends at the shank's
    node in the holder face.

    Parameters
    ----------
    holder : HolderSpec
    tool : ToolSpec
        Its shank fills the holder's bore over the inserted length.
    materials : mapping of str to Material
        Materials by name (built-ins and the document's own).

    shear : {"hutchinson", "cowper"} or float
        Shear coefficient model, or the coefficient itself.
    theory : {"timoshenko", "euler_bernoulli"}
    clamping : ClampingSpec, optional
        The holder–tool clamping along the insertion (``None``: composite + point joint).
    """
    length = holder.length_m
    insertion_start = length - min(tool.inserted_length_m, length)
    if clamping is not None and tool.inserted_length_m > _TOL_M:
        return clamped_holder_chain(holder, tool, clamping, materials, shear, theory)
    core = (tube(tool.shank_diameter_m, 0.0, materials[tool.material], shear, theory)
            if tool.inserted_length_m > _TOL_M else None)
    items: list[Beam | Spring | Ground] = []
    x0 = 0.0
    for i, seg in enumerate(holder.segments):
        x1 = x0 + seg.length_m
        annulus = tube(seg.outer_diameter_m, seg.inner_diameter_m, materials[seg.material], shear, theory)
        pieces = [(x0, x1)]
        if x0 + 1e-9 < insertion_start < x1 - 1e-9:
            pieces = [(x0, insertion_start), (insertion_start, x1)]
        for a, b in pieces:
            filling = core if a >= insertion_start - 1e-9 else None  # the tool core inside this piece
            if filling is not None and tool.shank_diameter_m > seg.inner_diameter_m * (1 + 1e-9):
                raise InputError(
                    "tool.shank_diameter_m",
                    f"the shank ({tool.shank_diameter_m:g} m) does not fit the bore "
                    f"({seg.inner_diameter_m:g} m) of holder.segments[{i}], which the inserted "
                    f"length ({tool.inserted_length_m:g} m) reaches")
            items.append(Beam(annulus if filling is None else composite(annulus, filling), b - a))
        x0 = x1
    return tuple(items)


def fluted_section(tool: ToolSpec, material: Material, shear: ShearModel | float,
                   theory: BeamTheory) -> Section:
    """Equivalent section of the fluted part: stiffness from d_I, mass from d_A (``docs/physics.md`` §5.1)."""
    d_i = tool.fluted_diameter_ratio * tool.diameter_m
    d_a = (tool.fluted_mass_diameter_ratio or tool.fluted_diameter_ratio) * tool.diameter_m
    stiff = tube(d_i, 0.0, material, shear, theory)
    if d_a == d_i:
        return stiff
    area_a = np.pi * d_a**2 / 4
    damping = 1.0 + 1j * material.loss_factor
    kappa = shear_coefficient(material.poisson_ratio, 0.0, shear)
    flex = 0j if theory == "euler_bernoulli" else 1.0 / (kappa * material.shear_modulus_pa * damping * area_a)
    return Section(ei=stiff.ei, shear_flexibility=complex(flex), rho_a=material.density_kg_m3 * area_a,
                   rho_i=stiff.rho_i)


def neck_pieces(tool: ToolSpec) -> tuple[tuple[float, float], ...]:
    """The neck as ``(length_m, diameter_m)`` pieces from the flute end toward the holder.

    Parameters
    ----------
    tool : ToolSpec

    Returns
    -------
    tuple of (float, float)
        Lengths and diameters, m; empty when the shank runs to the flutes.
    """
    if tool.neck_segments:
        return tool.neck_segments
    if tool.shoulder_length_m is not None and tool.shoulder_diameter_m is not None:
        return ((tool.shoulder_length_m - tool.flute_length_m, tool.shoulder_diameter_m),)
    return ()


def tool_chain(tool: ToolSpec, materials: Mapping[str, Material], shear: ShearModel | float = "hutchinson",
               theory: BeamTheory = "timoshenko") -> Chain:
    """Tool overhang from the holder face to the tip: shank, optional neck, flutes.

    Parameters
    ----------
    tool : ToolSpec
    materials : mapping of str to Material
        Materials by name (built-ins and the document's own).

    shear : {"hutchinson", "cowper"} or float
        Shear coefficient model, or the coefficient itself.
    theory : {"timoshenko", "euler_bernoulli"}
    """
    mat = materials[tool.material]
    necks = neck_pieces(tool)
    items: list[Beam | Spring | Ground] = []
    shoulder = (tool.shoulder_length_m if tool.shoulder_length_m is not None and not tool.neck_segments
                else tool.flute_length_m + sum(length for length, _ in necks))
    shank_length = tool.stickout_m - shoulder
    if shank_length > _TOL_M:
        items.append(Beam(tube(tool.shank_diameter_m, 0.0, mat, shear, theory), shank_length))
    for length, diameter in reversed(necks):
        if length > _TOL_M:
            items.append(Beam(tube(diameter, 0.0, mat, shear, theory), length))
    items.append(Beam(fluted_section(tool, mat, shear, theory), tool.flute_length_m))
    return tuple(items)


def build_model(spec: AssemblySpec, base_plane: str | None = None, spindle: Chain | None = None) -> AssemblyModel:
    """The chain model of an assembly.

    Parameters
    ----------
    spec : AssemblySpec
    base_plane : {None, "spindle_nose", "holder_tip"}
        For a measured spindle, the plane of the measurement; ``None`` for an analytical one.
    spindle : Chain, optional
        The spindle chain of ``spec``, already built (a batch builds it once for all tools).

    Returns
    -------
    AssemblyModel
    """
    shear, theory, mats = spec.shear_coefficient, spec.beam_theory, spec.materials
    if spindle is None:
        spindle = spindle_chain(spec.spindle, mats, shear, theory) if isinstance(spec.spindle, SpindleSpec) else ()
    holder: Chain = ()
    if base_plane != "holder_tip":
        if spec.holder is None:
            raise InputError("holder", "is required unless the measured spindle's plane is holder_tip")
        clamping = spec.holder_tool if isinstance(spec.holder_tool, ClampingSpec) else None
        holder = holder_chain(spec.holder, spec.tool, mats, shear, theory, clamping)
    elif spec.holder is not None:
        raise InputError("holder", "must be left out: the measured spindle (plane holder_tip) already "
                         "contains its holder")
    elif isinstance(spec.holder_tool, ClampingSpec):
        raise InputError("joints.holder_tool.model",
                         f"{spec.holder_tool.model!r} models the clamping from the holder's geometry, which a "
                         "holder_tip measurement does not give (it contains holder and clamping): use the point "
                         "joint, or measure the spindle at its nose")
    holder_tool = joint_spring(spec.holder_tool)
    if isinstance(spec.holder_tool, ClampingSpec) and spec.tool.inserted_length_m <= _TOL_M:
        assert spec.holder is not None  # a clamping on a holder_tip measurement is refused above
        holder_tool = face_contact(spec.holder, spec.tool, spec.holder_tool)
    return AssemblyModel(
        spindle=spindle,
        spindle_holder=joint_spring(spec.spindle_holder) if base_plane != "holder_tip" else None,
        holder=holder,
        holder_tool=holder_tool,
        tool=tool_chain(spec.tool, mats, shear, theory),
    )
