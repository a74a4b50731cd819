"""Withheld-effect benchmark of the sim-to-real diagnosis (issue 6, ``docs/diagnosis.md`` §5).

Each trial draws a hidden effect (or none), realises it physically in the independent FE
truth (``tests/analysis/diagnosis/truth.py``) with in-tolerance scatter of the nominal parameters and
1 % noise, measures five stickouts (50–82 mm, 50–8000 Hz, 2 Hz lines) and asks
``rcsa.analysis.diagnosis`` for a verdict against the RA-1 base model. Scores (``docs/diagnosis.md`` §5.2):

* top-1 attribution: ``status == identified`` and the named effect is the hidden one
  (an ``ambiguous`` verdict never counts as a top-1 hit); also the best-ranked effect, set
  accuracy (hidden ∈ {effect} ∪ ambiguous_with) and equivalence-class accuracy with the
  physically collinear pairs {holder_tool_joint, insertion_depth} and
  {spindle_holder_joint, spindle_rotational_receptance};
* all of them overall and where the effect's SNR ≥ 10 (SNR: whitened norm of the
  noise-free effect-only feature shift, i.e. truth with minus truth without the effect under
  the same nuisance draw, in the diagnoser's Σ), and per SNR bin;
* the confusion matrix (rows hidden, columns the verdict's effect; ``ambiguous`` verdicts in
  their own column), false claims on no-effect trials;
* held-out gap ratio √(χ²_after/χ²_before) on the held-out stickouts (58, 74 mm) and the
  held-out dB-RMS ratio, median over correct attributions;
* runtime per diagnosis (median, max; the first diagnosis of a worker includes the
  Monte-Carlo Σ, later ones reuse it).

Hybrid trials (``--hybrid``): the spindle is a stored measurement of the same FE truth — a
``point_receptance`` with 0.3 % noise, a ``direct_frf`` (rotations estimated by the
equivalent cantilever) and ``artifact_frfs`` on a test arbor, identified by the exact
three-FRF method (``tests/analysis/diagnosis/truth_hybrid.py``) — three stickouts (50, 66,
82 mm; leave-one-out held out), the classes a measured spindle admits, scored the same way
per kind and pooled (``bearings`` is never a candidate there; ``spindle_rotational_receptance``
is an error of the stored rotations). The SNR of a rotation error is that of the base model
on the erroneous versus the error-free stored spindle.

Run::

    .venv/bin/python benchmarks/bench_diagnosis.py --trials 250 --seed 1 --workers 2
    .venv/bin/python benchmarks/bench_diagnosis.py --hybrid --trials-per-class 12 --seed 2 --workers 2
    .venv/bin/python benchmarks/bench_diagnosis.py --check-mesh
    .venv/bin/python benchmarks/bench_diagnosis.py --solid3d --trials-per-class 4 --seed 3 --workers 2
    .venv/bin/python benchmarks/bench_diagnosis.py --trials 100 --tolerance-scale 2 --seed 4 --workers 2 \
        --out benchmarks/results/diagnosis_scatter2.json
    .venv/bin/python benchmarks/bench_diagnosis.py --out-of-catalogue --trials-per-class 15 --seed 5 --workers 2

Issue 31's published figures, on evaluation seeds (``EVALUATION_SEEDS``)::

    .venv/bin/python benchmarks/bench_diagnosis.py --hybrid --trials-per-class 12 --evaluation --workers 2 \
        --out benchmarks/results/diagnosis_hybrid_eval.json
    .venv/bin/python benchmarks/bench_diagnosis.py --trials 100 --tolerance-scale 2 --evaluation --workers 2 \
        --out benchmarks/results/diagnosis_scatter2_eval.json
    .venv/bin/python benchmarks/bench_diagnosis.py --solid3d --trials-per-class 3 --evaluation --workers 2
    .venv/bin/python benchmarks/bench_diagnosis.py --solid3d-cases --trials-per-class 2 --evaluation --workers 2

The solid3d, scatter and out-of-catalogue runs are the classes outside the diagnosis's own model world (issue 24;
``benchmarks/diagnosis_outside.py`` says what each scores).
    .venv/bin/python benchmarks/bench_diagnosis.py --calibrate holder_tool

The summary goes to stdout and, with every trial's record, to ``--out``
(default ``benchmarks/results/diagnosis.json``).
"""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
import time
from collections import Counter
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):  # one core per worker: CPU times comparable
    os.environ.setdefault(_var, "1")

import numpy as np  # noqa: E402

REPO = Path(__file__).resolve().parents[1]
if str(REPO) not in sys.path:
    sys.path.insert(0, str(REPO))


def _first_calls(case: str, run, modules_before_first_call: bool) -> dict:
    """``run()`` (a diagnosis: ``(cpu_s, wall_s, response)``) first in this process, again (Σ
    cached), again with Σ dropped, and RA-1's plain prediction at 10 000 lines, cold (the
    ratios' yardstick, as ``bench_engine.py`` times it). The diagnosis's modules are imported
    here only after the first call."""
    import rcsa

    first = run()
    warm = run()
    from rcsa.analysis.diagnosis import problem
    from rcsa.app import predictions
    from rcsa.reference import ra1

    problem._DRAW_CACHE.clear()
    cold_again = run()
    counted = _count_first_call(run)
    assembly = ra1({"start_hz": 1.0, "stop_hz": 10000.0, "step_hz": 1.0})
    predictions.SIDES.size = 0  # cold, as bench_engine.py times it: no spindle side kept across calls
    yardstick = []
    for _ in range(9):
        c0, t0 = time.process_time(), time.perf_counter()
        rcsa.predict(assembly)
        yardstick.append((time.process_time() - c0, time.perf_counter() - t0))
    pc = float(np.median([x[0] for x in yardstick]))
    pw = float(np.median([x[1] for x in yardstick]))
    # warm: the spindle side kept across calls, as a running service has it, the prediction computed
    predictions.SIDES.size = predictions.SIDES_KEPT
    from benchmarks._yardstick import warm_ra1_prediction_s

    pwc = warm_ra1_prediction_s(9)[1]
    return {"case": case, "first_cpu_s": first[0], "first_wall_s": first[1], "warm_cpu_s": warm[0],
            "warm_prediction_cpu_s": pwc, "first_over_warm_prediction_cpu": first[0] / pwc,
            "bytecode_cached": bool(sys.pycache_prefix) or not sys.dont_write_bytecode,
            "warm_wall_s": warm[1], "cold_in_warm_process_cpu_s": cold_again[0],
            "cold_in_warm_process_wall_s": cold_again[1], "prediction_cpu_s": pc, "prediction_wall_s": pw,
            "first_over_prediction_cpu": first[0] / pc, "first_over_prediction_wall": first[1] / pw,
            "verdict": first[2]["verdict"]["effect"], "phases_of_first_s": first[2].get("analysis", {}).get("timings_s"),
            "load_average": os.getloadavg(), "rcsa": str(Path(rcsa.__file__).parent),
            "scipy_loaded": any(m == "scipy" or m.startswith("scipy.") for m in sys.modules),
            "diagnosis_modules_before_first_call": modules_before_first_call,
            "first_call_counted": {**counted, "over_warm_prediction_cpu": {
                name: cpu / pwc for name, cpu in counted["cpu_s_by_phase"].items()}
                | {"insertion_fits": counted["insertion_fits_cpu_s"] / pwc}}}


