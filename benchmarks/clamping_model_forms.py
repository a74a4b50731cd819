"""Three changes of the clamping model's form tried against the thinnest nose's miss (issue 31).

With the committed coefficients the bonded model misses one row of the 3-D data set: the
thinnest nose (``nose_od1.6d``, a Ø16 nose around a Ø10 tool, itself a calibration case) on the
clamped base, whose second mode (7294 Hz) comes out about 2.5 % **low**. The beam is too soft
there (or too heavy; the masses are exact), so whatever is missing stiffens a thin nose more
than a thick one. Each variant below changes the model's form in one physically motivated way,
adds at most one coefficient, is fitted by the calibration's own least squares
(:func:`tests.oracles.solid3d.clamping_fit.fit`, from the committed coefficients, on the
calibration cases) and is then scored on every case and both bases
(:func:`tests.oracles.solid3d.clamping_scores.score_row`):

* ``committed``: the model as it is (the fit re-run from its own answer);
* ``cone_exponent``: the stiffness cone at a holder step reaches
  ``ℓ = c_s h^p (d/2)^(1−p)`` (h the radial step height, d the smaller diameter) instead of
  ``c_s h``: a large step on a thin nose softens the larger section over less length (p fitted);
* ``non_warping_holder_shear``: every holder section shears with the solid circle's shear
  coefficient instead of its hollow section's (short holder tubes between steps and the
  bonded shank cannot warp as a long thin tube does; a thin wall gains most);
* ``thin_wall_interface``: the holder side of the interface's surface compliance scales with
  the wall, ``τ/(τ + τ₀)`` (``τ = (D − d)/d``, the wall over the bore's radius; τ₀ fitted): a
  thin wall bonded on a stiff shank deforms less than a thick body (the committed fit tried only
  the opposite sign).

None of them brings the thin nose within 1.5 %; the record says by how much each moves it and
what it costs elsewhere. It also solves the thin nose's 3-D reference again on finer meshes
(:data:`MESH_FACTORS`): its modes still move there, but the ratio of its two modes does not, and
the beam's ratio stays about 3 % under it, so the miss is the model's, not the reference's
(``benchmarks/results/clamping_model_forms.json``, rendered in ``docs/model.md``). The variants
live only here: the product keeps the committed form.

Run: ``.venv/bin/python benchmarks/clamping_model_forms.py`` (about 8 minutes on one core).
"""

from __future__ import annotations

import contextlib
import statistics
import sys
import time
from collections.abc import Callable, Iterator
from dataclasses import asdict, dataclass, replace
from pathlib import Path
from typing import Any

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))

from tests.oracles.solid3d import clamping_fit  # noqa: E402
from tests.oracles.solid3d.clamping_scores import CALIBRATION_CASES, INFORMATION, score_row  # noqa: E402
from tests.oracles.solid3d.dataset import BASES, FREQUENCY_HZ, reference_cases, with_mesh  # noqa: E402
from tests.oracles.solid3d.solve import CUTOFF_FACTOR, build, solve_model  # noqa: E402

import rcsa.model.clamping as clamping  # noqa: E402
from rcsa.physics.sections import shear_coefficient  # noqa: E402
from record import load_average, write  # noqa: E402

#: The issue's targets: every peak within 1.5 % in frequency and 15 % in height.
TARGET = {"frequency": 0.015, "height": 0.15}
NOSES = ("nose_od1.6d", "nose_od2.2d", "nose_od3.2d", "nose_od4d")
#: Element sizes (× the data set's, every size and the grading) the thin nose's 3-D reference is
#: solved again at, the data set's first.
MESH_FACTORS = (1.0, 0.794, 0.63)


@dataclass(frozen=True, slots=True)
class VariantCoefficients:
    """The committed coefficients and the one a variant adds (1.0 = the variant's neutral start)."""

    interface: float
    step_cone: float
    holder_shear: float
    extra: float = 1.0


def _extra() -> float:
    return float(getattr(clamping.BULK_COEFFICIENTS, "extra", 1.0))


