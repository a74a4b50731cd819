"""The compute budget: refused before any work above the limits, and true to its word below.

* Every operation is refused above the sync limits with a problem that names the estimate,
  its terms, the limit, and how to shrink the request or run it as a job; the same request
  with ``Prefer: respond-async`` is accepted as a job (within the job limits).
* The worst request of each shape inside a budget (1.5 s, 7.5 % of the sync limit, to keep
  the suite fast: the estimates are linear in the sizes) runs in a fresh process: its CPU time
  stays within 1.5 × the estimate + 0.5 s (so a request inside the full sync limit of 20 s
  stays far below the stated bound of 60 s), and the largest prediction the sync memory
  limit admits stays below the stated peak RSS (1.5 GiB). ``benchmarks/bench_budget.py``
  runs the same cases at the full limit.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile

import pytest

from rcsa.app import budget
from rcsa.reference import ra1
from tests.helpers import REPO

from .budget_cases import worst_cases
from .conftest import assert_problem

SCALE = 0.075


def test_limits_and_the_stated_bound_leave_a_margin():
    assert budget.STATED_SYNC_BOUND.seconds >= 1.5 * budget.SYNC.seconds + 0.5
    assert budget.STATED_SYNC_BOUND.memory_bytes > budget.SYNC.memory_bytes
    assert budget.JOB.seconds > budget.SYNC.seconds and set(budget.OPERATIONS) >= {
        "prediction", "batch", "library", "lobes", "effects", "identification", "diagnosis"}


def test_a_request_over_the_budget_is_refused_with_its_cost_and_the_way_out(make_client):
    with make_client(job_workers=0) as client:  # the queued job is not run
        _refused_then_queued(client)


def _refused_then_queued(client) -> None:
    wide = ra1({"start_hz": 5.0, "stop_hz": 1.0e7, "step_hz": 1.0e4})  # the 10-minute effect analysis
    for path in ("/v1/tool-point-frf", "/v1/effects"):
        problem = assert_problem(client.post(path, json=wide), 422)
        assert problem["type"] == "urn:rcsa:problem:compute-budget-exceeded"
        cost, limit = problem["budget"]["cost"], problem["budget"]["limit"]
        assert cost["estimated_seconds"] > limit["estimated_seconds"] == budget.SYNC.seconds
        assert cost["terms"]["elements_cut_for_modes"] > 1000 and problem["budget"]["shrink"]
        assert "Prefer: respond-async" in problem["detail"] or "Make it smaller" in problem["detail"]
    effects = {"assembly": ra1({"start_hz": 5.0, "stop_hz": 5000.0, "step_hz": 5.0}), "band_hz": [5.0, 6.0e5]}
    problem = assert_problem(client.post("/v1/effects", json=effects), 422)
    assert "Prefer: respond-async" in problem["detail"] and "band_hz" in problem["detail"]
    queued = client.post("/v1/effects", json=effects, headers={"Prefer": "respond-async"})
    assert queued.status_code == 202 and queued.headers["location"].startswith("/v1/jobs/j-")
    assert client.get(queued.headers["location"]).json()["kind"] == "effects"


def test_every_route_states_its_body_limit_and_enforces_it(client):
    spec = client.get("/openapi.json").json()
    limits = {(path, method): op.get("x-max-body-bytes") for path, item in spec["paths"].items()
              for method, op in item.items() if method == "post"}
    assert all(limits.values()), [k for k, v in limits.items() if not v]
    assert limits[("/v1/diagnoses", "post")] == budget.BODY_LIMITS["diagnosis"]
    big = b'{"x": "' + b"a" * (budget.BODY_LIMITS["prediction"] + 1) + b'"}'
    problem = assert_problem(client.post("/v1/tool-point-frf", content=big,
                                         headers={"content-type": "application/json"}), 413)
    assert "x-max-body-bytes" in problem["detail"]


def _probe(cases: list[dict]) -> list[dict]:
    """Run ``cases`` in a fresh process with an empty default store of its own (not the
    worker's private ``$XDG_DATA_HOME`` that earlier tests wrote into), measuring each
    request's peak memory as that process's own (``_budget_probe.peak_rss_bytes``)."""
    with tempfile.TemporaryDirectory(prefix="rcsa-budget-probe-") as home:
        out = subprocess.run([sys.executable, "-m", "tests.service._budget_probe"], input=json.dumps(cases),
                             capture_output=True, text=True, cwd=REPO, timeout=600,
                             env={**os.environ, "XDG_DATA_HOME": home})
    assert out.returncode == 0, out.stderr[-3000:]
    return [json.loads(line) for line in out.stdout.splitlines()]


@pytest.mark.slow
def test_the_worst_requests_inside_the_budget_take_what_it_says():
    cases = worst_cases(SCALE * budget.SYNC.seconds, budget.SYNC.memory_bytes,
                        only=("prediction: segments", "prediction: band top", "effects", "diagnosis", "lobes sdm"))
    memory = ra1({"start_hz": 1.0, "stop_hz": 200_000.0, "step_hz": 1.0})  # the most lines a request may have
    assert budget.check("prediction", memory).memory_bytes > 0.5 * budget.SYNC.memory_bytes
    # in a process of its own: a peak RSS is the process's largest so far, and the worst lobes case before it
    # may reach the budget's memory
    results = _probe(cases) + _probe([{"label": "prediction: 200 000 lines", "operation": "prediction",
                                       "request": memory}])
    assert len(results) == len(cases) + 1
    for r in results:
        assert r["peak_rss_bytes"] <= budget.STATED_SYNC_BOUND.memory_bytes, r
    assert results[-1]["peak_rss_bytes"] <= results[-1]["estimated_memory_bytes"] + 256 * 2**20, results[-1]


def test_semi_discretization_is_priced_by_speeds_steps_and_modes_not_as_zero_order():
    base = {"assembly": ra1({"start_hz": 5.0, "stop_hz": 5000.0, "step_hz": 5.0}), "teeth": 4,
            "tangential_coefficient_n_m2": 6e8, "radial_ratio": 0.3, "radial_immersion": 0.5, "milling": "down",
            "spindle_speed_rpm": {"start": 2000, "stop": 30000, "count": 1000}}
    zoa = {**base, "method": "zoa"}
    sdm = {**base, "method": "semi_discretization"}
    zoa_s, sdm_cost = budget.estimate("lobes", zoa).seconds, budget.estimate("lobes", sdm)
    assert budget.estimate("lobes", base).seconds == pytest.approx(sdm_cost.seconds)  # auto: the SDM here
    model = budget.SDM_COST
    t = budget.sdm_terms(sdm)
    # the steps that resolve the cut: 10 per cycle of 1.2 x the band's top (5 kHz) over the tooth period
    # (4 teeth at a/D 0.5 always cut), at 2 000 rpm 450 -> the band 453; RA-1 has 7 modes in the band
    assert t.speeds == 1000 and t.step_max == 453 and t.states == 4 * 7
    assert sdm_cost.seconds == pytest.approx(zoa_s + model.seconds(t), rel=1e-12)
    assert sdm_cost.seconds > 20 * zoa_s and sdm_cost.terms["steps_total"] == t.step_sum
    # growing with the speeds, the steps (a lower speed, a higher band top) and the modes
    fewer = budget.sdm_terms({**sdm, "spindle_speed_rpm": {"start": 2000, "stop": 30000, "count": 500}})
    slower = budget.sdm_terms({**sdm, "spindle_speed_rpm": {"start": 1000, "stop": 30000, "count": 1000}})
    capped = budget.sdm_terms({**sdm, "modes_per_direction": 2})
    assert model.seconds(fewer) < model.seconds(t) < model.seconds(slower)
    assert capped.states == 8 and model.seconds(capped) < model.seconds(t)
    fixed = budget.sdm_terms({**sdm, "steps_per_period": 40})
    assert fixed.step_sum == 40 * 1000 and fixed.step_max == 40
    # a list of speeds is priced as such
    listed = budget.sdm_terms({**sdm, "spindle_speed_rpm": [20000.0, 25000.0, 30000.0]})
    assert listed.speeds == 3 and listed.step_max < t.step_max
    # memory: bounded by the chunk of period maps in flight, plus what every speed keeps
    assert model.memory_bytes(t) <= model.chunk_bytes + t.speeds * model.mem_speed_bytes
    more = {**sdm, "spindle_speed_rpm": {"start": 500, "stop": 30000, "count": 5000}}
    with pytest.raises(budget.BudgetExceeded, match="fewer speeds"):
        budget.check("lobes", more)
    assert budget.check("lobes", more, mode="job").seconds > budget.SYNC.seconds


def test_the_lobes_figure_and_csv_of_semi_discretization_are_under_the_budget(client):
    sdm = {"assembly": ra1({"start_hz": 5.0, "stop_hz": 5000.0, "step_hz": 5.0}), "teeth": 4,
           "tangential_coefficient_n_m2": 6e8, "radial_ratio": 0.3, "radial_immersion": 0.5, "milling": "down",
           "method": "semi_discretization", "modes_per_direction": 8,
           "spindle_speed_rpm": {"start": 500, "stop": 30000, "count": 5000}}
    for path in ("/v1/plots/lobes", "/v1/exports/lobes.csv", "/v1/stability-lobes"):
        problem = assert_problem(client.post(path, json=sdm), 422)
        assert problem["type"].endswith("compute-budget-exceeded"), (path, problem)
        assert problem["budget"]["cost"]["terms"]["steps_max"] > 1000
