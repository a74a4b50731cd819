"""The 3-D reference data set: its cases, its files, and the beam model's view of each case.

``benchmarks/bench_solid3d.py --write-data`` computes every case of :func:`reference_cases`
and writes ``tests/data/solid3d/``: ``cases.json`` (each case in the contract's terms, with
its mesh, DOFs, convergence estimate and wall time) and one ``<name>.npz`` per case holding
the tool-point h for the two bases. :func:`load_case` reads one back.

Bases: ``clamped`` (the holder's base face fixed) and ``spindle`` (RA-1's spindle with
RA-1's spindle–holder joint, condensed by rcsa to a 2×2 point receptance at the gauge line:
:func:`spindle_base_receptance`).
"""

from __future__ import annotations

import json
import math
from dataclasses import asdict, replace
from pathlib import Path
from typing import Any

import numpy as np

from tests.oracles.solid3d.case import (
    Flutes,
    HolderRing,
    HolderSegment,
    Interface,
    MeshSize,
    ShankFlat,
    SolidCase,
    SolidMaterial,
    ToolGeometry,
)
from tests.oracles.solid3d.reduction import ReducedModel

__all__ = ["BASES", "DATA_DIR", "FAMILIES", "FAMILY_REFERENCE", "FREQUENCY_HZ", "beam_document", "beam_tip_h",
           "case_document", "case_family", "family_cases", "load_case", "load_reduced", "reference_cases",
           "render_readme", "spindle_base_receptance", "standard_case", "with_mesh"]

DATA_DIR = Path(__file__).resolve().parents[2] / "data" / "solid3d"
#: the data set's frequency grid, Hz
FREQUENCY_HZ = np.arange(100.0, 8000.0 + 0.5, 1.0)
#: holder families: the issue-24 holder (a shrink-fit-like stepped holder, cylindrical nose) and
#: four built to test the clamping model on holders its calibration did not see
FAMILIES = ("stepped", "shrink_slender", "hydraulic", "collet", "sidelock")
#: each family's case whose mesh-convergence sequence sets the order of its cases' estimates
FAMILY_REFERENCE = {"stepped": "base_d10", "shrink_slender": "shrink_slender_d10", "hydraulic": "hydraulic_d12",
                    "collet": "collet_d10", "sidelock": "sidelock_d10"}
BASES = ("clamped", "spindle")
#: element size in the tool, as a fraction of the shank diameter (the data set's mesh)
TOOL_SIZE_RATIO = 0.15


def standard_case(diameter_m: float = 0.010, *, nose_outer_diameter_m: float | None = None,
                  insertion_diameters: float = 3.5, stickout_diameters: float = 4.0,
                  interface: Interface | None = None, flutes: Flutes | None = None,
                  rigid_holder: bool = False) -> SolidCase:
    """A shrink-fit-like holder with a carbide end mill of diameter d (shank = cutting = bore).

    Holder (from the gauge line): flange Ø63 × 24 mm, body Ø max(40, nose + 14 mm) × 30 mm,
    nose Ø 2.6 d × max(40 mm, insertion) — at d = 10 mm the issue's Ø63 × 24, Ø40 × 30,
    Ø26 × 40 with a Ø10 bore; the bore runs through. Tool: insertion 3.5 d, stickout 4 d,
    flute length 2.5 d, round flutes at 0.8 d unless ``flutes`` are given.

    Parameters
    ----------
    diameter_m : float
        d, m.
    nose_outer_diameter_m : float, optional
        Default 2.6 d.
    insertion_diameters, stickout_diameters : float
        Inserted length and stickout in diameters.
    interface : Interface, optional
        Default bonded.
    flutes : Flutes, optional
    rigid_holder : bool

    Returns
    -------
    SolidCase
    """
    d = diameter_m
    nose = nose_outer_diameter_m or 2.6 * d
    insertion, stickout = insertion_diameters * d, stickout_diameters * d
    nose_length = max(0.040, insertion)
    body = max(0.040, nose + 0.014)
    holder = (HolderSegment(0.024, 0.063, d), HolderSegment(0.030, body, d), HolderSegment(nose_length, nose, d))
    tool = ToolGeometry(diameter_m=d, shank_diameter_m=d, overall_length_m=round(insertion + stickout, 9),
                        flute_length_m=2.5 * d, stickout_m=stickout, flutes=flutes)
    return SolidCase(holder, tool, interface=interface or Interface(), rigid_holder=rigid_holder,
                     mesh=MeshSize(TOOL_SIZE_RATIO * d, 0.008, 0.3))


