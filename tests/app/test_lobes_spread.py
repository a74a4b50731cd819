"""A semi-discretization spread over workers (:func:`rcsa.app.analyses.spread_sdm_solver`) answers as one call does.

The speeds are cut into consecutive parts of about equal cost, each solved on its own and joined. Every speed's limit is searched, bracketed and checked by itself, so the parts give
the answers of one call over all speeds; what differs is only where each search starts (the
coarse-to-fine guesses come from other neighbours). A speed whose two resolutions lie at the edge
of ``RESOLVED_RTOL`` may therefore be refined in one and not in the other: the answers then
differ by less than that (both are within it of their own finer check), never in kind.
"""

from __future__ import annotations

import json
from collections.abc import Callable, Iterator, Sequence
from typing import Any

import numpy as np
import pytest
from typer.testing import CliRunner

from rcsa.analysis.lobes.semi_discretization import DEPTH_RTOL, RESOLVED_RTOL
from rcsa.app import analyses
from rcsa.app.analyses import (
    SDM_MIN_SPEEDS_PER_PART,
    SDM_PARTS_PER_SLOT,
    spread_sdm_solver,
    stability_lobes_answer,
)
from rcsa.cli import app
from rcsa.infra.compute_backends import LocalBackend

#: Insperger & Stépán's single-mode benchmark, 2 teeth, a/D = 0.05 down milling (flip and Hopf lobes):
#: 150 speeds: four parts for the two slots a backend that does not say has.
REQUEST = {"modal_x": [{"frequency_hz": 922.0, "damping_ratio": 0.011, "modal_mass_kg": 0.03993}],
           "teeth": 2, "tangential_coefficient_n_m2": 6.0e8, "radial_ratio": 1.0 / 3.0, "radial_immersion": 0.05,
           "milling": "down", "spindle_speed_rpm": {"start": 5000, "stop": 25000, "count": 150}}
#: Answers of a borderline speed refined in one solution and not in the other differ by less than the
#: resolution claim and the depth bracket together.
AGREE_RTOL = RESOLVED_RTOL + 2 * DEPTH_RTOL


class InlineBackend:
    """A backend that is not this process's own (so the speeds are split) but runs each part here, in order."""

    name = "inline"

    def describe(self) -> dict[str, Any]:
        return {"backend": self.name}

    def __init__(self) -> None:
        self.parts: list[np.ndarray] = []

    def map(self, fn: Callable[[Any, Any], Any], chunks: Sequence[Any], *, shared: Any = None, ordered: bool = True,
            on_wait: Callable[[], None] | None = None) -> Iterator[tuple[int, Any]]:
        for i, chunk in enumerate(chunks):
            self.parts.append(np.asarray(chunk))
            yield i, fn(chunk, shared)


@pytest.fixture(scope="module")
def one_call():
    return stability_lobes_answer(REQUEST)


@pytest.fixture
def spread_any_cost(monkeypatch):
    """The request here costs too little to be worth workers by default: spread it all the same."""
    monkeypatch.setattr(analyses, "SDM_MIN_SPREAD_COST", 0.0)


def assert_same_answers(spread: dict[str, Any], whole: dict[str, Any]) -> None:
    """The same answers within ``AGREE_RTOL``, and solved apart: where each speed's search starts
    moves some limits within their brackets (a call that was not split gives them bit for bit)."""
    a, b = np.array(spread["depth_limit_m"], dtype=float), np.array(whole["depth_limit_m"], dtype=float)
    assert np.array_equal(np.isnan(a), np.isnan(b))
    ok = np.isfinite(b)
    assert np.max(np.abs(a[ok] / b[ok] - 1.0)) <= AGREE_RTOL
    assert not np.array_equal(a[ok], b[ok])
    assert spread["instability"] == whole["instability"]
    assert spread["spindle_speed_rpm"] == whole["spindle_speed_rpm"]
    assert spread["resolved"] == whole["resolved"]
    assert set(spread) == set(whole)


def test_the_parts_are_consecutive_and_cover_every_speed_once(one_call, spread_any_cost):
    backend = InlineBackend()
    spread = stability_lobes_answer(REQUEST, backend=backend)
    assert len(backend.parts) == 2 * SDM_PARTS_PER_SLOT and all(p.size >= SDM_MIN_SPEEDS_PER_PART for p in backend.parts)
    np.testing.assert_array_equal(np.concatenate(backend.parts), one_call.nominal.spindle_speed_rpm)
    assert_same_answers(spread.to_dict(), one_call.to_dict())
    assert spread.nominal.modal_model is not None and spread.nominal.scheme == one_call.nominal.scheme


def test_a_few_speeds_or_this_process_are_not_split(spread_any_cost):
    assert spread_sdm_solver(LocalBackend()) is None
    backend = InlineBackend()
    few = {**REQUEST, "spindle_speed_rpm": {"start": 5000, "stop": 25000, "count": 2 * SDM_MIN_SPEEDS_PER_PART - 1}}
    stability_lobes_answer(few, backend=backend)
    assert backend.parts == []


def test_work_cheaper_than_starting_workers_is_not_split():
    """150 speeds of one mode, 16 steps each: 3 600 steps of cost, about a second of one core."""
    backend = InlineBackend()
    stability_lobes_answer(REQUEST, backend=backend)
    assert backend.parts == []


def test_zero_order_lobes_are_not_split():
    backend = InlineBackend()
    slotting = {**REQUEST, "radial_immersion": 1.0, "method": "zoa"}
    assert stability_lobes_answer(slotting, backend=backend).to_dict()["method"] == "zoa"
    assert backend.parts == []


def test_rcsa_lobes_on_two_worker_processes_answers_as_in_one(tmp_path, one_call, spread_any_cost):
    request = tmp_path / "lobes.json"
    request.write_text(json.dumps(REQUEST))
    runner = CliRunner()
    two = runner.invoke(app, ["lobes", str(request), "--json", "--workers", "2"])
    assert two.exit_code == 0, two.stderr
    assert_same_answers(json.loads(two.stdout), one_call.to_dict())