@contextlib.contextmanager
def _patched(name: str, make: Callable[[Any], Any]) -> Iterator[None]:
    """``clamping.<name>`` replaced by ``make(original)`` inside the block."""
    original = getattr(clamping, name)
    setattr(clamping, name, make(original))
    try:
        yield
    finally:
        setattr(clamping, name, original)


def _cone_exponent(original: Callable[..., float]) -> Callable[..., float]:
    def length(step_cone: float, big: float, small: float, section: float) -> float:
        p = _extra()
        return original(step_cone * (small / (big - small)) ** (1.0 - p), big, small, section)
    return length


def _non_warping(original: Callable[..., Any]) -> Callable[..., Any]:
    def tube(outer: float, inner: float, material: Any, shear: Any, theory: Any) -> Any:
        if isinstance(shear, str):
            shear = shear_coefficient(material.poisson_ratio, 0.0, shear)
        return original(outer, inner, material, shear, theory)
    return tube


def _thin_wall(original: Callable[..., Any]) -> Callable[..., Any]:
    def per_length(spec: Any, outer: float, bore: float, shank: float, holder: Any, tool: Any,
                   coefficients: Any = None, contact_length_m: float | None = None) -> Any:
        tau = (outer - bore) / bore
        stiffer = replace(holder, youngs_modulus_pa=holder.youngs_modulus_pa * (tau + _extra()) / tau)
        return original(spec, outer, bore, shank, stiffer, tool, coefficients, contact_length_m)
    return per_length


#: name → (the patched function of ``rcsa.model.clamping`` and its maker, the added coefficient's
#: start and bounds), or None for the committed form.
VARIANTS: dict[str, tuple[str, Callable[[Any], Any], float, tuple[float, float]] | None] = {
    "committed": None,
    "cone_exponent": ("step_cone_length_m", _cone_exponent, 0.7, (0.05, 2.0)),
    "non_warping_holder_shear": ("tube", _non_warping, 1.0, (1.0, 1.0)),
    "thin_wall_interface": ("interface_per_length", _thin_wall, 1.0, (0.01, 20.0)),
}


def _scores() -> dict[str, Any]:
    rows = []
    for name in reference_cases():
        if name in INFORMATION:
            continue
        for base in BASES:
            s = score_row(name, base, "clamping")
            rows.append({"case": name, "base": base, "max_frequency_error": s["max_frequency_error"],
                         "max_height_error": s["max_height_error"], "mean_abs_db": s["mean_abs_db"],
                         "last_peak_frequency_error": s["peaks"][-1]["frequency_error"]})
    worst = max(rows, key=lambda r: r["max_frequency_error"])
    within = [r for r in rows if r["max_frequency_error"] <= TARGET["frequency"]
              and r["max_height_error"] <= TARGET["height"]]
    clamped = [r for r in rows if r["base"] == "clamped"]
    noses = {r["case"]: r["last_peak_frequency_error"] for r in clamped if r["case"] in NOSES}
    return {"rows": len(rows), "rows_within_target": len(within),
            "rows_missed": [f"{r['case']} ({r['base']})" for r in rows if r not in within],
            "worst_frequency_error": worst["max_frequency_error"], "worst_case": worst["case"],
            "worst_base": worst["base"],
            "thin_nose_second_mode_error": noses["nose_od1.6d"], "nose_second_mode_errors": noses,
            "median_clamped_mean_abs_db": statistics.median(r["mean_abs_db"] for r in clamped),
            "max_clamped_mean_abs_db": max(r["mean_abs_db"] for r in clamped), "table": rows}