def reference_cases() -> dict[str, tuple[SolidCase, str]]:
    """Every case of the data set: name → (case, one-line description).

    Returns
    -------
    dict
    """
    cases: dict[str, tuple[SolidCase, str]] = {
        "base_d10": (standard_case(), "the issue's holder (Ø63x24, Ø40x30, Ø26x40, Ø10 bore), Ø10 carbide tool, "
                                      "insertion 35 mm, stickout 40 mm, bonded"),
    }
    for d in (0.006, 0.008, 0.012, 0.016, 0.020):
        cases[f"diameter_d{d * 1e3:g}"] = (standard_case(d), f"tool and bore Ø{d * 1e3:g} mm, nose 2.6 d, "
                                                             "insertion 3.5 d, stickout 4 d, bonded")
    for ratio in (1.6, 2.2, 3.2, 4.0):
        cases[f"nose_od{ratio:g}d"] = (standard_case(nose_outer_diameter_m=ratio * 0.010),
                                       f"Ø10 tool, nose Ø{ratio * 10:g} mm (wall {(ratio - 1) * 5:g} mm), bonded")
    for n in (2.0, 3.0, 5.0):
        cases[f"insertion_{n:g}d"] = (standard_case(insertion_diameters=n), f"Ø10 tool, insertion {n:g} d, bonded")
    for n in (3.0, 5.0, 6.0):
        cases[f"stickout_{n:g}d"] = (standard_case(stickout_diameters=n), f"Ø10 tool, stickout {n:g} d, bonded")
    for k in (1e13, 3e13, 1e14, 1e15):
        cases[f"layer_k{k:.0e}".replace("+", "")] = (
            standard_case(interface=Interface("layer", k)),
            f"Ø10 tool, spring layer k_n = k_t = {k:.0e} N/m^3 over the insertion")
    cases["contact_front_15mm"] = (standard_case(interface=Interface(contact_stop_m=0.015)),
                                   "Ø10 tool, bonded over the front 15 mm of the bore only (gap behind)")
    cases["contact_lost_front_10mm"] = (standard_case(interface=Interface(contact_start_m=0.010)),
                                        "Ø10 tool, contact lost over the front 10 mm of the bore (bonded behind)")
    cases["flutes_2"] = (standard_case(flutes=Flutes(2, 0.5 * 0.010, 0.27 * 0.010)),
                         "Ø10 tool, real 2-flute section (core 0.5 d, gullet radius 0.27 d, gullets on x), straight")
    cases["flutes_4"] = (standard_case(flutes=Flutes(4, 0.6 * 0.010, 0.16 * 0.010)),
                         "Ø10 tool, real 4-flute section (core 0.6 d, gullet radius 0.16 d, gullets on x, y), straight")
    cases["rigid_holder"] = (standard_case(rigid_holder=True),
                             "the base case with the holder rigid (tied to the base's rigid-body DOFs)")
    cases.update({name: (case, text) for name, (case, text, _) in family_cases().items()})
    return cases


def case_family(name: str) -> str:
    """The holder family of a case of :func:`reference_cases`."""
    found = family_cases().get(name)
    return found[2] if found is not None else "stepped"


def _tool(d: float, insertion_m: float, stickout_m: float, flat: ShankFlat | None = None) -> ToolGeometry:
    return ToolGeometry(diameter_m=d, shank_diameter_m=d, overall_length_m=round(insertion_m + stickout_m, 9),
                        flute_length_m=2.5 * d, stickout_m=stickout_m, flat=flat)


def _mesh(d: float) -> MeshSize:
    return MeshSize(TOOL_SIZE_RATIO * d, 0.008, 0.3)