def _count_first_call(run) -> dict:
    """An untimed repeat of the first call with its per-process caches dropped (the Monte-Carlo
    Σ, the whole-insertion interpolants and the two-ports kept from them; the modules stay
    imported), counting what it does: the model's tool-point solves (``Solver.tip_h``: one
    configuration at one stickout) and the CPU of each phase of the diagnosis, and the
    interpolants built and their CPU. It says where a first diagnosis's time goes, and what a
    phase costs whatever the others did."""
    from rcsa.analysis.diagnosis import chain_items, perturbed_model, problem, state
    from rcsa.physics import insertion
    from rcsa.physics.subassembly_cache import LruStore

    problem._DRAW_CACHE.clear()
    kept_fits, insertion._WHOLE_FITS = insertion._WHOLE_FITS, insertion._BandFits(insertion._FITS_MAX)
    kept_ports, chain_items._TWO_PORTS = chain_items._TWO_PORTS, LruStore(chain_items.TWO_PORTS_KEPT)
    solves, fits = [0], [0, 0.0]
    by_phase: dict[str, int] = {}
    cpu_by_phase: dict[str, float] = {}
    last = [0, time.process_time()]
    tip_h, make_fit, mark = perturbed_model.Solver.tip_h, insertion._make_insertion_fit, state._Phases.mark

    def counted_tip_h(self, parts, lines=slice(None)):
        solves[0] += 1
        return tip_h(self, parts, lines)

    def counted_fit(ins, top):
        c0 = time.process_time()
        try:
            return make_fit(ins, top)
        finally:
            fits[0] += 1
            fits[1] += time.process_time() - c0

    def counted_mark(self, name):
        now = time.process_time()
        by_phase[name], cpu_by_phase[name] = solves[0] - last[0], now - last[1]
        last[:] = [solves[0], now]
        mark(self, name)

    last[1] = time.process_time()
    perturbed_model.Solver.tip_h, insertion._make_insertion_fit, state._Phases.mark = (
        counted_tip_h, counted_fit, counted_mark)
    try:
        run()
    finally:
        perturbed_model.Solver.tip_h, insertion._make_insertion_fit, state._Phases.mark = tip_h, make_fit, mark
        insertion._WHOLE_FITS, chain_items._TWO_PORTS = kept_fits, kept_ports
    return {"tip_solves_by_phase": by_phase, "tip_solves": solves[0], "cpu_s_by_phase": cpu_by_phase,
            "insertion_fits": fits[0], "insertion_fits_cpu_s": fits[1]}


def first_call_child(case: str, request_path: str) -> dict:
    """A fresh process that has imported only ``rcsa`` and numpy: the first ``rcsa.diagnose`` in
    it (the diagnosis's modules load inside the call), then as :func:`_first_calls`. Runs before
    this module imports anything else."""
    import rcsa

    request = json.loads(Path(request_path).read_text())

    def run() -> tuple[float, float, dict]:
        c0, t0 = time.process_time(), time.perf_counter()
        r = rcsa.diagnose(request)
        return time.process_time() - c0, time.perf_counter() - t0, r

    return _first_calls(case, run, False)


if __name__ == "__main__" and len(sys.argv) == 4 and sys.argv[1] == "--first-call":
    print(json.dumps(first_call_child(sys.argv[2], sys.argv[3])))
    sys.exit(0)

from tests.analysis.diagnosis import truth, truth_hybrid  # noqa: E402

from rcsa.analysis.diagnosis.perturbed_model import BaseReceptance, Knobs  # noqa: E402
from rcsa.analysis.diagnosis.report import build_response  # noqa: E402
from rcsa.analysis.diagnosis.state import Analysis, analyse  # noqa: E402
from rcsa.measured.hybrid import base_resolver, measured_base  # noqa: E402

EQUIVALENT = ({"holder_tool_joint", "insertion_depth"}, {"spindle_holder_joint", "spindle_rotational_receptance"})
SNR_BINS = ((0.0, 5.0), (5.0, 10.0), (10.0, 20.0), (20.0, float("inf")))
DEFAULT_OUT = REPO / "benchmarks" / "results" / "diagnosis.json"
#: Seeds whose trials were looked at while the diagnosis was tuned (the figures published before
#: issue 31 — matched 1, hybrid 2, 3-D 3, doubled scatter 4, out of the catalogue 5 — and the
#: claim-rule and model-form calibration of issue 31: hybrid 2 and 6, doubled scatter 2 and 4,
#: the 3-D data-set cases 31; hybrid 3102, first meant for evaluation: a run of it stopped after
#: 174 trials was looked at trial by trial before the claim rule's scatter bound was set, so it
#: is a tuning seed now; doubled scatter 3113, 100 trials recording the remainder's scatter scale
#: for the next claim rule, ``diagnosis_scatter2_tune3113.json``). Their figures say how the rules
#: were chosen, not how they do.
TUNING_SEEDS = (1, 2, 3, 4, 5, 6, 31, 3102, 3113)
#: Seeds never used while tuning, one per benchmark: ``--evaluation`` picks the benchmark's own,
#: and the published figures of issue 31 come from them.
EVALUATION_SEEDS = {"matched": 3101, "hybrid": 3112, "solid3d": 3103, "scatter2": 3104, "out_of_catalogue": 3105,
                    "solid3d_cases": 3106}


def seed_role(seed: int) -> str:
    """``tuning``, ``evaluation`` or ``other`` (written into every result file)."""
    return "tuning" if seed in TUNING_SEEDS else "evaluation" if seed in EVALUATION_SEEDS.values() else "other"


#: Model forms whose proposal names a class's hidden physics: the ``holder_tool_joint`` truth is
#: the tool core held by springs per unit length along the whole insertion (``truth.py``), i.e.
#: a clamping along the insertion — ``clamping_model`` proposing ``contact`` (or ``bonded``) is
#: that physics, named as a model form. Scored as a right answer, and counted apart
#: (``top1_strict`` does not).
FORM_NAMES_CLASS = {"holder_tool_joint": ("clamping_model", ("contact", "bonded"))}


def _equivalent(a: str, b: str) -> bool:
    return a == b or any(a in s and b in s for s in EQUIVALENT)


def _names(effect: str, named: str, proposed_model: str | None) -> bool:
    """Whether a verdict ``named`` (with the model it proposes) names the hidden ``effect``."""
    form = FORM_NAMES_CLASS.get(effect)
    return named == effect or (form is not None and named == form[0] and proposed_model in form[1])


def run_trial(index: int, effect: str, seed: int, tolerance_scale: float = 1.0, extra=None) -> dict:
    """One trial: truth, diagnosis, scores (runs in a worker process); ``extra(analysis)`` adds to the record."""
    rng = np.random.default_rng([seed, index])
    t0 = time.perf_counter()
    trial = truth.make_trial(rng, effect, tolerance_scale=tolerance_scale)
    t_truth = time.perf_counter() - t0
    t1, c1 = time.perf_counter(), time.process_time()
    a = analyse(trial.request)
    r = build_response(a)
    t_diag, c_diag = time.perf_counter() - t1, time.process_time() - c1
    snr = 0.0
    if effect != "none":
        snr = float(np.linalg.norm(a.like.w @ (_features(a, trial.clean) - _features(a, trial.clean_null))))
    out = _record(index, effect, trial.params, a, r, snr, t_diag, t_truth, c_diag)
    return out if extra is None else {**out, **extra(a)}


