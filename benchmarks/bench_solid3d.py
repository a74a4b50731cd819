"""The 3-D linear-elastic reference of holder + tool: verification, convergence, data set (issue 24).

Prints
1. the rod verification table (3-D vs exact Timoshenko / rcsa's exact chain);
2. the mesh-convergence table of the base case (tool-mode frequency, peak and static
   compliance at 4 sizes; observed order and Richardson estimate of the remaining error)
   and the Craig–Bampton truncation error against a direct sparse complex solve;
3. the case list: per base (clamped, RA-1 spindle) the tool-mode frequency and peak of the
   3-D reference, and — for information — rcsa's beam prediction of the same geometry
   (composite insertion, rigid point joint at the holder face): frequency error of the
   largest peak, peak-height error, mean |dB| over 100–6000 Hz;
4. the rigid-holder measurement (how much of the 3-D model's extra compliance the holder's
   deformation accounts for).

``--write-data`` writes ``tests/data/solid3d/`` (cases.json, one .npz per case).

    .venv/bin/python benchmarks/bench_solid3d.py --write-data      # ~1 h on a loaded 2-core VM
    .venv/bin/python benchmarks/bench_solid3d.py --cases base_d10   # one case
"""

from __future__ import annotations

import argparse
import json
import os
import time
from pathlib import Path

import numpy as np
from filelock import FileLock
from tests.oracles.solid3d import dataset
from tests.oracles.solid3d.case import CARBIDE, STEEL, MeshSize
from tests.oracles.solid3d.dataset import (
    BASES,
    FAMILY_REFERENCE,
    FREQUENCY_HZ,
    beam_tip_h,
    case_document,
    case_family,
    load_case,
    reference_cases,
    render_readme,
    spindle_base_receptance,
    standard_case,
    with_mesh,
)
from tests.oracles.solid3d.geometry import Piece
from tests.oracles.solid3d.reduction import reduced_arrays
from tests.oracles.solid3d.solve import (
    CUTOFF_FACTOR,
    ReceptanceBase,
    SolidModel,
    build,
    build_body,
    largest_peak,
    solve_model,
    truncation_error,
)

from rcsa.physics.chain import Beam, Ground
from rcsa.physics.materials import Material
from rcsa.physics.natural_frequencies import natural_frequencies_hz
from rcsa.physics.sections import composite, tube

#: where --write-data writes (``--out`` overrides the data set's folder)
OUT = [dataset.DATA_DIR]
RC_STEEL = Material(210e9, 0.30, 7850.0)
RC_CARBIDE = Material(600e9, 0.22, 14500.0)
CUTOFF_HZ = CUTOFF_FACTOR * float(FREQUENCY_HZ[-1])
#: mesh factors of the convergence sequence (× the data set's sizes), coarse → fine
CONVERGENCE_FACTORS = (2.0, 1.587, 1.26, 1.0)
#: the coarser mesh every case is also solved on, for its own convergence estimate
CHECK_FACTOR = 1.587
#: the tool mode on an elastic base: the largest peak within these multiples of the clamped tool mode
TOOL_BAND = (0.5, 1.1)


def load() -> str:
    """The 1-minute load average, for the record."""
    return f"load {os.getloadavg()[0]:.1f}"


def mean_abs_db(a: np.ndarray, b: np.ndarray) -> float:
    """Mean |20 log10(|a| / |b|)| over the grid, dB."""
    return float(np.mean(np.abs(20 * np.log10(np.abs(a) / np.abs(b)))))


# ------------------------------------------------------------------------------------------
# 1. rods


def _free_rod(pieces: tuple[Piece, ...], size_m: float) -> np.ndarray:
    from tests.oracles.solid3d.assembly import assemble
    from tests.oracles.solid3d.case import Interface
    from tests.oracles.solid3d.geometry import mesh_pieces
    from tests.oracles.solid3d.reduction import free_frequencies_hz

    mesh = mesh_pieces(pieces, MeshSize(size_m, size_m), quarter=True)
    mats = assemble(mesh, (STEEL, CARBIDE), Interface(), "free", max(p.z1_m for p in pieces))
    return free_frequencies_hz(mats, 3)


