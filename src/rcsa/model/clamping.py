"""Holder–tool clamping along the insertion: the interface between shank and bore, from geometry.

With ``joints.holder_tool.model`` ``"bonded"`` or ``"contact"`` the inserted shank and the
holder around it are two beams joined along the insertion by a distributed interface
(:class:`rcsa.physics.insertion.Insertion`). Its stiffness per unit length is the series
combination of

* the **holder wall** around the bore, deforming under the shank's lateral push — stiffer for
  a thicker wall (outer-to-bore diameter ratio ``D/d``), softer for a thin one (ovalisation);
* the **shank's own surface layer**, deforming locally under the same pressure;
* for ``contact``, the **interface itself**: a stiffness per unit area ``k_n`` normal and
  ``k_t = r_t k_n`` tangential. A lateral relative displacement δ of the shank opens the gap
  by ``δ cos θ`` and slides it by ``δ sin θ`` around the circumference, so per unit length
  ``k_w = π (d/2) (k_n + k_t)``; a relative rotation φ slides it axially by ``φ (d/2) cos θ``,
  so ``k_θ = π (d/2)³ k_t``.

The bulk terms (holder wall and shank) are elasticity solved in 3-D, not beam theory: their
dimensionless form is fixed by the problem (``k_w / E`` depends on ``D/d`` and ν only; ``k_θ /
(E d²)`` likewise) and the coefficients of :data:`BULK_COEFFICIENTS` are fitted to the 3-D
finite-element reference of ``tests/oracles/solid3d`` (``benchmarks/calibrate_clamping.py``
regenerates them; ``docs/model.md`` "Clamping along the insertion" gives the fit, its validity range and its error).

A clamping given by its pressure instead of its stiffness uses the stated contact model
:func:`rcsa.physics.insertion.contact_stiffness_n_m3` (``k_n = p / σ``).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from rcsa.errors import InputError
from rcsa.model.contract import ClampingSpec, HolderSpec, SegmentSpec, ToolSpec
from rcsa.physics.chain import Beam, Chain, Spring
from rcsa.physics.insertion import Insertion, InsertionPiece
from rcsa.physics.materials import Material
from rcsa.physics.sections import BeamTheory, Section, ShearModel, shear_coefficient, tube

__all__ = ["BULK_COEFFICIENTS", "CALIBRATED_GEOMETRY_RANGES", "FITTED", "BulkCoefficients", "arc_per_length", "clamped_holder_chain",
           "clamping_notes", "face_contact", "interface_per_length",
           "step_cone_length_m"]

_TOL_M = 1e-12


@dataclass(frozen=True, slots=True)
class BulkCoefficients:
    """Dimensionless coefficients of a clamping's elasticity that beam theory does not give.

    Interface (the bulk of shank and holder around the bore), per unit area of the bore, the
    same in every direction (normal, circumferential, axial: an isotropic layer, so that the
    rotational interface is half the translational one per (d/2)², :func:`interface_per_length`):
    ``1/k = (π d / interface) (1/E_t + 1/E_h)``, each body's surface as compliant as its
    modulus says. No dependence on the holder's wall: fitted as ``τ^b/(1 + τ^b)`` (τ the wall
    over the bore radius), the exponent went to its bound (0.2, no dependence over walls of
    0.3–1.6 d) with a singular value 40 times below the others' (``benchmarks/calibrate_clamping.py``).

    Holder sections: next to a step from a larger outer diameter D to a smaller d the larger
    section does not bend as a whole at once: over ``ℓ = step_cone (D − d)/2`` from the step (at
    most the section's length; cones from both its ends overlapping take the thinner) its
    stiffness grows as a cone from d to D (the 45° load-spreading cone at ``step_cone = 1``), its
    mass unchanged. A holder's sections are stubby (length about their diameter) and their ends
    are kept from warping by the steps and the face they sit on: their shear stiffness is
    ``holder_shear`` times the long beam's κGA.

    Parameters
    ----------
    interface : float
        Interface coefficient.
    step_cone : float
        Length of the stiffness cone at a holder step, per radial step height.
    holder_shear : float
        The holder sections' shear stiffness over Timoshenko's κGA.
    """

    interface: float
    step_cone: float
    holder_shear: float = 1.0


#: The fitted coefficients (``benchmarks/calibrate_clamping.py --fit``).
BULK_COEFFICIENTS = BulkCoefficients(interface=8.18, step_cone=1.24, holder_shear=1.18)
#: The coefficients the calibration fits (every one of :data:`BULK_COEFFICIENTS`).
FITTED = ("interface", "step_cone", "holder_shear")
#: Pieces a step's stiffness cone is cut into (constant sections at their mid-diameters).
CONE_PIECES = 4
#: The ranges the calibration cases cover (``tests/data/solid3d``): the nose's outer diameter over
#: the shank's, the shank diameter (m) and the inserted length in shank diameters.
CALIBRATED_GEOMETRY_RANGES = {"wall_ratio": (1.6, 3.2), "shank_diameter_m": (0.006, 0.020), "insertion_diameters": (2.0, 5.0)}


def interface_per_length(clamping: ClampingSpec, holder_outer_diameter_m: float, bore_diameter_m: float,
                         shank_diameter_m: float, holder: Material, tool: Material,
                         coefficients: BulkCoefficients | None = None,
                         contact_length_m: float | None = None) -> tuple[complex, complex]:
    """Interface stiffness per unit length between shank and holder, ``(k_w, k_θ)``.

    Parameters
    ----------
    clamping : ClampingSpec
        The clamping model (bonded, or contact with its interface stiffness per area).
    holder_outer_diameter_m, bore_diameter_m : float
        The holder section around the shank, m.
    shank_diameter_m : float
        Shank diameter, m (the bore's, when it is larger: the shank touches the bore).
    holder, tool : Material
        Holder and tool materials.
    coefficients : BulkCoefficients, optional
        The bulk coefficients (default :data:`BULK_COEFFICIENTS`, the fitted ones).
    contact_length_m : float, optional
        Length of the contact along the bore, m: a side-lock screw's face (``screw_diameter_m``)
        is spread over it.

    Returns
    -------
    k_w : complex
        Translational, N/m per m (complex with the materials' and the interface's loss).
    k_theta : complex
        Rotational, N·m/rad per m.

    Examples
    --------
    >>> from rcsa.physics.materials import BUILTIN_MATERIALS as m
    >>> kw, kt = interface_per_length(ClampingSpec("bonded"), 0.026, 0.010, 0.010, m["steel"], m["carbide"])
    >>> 1e11 < kw.real < 1e13, kt.real > 0
    (True, True)
    """
    c = BULK_COEFFICIENTS if coefficients is None else coefficients
    if holder_outer_diameter_m <= bore_diameter_m:
        return 0j, 0j
    e_h = holder.youngs_modulus_pa * (1 + 1j * holder.loss_factor)
    e_t = tool.youngs_modulus_pa * (1 + 1j * tool.loss_factor)
    # per unit area, the same normal, circumferential and axial (an isotropic bulk)
    normal = tangential = axial = c.interface / (math.pi * shank_diameter_m * (1.0 / e_t + 1.0 / e_h))
    if clamping.model == "contact":
        assert clamping.interface_stiffness_n_m3 is not None
        k_n = clamping.interface_stiffness_n_m3 * (1 + 1j * clamping.interface_loss_factor)
        k_t = clamping.interface_tangential_ratio * k_n
        normal, tangential, axial = (1.0 / (1.0 / normal + 1.0 / k_n), 1.0 / (1.0 / tangential + 1.0 / k_t),
                                     1.0 / (1.0 / axial + 1.0 / k_t))
    elif clamping.interface_loss_factor:  # bonded: a loss of the clamping itself (0 as parsed; analyses add it)
        loss = 1 + 1j * clamping.interface_loss_factor
        normal, tangential, axial = normal * loss, tangential * loss, axial * loss
    screw = 0.0
    if clamping.screw_diameter_m is not None and contact_length_m:
        screw = math.pi * clamping.screw_diameter_m**2 / 4.0 / contact_length_m
    k_w, k_theta = arc_per_length(normal, tangential, axial, shank_diameter_m, clamping.contact_arc_deg, screw)
    return complex(k_w * clamping.interface_stiffness_scale), complex(k_theta * clamping.interface_stiffness_scale)


def arc_per_length(normal_n_m3: complex, tangential_n_m3: complex, axial_n_m3: complex, shank_diameter_m: float,
                   arc_deg: float = 360.0, screw_m2_per_m: float = 0.0) -> tuple[complex, complex]:
    """Stiffness per unit length of an interface over an arc of the bore, from its stiffness per area.

    The arc, of half-angle α, is centred on the direction of the lateral relative displacement
    δ (θ measured from it): the gap opens by ``δ cos θ`` and slides by ``δ sin θ``, so
    ``k_w = r [k_n (α + ½ sin 2α) + k_t (α − ½ sin 2α)]``. A relative rotation φ slides the
    surface axially by ``φ r cos θ``; all round this gives ``k_θ = π r³ k_z``. Over a part of the
    circumference only, the shank is free to slide axially as a whole: the slip ``u + φ r cos θ``
    with the ``u`` of least energy, so ``k_θ = r² k_z (C₂ − C₁²/W)`` with the contact's weights
    ``W = ∫ w``, ``C₁ = ∫ w cos θ``, ``C₂ = ∫ w cos² θ`` (``w = r dθ`` on the arc). A side-lock
    screw's face on the shank's flat, opposite the arc, adds its area per unit length ``s`` at
    ``cos θ = −1`` (on the far side from the arc's centre): ``k_n s`` to ``k_w`` and its weight to
    the slip's, which it holds. All round and with no screw: ``π r (k_n + k_t)`` and ``π r³ k_z``
    (:func:`rcsa.physics.insertion.contact_per_length`).

    Parameters
    ----------
    normal_n_m3, tangential_n_m3, axial_n_m3 : complex
        Stiffness per unit area: normal, circumferential and axial shear, N/m³.
    shank_diameter_m : float
        m.
    arc_deg : float
        The arc, degrees (360: all round).
    screw_m2_per_m : float
        A side-lock screw's contact area per unit length of the contact, m²/m (0: none).

    Returns
    -------
    k_w : complex
        N/m per m.
    k_theta : complex
        N·m/rad per m.

    Examples
    --------
    Over 120° the lateral stiffness is a third of the all-round one, and the rotational one,
    the shank free to slide, falls far more:

    >>> [tuple(round(k.real / u, 4) for k, u in zip(arc_per_length(1e14, 1e14, 1e14, 0.010, deg), (1e12, 1e6)))
    ...  for deg in (360.0, 120.0)]
    [(3.1416, 39.2699), (1.0472, 0.5977)]
    """
    r = shank_diameter_m / 2
    alpha = math.radians(arc_deg) / 2
    even, odd = alpha + 0.5 * math.sin(2 * alpha), alpha - 0.5 * math.sin(2 * alpha)
    k_w = r * (normal_n_m3 * even + tangential_n_m3 * odd) + normal_n_m3 * screw_m2_per_m
    if arc_deg >= 360.0 and screw_m2_per_m == 0.0:
        return complex(k_w), complex(r**3 * axial_n_m3 * even)
    weight = 2 * alpha * r + screw_m2_per_m
    first = 2 * r * math.sin(alpha) - screw_m2_per_m     # ∫ w cos θ, θ from the arc's centre
    second = r * even + screw_m2_per_m
    return complex(k_w), complex(r**2 * axial_n_m3 * (second - first**2 / weight))


@dataclass(frozen=True, slots=True)
class _HolderPiece:
    """A uniform length of the holder: its segment, and the outer diameter its stiffness sees."""

    x0_m: float
    x1_m: float
    index: int
    segment: SegmentSpec
    stiffness_diameter_m: float


def step_cone_length_m(step_cone: float, big_diameter_m: float, small_diameter_m: float, section_length_m: float
                       ) -> float:
    """How far a holder section's stiffness cone reaches from a step down to a smaller section.

    ``ℓ = step_cone (D − d)/2``, at most the section's length (:class:`BulkCoefficients`).

    Parameters
    ----------
    step_cone : float
        The cone's length per radial step height (``BulkCoefficients.step_cone``).
    big_diameter_m, small_diameter_m : float
        Outer diameters of the section and of its smaller neighbour, m.
    section_length_m : float
        The section's length, m.

    Returns
    -------
    float
        ℓ, m.

    Examples
    --------
    >>> round(step_cone_length_m(1.0, 0.040, 0.026, 0.030), 6), step_cone_length_m(1.0, 0.063, 0.010, 0.024)
    (0.007, 0.024)
    """
    return min(step_cone * (big_diameter_m - small_diameter_m) / 2.0, section_length_m)


def _holder_pieces(holder: HolderSpec, step_cone: float) -> list[_HolderPiece]:
    """The holder cut into uniform pieces, with each step's stiffness cone (:class:`BulkCoefficients`)."""
    segs = holder.segments
    bounds = np.cumsum([0.0] + [s.length_m for s in segs])
    out: list[_HolderPiece] = []
    for i, seg in enumerate(segs):
        x0, x1, big = float(bounds[i]), float(bounds[i + 1]), seg.outer_diameter_m
        # cone lengths at the step before (toward the gauge line) and after (toward the tool end)
        cones = []
        for j, at in ((i - 1, x0), (i + 1, x1)):
            small = segs[j].outer_diameter_m if 0 <= j < len(segs) else big
            if step_cone > 0 and small < big:
                cones.append((at, small, step_cone_length_m(step_cone, big, small, seg.length_m)))
        cuts = {x0, x1}
        for at, _, ell in cones:
            cuts.update(at + np.sign(x0 + x1 - 2 * at) * ell * np.arange(1, CONE_PIECES + 1) / CONE_PIECES)
        xs = sorted(cuts)
        for a, b in zip(xs[:-1], xs[1:], strict=True):
            mid, d = 0.5 * (a + b), big
            for at, small, ell in cones:
                if abs(mid - at) < ell:
                    d = min(d, small + (big - small) * abs(mid - at) / ell)
            out.append(_HolderPiece(a, b, i, seg, d))
    return out


def _annulus(piece: _HolderPiece, material: Material, shear: ShearModel | float, theory: BeamTheory,
             holder_shear: float = 1.0, filled: bool = False) -> Section:
    """The piece's section: stiffness (EI, κGA) of its stiffness diameter, mass (ρA, ρI) of its own.

    ``filled``: the shank touches the bore here, so the annulus shears as the outer part of the
    solid section it forms with the shank (the shear coefficient of the solid circle, not the
    hollow one's: a bonded core keeps the thin wall from shearing on its own).
    """
    seg = piece.segment
    if filled and isinstance(shear, str):
        shear = shear_coefficient(material.poisson_ratio, 0.0, shear)
    real = tube(seg.outer_diameter_m, seg.inner_diameter_m, material, shear, theory)
    stiff = real if piece.stiffness_diameter_m >= seg.outer_diameter_m else \
        tube(piece.stiffness_diameter_m, seg.inner_diameter_m, material, shear, theory)
    return Section(stiff.ei, stiff.shear_flexibility / holder_shear, real.rho_a, real.rho_i)


def clamped_holder_chain(holder: HolderSpec, tool: ToolSpec, clamping: ClampingSpec,
                         materials: Mapping[str, Material], shear: ShearModel | float = "hutchinson",
                         theory: BeamTheory = "timoshenko", coefficients: BulkCoefficients | None = None) -> Chain:
    """The holder chain with a clamping along the insertion: beams, then one :class:`Insertion`.

    From the gauge line to where the insertion starts, the holder annulus (solid where it has no
    bore); from there to the holder's tool-end face, holder annulus and shank core joined by the
    interface, one :class:`~rcsa.physics.insertion.Insertion` that ends at the shank's node in
    the face. Cut at the holder's steps (each with its stiffness cone) and where the contact
    begins and ends: the shank touches the bore from ``front_gap_length_m`` behind the face over
    ``contact_length_m`` (default: to the end of the insertion); elsewhere the two beams are free
    of each other.

    Parameters
    ----------
    holder : HolderSpec
    tool : ToolSpec
        Its shank fills the bore over the inserted length (beyond the holder: ignored); > 0.
    clamping : ClampingSpec
    materials : mapping of str to Material
        Materials by name.
    shear : {"hutchinson", "cowper"} or float
    theory : {"timoshenko", "euler_bernoulli"}
    coefficients : BulkCoefficients, optional
        Default :data:`BULK_COEFFICIENTS`.

    Returns
    -------
    Chain

    Raises
    ------
    InputError
        The shank does not fit a bore it reaches, or the front gap leaves no contact.
    """
    c = BULK_COEFFICIENTS if coefficients is None else coefficients
    length = holder.length_m
    start = length - min(tool.inserted_length_m, length)
    gap_start = length - clamping.front_gap_length_m  # contact over [contact_start, gap_start]
    if gap_start <= start + _TOL_M:
        raise InputError("joints.holder_tool.front_gap_length_m",
                         f"leaves no contact: the inserted length in the holder is {length - start:g} m, the front "
                         f"gap {clamping.front_gap_length_m:g} m")
    contact_start = start if clamping.contact_length_m is None else max(start, gap_start - clamping.contact_length_m)
    tool_material = materials[tool.material]
    core = tube(tool.shank_diameter_m, 0.0, tool_material, shear, theory)
    beams: list[Beam] = []
    pieces: list[InsertionPiece] = []
    for hp in _holder_pieces(holder, c.step_cone):
        cuts = sorted({x for x in (start, contact_start, gap_start) if hp.x0_m + 1e-9 < x < hp.x1_m - 1e-9})
        seg, mat = hp.segment, materials[hp.segment.material]
        section = _annulus(hp, mat, shear, theory, c.holder_shear)
        for a, b in zip([hp.x0_m, *cuts], [*cuts, hp.x1_m], strict=True):
            if a < start - 1e-9:
                beams.append(Beam(section, b - a))
                continue
            if tool.shank_diameter_m > seg.inner_diameter_m * (1 + 1e-9):
                raise InputError(
                    "tool.shank_diameter_m",
                    f"the shank ({tool.shank_diameter_m:g} m) does not fit the bore ({seg.inner_diameter_m:g} m) of "
                    f"holder.segments[{hp.index}], which the inserted length ({tool.inserted_length_m:g} m) reaches")
            touching = contact_start - 1e-9 <= a and b <= gap_start + 1e-9
            k_w, k_theta = ((0j, 0j) if not touching else
                            interface_per_length(clamping, seg.outer_diameter_m, seg.inner_diameter_m,
                                                 tool.shank_diameter_m, mat, tool_material, c, gap_start - contact_start))
            annulus = _annulus(hp, mat, shear, theory, c.holder_shear, filled=True) if touching else section
            pieces.append(InsertionPiece(annulus, core, b - a, k_w, k_theta))
    return (*beams, Insertion(tuple(pieces)))


def face_contact(holder: HolderSpec, tool: ToolSpec, clamping: ClampingSpec) -> Spring | None:
    """The joint of a face-mounted tool (nothing inserted: a shell or face mill on an arbor).

    The tool's back face sits on the holder's front face; the contact is the annulus between
    the holder's last bore and the smaller of the two outer diameters. ``bonded``: an ideal
    face, rigid (``None``). ``contact``: the normal interface stiffness resists the rotation
    through the contact's second moment of area (``k_r = k_n I``), the tangential one the
    shear (``k_t = r_t k_n A``); the interface's loss factor is not carried (a point joint has
    viscous dampers only), the materials' is.

    Parameters
    ----------
    holder : HolderSpec
    tool : ToolSpec
        Face-mounted: ``stickout_m`` equal to ``overall_length_m``.
    clamping : ClampingSpec

    Returns
    -------
    Spring or None
    """
    if clamping.model != "contact" or clamping.interface_stiffness_n_m3 is None:
        return None
    last = holder.segments[-1]
    outer = min(last.outer_diameter_m, tool.shank_diameter_m)
    inner = min(last.inner_diameter_m, outer)
    area_m2 = math.pi * (outer**2 - inner**2) / 4.0
    inertia_m4 = math.pi * (outer**4 - inner**4) / 64.0
    k_n = clamping.interface_stiffness_n_m3 * clamping.interface_stiffness_scale
    return Spring(clamping.interface_tangential_ratio * k_n * area_m2, 0.0, k_n * inertia_m4, 0.0)


def clamping_notes(holder: HolderSpec, tool: ToolSpec, clamping: ClampingSpec) -> tuple[str, ...]:
    """Notes where a clamping model is used outside the range it was calibrated on.

    Parameters
    ----------
    holder : HolderSpec
    tool : ToolSpec
    clamping : ClampingSpec

    Returns
    -------
    tuple of str
    """
    if tool.inserted_length_m <= _TOL_M:
        return (f"face-mounted tool with clamping model {clamping.model!r}: "
                + ("an ideal (rigid) face" if clamping.model == "bonded" else
                   "the face contact's normal and tangential stiffness (its loss factor is not carried)")
                + "; face contacts are not calibrated on the 3-D reference",)
    notes = []
    d = tool.shank_diameter_m
    inserted = min(tool.inserted_length_m, holder.length_m) / d
    checks = [("the nose's outer diameter", holder.segments[-1].outer_diameter_m / d, "wall_ratio", "× the shank's"),
              ("the shank diameter", d * 1e3, "shank_diameter_m", " mm"),
              ("the inserted length", inserted, "insertion_diameters", " shank diameters")]
    for what, value, key, unit in checks:
        lo, hi = CALIBRATED_GEOMETRY_RANGES[key]
        scale = 1e3 if key == "shank_diameter_m" else 1.0
        if not lo * scale * (1 - 1e-9) <= value <= hi * scale * (1 + 1e-9):
            notes.append(f"clamping model {clamping.model!r}: {what} ({value:.3g}{unit}) is outside the range it was "
                         f"calibrated on ({lo * scale:g}–{hi * scale:g}{unit}); its interface stiffness is "
                         "extrapolated")
    return tuple(notes)