def run_hybrid_trial(index: int, effect: str, kind: str, seed: int,
                     length_log_sd: float = truth_hybrid.LENGTH_LOG_SD, extra=None) -> dict:
    """One hybrid trial (measured spindle of ``kind``): truth, diagnosis, scores (``extra`` as in :func:`run_trial`)."""
    rng = np.random.default_rng([seed, index])
    t0 = time.perf_counter()
    trial = truth_hybrid.make_hybrid_trial(rng, effect, kind, length_log_sd=length_log_sd)
    t_truth = time.perf_counter() - t0
    t1, c1 = time.perf_counter(), time.process_time()
    a = analyse(trial.request, base_resolver(trial.source))
    r = build_response(a)
    t_diag, c_diag = time.perf_counter() - t1, time.process_time() - c1
    p = a.problem
    snr = 0.0
    if effect == "spindle_rotational_receptance":  # the base model on the erroneous vs the error-free spindle
        if kind == "direct_frf":
            length = trial.request["assembly"]["spindle"]["effective_length_m"]
            f_null = p.features(p.h(Knobs(base_rotation_scale=length / trial.length_null_m)))
        else:
            assert trial.source_null is not None
            mb = measured_base(next(iter(trial.source_null)), p.solver.frequency_hz, trial.source_null)
            f_null = p.features(p.h(Knobs(), BaseReceptance(mb.receptance)))
        snr = float(np.linalg.norm(a.like.w @ (p.base_features - f_null)))
    elif effect != "none":
        snr = float(np.linalg.norm(a.like.w @ (_features(a, trial.clean) - _features(a, trial.clean_null))))
    out = _record(index, effect, trial.params, a, r, snr, t_diag, t_truth, c_diag)
    out["kind"] = kind
    out["not_applicable"] = [x["effect"] for x in r["not_applicable"]]
    return out if extra is None else {**out, **extra(a)}


def _false_claim(r: dict) -> bool:
    """A claim (identified or ambiguous) naming no effect equivalent to the hidden one (a model
    form that names the hidden physics, :data:`FORM_NAMES_CLASS`, is no false claim)."""
    if r["status"] == "none":
        return False
    named = [r["verdict"], *r["ambiguous_with"]]
    return r["effect"] == "none" or not (any(_equivalent(x, r["effect"]) for x in named)
                                         or _names(r["effect"], r["verdict"], r.get("form_verdict")))


def _features(a: Analysis, hs: list[np.ndarray]) -> np.ndarray:
    p = a.problem
    return p.features([hs[c.index][c.lines] for c in p.configs])


def _record(index: int, effect: str, params: dict, a: Analysis, r: dict, snr: float, t_diag: float,
            t_truth: float, cpu_diag: float) -> dict:
    v = r["verdict"]
    first = r["effects"][0] if r["effects"] else None
    ranked = [e["effect"] for e in r["ranking"]]
    proposed = first.get("proposed_model") if first else None
    correct = v["status"] == "identified" and _names(effect, v["effect"], proposed)
    out = {
        "index": index, "effect": effect, "params": {k: float(x) for k, x in params.items()},
        "status": v["status"], "verdict": v["effect"], "ambiguous_with": v["ambiguous_with"],
        "log_bayes_factor": v["log_bayes_factor"], "snr_true": snr, "snr_fitted": v["snr"],
        "top1": correct, "top1_strict": v["status"] == "identified" and v["effect"] == effect,
        "form_verdict": proposed, "best_ranked": ranked[0] if ranked else "none",
        "in_set": effect in [v["effect"], *v["ambiguous_with"]],
        "equivalent": (v["status"] == "identified" and (_equivalent(v["effect"], effect) or correct)) or (
            v["status"] == "ambiguous" and all(_equivalent(x, effect) for x in [v["effect"], *v["ambiguous_with"]])),
        "confirmed": v["confirmed_on_held_out"],
        "held_out_gap_ratio": first["held_out_gap_ratio"] if first else None,
        "held_out_db_before": first["held_out_gap_before_db"] if first else None,
        "held_out_db_after": first["held_out_gap_after_db"] if first else None,
        "gap_p_value": r["gap"]["p_value"],
        "second_effect": r["effects"][-1]["effect"] if r["effects"] and "given" in r["effects"][-1] else None,
        "residual_p_value": first["residual_p_value"] if first else None,
        # the scatter the remainder shows (ŝ) and whether it is beyond every scale the prior allows: what an
        # offline rule weighing the ambiguity at Σ·ŝ² needs (issue 31: the doubled-scatter false claims)
        "scatter_scale": r["analysis"].get("scatter_scale"),
        "remainder_beyond_scatter": r["analysis"].get("remainder_beyond_scatter"),
        "collinear_rivals": [x["effect"] for x in v["collinear_rivals"]],
        "runtime_s": t_diag, "cpu_s": cpu_diag, "truth_s": t_truth,
        "ranking": [(e["effect"], round(e["log_bayes_factor"], 2)) for e in r["ranking"]],
    }
    if first is not None and effect != "none":
        out["parameters"] = {k: (p_["value"], p_["sd"]) for k, p_ in first["parameters"].items()}
    return out


def timing(repeats: int = 3) -> dict:
    """CPU and wall time of one diagnosis, and what takes what (the phases of the best cold run).

    Fixed seeded requests with a hidden 1-8 g sensor mass: RA-1 with 5 stickouts (analytical
    spindle), and 3 stickouts on each kind of measured spindle. "cold" computes the
    Monte-Carlo Σ; "warm" repeats the request with its draws cached (a re-run with other
    options, or the benchmark's later trials of one worker on the same lines).
    """
    from rcsa.analysis.diagnosis import problem

    cases = [("analytical, 5 stickouts", truth.make_trial(np.random.default_rng([7, 0]), "sensor_mass",
                                                          with_null=False).request, None)]
    for kind in truth_hybrid.KINDS:
        trial = truth_hybrid.make_hybrid_trial(np.random.default_rng([7, 1]), "sensor_mass", kind, with_null=False)
        cases.append((f"{kind}, 3 stickouts", trial.request, base_resolver(trial.source)))
    out = {}
    for name, request, resolve in cases:
        runs = []
        for i in range(repeats + 2):
            if i < repeats:
                problem._DRAW_CACHE.clear()
            c0, t0 = time.process_time(), time.perf_counter()
            r = build_response(analyse(request, resolve))
            runs.append({"cpu_s": time.process_time() - c0, "wall_s": time.perf_counter() - t0,
                         "phases_s": r["analysis"]["timings_s"], "verdict": r["verdict"]["effect"]})
        cold, warm = runs[:repeats], runs[repeats:]
        best = min(cold, key=lambda x: x["cpu_s"])
        out[name] = {"cold_cpu_s": best["cpu_s"], "cold_wall_s": min(x["wall_s"] for x in cold),
                     "warm_cpu_s": min(x["cpu_s"] for x in warm), "warm_wall_s": min(x["wall_s"] for x in warm),
                     "phases_of_best_cold_run_s": best["phases_s"], "verdict": best["verdict"]}
        ph = " ".join(f"{k} {v:.2f}" for k, v in best["phases_s"].items())
        print(f"{name:34s} cold CPU {best['cpu_s']:.2f} s (wall {out[name]['cold_wall_s']:.2f}), "
              f"warm CPU {out[name]['warm_cpu_s']:.2f} s | phases (wall, s): {ph}", flush=True)
    return out