def family_cases() -> dict[str, tuple[SolidCase, str, str]]:
    """The holder families other than the issue-24 holder: name → (case, description, family).

    Two of each (another tool diameter, holder size and stickout), steel holders, carbide
    tools with round flutes at 0.8 d:

    * ``shrink_slender``: a slim shrink-fit chuck whose nose is a 4.5° cone down to a wall of
      half the bore at the face; bonded.
    * ``hydraulic``: a hydraulic chuck: a thick body whose expansion sleeve and oil chamber
      act on the shank as a compliant layer (k_n = 6e12 N/m³, k_t = 0.4 k_n: the oil film's
      bulk stiffness over its thickness, the sleeve's shear), over the sleeve's length only.
    * ``collet``: an ER collet chuck: the collet grips the front of the shank only (partial
      contact, gaps in front of and behind it) and its clamping nut is a ring around the nose,
      screwed on over its back third and standing 0.3 mm off the nose in front (its mass).
    * ``sidelock``: a Weldon side-lock holder: a flat on the shank with the screw on it, the
      shank pushed against the back of the bore (contact over a 120° arc opposite the screw,
      at the back of the bore only; a clearance in front).

    Returns
    -------
    dict
    """
    out: dict[str, tuple[SolidCase, str, str]] = {}
    for d, stickout, insertion, front, nose_len in ((0.010, 0.045, 0.036, 0.020, 0.060),
                                                    (0.006, 0.030, 0.024, 0.013, 0.050)):
        back = front + 2 * nose_len * math.tan(math.radians(4.5))
        holder = (HolderSegment(0.022, 0.063, d), HolderSegment(0.010, 0.044, d),
                  HolderSegment(nose_len, round(back, 6), d, outer_diameter_end_m=front))
        out[f"shrink_slender_d{d * 1e3:g}"] = (
            SolidCase(holder, _tool(d, insertion, stickout), mesh=_mesh(d)),
            f"slim shrink-fit: Ø63x22 flange, Ø44x10 body, 4.5° nose cone Ø{back * 1e3:.1f}->Ø{front * 1e3:g} over "
            f"{nose_len * 1e3:g} mm, Ø{d * 1e3:g} tool, insertion {insertion * 1e3:g} mm, stickout {stickout * 1e3:g} mm, "
            "bonded", "shrink_slender")
    for d, body, nose, nose_len, stickout, insertion, sleeve in ((0.012, 0.050, 0.032, 0.052, 0.048, 0.046, (0.005, 0.041)),
                                                                 (0.020, 0.056, 0.045, 0.055, 0.060, 0.050, (0.006, 0.046))):
        holder = (HolderSegment(0.024, 0.063, d), HolderSegment(0.028, body, d), HolderSegment(nose_len, nose, d))
        layer = Interface("layer", 6e12, tangential_ratio=0.4, contact_start_m=sleeve[0], contact_stop_m=sleeve[1])
        out[f"hydraulic_d{d * 1e3:g}"] = (
            SolidCase(holder, _tool(d, insertion, stickout), interface=layer, mesh=_mesh(d)),
            f"hydraulic chuck: Ø63x24 flange, Ø{body * 1e3:g}x28 body, Ø{nose * 1e3:g}x{nose_len * 1e3:g} nose, Ø{d * 1e3:g} "
            f"tool, insertion {insertion * 1e3:g} mm, stickout {stickout * 1e3:g} mm, sleeve as a layer k_n 6e12 N/m^3, "
            f"k_t 0.4 k_n, {sleeve[0] * 1e3:g}-{sleeve[1] * 1e3:g} mm deep", "hydraulic")
    for d, neck, nose, nose_len, nut, stickout, insertion, grip in ((0.010, 0.032, 0.034, 0.026, (0.042, 0.020, 0.008),
                                                                    0.040, 0.032, (0.001, 0.020)),
                                                                   (0.016, 0.040, 0.044, 0.030, (0.050, 0.022, 0.009),
                                                                    0.056, 0.040, (0.0015, 0.026))):
        holder = (HolderSegment(0.024, 0.063, d), HolderSegment(0.025, neck, d), HolderSegment(nose_len, nose, d))
        ring = HolderRing(nut[0], nut[1], attached_length_m=nut[2], clearance_m=3e-4)
        grip_face = Interface(contact_start_m=grip[0], contact_stop_m=grip[1])
        out[f"collet_d{d * 1e3:g}"] = (
            SolidCase(holder, _tool(d, insertion, stickout), interface=grip_face, mesh=_mesh(d), rings=(ring,)),
            f"ER collet chuck: Ø63x24 flange, Ø{neck * 1e3:g}x25 neck, Ø{nose * 1e3:g}x{nose_len * 1e3:g} nose, nut "
            f"Ø{nut[0] * 1e3:g}x{nut[1] * 1e3:g} screwed on over {nut[2] * 1e3:g} mm, Ø{d * 1e3:g} tool gripped "
            f"{grip[0] * 1e3:g}-{grip[1] * 1e3:g} mm deep, insertion {insertion * 1e3:g} mm, stickout {stickout * 1e3:g} mm",
            "collet")
    for d, body, body_len, depth, flat_at, screw, stickout, insertion, gap in (
            (0.010, 0.040, 0.050, 0.0010, (0.018, 0.014), 0.005, 0.040, 0.036, 0.014),
            (0.016, 0.050, 0.055, 0.0014, (0.026, 0.020), 0.008, 0.060, 0.048, 0.020)):
        holder = (HolderSegment(0.024, 0.063, d), HolderSegment(body_len, body, d))
        flat = ShankFlat(depth, flat_at[0], flat_at[1], screw)
        back_contact = Interface(contact_start_m=gap, arc_deg=120.0)
        out[f"sidelock_d{d * 1e3:g}"] = (
            SolidCase(holder, _tool(d, insertion, stickout, flat), interface=back_contact, mesh=_mesh(d)),
            f"Weldon side-lock: Ø63x24 flange, Ø{body * 1e3:g}x{body_len * 1e3:g} body, Ø{d * 1e3:g} tool with a "
            f"{depth * 1e3:g} mm flat {flat_at[0] * 1e3:g}-{sum(flat_at) * 1e3:g} mm deep, Ø{screw * 1e3:g} screw on "
            f"it, contact over 120° at the back of the bore from {gap * 1e3:g} mm deep, insertion {insertion * 1e3:g} "
            f"mm, stickout {stickout * 1e3:g} mm", "sidelock")
    return out


