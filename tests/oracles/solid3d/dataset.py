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
from dataclasses import asdict, replace
from pathlib import Path
from typing import Any

import numpy as np

from tests.oracles.solid3d.case import (
    Flutes,
    HolderSegment,
    Interface,
    MeshSize,
    SolidCase,
    SolidMaterial,
    ToolGeometry,
)

__all__ = ["BASES", "DATA_DIR", "FREQUENCY_HZ", "beam_document", "beam_tip_h", "case_document", "load_case",
           "reference_cases", "render_readme", "spindle_base_receptance", "standard_case", "with_mesh"]

DATA_DIR = Path(__file__).resolve().parents[2] / "data" / "solid3d"
#: the data set's frequency grid, Hz
FREQUENCY_HZ = np.arange(100.0, 6000.0 + 0.5, 1.0)
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
    return cases


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
    return {
        "holder": {"segments": [{"length_m": s.length_m, "outer_diameter_m": s.outer_diameter_m,
                                 "inner_diameter_m": s.inner_diameter_m, "material": "steel"}
                                for s in case.holder_segments]},
        "tool": tool_doc,
        "materials": {"steel": _material(case.holder_material), "carbide": _material(case.tool_material)},
        "interface": asdict(case.interface),
        "rigid_holder": case.rigid_holder,
        "mesh": asdict(case.mesh),
    }


def beam_document(case: SolidCase, frequency_hz: np.ndarray = FREQUENCY_HZ) -> dict[str, Any]:
    """The rcsa assembly of the same geometry on RA-1's spindle, with a rigid holder–tool joint.

    The contract's beam model: composite insertion, rigid point joint at the holder face,
    fluted part at ``fluted_diameter_ratio · DC`` (a real flute section has no contract
    equivalent beyond that ratio). RA-1's spindle and spindle–holder joint are kept.

    Parameters
    ----------
    case : SolidCase
    frequency_hz : numpy.ndarray
        Evenly spaced, Hz.

    Returns
    -------
    dict
    """
    from rcsa.reference import ra1

    doc = ra1({"start_hz": float(frequency_hz[0]), "stop_hz": float(frequency_hz[-1]),
               "step_hz": float(frequency_hz[1] - frequency_hz[0])})
    mine = case_document(case)
    doc["holder"] = mine["holder"]
    doc["tool"] = {k: v for k, v in mine["tool"].items() if k != "flutes"}
    doc["materials"] = {**doc.get("materials", {}), **mine["materials"]}
    doc["joints"] = {"spindle_holder": doc["joints"]["spindle_holder"]}
    return doc


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
        out: dict[str, Any] = {k: data[k] for k in data.files}
    out["frequency_hz"] = np.arange(grid["start_hz"], grid["stop_hz"] + 0.5 * grid["step_hz"], grid["step_hz"])
    for base in BASES:
        out[f"h_{base}"] = out[f"h_{base}"].astype(complex)
    out["case"] = entry
    return out


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
    conv = index.get("convergence", {}).get("tool_mode_hz", {})
    lines = [
        "# 3-D reference data set (holder + tool, linear elasticity)",
        "",
        "Written by `" + index.get("command", "python benchmarks/bench_solid3d.py --write-data") + "` (from the "
        "repository root, with the test extra installed); read with `tests.oracles.solid3d.dataset.load_case(name)`.",
        "Do not edit by hand.",
        "",
        "* `cases.json`: the frequency grid (100-6000 Hz, 1 Hz), the two bases, the base case's mesh-convergence "
        "sequence, and per case: the geometry in the contract's terms (`holder.segments`, `tool`, `materials`), "
        "the interface, `rigid_holder`, the mesh sizes, DOFs, elements, wall time, and per base the largest peak "
        "and the tool-mode peak with their convergence estimates and rcsa's beam prediction of the same geometry.",
        "* `<case>.npz`: `h_clamped`, `h_spindle` (tool-point receptance m/N, complex64, on the grid), "
        "`natural_frequencies_clamped_hz`, `natural_frequencies_spindle_hz` (undamped, in the band).",
        "* `spindle_base.npz`: the spindle base's 2x2 receptance at the gauge line (`receptance`, complex64; "
        "`undamped_receptance`, float32), rcsa's convention.",
        "",
        "Bases: `clamped` = the holder's base face fixed; `spindle` = RA-1's spindle and spindle-holder joint, "
        "condensed by rcsa to a 2x2 point receptance at the gauge line, coupled to the rigid base face in both "
        "bending planes (axial and torsion held).",
        "",
        f"Convergence (base case, clamped, tool mode): observed order {conv.get('observed_order', float('nan')):.2f}, "
        f"order used {conv.get('order', float('nan')):.2f}, remaining error of the data set's mesh "
        f"{conv.get('remaining_rel', float('nan')):.2%}.",
        "",
        "| case | what | DOF | clamped tool mode, Hz | conv. | spindle tool mode, Hz | conv. | wall s |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for name, e in index["cases"].items():
        c, sp_ = e["bases"]["clamped"]["tool_mode"], e["bases"]["spindle"]["tool_mode"]
        lines.append(f"| `{name}` | {e['description']} | {e['n_dof']} | {c['frequency_hz']:.1f} | "
                     f"{c['convergence']['frequency_rel']:.2%} | {sp_['frequency_hz']:.1f} | "
                     f"{sp_['convergence']['frequency_rel']:.2%} | {e['wall_s']:.0f} |")
    return "\n".join(lines) + "\n"