FRESH_CASES = ("example", "analytical5", *(f"hybrid:{k}" for k in truth_hybrid.KINDS))


def _fresh_request(case: str) -> tuple[dict, object]:
    """The request of a fresh-process timing case, and its base resolver (None: analytical)."""
    if case == "example":
        return json.loads((REPO / "examples" / "diagnosis.json").read_text()), None
    if case == "analytical5":
        return truth.make_trial(np.random.default_rng([7, 0]), "sensor_mass", with_null=False).request, None
    kind = case.split(":", 1)[1]
    trial = truth_hybrid.make_hybrid_trial(np.random.default_rng([7, 1]), "sensor_mass", kind, with_null=False)
    return trial.request, base_resolver(trial.source)


def fresh_child(case: str) -> dict:
    """One fresh process: the first diagnosis in it, then as :func:`_first_calls`.

    The request is built before the clock starts (the benchmark's truth); the first call
    includes whatever the diagnosis imports on first use.
    """
    import rcsa

    request, resolve = _fresh_request(case)

    def run() -> tuple[float, float, dict]:
        c0, t0 = time.process_time(), time.perf_counter()
        r = build_response(analyse(request, resolve)) if resolve is not None else rcsa.diagnose(request)
        return time.process_time() - c0, time.perf_counter() - t0, r

    return _first_calls(case, run, True)


def timing_fresh(repeats: int = 3, cases: tuple[str, ...] = FRESH_CASES) -> dict:
    """The first diagnosis in ``repeats`` fresh processes per case; the best (least CPU) first run of each.

    Analytical cases (JSON requests) run in :func:`first_call_child` (only ``rcsa`` and numpy
    imported before the call); hybrid ones, which need the benchmark's truth for their
    measured spindle, in :func:`fresh_child` (the diagnosis's modules imported before it).
    """
    import subprocess
    import tempfile

    env = dict(os.environ)
    if os.environ.get("RCSA_TIMING_BYTECODE") == "1":
        # the modules' bytecode compiled once, as an installed wheel or the Docker image has it
        # (an editable install under PYTHONDONTWRITEBYTECODE=1 compiles every module in every process)
        prefix = tempfile.mkdtemp(prefix="rcsa-pyc-")
        env["PYTHONPYCACHEPREFIX"] = prefix
        subprocess.run([sys.executable, "-m", "compileall", "-q", str(REPO / "src"), str(REPO / "benchmarks"),
                        str(REPO / "tests")], env=env, check=True, capture_output=True)
        env["PYTHONDONTWRITEBYTECODE"] = "1"
    out = {}
    for case in cases:
        runs = []
        for _ in range(repeats):
            if case.startswith("hybrid:"):
                argv = [sys.executable, __file__, "--timing-child", case]
            else:
                path = Path(tempfile.mkdtemp()) / "request.json"
                path.write_text(json.dumps(_fresh_request(case)[0], default=lambda x: np.asarray(x).tolist()))
                argv = [sys.executable, __file__, "--first-call", case, str(path)]
            done = subprocess.run(argv, capture_output=True, text=True, check=True, cwd=REPO, env=env)
            runs.append(json.loads(done.stdout.strip().splitlines()[-1]))
        best = min(runs, key=lambda x: x["first_cpu_s"])
        out[case] = {**best, "runs": runs}
        print(f"{case:22s} first in a process: CPU {best['first_cpu_s']:.2f} s (wall {best['first_wall_s']:.2f}) = "
              f"{best['first_over_warm_prediction_cpu']:.0f}x a warm RA-1 prediction at 10 000 lines "
              f"({best['warm_prediction_cpu_s'] * 1e3:.1f} ms), {best['first_over_prediction_cpu']:.0f}x a cold one "
              f"({best['prediction_cpu_s'] * 1e3:.1f} ms CPU); Σ cached {best['warm_cpu_s']:.2f} s; Σ dropped "
              f"{best['cold_in_warm_process_cpu_s']:.2f} s; bytecode cached {best['bytecode_cached']} | "
              f"load {best['load_average'][0]:.1f} ({best['rcsa']})", flush=True)
    return out


def upper_bound_95(k: int, n: int) -> float:
    """One-sided 95 % Clopper–Pearson upper bound of a rate seen ``k`` times in ``n`` trials.

    >>> round(upper_bound_95(0, 60), 4)   # 1 − 0.05^(1/60)
    0.0487
    """
    if n == 0:
        return 1.0
    if k >= n:
        return 1.0

    def cdf(p: float) -> float:  # P(X ≤ k), X ~ Binomial(n, p)
        return sum(math.comb(n, j) * p**j * (1 - p) ** (n - j) for j in range(k + 1))
    lo, hi = k / n, 1.0
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if cdf(mid) > 0.05 else (lo, mid)
    return hi


