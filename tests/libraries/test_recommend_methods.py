"""Presets by method (contract v1.2: ``zoa | semi_discretization | auto``), the flute-length cap,
true refusals, chunked pockets on a backend, the recommendation as a job, robust SDM presets."""

from __future__ import annotations

import json
import pickle
import time

import numpy as np
import pytest

from rcsa.analysis.lobes import tool_pockets as tp
from rcsa.analysis.lobes.options import auto_method, teeth_in_cut
from rcsa.analysis.lobes.pockets import PocketRule
from rcsa.analysis.lobes.semi_discretization import semi_discretization_lobes_many
from rcsa.analysis.lobes.tool_pockets import CutSettings, ToolCut, tool_pockets
from rcsa.app.jobs import Workbench
from rcsa.app.presets import recommend_predicted
from rcsa.errors import InputError
from rcsa.libraries.recommend import parse_recommend_options, pockets_on
from rcsa.reference import ra1
from tests.helpers import REPO

SAMPLE = (REPO / "tests" / "data" / "tool-libraries" / "fusion-synthetic" / "synthetic_library.json").read_bytes()
GRID = {"start_hz": 5.0, "stop_hz": 5000.0, "step_hz": 5.0}
RA1 = ra1(GRID)
SETTINGS = {"spindle": RA1["spindle"], "frequency": GRID, "joints": RA1["joints"]}
# a narrow, high speed range keeps the semi-discretization cheap (few steps per tooth period)
OPTIONS = {"material": "aluminium-7075", "max_rpm": 24000, "min_rpm": 15000}
AL = (1319.41e6, 788.83 / 1319.41)


def recommend(data: bytes = SAMPLE, **options):
    return recommend_predicted(Workbench(None), data, {**OPTIONS, **options}, file_name="shop.json", **SETTINGS)


@pytest.fixture(scope="module")
def ra1_frf():
    import rcsa

    p = rcsa.predict(ra1({"start_hz": 200.0, "stop_hz": 5000.0, "step_hz": 2.0}))
    return p.frequency_hz, p.tool_point.h


def test_auto_picks_zero_order_only_where_it_is_exact():
    """Even-toothed slotting (4 teeth or more): the directional matrix is constant; anywhere else
    zero-order averaging was measured up to +11 % above the converged limit even with a tooth always
    in the cut (docs/presets.md "Which method"), so the semi-discretization."""
    assert teeth_in_cut(4, 0.5) == pytest.approx(1.0) and teeth_in_cut(2, 1.0) == pytest.approx(1.0)
    assert [auto_method(n, 1.0)[0] for n in (4, 6, 8)] == ["zoa"] * 3
    assert [auto_method(n, ae)[0] for n, ae in ((4, 0.5), (6, 0.3), (3, 0.75), (2, 1.0), (3, 1.0), (1, 1.0),
                                                (2, 0.5), (4, 0.2), (6, 0.05))] == ["semi_discretization"] * 9
    assert "teeth in the cut" in auto_method(1, 0.05)[1] and "exact" in auto_method(4, 1.0)[1]


@pytest.mark.parametrize("method", ["zoa", "semi_discretization", "auto"])
def test_the_three_methods_are_accepted_and_auto_is_the_default(method):
    assert parse_recommend_options({**OPTIONS, "method": method}).method == method
    assert parse_recommend_options(OPTIONS).method == "auto"
    with pytest.raises(InputError) as err:
        parse_recommend_options({**OPTIONS, "method": "fourier"})
    assert err.value.field == "method" and "semi_discretization" in str(err.value)


