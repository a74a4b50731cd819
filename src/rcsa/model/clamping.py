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
regenerates them; README "Clamping models" gives the fit, its validity range and its error).

A clamping given by its pressure instead of its stiffness uses the stated contact model
:func:`rcsa.physics.insertion.contact_stiffness_n_m3` (``k_n = p / σ``).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass

from rcsa.errors import InputError
from rcsa.model.contract import ClampingSpec, HolderSpec, ToolSpec
from rcsa.physics.chain import Spring
from rcsa.physics.insertion import Insertion, InsertionPiece, contact_per_length
from rcsa.physics.materials import Material
from rcsa.physics.sections import BeamTheory, ShearModel, tube

__all__ = ["BULK_COEFFICIENTS", "VALID_WALL_RATIO", "BulkCoefficients", "clamping_notes", "face_contact", "insertion_item", "interface_per_length"]

_TOL_M = 1e-12


@dataclass(frozen=True, slots=True)
class BulkCoefficients:
    """Dimensionless coefficients of the bulk interface stiffness (holder wall and shank surface).

    Holder wall, per unit length: ``k_h = E_h a_h τ^b_h / (1 + τ^b_h)`` with ``τ = (D − d)/d``
    (wall thickness over bore radius ×½), so a thin wall ovalises (``k_h ∝ τ^b``) and a thick
    one tends to ``a_h E_h``. Shank surface: ``k_s = a_s E_t``. In series: ``1/k_w = 1/k_h +
    1/k_s``. Rotational: ``k_θ = c_θ k_w (d/2)²``.

    Parameters
    ----------
    a_h, b_h : float
        Holder-wall coefficient and exponent.
    a_s : float
        Shank-surface coefficient.
    c_theta : float
        Rotational over translational, per (d/2)².
    """

    a_h: float
    b_h: float
    a_s: float
    c_theta: float


#: The fitted coefficients (``benchmarks/calibrate_clamping.py``).
BULK_COEFFICIENTS = BulkCoefficients(a_h=2.0, b_h=2.0, a_s=3.0, c_theta=1.0)
#: Holder outer diameter over bore diameter covered by the calibration cases.
VALID_WALL_RATIO = (1.3, 4.0)


def interface_per_length(clamping: ClampingSpec, holder_outer_diameter_m: float, bore_diameter_m: float,
                         shank_diameter_m: float, holder: Material, tool: Material,
                         coefficients: BulkCoefficients = BULK_COEFFICIENTS) -> tuple[complex, complex]:
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
    coefficients : BulkCoefficients
        The bulk coefficients (the fitted ones by default).

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
    c = coefficients
    d = shank_diameter_m
    tau = max(holder_outer_diameter_m - bore_diameter_m, 0.0) / d
    wall = tau**c.b_h / (1.0 + tau**c.b_h)
    k_h = holder.youngs_modulus_pa * (1 + 1j * holder.loss_factor) * c.a_h * wall
    k_s = tool.youngs_modulus_pa * (1 + 1j * tool.loss_factor) * c.a_s
    k_w = 1.0 / (1.0 / k_h + 1.0 / k_s) if wall > 0 else 0j
    k_theta = c.c_theta * k_w * (d / 2) ** 2
    if clamping.model == "contact":
        assert clamping.interface_stiffness_n_m3 is not None
        k_n = clamping.interface_stiffness_n_m3 * (1 + 1j * clamping.interface_loss_factor)
        k_t = clamping.interface_tangential_ratio * k_n
        iw, itheta = contact_per_length(k_n, k_t, d)
        k_w, k_theta = 1.0 / (1.0 / k_w + 1.0 / iw), 1.0 / (1.0 / k_theta + 1.0 / itheta)
    return complex(k_w * clamping.interface_scale), complex(k_theta * clamping.interface_scale)


def insertion_item(holder: HolderSpec, tool: ToolSpec, clamping: ClampingSpec, materials: Mapping[str, Material],
                   shear: ShearModel | float = "hutchinson", theory: BeamTheory = "timoshenko") -> Insertion:
    """The chain item of the inserted length: holder annulus and shank core, joined by the interface.

    Pieces from where the insertion starts (toward the spindle) to the holder's tool-end face,
    cut at the holder's section steps and where the contact begins and ends: the shank touches
    the bore from ``front_gap_length_m`` behind the face over ``contact_length_m`` (default: to
    the end of the insertion); elsewhere the two beams are free of each other.

    Parameters
    ----------
    holder : HolderSpec
    tool : ToolSpec
        Its shank fills the bore over the inserted length (beyond the holder: ignored).
    clamping : ClampingSpec
    materials : mapping of str to Material
        Materials by name.
    shear : {"hutchinson", "cowper"} or float
    theory : {"timoshenko", "euler_bernoulli"}

    Returns
    -------
    Insertion

    Raises
    ------
    InputError
        The shank does not fit a bore it reaches, or the front gap leaves no contact.
    """
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
    pieces: list[InsertionPiece] = []
    x0 = 0.0
    for i, seg in enumerate(holder.segments):
        x1 = x0 + seg.length_m
        cuts = sorted({x for x in (start, contact_start, gap_start) if x0 + 1e-9 < x < x1 - 1e-9})
        for a, b in zip([x0, *cuts], [*cuts, x1], strict=True):
            if a < start - 1e-9:
                continue
            if tool.shank_diameter_m > seg.inner_diameter_m * (1 + 1e-9):
                raise InputError(
                    "tool.shank_diameter_m",
                    f"the shank ({tool.shank_diameter_m:g} m) does not fit the bore ({seg.inner_diameter_m:g} m) of "
                    f"holder.segments[{i}], which the inserted length ({tool.inserted_length_m:g} m) reaches")
            holder_material = materials[seg.material]
            annulus = tube(seg.outer_diameter_m, seg.inner_diameter_m, holder_material, shear, theory)
            touching = contact_start - 1e-9 <= a and b <= gap_start + 1e-9
            k_w, k_theta = ((0j, 0j) if not touching else
                            interface_per_length(clamping, seg.outer_diameter_m, seg.inner_diameter_m,
                                                 tool.shank_diameter_m, holder_material, tool_material))
            pieces.append(InsertionPiece(annulus, core, b - a, k_w, k_theta))
        x0 = x1
    return Insertion(tuple(pieces))


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
    k_n = clamping.interface_stiffness_n_m3 * clamping.interface_scale
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
    length = holder.length_m
    start = length - min(tool.inserted_length_m, length)
    x0 = 0.0
    lo, hi = VALID_WALL_RATIO
    for i, seg in enumerate(holder.segments):
        x1 = x0 + seg.length_m
        if x1 > start + 1e-9:
            ratio = seg.outer_diameter_m / tool.shank_diameter_m
            if not lo <= ratio <= hi:
                notes.append(f"clamping model {clamping.model!r}: holder.segments[{i}] has an outer diameter "
                             f"{ratio:.3g} times the shank's, outside the calibrated range {lo:g}–{hi:g}; "
                             "the interface stiffness is extrapolated")
        x0 = x1
    return tuple(notes)