def rods() -> list[tuple[str, np.ndarray, np.ndarray]]:
    """(name, 3-D, reference) natural frequencies of the verification rods."""
    rows = []
    rows.append(("free-free Ø20x300 steel (O5, exact)", _free_rod((Piece("holder", 0, 0.3, 0.02),), 0.0025),
                 np.array([1011.50, 2732.44, 5209.91])))
    rows.append(("free-free Ø80x250 steel (O4, exact)", _free_rod((Piece("holder", 0, 0.25, 0.08),), 0.01),
                 np.array([4823.72, 10526.82, 16753.17])))
    f = _free_rod((Piece("holder", 0, 0.3, 0.04, 0.02),), 0.005)
    exact = natural_frequencies_hz((Beam(tube(0.04, 0.02, RC_STEEL), 0.3),), 100.0, 1.2 * f[-1])[:3]
    rows.append(("free-free tube Ø40/Ø20x300 (rcsa)", f, exact))
    for d_o, d_i, length, size in ((0.02, 0.008, 0.3, 0.0025), (0.04, 0.016, 0.25, 0.005)):
        f = _free_rod((Piece("holder", 0, length, d_o, d_i), Piece("tool", 0, length, d_i)), size)
        section = composite(tube(d_o, d_i, RC_STEEL), tube(d_i, 0.0, RC_CARBIDE))
        exact = natural_frequencies_hz((Beam(section, length),), 100.0, 1.2 * f[-1])[:3]
        rows.append((f"free-free steel Ø{d_o * 1e3:g}/carbide Ø{d_i * 1e3:g} x{length * 1e3:g} (rcsa composite)",
                     f, exact))
    model = build_body((Piece("holder", 0, 0.15, 0.02),), (STEEL, STEEL), MeshSize(0.0025, 0.0025), "clamped",
                       20000.0)
    exact = natural_frequencies_hz((Ground(1e14, 0.0, 1e14, 0.0), Beam(tube(0.02, 0.0, RC_STEEL), 0.15)),
                                   100.0, 20000.0)[:3]
    rows.append(("cantilever Ø20x150, base face fixed (rcsa clamp)", model.reduced.fixed_base_frequencies_hz[:3],
                 exact))
    damped, undamped = spindle_base_receptance()
    model = build_body((Piece("holder", 0, 0.15, 0.04),), (STEEL, STEEL), MeshSize(0.004, 0.004), "elastic",
                       CUTOFF_HZ)
    frf = solve_model(model, FREQUENCY_HZ, ReceptanceBase(FREQUENCY_HZ, damped, undamped))
    from rcsa.model.assembly import build_model
    from rcsa.model.contract import parse_assembly
    from rcsa.reference import ra1

    chain = build_model(parse_assembly(ra1())).spindle_side()
    exact = natural_frequencies_hz(chain + (Beam(tube(0.04, 0.0, RC_STEEL), 0.15),), 100.0, 6000.0)
    assert frf.natural_frequencies_hz is not None
    rows.append(("Ø40x150 rod on RA-1 spindle receptance (rcsa chain)", frf.natural_frequencies_hz, exact))
    return rows


# ------------------------------------------------------------------------------------------
# 2. convergence


#: the order used for error estimates: the observed one, clipped to this range (a re-entrant,
#: bonded corner where the shank leaves the bore makes the stress singular, so the smooth P2
#: rates are not reached; with an irregular sequence the estimate falls back to first order)
ORDER_RANGE = (1.0, 2.0)