def summarise(records: list[dict]) -> dict:
    """Scores of ``docs/diagnosis.md`` §5.2 from the trial records."""
    eff = [r for r in records if r["effect"] != "none"]
    null = [r for r in records if r["effect"] == "none"]
    strong = [r for r in eff if r["snr_true"] >= 10]

    def rate(rs: list[dict], key: str) -> float | None:
        return float(np.mean([bool(r[key]) for r in rs])) if rs else None

    bins = {}
    for lo, hi in SNR_BINS:
        rs = [r for r in eff if lo <= r["snr_true"] < hi]
        bins[f"{lo:g}-{hi:g}"] = {"n": len(rs), "top1": rate(rs, "top1"), "equivalence": rate(rs, "equivalent"),
                                  "miss": float(np.mean([r["status"] == "none" for r in rs])) if rs else None}
    classes = [c for c in truth.EFFECTS if any(r["effect"] == c for r in records)]
    # model forms (clamping_model, interface_scale) are verdicts too: a column each
    forms = sorted({r["verdict"] for r in records if r["verdict"] not in truth.EFFECTS} - {"ambiguous"})
    columns = [*truth.EFFECTS, *forms, "ambiguous"]
    confusion = {h: dict.fromkeys(columns, 0) for h in classes}
    for r in records:
        col = "ambiguous" if r["status"] == "ambiguous" else r["verdict"]
        confusion[r["effect"]][col] += 1
    per_class = {}
    for c in classes:
        rs = [r for r in records if r["effect"] == c]
        if rs:
            per_class[c] = {"n": len(rs), "top1": rate(rs, "top1") if c != "none" else None,
                            "identified_or_set": rate(rs, "in_set") if c != "none" else None,
                            "median_snr": float(np.median([r["snr_true"] for r in rs])),
                            "ambiguous": int(sum(r["status"] == "ambiguous" for r in rs)),
                            "ambiguous_with": dict(Counter(x for r in rs for x in r["ambiguous_with"]))}
    good = [r for r in eff if r["top1"] and r["held_out_gap_ratio"] is not None]
    claims = [r for r in eff if r["status"] != "none" and r["held_out_gap_ratio"] is not None]
    db_ratio = [r["held_out_db_after"] / r["held_out_db_before"] for r in good if r["held_out_db_before"]]
    runtimes = [r["runtime_s"] for r in records]
    cpu = [r.get("cpu_s", np.nan) for r in records]
    return {
        "trials": len(records), "effect_trials": len(eff), "null_trials": len(null),
        "top1_all": rate(eff, "top1"), "top1_snr_ge_10": rate(strong, "top1"), "n_snr_ge_10": len(strong),
        "top1_strict_snr_ge_10": rate(strong, "top1_strict") if all("top1_strict" in r for r in strong) else None,
        "model_form_verdicts": dict(Counter(f"{r['effect']}->{r['verdict']}:{r['form_verdict']}" for r in records
                                            if r.get("form_verdict"))),
        "equivalence_all": rate(eff, "equivalent"), "equivalence_snr_ge_10": rate(strong, "equivalent"),
        "set_accuracy_all": rate(eff, "in_set"), "set_accuracy_snr_ge_10": rate(strong, "in_set"),
        "best_ranked_snr_ge_10": float(np.mean([r["best_ranked"] == r["effect"] for r in strong])) if strong else None,
        "false_claims_on_null": float(np.mean([r["status"] != "none" for r in null])) if null else None,
        # a verdict naming no effect of the hidden one's equivalence class (on no-effect data: any claim)
        "false_claims_all_trials": float(np.mean([_false_claim(r) for r in records])) if records else None,
        "false_claims_all_count": f"{sum(_false_claim(r) for r in records)}/{len(records)}",
        "false_claims_all_upper_95": upper_bound_95(sum(_false_claim(r) for r in records), len(records)),
        "wrong_effect_claims": int(sum(_false_claim(r) for r in eff)),
        "false_claims_count": f"{sum(r['status'] != 'none' for r in null)}/{len(null)}",
        "miss_rate": float(np.mean([r["status"] == "none" for r in eff])) if eff else None,
        "by_snr": bins,
        "median_held_out_gap_ratio_correct": float(np.median([r["held_out_gap_ratio"] for r in good])) if good else None,
        "median_held_out_gap_ratio_all_claims": (float(np.median([r["held_out_gap_ratio"] for r in claims]))
                                                 if claims else None),
        "median_held_out_db_ratio_correct": float(np.median(db_ratio)) if db_ratio else None,
        "median_held_out_db_before_after_correct": ([float(np.median([r["held_out_db_before"] for r in good])),
                                                     float(np.median([r["held_out_db_after"] for r in good]))]
                                                    if good else None),
        "confirmation_rate": rate([r for r in eff if r["status"] != "none" and r["confirmed"] is not None],
                                  "confirmed"),
        "spurious_second_effect": float(np.mean([r["second_effect"] is not None for r in eff])) if eff else None,
        "runtime_s": {"median": float(np.median(runtimes)), "p95": float(np.quantile(runtimes, 0.95)),
                      "max": float(np.max(runtimes))},
        "cpu_s": {"median": float(np.median(cpu)), "p95": float(np.quantile(cpu, 0.95)), "max": float(np.max(cpu))},
        "confusion": confusion, "per_class": per_class,
    }


def print_summary(s: dict) -> None:
    """Human-readable summary."""
    def pct(x: float | None) -> str:
        return "n/a" if x is None else f"{x:.3f}"
    print(f"trials {s['trials']} ({s['effect_trials']} with an effect, {s['null_trials']} without)")
    print(f"top-1 (identified and correct): all {pct(s['top1_all'])}, SNR>=10 {pct(s['top1_snr_ge_10'])} "
          f"(n={s['n_snr_ge_10']}); strictly the effect's own name: {pct(s['top1_strict_snr_ge_10'])}; "
          f"model forms as verdict: {s['model_form_verdicts']}")
    print(f"equivalence-class: all {pct(s['equivalence_all'])}, SNR>=10 {pct(s['equivalence_snr_ge_10'])}; "
          f"set accuracy SNR>=10 {pct(s['set_accuracy_snr_ge_10'])}; best-ranked SNR>=10 "
          f"{pct(s['best_ranked_snr_ge_10'])}")
    print(f"false claims, all trials (no effect of the hidden class named): {s['false_claims_all_count']} "
          f"(95 % upper bound {100 * s['false_claims_all_upper_95']:.1f} %)")
    print(f"false claims on no-effect data: {s['false_claims_count']} ({pct(s['false_claims_on_null'])}); "
          f"miss rate {pct(s['miss_rate'])}")
    for k, b in s["by_snr"].items():
        print(f"  SNR {k:>8s}: n={b['n']:3d} top1={pct(b['top1'])} equiv={pct(b['equivalence'])} miss={pct(b['miss'])}")
    print(f"held-out gap ratio (median, correct): {pct(s['median_held_out_gap_ratio_correct'])}; all claims "
          f"{pct(s['median_held_out_gap_ratio_all_claims'])}; dB ratio {pct(s['median_held_out_db_ratio_correct'])} "
          f"(median dB {s['median_held_out_db_before_after_correct']})")
    print(f"confirmation rate {pct(s['confirmation_rate'])}; spurious second effect {pct(s['spurious_second_effect'])}")
    print(f"runtime per diagnosis (wall, shared machine): median {s['runtime_s']['median']:.2f} s, "
          f"95 % {s['runtime_s']['p95']:.2f} s, max {s['runtime_s']['max']:.2f} s; CPU time: median "
          f"{s['cpu_s']['median']:.2f} s, 95 % {s['cpu_s']['p95']:.2f} s")
    cols = list(next(iter(s["confusion"].values())))
    short = {c: c[:6] for c in cols}
    print("confusion (rows hidden, columns verdict):")
    print(" " * 31 + " ".join(f"{short[c]:>6s}" for c in cols))
    for h, row in s["confusion"].items():
        print(f"  {h:29s}" + " ".join(f"{row[c]:6d}" for c in cols))
    print("per class:")
    for c, v in s["per_class"].items():
        print(f"  {c:29s} n={v['n']:3d} top1={pct(v['top1'])} median SNR={v['median_snr']:.1f} "
              f"ambiguous={v['ambiguous']} {v['ambiguous_with'] or ''}")


def check_mesh() -> None:
    """FE discretisation error of the truth against the exact RA-1 model, relative to |H|."""
    from tests.oracles.fe_assembly import tool_point_receptance

    from rcsa.model.assembly import build_model
    from rcsa.model.contract import parse_assembly
    from rcsa.physics.elimination import tip_receptance

    f = truth.FREQUENCY_HZ
    for stickout in truth.STICKOUTS_M:
        doc = {**truth.base_document(), "frequency": {"values_hz": f.tolist()}}
        doc["tool"]["stickout_m"] = stickout
        exact = tip_receptance(build_model(parse_assembly(doc)).chain(), 2 * np.pi * f)[:, 0, 0]
        fe = tool_point_receptance(doc, f, max_element_length_m=truth.MESH_M)[:, 0, 0]
        rel = np.abs(fe - exact) / np.abs(exact)
        print(f"stickout {stickout * 1e3:.0f} mm: max |FE-exact|/|H| = {rel.max():.2e}, median {np.median(rel):.2e}")