@pytest.mark.slow
def test_auto_presets_say_which_method_and_are_stable_by_semi_discretization_over_their_window():
    result = recommend()
    written = {t["index"]: t for t in result.report["tools"] if t["status"] == "written"}
    assert written[0]["lobe_method"] == "semi_discretization"  # 4 flutes at a_e/D 0.5: not slotting
    ball = written[1]  # 2 flutes: half a tooth in the cut
    assert ball["lobe_method"] == "semi_discretization" and "teeth in the cut" in ball["method_reason"]
    doc = json.loads(result.data)
    assert "semi_discretization stability lobes (auto)" in doc["data"][1]["start-values"]["presets"][-1]["description"]
    # the preset's window solved again, densely, with twice the steps per cycle the recommendation resolves its
    # cut with (checked and refined): stable at S x stepdown
    n, tol = ball["spindle_speed_rpm"], ball["speed_tolerance"]
    lobes_model = None
    frfs = __import__("rcsa.libraries.recommend_sources", fromlist=["predicted_frfs"]).predicted_frfs(
        __import__("rcsa.libraries.formats", fromlist=["read_library"]).read_library(SAMPLE, file_name="shop.json"),
        **SETTINGS).frfs
    frf = frfs[ball["id"]]
    from rcsa.analysis.lobes.modal_model import fit_modal_model

    lobes_model = fit_modal_model(frf.frequency_hz, frf.h)
    speeds = np.geomspace(n * (1 - tol), n * (1 + tol), 121)
    dense = semi_discretization_lobes_many(
        [lobes_model], teeth=ball["teeth"], tangential_coefficient_n_m2=AL[0], radial_ratio=AL[1],
        radial_immersion=0.5, milling="down", spindle_speed_rpm=[speeds], steps_per_cycle=20.0)[0]
    assert dense.resolved.all()
    assert np.nanmin(dense.depth_limit_m) >= ball["stepdown_m"] * ball["safety_factor"] * (1 - 1e-2)


def test_a_tool_stable_to_its_flute_length_gets_the_flute_length_and_says_so(ra1_frf):
    f, h = ra1_frf
    cut = ToolCut("short-flute", f, h, 1, 2e-4, 20000.0, 24000.0)  # 0.2 mm of flute
    found = tool_pockets([cut], CutSettings(*AL, 0.05, "down", PocketRule(), method="semi_discretization"))[0]
    assert found.pocket is not None and found.pocket.stepdown_m == pytest.approx(2e-4)
    assert found.pocket.limited_by == "flute_length" and found.stable_to_flute_length
    assert any("capped at the flute length" in n for n in found.notes)
    assert found.depth_limit_m >= 1.25 * 2e-4


def test_zero_order_that_cannot_judge_a_cut_refuses_with_that_reason(ra1_frf, monkeypatch):
    """Zero-order averaging may find no positive limit in a single-tooth, low-immersion cut: the
    refusal says so (a method limit), never "the receptances cannot chatter"."""
    f, h = ra1_frf

    def averaged_away(*args, **kwargs):
        raise InputError("frf_x", "no frequency gives a positive depth limit: the receptances cannot chatter "
                                  "in this cut (check the sign convention and the units, m/N)")

    monkeypatch.setattr(tp, "stability_lobes", averaged_away)
    found = tool_pockets([ToolCut("t", f, h, 1, 0.02, 20000.0, 24000.0)],
                         CutSettings(*AL, 0.05, "down", method="zoa"))[0]
    assert found.pocket is None and "zero-order averaging finds no positive depth limit" in found.refusal
    assert "cannot chatter" not in found.refusal and "semi_discretization" in found.refusal


class _ShuffledBackend:
    """Chunks pickled (as to a cluster's workers) and answered last first."""

    def map(self, fn, chunks, *, shared=None, ordered=True, on_wait=None):
        sent = [pickle.loads(pickle.dumps(c)) for c in chunks]
        shared = pickle.loads(pickle.dumps(shared))
        for i in reversed(range(len(sent))):
            yield i, pickle.loads(pickle.dumps(fn(sent[i], shared)))


@pytest.mark.slow
def test_pockets_in_chunks_on_a_backend_equal_the_local_ones(ra1_frf):
    f, h = ra1_frf
    cuts = [ToolCut(f"t{i}", f, h * (1 + 0.15 * i), 1 + i % 2, 0.02, 21000.0, 24000.0) for i in range(3)]
    settings = CutSettings(*AL, 0.05, "down", method="semi_discretization", sdm_speed_count=60)
    seen = []
    here = pockets_on()(cuts, settings)
    there = pockets_on(_ShuffledBackend(), tools_per_chunk=2)(cuts, settings, lambda d, t: seen.append((d, t)))
    assert [p.key for p in there] == [c.key for c in cuts]
    for a, b in zip(here, there, strict=True):
        assert a.pocket == b.pocket and a.notes == b.notes
    assert seen[0] == (0, 3) and seen[-1] == (3, 3) and len(seen) == 3