def richardson(values: list[float], factors: tuple[float, ...]) -> tuple[float, float, float, float]:
    """Observed order p, the order used, the extrapolated value and the finest value's relative error.

    From the last three levels (sizes in a constant ratio r): p = ln((f1−f2)/(f2−f3)) / ln r; the
    estimate uses p clipped to ``ORDER_RANGE`` (first order when p is undefined).
    """
    f1, f2, f3 = values[-3:]
    r = factors[-2] / factors[-1]
    ratio = (f1 - f2) / (f2 - f3) if f2 != f3 else np.inf
    p = float(np.log(ratio) / np.log(r)) if ratio > 0 and np.isfinite(ratio) else float("nan")
    used = float(np.clip(p, *ORDER_RANGE)) if np.isfinite(p) else ORDER_RANGE[0]
    extrapolated = f3 + (f3 - f2) / (r**used - 1)
    return p, used, float(extrapolated), float(abs(f3 - extrapolated) / abs(extrapolated))


def convergence(case_name: str = "base_d10", models: dict[float, SolidModel] | None = None) -> dict[str, object]:
    """The mesh-convergence sequence of a case (clamped base), sizes ``CONVERGENCE_FACTORS`` × the data set's.

    The models built are left in ``models`` (by factor) for :func:`run_case` to reuse.
    """
    case = reference_cases()[case_name][0]
    rows = []
    models = {} if models is None else models
    for factor in CONVERGENCE_FACTORS:
        t0 = time.perf_counter()
        model = build(with_mesh(case, factor), "elastic", CUTOFF_HZ)
        if factor in (1.0, CHECK_FACTOR):
            models[factor] = model
        frf = solve_model(model, FREQUENCY_HZ, "clamped")
        f_peak, m_peak = largest_peak(FREQUENCY_HZ, frf.h)
        rows.append({"factor": factor, "tool_m": case.mesh.tool_m * factor, "n_dof": frf.n_dof,
                     "tool_mode_hz": f_peak, "peak_m_n": m_peak, "static_m_n": float(abs(frf.h[0])),
                     "h": frf.h, "wall_s": time.perf_counter() - t0, "load": load()})
        print(f"  size x{factor:<5g} tool {case.mesh.tool_m * factor * 1e3:5.2f} mm  DOF {frf.n_dof:7d}  "
              f"tool mode {f_peak:9.2f} Hz  peak {m_peak:.5e} m/N  h(100 Hz) {abs(frf.h[0]):.5e} m/N  "
              f"{rows[-1]['wall_s']:6.1f} s ({load()})", flush=True)
    out: dict[str, object] = {"rows": rows, "case": case_name}
    for key in ("tool_mode_hz", "peak_m_n", "static_m_n"):
        p, used, extrapolated, err = richardson([float(r[key]) for r in rows], CONVERGENCE_FACTORS)
        out[key] = {"observed_order": p, "order": used, "extrapolated": extrapolated, "remaining_rel": err}
        print(f"  {key:13s}: observed order {p:5.2f} (used {used:.2f}), Richardson {extrapolated:.6g}, "
              f"finest within {err:.2%}")
    finest = rows[-1]["h"]
    for r in rows[:-1]:
        print(f"  mean |dB| of size x{r['factor']:g} vs x{rows[-1]['factor']:g}: "
              f"{mean_abs_db(r['h'], finest):.3f} dB")
    return out


# ------------------------------------------------------------------------------------------
# 3. cases