def calibrate(kind: str, evaluations: int = 400) -> dict[str, float]:
    """Distributed contact closest to RA-1's lumped joint (``truth.HT_DISTRIBUTED``/``SH_DISTRIBUTED``).

    Least squares (Nelder-Mead on log10 of the four per-length values, started from the stored
    ones) of the features of the nominal FE truth with the distributed contact against those
    with the point joint, at the five stickouts; frequencies weighted by 1/0.3 %, amplitudes
    and compliance by 1/3 %.
    """
    from scipy.optimize import minimize

    from rcsa.analysis.diagnosis.features import design_windows, extract

    f = np.geomspace(50.0, 8000.0, 1000)
    ones = dict.fromkeys(["tool_e", "tool_rho", "steel_e", "steel_rho", "loss", "bearing_k", "bearing_c",
                          "sh_kt", "sh_kr", "sh_c"], 1.0)
    nz = truth.Nuisance(ones, [{"ht_kt": 1.0, "ht_kr": 1.0, "ht_c": 1.0, "stickout_dm": 0.0}
                               for _ in truth.STICKOUTS_M])
    docs = truth.config_documents(truth.base_document(), nz, truth.STICKOUTS_M)
    targets = []
    for d in docs:
        h = truth.effect_frf("none", {}, d, f)
        w = design_windows(f, h)
        targets.append((w, extract(f, h, w)))
    start = truth.HT_DISTRIBUTED if kind == "holder_tool" else truth.SH_DISTRIBUTED
    keys = list(start)

    def cost(x: np.ndarray) -> float:
        c = 0.0
        for d, (w, f0) in zip(docs, targets, strict=True):
            spec = {k: start[k] * 10**xi for k, xi in zip(keys, x, strict=True)}
            if kind == "holder_tool":
                h = truth._solve(d, f, {"holder_tool_distributed": spec})
            else:
                spec.update(shank_segments=truth.TAPER_SHANK,
                            contact_length_m=sum(p["length_m"] for p in truth.TAPER_SHANK))
                h = truth._solve(truth._taper_spindle(d), f, {"spindle_holder_distributed": spec})
            weight = np.where([n.endswith("frequency") for n in w.names], 1 / 0.003, 1 / 0.03)
            c += float(np.sum(((extract(f, h, w) - f0) * weight) ** 2))
        return c

    res = minimize(cost, np.zeros(len(keys)), method="Nelder-Mead",
                   options={"maxfev": evaluations, "xatol": 1e-3, "fatol": 1e-3,
                            "initial_simplex": np.vstack([np.zeros(len(keys)), 0.3 * np.eye(len(keys))])})
    out = {k: float(start[k] * 10**xi) for k, xi in zip(keys, res.x, strict=True)}
    print(f"{kind}: cost {cost(np.zeros(len(keys))):.4g} -> {res.fun:.4g}: {out}")
    return out