@pytest.mark.slow
def test_robust_semi_discretization_presets_are_no_deeper_and_hold_for_the_drawn_modes(ra1_frf):
    from rcsa.analysis.lobes.robust_sdm import drawn_models, modal_ratios
    from rcsa.app.predictions import predict_draws

    _, draws, _ = predict_draws(ra1({"start_hz": 200.0, "stop_hz": 5000.0, "step_hz": 2.0}), {"draws": 12, "seed": 5})
    f, h = ra1_frf
    cut = ToolCut("t", f, h, 1, 0.02, 20000.0, 24000.0, h_draws=draws.h)
    common = {"method": "semi_discretization", "sdm_speed_count": 100}
    nominal = tool_pockets([cut], CutSettings(*AL, 0.05, "down", **common))[0]
    robust = tool_pockets([cut], CutSettings(*AL, 0.05, "down", **common, confidence=0.9))[0]
    assert robust.pocket is not None and robust.robust_depth_limit_m is not None
    assert robust.robust_depth_limit_m <= robust.depth_limit_m * (1 + 1e-12)
    assert robust.pocket.removal_index_rpm_m <= nominal.pocket.removal_index_rpm_m * (1 + 1e-9)
    # every drawn assembly's own modes: at every speed of the window, 90 % of them stable at S x stepdown
    model = robust.lobes.modal_model
    models = drawn_models(model, modal_ratios(model, f, h, draws.h))
    n, tol = robust.pocket.spindle_speed_rpm, 0.03
    speeds = np.geomspace(n * (1 - tol), n * (1 + tol), 31)
    solved = semi_discretization_lobes_many(models, teeth=1, tangential_coefficient_n_m2=AL[0], radial_ratio=AL[1],
                                            radial_immersion=0.05, milling="down", spindle_speed_rpm=[speeds] * 12)
    limits = np.array([np.where(np.isnan(r.depth_limit_m), np.inf, r.depth_limit_m) for r in solved])  # (draw, speed)
    stable = np.mean(limits >= robust.pocket.stepdown_m * 1.25 * (1 - 2e-3), axis=0)
    assert np.all(stable >= 0.9 - 1e-9), stable


def test_a_large_recommendation_runs_as_a_job_with_the_same_answer(tmp_path):
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        from fastapi.testclient import TestClient
    from service.main import create_app

    from tests.service.conftest import WRITE, settings_for

    form = {"material": "aluminium-7075", "max_rpm": "24000", "method": "zoa"}
    with TestClient(create_app(settings_for(tmp_path / "store"))) as client:
        sync = client.post("/v1/libraries/shop:sync", headers=WRITE, files={"library": ("shop.json", SAMPLE)},
                           data={"spindle": json.dumps(RA1["spindle"]), "frequency": json.dumps(GRID),
                                 "joints": json.dumps(RA1["joints"]), "natural_frequencies": "false"})
        assert sync.status_code == 201, sync.text  # the first sync creates the library
        now = client.post("/v1/libraries/shop:recommend", headers=WRITE, files={"library": ("shop.json", SAMPLE)},
                          data=form)
        later = client.post("/v1/libraries/shop:recommend", headers={**WRITE, "Prefer": "respond-async"},
                            files={"library": ("shop.json", SAMPLE)}, data=form)
        assert now.status_code == 200 and later.status_code == 202, later.text
        for _ in range(600):
            job = client.get(later.headers["location"], headers=WRITE).json()
            if job["status"] in ("succeeded", "failed"):
                break
            time.sleep(0.1)
        assert job["status"] == "succeeded" and job["progress"] == 1.0, job
        assert job["summary"] == now.json()["summary"]
        assert client.get(job["result_url"], headers=WRITE).json() == now.json()