def _material(m: SolidMaterial) -> dict[str, float]:
    return {"youngs_modulus_pa": m.youngs_modulus_pa, "poisson_ratio": m.poisson_ratio,
            "density_kg_m3": m.density_kg_m3, "loss_factor": m.loss_factor}


def case_document(case: SolidCase) -> dict[str, Any]:
    """A case in the contract's terms (holder segments, tool, materials) plus the 3-D extras.

    Parameters
    ----------
    case : SolidCase

    Returns
    -------
    dict
        ``holder``, ``tool`` (contract fields; ``flutes`` when a real section is used),
        ``materials`` (``steel`` for the holder, ``carbide`` for the tool), ``interface``,
        ``rigid_holder``, ``mesh``.
    """
    tool = case.tool
    tool_doc: dict[str, Any] = {"material": "carbide", "diameter_m": tool.diameter_m,
                                "shank_diameter_m": tool.shank_diameter_m,
                                "overall_length_m": tool.overall_length_m,
                                "flute_length_m": tool.flute_length_m, "stickout_m": tool.stickout_m,
                                "fluted_diameter_ratio": tool.fluted_diameter_ratio}
    if tool.flutes is not None:
        tool_doc["flutes"] = asdict(tool.flutes)
    if tool.flat is not None:
        tool_doc["flat"] = asdict(tool.flat)
    segments = []
    for seg in case.holder_segments:
        doc: dict[str, Any] = {"length_m": seg.length_m, "outer_diameter_m": seg.outer_diameter_m,
                               "inner_diameter_m": seg.inner_diameter_m, "material": "steel"}
        if seg.is_cone:
            doc["outer_diameter_end_m"] = seg.outer_diameter_end_m
        segments.append(doc)
    out = {
        "holder": {"segments": segments},
        "tool": tool_doc,
        "materials": {"steel": _material(case.holder_material), "carbide": _material(case.tool_material)},
        "interface": asdict(case.interface),
        "rigid_holder": case.rigid_holder,
        "mesh": asdict(case.mesh),
    }
    if case.rings:
        out["rings"] = [asdict(r) for r in case.rings]
    return out