def run_case(name: str, spindle: tuple[np.ndarray, np.ndarray], order: float, mesh_factor: float = 1.0,
             floor: float = 0.0, models: dict[float, SolidModel] | None = None) -> dict[str, object]:
    """Compute one case at the data set's mesh and at the size x ``CHECK_FACTOR`` mesh.

    The convergence estimate of a peak is the Richardson error from the two meshes with
    ``order`` (its family's observed one), but never below ``floor`` (its family's reference
    case's remaining error: two meshes of an irregular sequence can agree by chance). Models
    already built (by :func:`convergence`, keyed by mesh factor) are reused.
    """
    case, description = reference_cases()[name]
    case = with_mesh(case, mesh_factor)
    models = models or {}
    t0 = time.perf_counter()
    model = models.get(1.0) or build(case, "elastic", CUTOFF_HZ)
    base = ReceptanceBase(FREQUENCY_HZ, *spindle)
    frfs = {"clamped": solve_model(model, FREQUENCY_HZ, "clamped"), "spindle": solve_model(model, FREQUENCY_HZ, base)}
    wall = time.perf_counter() - t0 + (sum(model.timings_s.values()) if 1.0 in models else 0.0)
    coarse_model = models.get(CHECK_FACTOR) or build(with_mesh(case, CHECK_FACTOR), "elastic", CUTOFF_HZ)
    coarse = {"clamped": solve_model(coarse_model, FREQUENCY_HZ, "clamped"),
              "spindle": solve_model(coarse_model, FREQUENCY_HZ, base)}
    entry: dict[str, object] = {"description": description, "family": case_family(name), **case_document(case),
                                "n_dof": frfs["clamped"].n_dof, "n_elements": frfs["clamped"].n_elements,
                                "quarter_model": frfs["clamped"].quarter, "n_modes": frfs["clamped"].n_modes,
                                "straightened_elements": model.mesh.straightened,
                                "wall_s": round(wall, 1), "load_at_end": load(), "bases": {}}
    arrays: dict[str, np.ndarray] = {}
    beams = {b: beam_tip_h(case, b) for b in BASES}

    def band(h_clamped: np.ndarray) -> np.ndarray:
        f_clamped = largest_peak(FREQUENCY_HZ, h_clamped)[0]
        return (FREQUENCY_HZ >= TOOL_BAND[0] * f_clamped) & (FREQUENCY_HZ <= TOOL_BAND[1] * f_clamped)

    band_3d, band_beam = band(frfs["clamped"].h), band(beams["clamped"])
    for b in BASES:
        frf, c, beam = frfs[b], coarse[b], beams[b]
        scale = CHECK_FACTOR**order - 1     # Richardson with the base case's observed order
        natural = frf.natural_frequencies_hz if frf.natural_frequencies_hz is not None else np.array([])
        peaks = {}
        everything = np.ones(FREQUENCY_HZ.size, dtype=bool)
        for label, sel, sel_beam in (("largest_peak", everything, everything), ("tool_mode", band_3d, band_beam)):
            f3, m3 = largest_peak(FREQUENCY_HZ[sel], frf.h[sel])
            fc, mc = largest_peak(FREQUENCY_HZ[sel], c.h[sel])
            fb, mb = largest_peak(FREQUENCY_HZ[sel_beam], beam[sel_beam])
            peaks[label] = {"frequency_hz": round(f3, 3), "magnitude_m_n": m3,
                            "convergence": {"frequency_rel": max(abs(f3 - fc) / f3 / scale, floor),
                                            "magnitude_rel": abs(m3 - mc) / m3 / scale,
                                            "coarser_frequency_hz": round(fc, 3), "coarser_magnitude_m_n": mc},
                            "beam": {"frequency_hz": round(fb, 3), "magnitude_m_n": mb,
                                     "frequency_error": fb / f3 - 1, "peak_error": mb / m3 - 1}}
        coarse_natural = c.natural_frequencies_hz if c.natural_frequencies_hz is not None else np.array([])
        entry["bases"][b] = {  # type: ignore[index]
            **peaks, "natural_frequencies_hz": [round(float(x), 3) for x in natural],
            "coarser_natural_frequencies_hz": [round(float(x), 3) for x in coarse_natural],
            "mean_abs_db_vs_coarser_mesh": mean_abs_db(c.h, frf.h), "coarser_tool_m": case.mesh.tool_m * CHECK_FACTOR,
            "beam_mean_abs_db": mean_abs_db(beam, frf.h),
        }
        arrays[f"h_{b}"] = frf.h.astype(np.complex64)
        arrays[f"natural_frequencies_{b}_hz"] = natural
    arrays.update(reduced_arrays(model.reduced))
    return {"entry": entry, "arrays": arrays, "model": coarse_model}


