"""What a 3-D holder + tool case is: geometry in the contract's terms, materials, interface, mesh.

Everything here is plain immutable data (SI units in every name) and its validation; the
geometry is turned into solids by :mod:`tests.oracles.solid3d.geometry`.

Axis and frames: z runs from the holder's base face (the gauge line, z = 0) toward the tool
tip, i.e. rcsa's global axis (``docs/physics.md`` §2.1, spindle rear → tool tip). The tool-point
FRF is taken in the x–z plane: w = u_x, ψ = dw/dz = rotation about +y.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Literal

__all__ = [
    "CARBIDE",
    "STEEL",
    "Flutes",
    "HolderRing",
    "HolderSegment",
    "Interface",
    "MeshSize",
    "SolidCase",
    "ShankFlat",
    "SolidMaterial",
    "ToolGeometry",
]


@dataclass(frozen=True, slots=True)
class SolidMaterial:
    """An isotropic linear-elastic material with hysteretic damping E(1 + iη).

    Parameters
    ----------
    youngs_modulus_pa : float
        Young's modulus E, Pa.
    poisson_ratio : float
        Poisson's ratio ν.
    density_kg_m3 : float
        Density ρ, kg/m³.
    loss_factor : float
        Loss factor η ≥ 0 (the whole elasticity tensor is multiplied by 1 + iη).
    """

    youngs_modulus_pa: float
    poisson_ratio: float
    density_kg_m3: float
    loss_factor: float = 0.0

    def __post_init__(self) -> None:
        if not self.youngs_modulus_pa > 0:
            raise ValueError("youngs_modulus_pa must be > 0")
        if not -1.0 < self.poisson_ratio < 0.5:
            raise ValueError("poisson_ratio must lie in (-1, 0.5)")
        if not self.density_kg_m3 > 0:
            raise ValueError("density_kg_m3 must be > 0")
        if not self.loss_factor >= 0:
            raise ValueError("loss_factor must be >= 0")


#: rcsa's built-in ``steel`` (docs/contract.md "Assembly": materials)
STEEL = SolidMaterial(210e9, 0.30, 7850.0, 0.002)
#: rcsa's built-in ``carbide``
CARBIDE = SolidMaterial(600e9, 0.22, 14500.0, 0.002)


@dataclass(frozen=True, slots=True)
class HolderSegment:
    """One holder segment, listed from the gauge line (z = 0) toward the tool end.

    Parameters
    ----------
    length_m, outer_diameter_m : float
        m.
    inner_diameter_m : float
        Bore diameter, m (0 = solid).
    outer_diameter_end_m : float or None
        A cone: the outer diameter at the segment's tool end, m (``outer_diameter_m`` is then
        the one at its gauge-line end); None: a cylinder.
    """

    length_m: float
    outer_diameter_m: float
    inner_diameter_m: float = 0.0
    outer_diameter_end_m: float | None = None

    def __post_init__(self) -> None:
        if not (self.length_m > 0 and self.outer_diameter_m > 0):
            raise ValueError("holder segment length_m and outer_diameter_m must be > 0")
        if not 0 <= self.inner_diameter_m < min(self.outer_diameter_m, self.outer_diameter_end_m or math.inf):
            raise ValueError("holder segment inner_diameter_m must lie in [0, outer_diameter_m)")

    @property
    def is_cone(self) -> bool:
        """True for a conical segment."""
        return self.outer_diameter_end_m is not None and self.outer_diameter_end_m != self.outer_diameter_m


@dataclass(frozen=True, slots=True)
class HolderRing:
    """A ring around the holder's outside near its tool end (a collet chuck's clamping nut).

    The ring sits on the holder's outer surface: it is joined to it over ``attached_length_m``
    at its gauge-line end (the thread) and stands off it by ``clearance_m`` (radially) over the
    rest, so it adds its mass but little of its stiffness.

    Parameters
    ----------
    outer_diameter_m : float
        m.
    length_m : float
        Axial length, m.
    front_offset_m : float
        Distance of the ring's front face behind the holder's tool-end face, m (0: flush).
    attached_length_m : float
        Length over which it is joined to the holder (from its gauge-line end), m.
    clearance_m : float
        Radial gap between ring and holder over the rest of its length, m (> 0).
    """

    outer_diameter_m: float
    length_m: float
    front_offset_m: float = 0.0
    attached_length_m: float = 0.0
    clearance_m: float = 3e-4

    def __post_init__(self) -> None:
        if not (self.outer_diameter_m > 0 and self.length_m > 0 and self.clearance_m > 0):
            raise ValueError("ring outer_diameter_m, length_m and clearance_m must be > 0")
        if not (self.front_offset_m >= 0 and 0 < self.attached_length_m <= self.length_m):
            raise ValueError("ring: front_offset_m >= 0 and 0 < attached_length_m <= length_m are required")


@dataclass(frozen=True, slots=True)
class ShankFlat:
    """A side-lock (Weldon) flat on the shank and the clamping screw pressing on it.

    The flat is the plane ``x = d/2 − depth_m`` cut from the shank over an axial range inside
    the bore; the screw is a cylinder of holder steel along x, centred on the flat, filling
    the gap between the bore and the flat, its end face joined to the flat (the screw's
    preloaded contact, linearised). It pushes the shank toward −x: ``Interface.arc_deg`` says
    over which arc at the back of the bore the shank then touches.

    Parameters
    ----------
    depth_m : float
        Depth of the flat, m.
    start_m, length_m : float
        Depth of the flat's front end into the bore (from the holder's tool-end face) and its
        axial length, m.
    screw_diameter_m : float
        Diameter of the screw's contact face, m.
    """

    depth_m: float
    start_m: float
    length_m: float
    screw_diameter_m: float

    def __post_init__(self) -> None:
        if not (self.depth_m > 0 and self.start_m >= 0 and self.length_m > 0 and self.screw_diameter_m > 0):
            raise ValueError("flat: depth_m, length_m and screw_diameter_m > 0 and start_m >= 0 are required")
        if self.screw_diameter_m > self.length_m:
            raise ValueError("flat: the screw must fit on the flat (screw_diameter_m <= length_m)")


@dataclass(frozen=True, slots=True)
class Flutes:
    """A real fluted cross-section: n circular gullets cut from the cutting circle.

    The section is the disk of diameter DC minus ``count`` circles of radius
    ``gullet_radius_m`` whose centres lie at ``core_diameter_m / 2 + gullet_radius_m`` from
    the axis (each gullet touches the core circle), equally spaced, the first centred on
    the direction ``angle_deg`` from +x toward +y. The flutes are straight (no helix).

    Parameters
    ----------
    count : int
        Number of flutes, ≥ 2.
    core_diameter_m : float
        Web (core) diameter, m.
    gullet_radius_m : float
        Radius of the gullet arcs, m.
    angle_deg : float
        Orientation of the first gullet, degrees from +x (the direction of the FRF).
    """

    count: int
    core_diameter_m: float
    gullet_radius_m: float
    angle_deg: float = 0.0

    def __post_init__(self) -> None:
        if self.count < 2:
            raise ValueError("flutes.count must be >= 2")
        if not (self.core_diameter_m > 0 and self.gullet_radius_m > 0):
            raise ValueError("flutes.core_diameter_m and gullet_radius_m must be > 0")
        centre = self.core_diameter_m / 2 + self.gullet_radius_m
        if centre * math.sin(math.pi / self.count) <= self.gullet_radius_m:
            raise ValueError("flutes.gullet_radius_m: neighbouring gullets overlap")

    def mirror_symmetric_in_xz_and_yz(self) -> bool:
        """True when the section is symmetric about both the x–z and y–z planes."""
        step = 180.0 / self.count  # the gullet pattern's mirror lines are angle + k·step
        offsets = {round((self.angle_deg % step) / step, 9), round(((self.angle_deg - 90.0) % step) / step, 9)}
        return offsets <= {0.0, 1.0}


@dataclass(frozen=True, slots=True)
class ToolGeometry:
    """The tool, in the contract's meaning (``docs/contract.md`` "Assembly": tool).

    Parameters
    ----------
    diameter_m : float
        Cutting diameter DC, m.
    shank_diameter_m : float
        m; must equal the bore it sits in.
    overall_length_m : float
        OAL, m.
    flute_length_m : float
        LCF, m.
    stickout_m : float
        From the holder's tool-end face to the tip, m. The inserted length
        OAL − stickout fills the bore from the holder's tool end toward the spindle
        (beyond the holder's length it is ignored).
    fluted_diameter_ratio : float
        Without ``flutes``: the fluted part is a round section of diameter
        ``fluted_diameter_ratio · DC`` (the beam model's own assumption).
    flutes : Flutes or None
        A real fluted cross-section instead.
    flat : ShankFlat or None
        A side-lock flat on the shank, with its clamping screw.
    """

    diameter_m: float
    shank_diameter_m: float
    overall_length_m: float
    flute_length_m: float
    stickout_m: float
    fluted_diameter_ratio: float = 0.8
    flutes: Flutes | None = None
    flat: ShankFlat | None = None

    def __post_init__(self) -> None:
        for name in ("diameter_m", "shank_diameter_m", "overall_length_m", "flute_length_m", "stickout_m"):
            if not getattr(self, name) > 0:
                raise ValueError(f"tool.{name} must be > 0")
        if not self.flute_length_m <= self.stickout_m < self.overall_length_m:
            raise ValueError("tool: flute_length_m <= stickout_m < overall_length_m is required")
        if not 0 < self.fluted_diameter_ratio <= 1.0:
            raise ValueError("tool.fluted_diameter_ratio must lie in (0, 1]")
        if self.flutes is not None and self.flutes.core_diameter_m >= self.diameter_m:
            raise ValueError("tool.flutes.core_diameter_m must be smaller than diameter_m")
        if self.flat is not None:
            if self.flat.depth_m >= 0.5 * self.shank_diameter_m:
                raise ValueError("tool.flat.depth_m must be less than the shank radius")
            if self.flat.start_m + self.flat.length_m > self.inserted_length_m + 1e-12:
                raise ValueError("tool.flat must lie inside the inserted length")

    @property
    def inserted_length_m(self) -> float:
        """OAL − stickout, m."""
        return self.overall_length_m - self.stickout_m


InterfaceModel = Literal["bonded", "layer"]


@dataclass(frozen=True, slots=True)
class Interface:
    """How the shank is held in the bore.

    Parameters
    ----------
    model : {"bonded", "layer"}
        ``bonded``: shank and bore share their nodes over the contact region.
        ``layer``: zero-thickness springs between duplicated nodes of the shank and bore
        surfaces, normal stiffness per unit area ``interface_stiffness_n_m3`` and tangential
        ``tangential_ratio`` times that (consistent surface integral ∫Nᵀ k N dA).
    interface_stiffness_n_m3 : float or None
        Normal stiffness per unit area, N/m³ (required for ``layer``).
    tangential_ratio : float
        Tangential / normal stiffness (``layer``).
    loss_factor : float
        Hysteretic loss factor of the layer's springs, k(1 + iη). The default equals the
        built-in materials' η, so a uniform structure keeps one modal loss factor.
    contact_start_m, contact_stop_m : float, float or None
        The contact region, as depths into the bore measured from the holder's tool-end
        face (0 = the face); ``contact_stop_m = None`` = to the end of the insertion.
        Outside it the shank and the bore are separate (a gap).
    bottom : {"free", "connected"}
        The shank's end face inside the bore, where it meets holder material: a gap
        (default) or connected like the contact region.
    arc_deg : float
        The contact covers this arc of the bore's circumference, centred on its back (the
        −x side, opposite a side-lock screw); 360: all round.
    """

    model: InterfaceModel = "bonded"
    interface_stiffness_n_m3: float | None = None
    tangential_ratio: float = 1.0
    loss_factor: float = 0.002
    contact_start_m: float = 0.0
    contact_stop_m: float | None = None
    bottom: Literal["free", "connected"] = "free"
    arc_deg: float = 360.0

    def __post_init__(self) -> None:
        if self.model not in ("bonded", "layer"):
            raise ValueError("interface.model must be 'bonded' or 'layer'")
        if self.model == "layer" and not (self.interface_stiffness_n_m3 or 0) > 0:
            raise ValueError("interface.interface_stiffness_n_m3 must be > 0 for a layer")
        if not self.tangential_ratio >= 0 or not self.loss_factor >= 0:
            raise ValueError("interface.tangential_ratio and loss_factor must be >= 0")
        if self.contact_start_m < 0 or (self.contact_stop_m is not None
                                        and not self.contact_stop_m > self.contact_start_m):
            raise ValueError("interface: 0 <= contact_start_m < contact_stop_m is required")
        if self.bottom not in ("free", "connected"):
            raise ValueError("interface.bottom must be 'free' or 'connected'")
        if not 0 < self.arc_deg <= 360:
            raise ValueError("interface.arc_deg must lie in (0, 360]")


@dataclass(frozen=True, slots=True)
class MeshSize:
    """Target element sizes of the quadratic tetrahedra.

    Parameters
    ----------
    tool_m : float
        Element size in the tool and the bore wall, m.
    holder_m : float
        Largest element size (far in the flange), m.
    growth : float
        Size increase per metre of distance from the fine zone (dimensionless slope).
    """

    tool_m: float = 2.0e-3
    holder_m: float = 8.0e-3
    growth: float = 0.5

    def __post_init__(self) -> None:
        if not (0 < self.tool_m <= self.holder_m) or not self.growth > 0:
            raise ValueError("mesh: 0 < tool_m <= holder_m and growth > 0 are required")

    def scaled(self, factor: float) -> MeshSize:
        """The size field times ``factor`` everywhere (sizes and slope: a refinement sequence)."""
        return MeshSize(self.tool_m * factor, self.holder_m * factor, self.growth * factor)


Symmetry = Literal["auto", "quarter", "half", "full"]


@dataclass(frozen=True, slots=True)
class SolidCase:
    """A holder + tool case for the 3-D reference.

    Parameters
    ----------
    holder_segments : tuple of HolderSegment
        From the gauge line toward the tool end (``docs/contract.md`` "Assembly": ``holder.segments``).
    tool : ToolGeometry
    holder_material, tool_material : SolidMaterial
    interface : Interface
    mesh : MeshSize
    rigid_holder : bool
        The holder moves as one rigid body with the base face (exact: its nodes are tied
        to the base's rigid-body DOFs); the tool is then held by a rigid bore.
    symmetry : {"auto", "quarter", "half", "full"}
        ``quarter`` models x ≥ 0, y ≥ 0 with the symmetry conditions of bending in x
        (exact for sections symmetric about the x–z and y–z planes); ``half`` models y ≥ 0
        (exact when symmetric about the x–z plane only: a side-lock screw along x, an arc of
        contact centred on −x); ``auto`` takes the smallest valid one.
    rings : tuple of HolderRing
        Rings around the holder near its tool end (a clamping nut).
    """

    holder_segments: tuple[HolderSegment, ...]
    tool: ToolGeometry
    holder_material: SolidMaterial = STEEL
    tool_material: SolidMaterial = CARBIDE
    interface: Interface = field(default_factory=Interface)
    mesh: MeshSize = field(default_factory=MeshSize)
    rigid_holder: bool = False
    symmetry: Symmetry = "auto"
    rings: tuple[HolderRing, ...] = ()

    def __post_init__(self) -> None:
        if not self.holder_segments:
            raise ValueError("holder_segments must not be empty")
        if self.symmetry not in ("auto", "quarter", "half", "full"):
            raise ValueError("symmetry must be 'auto', 'quarter', 'half' or 'full'")
        if self.symmetry == "quarter" and not self.quarter_symmetric():
            raise ValueError("symmetry='quarter' needs a section symmetric about the x-z and y-z planes")
        if self.symmetry == "half" and not self.half_symmetric():
            raise ValueError("symmetry='half' needs a body symmetric about the x-z plane")
        for ring in self.rings:
            if ring.front_offset_m + ring.length_m > self.holder_length_m:
                raise ValueError("a ring must lie along the holder")
        start = self.insertion_start_m
        z0 = 0.0
        for i, seg in enumerate(self.holder_segments):
            z1 = z0 + seg.length_m
            if z1 > start + 1e-12 and abs(seg.inner_diameter_m - self.tool.shank_diameter_m) > 1e-9:
                raise ValueError(f"holder_segments[{i}].inner_diameter_m: the inserted shank "
                                 f"(Ø{self.tool.shank_diameter_m:g} m) must fill this bore exactly")
            z0 = z1
        if self.tool.inserted_length_m <= 0:
            raise ValueError("tool: the inserted length overall_length_m - stickout_m must be > 0")

    @property
    def holder_length_m(self) -> float:
        """Total holder length (base face to tool-end face), m."""
        return float(sum(s.length_m for s in self.holder_segments))

    @property
    def insertion_start_m(self) -> float:
        """z of the shank's end inside the bore, m."""
        return self.holder_length_m - min(self.tool.inserted_length_m, self.holder_length_m)

    @property
    def tip_z_m(self) -> float:
        """z of the tool tip, m."""
        return self.holder_length_m + self.tool.stickout_m

    def quarter_symmetric(self) -> bool:
        """True when the geometry allows the quarter model."""
        round_contact = self.interface.arc_deg == 360.0 and self.tool.flat is None
        return round_contact and (self.tool.flutes is None or self.tool.flutes.mirror_symmetric_in_xz_and_yz())

    def half_symmetric(self) -> bool:
        """True when the geometry is symmetric about the x–z plane (the half model y ≥ 0)."""
        if self.tool.flutes is None:
            return True
        half_step = 180.0 / self.tool.flutes.count   # gullets mirrored about x: angle a multiple of half a pitch
        return round((self.tool.flutes.angle_deg % half_step) / half_step, 9) in (0.0, 1.0)

    def uses_quarter(self) -> bool:
        """Whether the mesh is the quarter model."""
        return self.symmetry == "quarter" or (self.symmetry == "auto" and self.quarter_symmetric())

    def uses_half(self) -> bool:
        """Whether the mesh is the half model (y ≥ 0)."""
        return self.symmetry == "half" or (self.symmetry == "auto" and not self.quarter_symmetric()
                                           and self.half_symmetric())