def beam_document(case: SolidCase, frequency_hz: np.ndarray = FREQUENCY_HZ) -> dict[str, Any]:
    """The rcsa assembly of the same geometry on RA-1's spindle, with a rigid holder–tool joint.

    The contract's beam model: composite insertion, rigid point joint at the holder face,
    fluted part at ``fluted_diameter_ratio · DC`` (a real flute section has no contract
    equivalent beyond that ratio). A cone is stepped as a tool library's cone is
    (:func:`rcsa.libraries.profiles.cone_cylinders`); a nut is the holder's outline over its
    length, as a library draws the holder; a side-lock flat is left out (the contract's shank is
    round). RA-1's spindle and spindle–holder joint are kept.

    Parameters
    ----------
    case : SolidCase
    frequency_hz : numpy.ndarray
        Evenly spaced, Hz.

    Returns
    -------
    dict
    """
    from rcsa.libraries.profiles import cone_cylinders
    from rcsa.reference import ra1

    doc = ra1({"start_hz": float(frequency_hz[0]), "stop_hz": float(frequency_hz[-1]),
               "step_hz": float(frequency_hz[1] - frequency_hz[0])})
    mine = case_document(case)
    segments = []
    for seg in mine["holder"]["segments"]:    # a cone stepped as a tool library's cone is
        end = seg.pop("outer_diameter_end_m", None)
        pieces = [(seg["length_m"], seg["outer_diameter_m"])] if end is None else \
            cone_cylinders(seg["length_m"], seg["outer_diameter_m"], end)
        segments.extend({**seg, "length_m": length, "outer_diameter_m": od} for length, od in pieces)
    for ring in case.rings:                   # a nut is part of the holder's outline, as a library draws it
        segments = _with_ring(segments, case.holder_length_m - ring.front_offset_m - ring.length_m,
                              case.holder_length_m - ring.front_offset_m, ring.outer_diameter_m)
    doc["holder"] = {"segments": segments}
    doc["tool"] = {k: v for k, v in mine["tool"].items() if k not in ("flutes", "flat")}
    doc["materials"] = {**doc.get("materials", {}), **mine["materials"]}
    doc["joints"] = {"spindle_holder": doc["joints"]["spindle_holder"]}
    return doc


def _with_ring(segments: list[dict[str, Any]], z0_m: float, z1_m: float, outer_diameter_m: float
               ) -> list[dict[str, Any]]:
    """Contract holder segments with the outline widened to ``outer_diameter_m`` over z0–z1."""
    out, z = [], 0.0
    for seg in segments:
        a, b = z, z + seg["length_m"]
        cuts = sorted({a, b, *(x for x in (z0_m, z1_m) if a + 1e-12 < x < b - 1e-12)})
        for lo, hi in zip(cuts[:-1], cuts[1:], strict=True):
            inside = z0_m - 1e-12 <= lo and hi <= z1_m + 1e-12
            out.append({**seg, "length_m": round(hi - lo, 12),
                        "outer_diameter_m": max(seg["outer_diameter_m"], outer_diameter_m) if inside
                        else seg["outer_diameter_m"]})
        z = b
    return out


def spindle_base_receptance(frequency_hz: np.ndarray = FREQUENCY_HZ) -> tuple[np.ndarray, np.ndarray]:
    """RA-1's spindle and spindle–holder joint as a point receptance at the gauge line (rcsa).

    Parameters
    ----------
    frequency_hz : numpy.ndarray, shape (nfreq,)

    Returns
    -------
    (numpy.ndarray, numpy.ndarray)
        Damped and undamped receptance, shape (nfreq, 2, 2), rcsa's convention.
    """
    from rcsa.model.assembly import build_model
    from rcsa.model.contract import parse_assembly
    from rcsa.physics.elimination import tip_receptance
    from rcsa.reference import ra1

    chain = build_model(parse_assembly(ra1())).spindle_side()
    omega = 2 * np.pi * np.asarray(frequency_hz, dtype=float)
    return tip_receptance(chain, omega), tip_receptance(tuple(item.undamped() for item in chain), omega)