def rigid_holder_share(h_base: complex, h_rigid: complex) -> dict[str, float]:
    """Static tool-point compliance (clamped base): how much of the 3-D excess the holder accounts for.

    ``h_base``, ``h_rigid``: the 3-D h at the grid's first line (100 Hz, quasi-static) of the
    base case and of its rigid-holder variant.
    """
    base = reference_cases()["base_d10"][0]
    f = FREQUENCY_HZ[:2]
    c3, c3_rigid = abs(h_base), abs(h_rigid)
    cb = abs(beam_tip_h(base, "clamped", f)[0])
    cb_rigid = abs(beam_tip_h(base, "clamped", f, rigid_holder=True)[0])
    share = 1 - (c3_rigid - cb_rigid) / (c3 - cb)
    print(f"  h(100 Hz), clamped base: 3-D {c3:.4e}, 3-D rigid holder {c3_rigid:.4e}, beam {cb:.4e}, "
          f"beam with the tool clamped at the holder face {cb_rigid:.4e} m/N")
    print(f"  3-D excess over the beam: {c3 - cb:.3e} m/N ({(c3 - cb) / cb:+.1%});"
          f" with both holders rigid: {c3_rigid - cb_rigid:.3e} m/N ({(c3_rigid - cb_rigid) / cb_rigid:+.1%})")
    print(f"  share of the excess removed by making the holder rigid: {share:.0%}")
    return {"solid_m_n": c3, "solid_rigid_holder_m_n": c3_rigid, "beam_m_n": cb, "beam_rigid_holder_m_n": cb_rigid,
            "share_removed": share}


def read_index() -> dict[str, object]:
    """cases.json as it stands (cases are added one by one), with the grid and the bases described."""
    path = OUT[0] / "cases.json"
    index = json.loads(path.read_text()) if path.exists() else {"cases": {}}
    index["frequency"] = {"start_hz": float(FREQUENCY_HZ[0]), "stop_hz": float(FREQUENCY_HZ[-1]), "step_hz": 1.0}
    index["bases"] = {"clamped": "the holder's base face (z = 0, the gauge line) fixed",
                      "spindle": "RA-1's spindle and spindle-holder joint condensed by rcsa to a 2x2 point "
                                 "receptance at the gauge line (spindle_base.npz)"}
    index["command"] = "python benchmarks/bench_solid3d.py --write-data"
    return index


def write_index(index: dict[str, object]) -> None:
    OUT[0].mkdir(parents=True, exist_ok=True)
    (OUT[0] / "cases.json").write_text(json.dumps(index, indent=1, default=float) + "\n")