def run_variant(name: str, fit_rows: list[clamping_fit.Row]) -> dict[str, Any]:
    """Fit the variant's coefficients on the calibration cases, then score every row."""
    variant = VARIANTS[name]
    committed = clamping.BULK_COEFFICIENTS
    start = VariantCoefficients(committed.interface, committed.step_cone, committed.holder_shear)
    names = list(clamping.FITTED)
    bounds = dict(clamping_fit.BOUNDS)
    stack = contextlib.ExitStack()
    if variant is not None:
        target, maker, extra_start, extra_bounds = variant
        stack.enter_context(_patched(target, maker))
        start = replace(start, extra=extra_start)
        if extra_bounds[0] < extra_bounds[1]:
            names.append("extra")
            bounds["extra"] = extra_bounds
    t0 = time.perf_counter()
    saved_bounds, clamping_fit.BOUNDS = clamping_fit.BOUNDS, bounds
    try:
        with stack:
            fitted = clamping_fit.fit(fit_rows, names, start, tolerance=1e-6, max_evaluations=120)
            clamping.BULK_COEFFICIENTS = fitted.coefficients
            try:
                scores = _scores()
            finally:
                clamping.BULK_COEFFICIENTS = committed
    finally:
        clamping_fit.BOUNDS = saved_bounds
    out = {"fitted": names, "coefficients": asdict(fitted.coefficients), "rms": fitted.rms,
           "singular_values": fitted.singular_values.tolist(), "evaluations": fitted.evaluations,
           "seconds": time.perf_counter() - t0, **scores}
    print(f"{name:26s} coefficients {[round(v, 3) for v in asdict(fitted.coefficients).values()]}  "
          f"thin nose {scores['thin_nose_second_mode_error'] * 100:+.2f} %  worst {scores['worst_case']} "
          f"({scores['worst_base']}) {scores['worst_frequency_error'] * 100:.2f} %  rows within "
          f"{scores['rows_within_target']}/{scores['rows']}  median clamped dB "
          f"{scores['median_clamped_mean_abs_db']:.2f}  smallest singular value {min(out['singular_values']):.2f}",
          flush=True)
    return out


def reference_on_finer_meshes(name: str = "nose_od1.6d") -> dict[str, Any]:
    """The case's 3-D reference (clamped base) on the meshes of :data:`MESH_FACTORS`: its first two
    natural frequencies and their ratio, against the committed model's peaks."""
    case = reference_cases()[name][0]
    meshes = []
    for factor in MESH_FACTORS:
        t0 = time.perf_counter()
        model = build(with_mesh(case, factor), "elastic", CUTOFF_FACTOR * float(FREQUENCY_HZ[-1]))
        frf = solve_model(model, FREQUENCY_HZ, "clamped")
        assert frf.natural_frequencies_hz is not None
        modes = [float(x) for x in frf.natural_frequencies_hz[:2]]
        meshes.append({"factor": factor, "n_dof": frf.n_dof, "natural_frequencies_hz": modes,
                       "ratio": modes[1] / modes[0], "seconds": time.perf_counter() - t0})
        print(f"  {name} 3-D, sizes x{factor:g}: {frf.n_dof} DOF, modes {modes[0]:.2f} / {modes[1]:.2f} Hz, "
              f"ratio {modes[1] / modes[0]:.4f}", flush=True)
    beam = [float(p["model_hz"]) for p in score_row(name, "clamped", "clamping")["peaks"]]
    first, finest = meshes[0]["natural_frequencies_hz"], meshes[-1]["natural_frequencies_hz"]
    return {"case": name, "base": "clamped", "meshes": meshes, "model_hz": beam, "model_ratio": beam[1] / beam[0],
            "finest_shift": [b / a - 1.0 for a, b in zip(first, finest, strict=True)],
            "model_error_vs_finest": [m / f - 1.0 for m, f in zip(beam, finest, strict=True)]}


def main() -> None:
    load = load_average()
    fit_rows = clamping_fit.prepare(CALIBRATION_CASES)
    variants = {name: run_variant(name, fit_rows) for name in VARIANTS}
    write("clamping_model_forms", {"target": TARGET, "calibration_cases": list(CALIBRATION_CASES),
                                   "variants": variants, "thin_nose_reference": reference_on_finer_meshes()},
          load_start=load)


if __name__ == "__main__":
    main()