def beam_tip_h(case: SolidCase, base: str, frequency_hz: np.ndarray = FREQUENCY_HZ, rigid_holder: bool = False
               ) -> np.ndarray:
    """rcsa's tool-point h of the case (contract beam model, rigid holder–tool point joint).

    Parameters
    ----------
    case : SolidCase
    base : {"clamped", "spindle"}
        ``clamped``: the holder's gauge-line end fixed; ``spindle``: RA-1's spindle side.
    frequency_hz : numpy.ndarray
    rigid_holder : bool
        Drop the holder: the tool overhang clamped at the holder face (the beam's view of a
        rigid holder with a clamped base). A case with ``rigid_holder`` gets a holder of
        steel 10⁴ times stiffer on either base.

    Returns
    -------
    numpy.ndarray, shape (nfreq,), complex
    """
    from rcsa.model.assembly import build_model, holder_chain
    from rcsa.model.contract import parse_assembly
    from rcsa.physics.chain import Ground
    from rcsa.physics.elimination import tip_receptance

    spec = parse_assembly(beam_document(case, frequency_hz))
    model = build_model(spec)
    if case.rigid_holder:   # the beam's rigid holder: its steel 10⁴ times stiffer (past the contract's bounds)
        steel = spec.materials["steel"]
        stiff = {**spec.materials, "steel": replace(steel, youngs_modulus_pa=1e4 * steel.youngs_modulus_pa)}
        assert spec.holder is not None
        model = replace(model, holder=holder_chain(spec.holder, spec.tool, stiff, spec.shear_coefficient,
                                                   spec.beam_theory))
    omega = 2 * np.pi * np.asarray(frequency_hz, dtype=float)
    clamp = (Ground(1e15, 0.0, 1e15, 0.0),)
    if rigid_holder:
        if base != "clamped":
            raise ValueError("the beam's rigid holder is defined for the clamped base only")
        chain = clamp + model.tool_side()
    elif base == "clamped":
        chain = clamp + model.holder + model.tool_side()
    elif base == "spindle":
        chain = model.chain()
    else:
        raise ValueError("base must be 'clamped' or 'spindle'")
    return tip_receptance(chain, omega)[:, 0, 0]


def load_case(name: str, directory: Path = DATA_DIR) -> dict[str, Any]:
    """One case of the data set.

    Parameters
    ----------
    name : str
        A key of ``cases.json``.
    directory : pathlib.Path

    Returns
    -------
    dict
        ``frequency_hz`` (nfreq,), ``h_clamped`` and ``h_spindle`` (nfreq,) complex m/N,
        ``natural_frequencies_clamped_hz``, ``natural_frequencies_spindle_hz``, and
        ``case`` (the entry of ``cases.json``).
    """
    index = json.loads((directory / "cases.json").read_text())
    entry = index["cases"][name]
    grid = index["frequency"]
    with np.load(directory / f"{name}.npz") as data:
        out: dict[str, Any] = {k: data[k] for k in data.files if not k.startswith("reduced_")}
    out["frequency_hz"] = np.arange(grid["start_hz"], grid["stop_hz"] + 0.5 * grid["step_hz"], grid["step_hz"])
    for base in BASES:
        out[f"h_{base}"] = out[f"h_{base}"].astype(complex)
    out["case"] = entry
    return out


def load_reduced(name: str, directory: Path = DATA_DIR) -> ReducedModel:
    """The stored Craig–Bampton model of a case (the data set's mesh, base DOFs kept).

    With it the case's tool-point receptance is exact on any base receptance and any grid up to
    its cut-off / 2.5 (:func:`tests.oracles.solid3d.reduction.tip_receptance`; base held:
    ``base_stiffness=None``).

    Parameters
    ----------
    name : str
    directory : pathlib.Path

    Returns
    -------
    ReducedModel
    """
    from tests.oracles.solid3d.reduction import reduced_from_arrays

    with np.load(directory / f"{name}.npz") as data:
        return reduced_from_arrays({k: data[k] for k in data.files if k.startswith("reduced_")})