def example(request_path: Path, png_path: Path, effect: str = "holder_tool_joint", seed: int = 3) -> None:
    """The worked example of docs/diagnosis.md: one trial's request, its diagnosis and the figure."""
    from rcsa.analysis.diagnosis.report import diagnosis_figure
    from rcsa.analysis.figures import save_figure

    trial = truth.make_trial(np.random.default_rng([seed, 0]), effect, with_null=False)
    request_path.parent.mkdir(parents=True, exist_ok=True)
    request_path.write_text(json.dumps(trial.request))
    a = analyse(trial.request)
    r = build_response(a)
    png_path.parent.mkdir(parents=True, exist_ok=True)
    save_figure(diagnosis_figure(a, r), png_path)
    print(f"hidden {effect} {trial.params}")
    print(json.dumps({"verdict": r["verdict"], "gap_summary": r["gap"]["summary"],
                      "effects": [{k: v for k, v in e.items() if k != "corrected_h"} for e in r["effects"]],
                      "ranking": [(e["effect"], round(e["log_bayes_factor"], 1)) for e in r["ranking"]],
                      "runtime_s": r["runtime_s"]}, indent=1))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--trials", type=int, default=250, help="number of trials (balanced over the 10 classes)")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--workers", type=int, default=min(2, os.cpu_count() or 1))
    ap.add_argument("--classes", nargs="*", default=list(truth.EFFECTS), choices=truth.EFFECTS)
    ap.add_argument("--tolerance-scale", type=float, default=1.0,
                    help="true tolerances relative to those the diagnoser assumes (misspecification run)")
    ap.add_argument("--out", type=Path, default=DEFAULT_OUT)
    ap.add_argument("--hybrid", action="store_true", help="measured-spindle trials (writes diagnosis_hybrid.json)")
    ap.add_argument("--kinds", nargs="*", default=list(truth_hybrid.KINDS), choices=truth_hybrid.KINDS)
    ap.add_argument("--trials-per-class", type=int, default=12, help="hybrid: trials per class and kind")
    ap.add_argument("--length-log-sd", type=float, default=truth_hybrid.LENGTH_LOG_SD,
                    help="hybrid: how well the cantilever length of a direct_frf spindle is known (ln sd; "
                         "the estimate scatters by it and the request states it)")
    ap.add_argument("--score-partial", type=Path, metavar="JSONL",
                    help="hybrid: only score the records a cut-short run wrote (with that run's settings)")
    ap.add_argument("--check-mesh", action="store_true", help="only print the FE truth's discretisation error")
    ap.add_argument("--calibrate", choices=["holder_tool", "spindle_holder"],
                    help="only refit the distributed contact closest to the base joint")
    ap.add_argument("--example", nargs=2, type=Path, metavar=("REQUEST_JSON", "PNG"),
                    help="only write the worked example's request and figure (docs/diagnosis.md)")
    ap.add_argument("--example-effect", default="holder_tool_joint", choices=truth.EFFECTS)
    ap.add_argument("--timing", action="store_true",
                    help="only time one diagnosis per kind of spindle, cold and warm, with its phases")
    ap.add_argument("--timing-fresh", action="store_true",
                    help="only time the first diagnosis in fresh processes (examples/diagnosis.json, 5 stickouts, "
                         "3 stickouts per measured spindle), with a repeat and RA-1's prediction in each")
    ap.add_argument("--timing-child", choices=FRESH_CASES, help=argparse.SUPPRESS)
    ap.add_argument("--solid3d", action="store_true",
                    help="3-D reference truths, bonded and point base (writes diagnosis_solid3d.json)")
    ap.add_argument("--solid3d-cases", nargs="*", metavar="CASE",
                    help="cases of the 3-D data set tests/data/solid3d (default: every one outside the clamping "
                         "calibration), one tap test each per base model (writes diagnosis_solid3d_cases.json)")
    ap.add_argument("--base-models", nargs="*", default=["point", "point_ra1", "bonded"],
                    choices=["point", "point_ra1", "bonded"], help="--solid3d-cases: the base models")
    ap.add_argument("--solid3d-write-data", action="store_true",
                    help="only build and store the 3-D truths' reduced models (tests/data/diagnosis_solid3d)")
    ap.add_argument("--out-of-catalogue", action="store_true",
                    help="holder crack, non-uniform layer, holder mass (writes diagnosis_out_of_catalogue.json)")
    ap.add_argument("--claim-data", nargs="+", choices=["hybrid", "matched", "scatter2"], metavar="SET",
                    help="only record what the claim rule needs (diagnosis_calibration.claim_data) on a tuning seed: "
                         "hybrid (--trials-per-class per class and kind), matched and scatter2 (per class)")
    ap.add_argument("--form-error", action="store_true",
                    help="only measure the candidates' form error on correct fits (--trials-per-class per effect)")
    ap.add_argument("--evaluation", action="store_true",
                    help="use the benchmark's evaluation seed (EVALUATION_SEEDS: never used while tuning)")
    args = ap.parse_args()
    if args.evaluation:
        kind = ("solid3d_cases" if args.solid3d_cases is not None else "solid3d" if args.solid3d else
                "out_of_catalogue" if args.out_of_catalogue else "hybrid" if args.hybrid else
                "scatter2" if args.tolerance_scale == 2.0 else "matched")
        args.seed = EVALUATION_SEEDS[kind]
    if args.solid3d_write_data:
        from tests.analysis.diagnosis import truth_solid3d

        truth_solid3d.write_data()
        return
    if args.solid3d or args.out_of_catalogue or args.solid3d_cases is not None:
        run_outside(args)
        return
    if args.claim_data:
        from benchmarks.diagnosis_calibration import claim_trial

        n = args.trials_per_class
        plan = [(e, k, 1.0) for k in args.kinds for e in truth_hybrid.HYBRID_EFFECTS for _ in range(n)
                if "hybrid" in args.claim_data]
        plan += [(e, "matched", 1.0) for e in truth.EFFECTS for _ in range(n) if "matched" in args.claim_data]
        plan += [(e, "matched", 2.0) for e in truth.EFFECTS for _ in range(n) if "scatter2" in args.claim_data]
        out = args.out.with_suffix(".jsonl")
        with ProcessPoolExecutor(max_workers=args.workers) as pool, out.open("a") as fh:
            futures = [pool.submit(claim_trial, i, e, k, args.seed, ts) for i, (e, k, ts) in enumerate(plan)]
            for n_done, fut in enumerate(futures):
                rec = fut.result()
                rec["seed"] = args.seed
                fh.write(json.dumps(rec) + "\n")
                fh.flush()
                print(f"[{n_done + 1}/{len(plan)}] {rec['kind']:16s} {rec['effect']:29s} -> {rec['status']:10s} "
                      f"{rec['verdict']:29s} SNR {rec['snr_true']:5.1f}", flush=True)
        return
    if args.form_error:
        from benchmarks.diagnosis_calibration import form_error

        form_error(args)
        return
    if args.timing_child:
        print(json.dumps(fresh_child(args.timing_child)))
        return
    if args.timing_fresh:
        result = {"machine": machine(), "timing_fresh": timing_fresh()}
        path = DEFAULT_OUT.with_name(os.environ.get("RCSA_TIMING_OUT", "diagnosis_timing_fresh.json"))
        path.write_text(json.dumps(result, indent=1))
        print(f"wrote {path}")
        return
    if args.timing:
        result = {"machine": machine(), "timing": timing()}
        path = DEFAULT_OUT.with_name("diagnosis_timing.json")
        path.write_text(json.dumps(result, indent=1))
        print(f"wrote {path}")
        return
    if args.example:
        example(*args.example, effect=args.example_effect, seed=args.seed)
        return
    if args.check_mesh:
        check_mesh()
        return
    if args.calibrate:
        calibrate(args.calibrate)
        return
    if args.score_partial:
        score_partial(args)
        return
    if args.hybrid:
        run_hybrid(args)
        return
    plan_rng = np.random.default_rng(args.seed)
    plan = [args.classes[i % len(args.classes)] for i in range(args.trials)]
    plan = [plan[i] for i in plan_rng.permutation(len(plan))]
    t0 = time.perf_counter()
    records: list[dict] = []
    args.out.parent.mkdir(parents=True, exist_ok=True)
    partial = args.out.with_suffix(".partial.jsonl")  # as in run_hybrid: a run cut short can still be scored
    partial.write_text("")
    load = [os.getloadavg()[0]]
    with ProcessPoolExecutor(max_workers=args.workers) as pool:
        futures = [pool.submit(run_trial, i, e, args.seed, args.tolerance_scale) for i, e in enumerate(plan)]
        for k, fut in enumerate(futures):
            rec = fut.result()
            records.append(rec)
            load.append(os.getloadavg()[0])
            with partial.open("a") as fh:
                fh.write(json.dumps(rec) + "\n")
            print(f"[{k + 1}/{len(plan)}] {rec['effect']:29s} -> {rec['status']:10s} {rec['verdict']:29s} "
                  f"SNR {rec['snr_true']:5.1f} lnBF {rec['log_bayes_factor'] or 0:7.1f} {rec['runtime_s']:.1f} s",
                  flush=True)
    summary = summarise(records)
    summary["wall_time_s"] = time.perf_counter() - t0
    summary["command"] = " ".join(["benchmarks/bench_diagnosis.py", *sys.argv[1:]])
    summary["settings"] = {"stickouts_m": list(truth.STICKOUTS_M), "band_hz": [50.0, 8000.0], "line_step_hz": 2.0,
                           "noise": "1 % + floor -50 dB of peak, 5 averages", "seed": args.seed,
                           "seed_role": seed_role(args.seed),
                           "tolerance_scale": args.tolerance_scale, "workers": args.workers,
                           "machine": machine(), "load_average": {"min": min(load), "max": max(load),
                                                                  "median": float(np.median(load))}}
    print_summary(summary)
    args.out.write_text(json.dumps({"summary": summary, "trials": records}, indent=1))
    partial.unlink()
    print(f"wrote {args.out}")