def write_case(name: str, res: dict[str, object]) -> None:
    """One case's arrays and its entry of cases.json (written as soon as it is computed; several
    runs with disjoint ``--cases`` may write at once)."""
    OUT[0].mkdir(parents=True, exist_ok=True)
    np.savez_compressed(OUT[0] / f"{name}.npz", **res["arrays"])  # type: ignore[arg-type]
    with FileLock(OUT[0] / ".cases.lock"):
        index = read_index()
        index["cases"][name] = res["entry"]  # type: ignore[index]
        write_index(index)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--write-data", action="store_true", help="write tests/data/solid3d/")
    parser.add_argument("--out", type=Path, help="with --write-data: write this folder instead")
    parser.add_argument("--cases", nargs="*", help="only these cases (default: all)")
    parser.add_argument("--skip-verification", action="store_true", help="no rod table")
    parser.add_argument("--skip-convergence", action="store_true", help="no convergence sequence (order 1)")
    parser.add_argument("--mesh-factor", type=float, default=1.0, help="all cases' element sizes times this")
    parser.add_argument("--no-cases", action="store_true", help="verification and convergence only")
    parser.add_argument("--order", type=float, help="with --skip-convergence: the order of the estimates")
    parser.add_argument("--floor", type=float, default=0.0,
                        help="with --skip-convergence: the base case's remaining relative error")
    args = parser.parse_args()
    if args.out is not None:
        OUT[0] = args.out
    t_start = time.perf_counter()
    print(f"3-D reference benchmark ({load()}, 2-core AMD EPYC VM shared with other work)")
    if not args.skip_verification:
        print("\n1. Rods: 3-D (quadratic tetrahedra, quarter model) vs beam theory")
        for name, f3, ref in rods():
            err = f3[:3] / ref[:3] - 1 if f3.size >= 3 else f3 / ref[: f3.size] - 1
            print(f"  {name:55s} " + "  ".join(f"{a:9.2f}/{b:9.2f} ({e:+.2%})" for a, b, e in zip(f3, ref, err,
                                                                                                strict=False)))
        print(f"  ({load()})")
    damped, undamped = spindle_base_receptance()
    names = [] if args.no_cases else args.cases or list(reference_cases())
    # each family's reference case first: its convergence sequence sets the order of the others'
    names.sort(key=lambda n: (list(FAMILY_REFERENCE).index(case_family(n)), n != FAMILY_REFERENCE[case_family(n)]))
    families = sorted({case_family(n) for n in names} | ({"stepped"} if args.no_cases else set()),
                      key=list(FAMILY_REFERENCE).index)
    convergences: dict[str, dict[str, object]] = {}
    built: dict[str, dict[float, SolidModel]] = {}
    stored = read_index().get("convergence_by_family", {})
    for family in families:
        reference = FAMILY_REFERENCE[family]
        if args.skip_convergence:
            old = stored.get(family, {}).get("tool_mode_hz", {})  # type: ignore[union-attr]
            convergences[family] = {"rows": [], "tool_mode_hz": {"order": args.order or old.get("order", 1.0),
                                                                 "remaining_rel": args.floor or
                                                                 old.get("remaining_rel", 0.0)}}
            continue
        print(f"\n2. Convergence of {reference} (family {family}, clamped base), mesh sizes × the data set's")
        built[reference] = {}
        convergences[family] = convergence(reference, built[reference] if reference in names else None)
    results: dict[str, dict[str, object]] = {}
    print(f"\n3. Cases (reference mesh: tool {standard_case().mesh.tool_m * 1e3:g} mm at d = 10 mm, 0.15 d in general;"
          f" convergence estimate = Richardson with its family's order from the size x{CHECK_FACTOR:g} mesh)")
    print(f"  {'case':24s} {'base':8s} {'DOF':>7s} | {'largest peak':^29s} | {'tool mode':^29s} | "
          f"{'beam':^30s} | {'wall s':>6s}")
    print(f"  {'':24s} {'':8s} {'':7s} | {'Hz':>8s} {'m/N':>10s} {'conv':>9s} | {'Hz':>8s} {'m/N':>10s} "
          f"{'conv':>9s} | {'df lp':>7s} {'dpk lp':>7s} {'df tm':>7s} {'dpk tm':>7s} {'dB':>5s} |")
    for name in names:
        conv = convergences[case_family(name)]["tool_mode_hz"]
        order, floor = float(conv["order"]), float(conv.get("remaining_rel", 0.0))  # type: ignore[index,union-attr]
        res = run_case(name, (damped, undamped), order, args.mesh_factor, floor, built.pop(name, None))
        results[name] = res
        e = res["entry"]
        for b in BASES:
            r = e["bases"][b]  # type: ignore[index]
            lp, tm = r["largest_peak"], r["tool_mode"]
            print(f"  {name:24s} {b:8s} {e['n_dof']:7d} | {lp['frequency_hz']:8.1f} {lp['magnitude_m_n']:10.3e} "
                  f"{lp['convergence']['frequency_rel']:4.1%}/{lp['convergence']['magnitude_rel']:4.1%} | "
                  f"{tm['frequency_hz']:8.1f} {tm['magnitude_m_n']:10.3e} "
                  f"{tm['convergence']['frequency_rel']:4.1%}/{tm['convergence']['magnitude_rel']:4.1%} | "
                  f"{lp['beam']['frequency_error']:+7.1%} {lp['beam']['peak_error']:+7.1%} "
                  f"{tm['beam']['frequency_error']:+7.1%} {tm['beam']['peak_error']:+7.1%} "
                  f"{r['beam_mean_abs_db']:5.2f} | {e['wall_s']:6.1f}", flush=True)
        if name == "base_d10":
            t0 = time.perf_counter()
            probe = np.array([300.0, 2000.0, 4500.0, 5900.0])
            model = res["model"]      # the size x CHECK_FACTOR mesh: a direct solve of the finest costs minutes
            err_c = truncation_error(model, probe, "clamped")  # type: ignore[arg-type]
            base_probe = ReceptanceBase(probe, *spindle_base_receptance(probe))
            err_s = truncation_error(model, probe, base_probe)  # type: ignore[arg-type]
            res["entry"]["truncation_error"] = {"clamped": err_c, "spindle": err_s,  # type: ignore[index]
                                                "frequencies_hz": probe.tolist(), "mesh_factor": CHECK_FACTOR}
            print(f"  Craig-Bampton vs direct sparse complex solve (mesh x{CHECK_FACTOR:g}) at {probe.tolist()} Hz: "
                  "max |dh|/max|h| "
                  f"{err_c:.1e} (clamped), {err_s:.1e} (spindle) [{time.perf_counter() - t0:.0f} s]")
        if args.write_data:
            write_case(name, res)
        res.pop("model")
    stored = {n: load_case(n, OUT[0])["h_clamped"][0] for n in ("base_d10", "rigid_holder")
              if n not in results and args.write_data and (OUT[0] / f"{n}.npz").exists()}
    h0 = {**stored, **{n: r["arrays"]["h_clamped"][0] for n, r in results.items()}}  # type: ignore[index]
    if "base_d10" in h0 and "rigid_holder" in h0:
        print("\n4. Rigid holder (from this run's or the stored cases)")
        share = rigid_holder_share(complex(h0["base_d10"]), complex(h0["rigid_holder"]))
        if args.write_data:
            with FileLock(OUT[0] / ".cases.lock"):
                index = read_index()
                index["rigid_holder_share"] = share
                write_index(index)
    if args.write_data and not args.skip_convergence:
        with FileLock(OUT[0] / ".cases.lock"):
            index = read_index()
            by_family = index.setdefault("convergence_by_family", {})
            for family, conv in convergences.items():
                record = {k: v for k, v in conv.items() if k != "rows"}
                record["sequence"] = [{k: v for k, v in r.items() if k != "h"}  # type: ignore[union-attr]
                                      for r in conv["rows"]]  # type: ignore[union-attr]
                record["factors"] = list(CONVERGENCE_FACTORS)
                by_family[family] = record  # type: ignore[index]
                if family == "stepped":
                    index["convergence"] = record
            write_index(index)
        np.savez_compressed(OUT[0] / "spindle_base.npz", receptance=damped.astype(np.complex64),
                            undamped_receptance=undamped.real.astype(np.float32))
    if args.write_data:
        (OUT[0] / "README.md").write_text(render_readme(read_index()))
        print(f"\nwrote {OUT[0]} ({sum(p.stat().st_size for p in OUT[0].iterdir()) / 1e6:.2f} MB)")
    print(f"\ntotal {time.perf_counter() - t_start:.0f} s ({load()})")


if __name__ == "__main__":
    main()
