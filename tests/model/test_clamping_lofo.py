"""Leave one holder family out: the published folds hold against the 3-D oracle, row by row.

``benchmarks/calibrate_clamping.py --lofo`` fits the clamping coefficients once per holder
family on the calibration cases of the *other* families and scores every case of the family
left out (``benchmarks/results/clamping_lofo.json``, rendered in the README). Here each fold is
checked: nothing of its family entered its fit, it scores every case of the family, and every
row, re-scored with the fold's coefficients against the 3-D truth, gives the published figures
and meets the targets (every peak of 100–8000 Hz within 1.5 % in frequency, 15 % in height). The
one row the README names as missed is marked so, strictly: if it starts to pass, the README's
claim is stale and this fails.
"""

from __future__ import annotations

import json
from dataclasses import replace
from pathlib import Path

import pytest

import rcsa.model.clamping as clamping
from tests.oracles.solid3d.clamping_scores import CALIBRATION_CASES, INFORMATION, score_row
from tests.oracles.solid3d.dataset import BASES, FAMILIES, case_family, reference_cases

RESULTS = Path(__file__).resolve().parents[2] / "benchmarks" / "results" / "clamping_lofo.json"
FOLDS = {f["family"]: f for f in json.loads(RESULTS.read_text(encoding="utf-8"))["figures"]["folds"]}
#: The one published miss (README "Clamping along the insertion"): the thinnest nose's second mode.
MISSED = {("stepped", "nose_od1.6d", "clamped")}


def test_every_family_has_a_fold_that_never_saw_it():
    assert set(FOLDS) == set(FAMILIES)
    for family, fold in FOLDS.items():
        assert set(fold["trained_on"]) <= set(CALIBRATION_CASES), family
        assert all(case_family(n) != family for n in fold["trained_on"]), family
        expected = [n for n in reference_cases() if case_family(n) == family and n not in INFORMATION]
        assert sorted(fold["cases"]) == sorted(expected), family


ROWS = [pytest.param(family, row["case"], row["base"], id=f"{family}-{row['case']}-{row['base']}",
                     marks=[pytest.mark.xfail(strict=True, reason="published miss")]
                     if (family, row["case"], row["base"]) in MISSED else [])
        for family, fold in FOLDS.items() for row in fold["rows"]]


@pytest.mark.parametrize(("family", "name", "base"), ROWS)
def test_every_row_of_a_left_out_family_meets_the_targets(family, name, base, monkeypatch):
    fold = FOLDS[family]
    published = next(r["clamping"] for r in fold["rows"] if r["case"] == name and r["base"] == base)
    monkeypatch.setattr(clamping, "BULK_COEFFICIENTS", replace(clamping.BULK_COEFFICIENTS, **fold["coefficients"]))
    s = score_row(name, base, "clamping")
    assert base in BASES and s["peaks"]
    assert s["max_frequency_error"] == pytest.approx(published["max_frequency_error"], abs=1e-6)
    assert s["max_height_error"] == pytest.approx(published["max_height_error"], abs=1e-5)
    assert s["max_frequency_error"] <= 0.015, s["peaks"]
    assert s["max_height_error"] <= 0.15, s["peaks"]