def run_outside(args: argparse.Namespace) -> None:
    """The 3-D (``--solid3d``) or out-of-catalogue (``--out-of-catalogue``) trials, scored and written."""
    from benchmarks import diagnosis_outside as outside
    from tests.analysis.diagnosis import truth_solid3d

    if args.solid3d_cases is not None:
        cases = args.solid3d_cases or truth_solid3d.dataset_cases_outside_calibration()
        plan = [(c, m) for m in args.base_models for c in cases for _ in range(args.trials_per_class)]
        name, fn = "diagnosis_solid3d_cases.json", outside.run_dataset_trial
        jobs = [(i, c, m, args.seed) for i, (c, m) in enumerate(plan)]
    elif args.solid3d:
        variants = list(truth_solid3d.VARIANTS)
        plan = [(v, m) for m in ("bonded", "point") for v in variants for _ in range(args.trials_per_class)]
        name, fn = "diagnosis_solid3d.json", outside.run_solid_trial
        jobs = [(i, v, m, args.seed, args.tolerance_scale) for i, (v, m) in enumerate(plan)]
    else:
        plan = [e for e in truth.OUT_OF_CATALOGUE for _ in range(args.trials_per_class)]
        name, fn = "diagnosis_out_of_catalogue.json", outside.run_ooc_trial
        jobs = [(i, e, args.seed) for i, e in enumerate(plan)]
    out = args.out if args.out != DEFAULT_OUT else DEFAULT_OUT.with_name(name)
    partial = out.with_suffix(".partial.jsonl")
    partial.write_text("")
    t0 = time.perf_counter()
    load = [os.getloadavg()[0]]
    records = []
    with ProcessPoolExecutor(max_workers=args.workers) as pool:
        futures = [pool.submit(fn, *job) for job in jobs]
        for n, fut in enumerate(futures):
            rec = fut.result()
            records.append(rec)
            load.append(os.getloadavg()[0])
            with partial.open("a") as fh:
                fh.write(json.dumps(rec) + "\n")
            print(f"[{n + 1}/{len(jobs)}] {rec.get('variant', rec.get('case', rec.get('effect'))):18s} "
                  f"{rec.get('base_model', ''):6s} "
                  f"-> {rec['status']:10s} {rec['verdict']:29s} dB {rec['base_db_error']:.2f} -> "
                  f"{rec['corrected_db_error']:.2f} (calibrated {rec['calibrated_db_error']:.2f}) "
                  f"{rec['runtime_s']:.1f} s", flush=True)
    summary = (outside.summarise_dataset(records) if args.solid3d_cases is not None else
               outside.summarise_solid(records) if args.solid3d else outside.summarise_ooc(records))
    summary.update(command=" ".join(["benchmarks/bench_diagnosis.py", *sys.argv[1:]]),
                   wall_time_s=time.perf_counter() - t0, machine=machine(), workers=args.workers, seed=args.seed,
                   seed_role=seed_role(args.seed),
                   load_average={"min": min(load), "max": max(load), "median": float(np.median(load))})
    print(json.dumps(summary, indent=1))
    out.write_text(json.dumps({"summary": summary, "trials": records}, indent=1))
    partial.unlink()
    print(f"wrote {out}")


def machine() -> str:
    """CPU model and count (what the runtimes were measured on)."""
    model = "unknown CPU"
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                model = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    return f"{model}, {os.cpu_count()} cores (shared)"


def hybrid_summary(records: list[dict], args: argparse.Namespace, planned: int) -> dict:
    """Scores of hybrid trials per kind of spindle and pooled, printed; ``planned`` trials were asked for."""
    kinds = [k for k in args.kinds if any(r["kind"] == k for r in records)]
    summary = {"pooled": summarise(records), "by_kind": {k: summarise([r for r in records if r["kind"] == k])
                                                         for k in kinds}}
    rot = [r for r in records if r["kind"] == "direct_frf" and r["effect"] == "spindle_rotational_receptance"]
    strong = [r for r in rot if r["snr_true"] >= 10]
    summary["direct_frf_rotation_named"] = {
        "n": len(rot), "identified": float(np.mean([r["top1"] for r in rot])) if rot else None,
        "named_in_verdict": float(np.mean([r["in_set"] for r in rot])) if rot else None,
        "n_snr_ge_10": len(strong),
        "identified_snr_ge_10": float(np.mean([r["top1"] for r in strong])) if strong else None}
    summary["trials_done"], summary["trials_planned"] = len(records), planned
    summary["command"] = " ".join(["benchmarks/bench_diagnosis.py", *sys.argv[1:]])
    summary["settings"] = {"stickouts_m": list(truth_hybrid.STICKOUTS_M), "band_hz": [50.0, 8000.0],
                           "line_step_hz": 2.0, "noise": "taps 1 % + floor -50 dB of peak, 5 averages; "
                           "stored spindle FRFs 0.3 %", "plane": "spindle_nose", "kinds": list(args.kinds),
                           "trials_per_class_and_kind": args.trials_per_class, "seed": args.seed,
                           "seed_role": seed_role(args.seed),
                           "direct_frf_length_log_sd": args.length_log_sd,
                           "workers": args.workers, "machine": machine()}
    for k in kinds:
        print(f"===== {k}")
        print_summary(summary["by_kind"][k])
    print("===== pooled")
    print_summary(summary["pooled"])
    print(f"direct_frf rotation errors named: {summary['direct_frf_rotation_named']}")
    print(f"trials: {len(records)} of {planned} planned")
    return summary


def score_partial(args: argparse.Namespace) -> None:
    """Score the records a cut-short hybrid run wrote (``--score-partial``) as the full run would."""
    records = [json.loads(line) for line in args.score_partial.read_text().splitlines() if line.strip()]
    classes = [c for c in truth_hybrid.HYBRID_EFFECTS if c in args.classes or args.classes == list(truth.EFFECTS)]
    summary = hybrid_summary(records, args, planned=len(classes) * len(args.kinds) * args.trials_per_class)
    summary["cut_short"] = True
    out = args.out if args.out != DEFAULT_OUT else DEFAULT_OUT.with_name("diagnosis_hybrid.json")
    out.write_text(json.dumps({"summary": summary, "trials": records}, indent=1))
    print(f"wrote {out}")


def run_hybrid(args: argparse.Namespace) -> None:
    """The hybrid benchmark: every kind of measured spindle × every class it admits."""
    classes = [c for c in truth_hybrid.HYBRID_EFFECTS if c in args.classes or args.classes == list(truth.EFFECTS)]
    plan = [(e, k) for k in args.kinds for e in classes for _ in range(args.trials_per_class)]
    plan = [plan[i] for i in np.random.default_rng(args.seed).permutation(len(plan))]
    t0 = time.perf_counter()
    records: list[dict] = []
    out = args.out if args.out != DEFAULT_OUT else DEFAULT_OUT.with_name("diagnosis_hybrid.json")
    out.parent.mkdir(parents=True, exist_ok=True)
    partial = out.with_suffix(".partial.jsonl")  # every record as it comes: a run cut short can still be scored
    partial.write_text("")
    load = [os.getloadavg()[0]]
    with ProcessPoolExecutor(max_workers=args.workers) as pool:
        futures = [pool.submit(run_hybrid_trial, i, e, k, args.seed, args.length_log_sd)
                   for i, (e, k) in enumerate(plan)]
        for n, fut in enumerate(futures):
            rec = fut.result()
            records.append(rec)
            load.append(os.getloadavg()[0])
            with partial.open("a") as fh:
                fh.write(json.dumps(rec) + "\n")
            print(f"[{n + 1}/{len(plan)}] {rec['kind']:16s} {rec['effect']:29s} -> {rec['status']:10s} "
                  f"{rec['verdict']:29s} SNR {rec['snr_true']:5.1f} lnBF {rec['log_bayes_factor'] or 0:7.1f} "
                  f"{rec['runtime_s']:.1f} s", flush=True)
    summary = hybrid_summary(records, args, planned=len(plan))
    summary["wall_time_s"] = time.perf_counter() - t0
    summary["settings"]["load_average"] = {"min": min(load), "max": max(load), "median": float(np.median(load))}
    out.write_text(json.dumps({"summary": summary, "trials": records}, indent=1))
    partial.unlink()
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