def with_mesh(case: SolidCase, factor: float) -> SolidCase:
    """The case with every element size times ``factor``."""
    return replace(case, mesh=case.mesh.scaled(factor))



def render_readme(index: dict[str, Any]) -> str:
    """The data set's README.md, from ``cases.json``.

    Parameters
    ----------
    index : dict
        The parsed ``cases.json``.

    Returns
    -------
    str
    """
    grid = index["frequency"]
    band = f"{grid['start_hz']:g}-{grid['stop_hz']:g} Hz, {grid['step_hz']:g} Hz"
    lines = [
        "# 3-D reference data set (holder + tool, linear elasticity)",
        "",
        "Written by `" + index.get("command", "python benchmarks/bench_solid3d.py --write-data") + "` (from the "
        "repository root, with the test extra installed); read with `tests.oracles.solid3d.dataset.load_case(name)` "
        "and `load_reduced(name)`. Do not edit by hand.",
        "",
        f"* `cases.json`: the frequency grid ({band}), the two bases, each holder family's mesh-convergence "
        "sequence, and per case: its family, the geometry in the contract's terms (`holder.segments`, a cone's "
        "`outer_diameter_end_m`, `tool`, a side-lock `flat`, a nut's `rings`, `materials`), the interface, "
        "`rigid_holder`, the mesh sizes, DOFs, elements, wall time, and per base the undamped natural frequencies "
        "on the data set's mesh and on one 1.587 times coarser, the largest peak and the tool-mode peak with their "
        "convergence estimates and rcsa's beam prediction of the same geometry.",
        "* `<case>.npz`: `h_clamped`, `h_spindle` (tool-point receptance m/N, complex64, on the grid), "
        "`natural_frequencies_clamped_hz`, `natural_frequencies_spindle_hz` (undamped, in the band), and the "
        "Craig-Bampton model of the data set's mesh (`reduced_*`: per-part stiffness with its loss factor, mass, "
        "tip loads, base DOFs last), from which the tool-point receptance on any base and grid up to "
        f"{grid['stop_hz']:g} Hz is exact (`load_reduced`).",
        "* `spindle_base.npz`: the spindle base's 2x2 receptance at the gauge line (`receptance`, complex64; "
        "`undamped_receptance`, float32), rcsa's convention.",
        "",
        "Bases: `clamped` = the holder's base face fixed; `spindle` = RA-1's spindle and spindle-holder joint, "
        "condensed by rcsa to a 2x2 point receptance at the gauge line, coupled to the rigid base face in both "
        "bending planes (axial and torsion held).",
        "",
        "Convergence (each family's reference case, clamped, tool mode; each case's estimate uses its family's "
        "order, never below its family's remaining error):",
        "",
    ]
    for family, conv in index.get("convergence_by_family", {}).items():
        c = conv.get("tool_mode_hz", {})
        lines.append(f"* {family} (`{conv.get('case', '')}`): observed order {c.get('observed_order', float('nan')):.2f}, "
                     f"order used {c.get('order', float('nan')):.2f}, remaining error of the data set's mesh "
                     f"{c.get('remaining_rel', float('nan')):.2%}.")
    lines += [
        "",
        "| case | family | what | DOF | clamped tool mode, Hz | conv. | spindle tool mode, Hz | conv. | wall s |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for name, e in index["cases"].items():
        c, sp_ = e["bases"]["clamped"]["tool_mode"], e["bases"]["spindle"]["tool_mode"]
        lines.append(f"| `{name}` | {e.get('family', 'stepped')} | {e['description']} | {e['n_dof']} | "
                     f"{c['frequency_hz']:.1f} | {c['convergence']['frequency_rel']:.2%} | {sp_['frequency_hz']:.1f} | "
                     f"{sp_['convergence']['frequency_rel']:.2%} | {e['wall_s']:.0f} |")
    return "\n".join(lines) + "\n"
