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
from tests.helpers import REPO

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

    def __init__(self, slots: int | None = None) -> None:
        self.slots = slots
        self.parts: list[list[tuple[int, np.ndarray]]] = []

    def describe(self) -> dict[str, Any]:
        return {"backend": self.name} if self.slots is None else {"backend": self.name, "workers": self.slots}

    def map(self, fn: Callable[[Any, Any], Any], chunks: Sequence[Any], *, shared: Any = None, ordered: bool = True,
            on_wait: Callable[[], None] | None = None) -> Iterator[tuple[int, Any]]:
        for i, chunk in enumerate(chunks):
            self.parts.append(chunk)
            yield i, fn(chunk, shared)

    def speeds(self, model: int = 0) -> list[np.ndarray]:
        """The speeds of ``model`` in each part, in order."""
        return [speeds for part in self.parts for which, speeds in part if which == model]


@pytest.fixture(scope="module")
def one_call():
    return stability_lobes_answer(REQUEST)


@pytest.fixture
def spread_any_cost(monkeypatch):
    """The request here costs too little to be worth workers by default: spread it all the same."""
    monkeypatch.setattr(analyses, "SDM_MIN_SPREAD_COST", 0.0)


def assert_same_answers(spread: dict[str, Any], whole: dict[str, Any], apart: bool = True) -> None:
    """The same answers within ``AGREE_RTOL`` and, with ``apart``, solved apart: where each speed's
    search starts moves some limits within their brackets (a call that was not split gives them bit
    for bit)."""
    a, b = np.array(spread["depth_limit_m"], dtype=float), np.array(whole["depth_limit_m"], dtype=float)
    assert np.array_equal(np.isnan(a), np.isnan(b))
    ok = np.isfinite(b)
    assert np.max(np.abs(a[ok] / b[ok] - 1.0)) <= AGREE_RTOL
    assert not apart or not np.array_equal(a[ok], b[ok])
    assert spread["instability"] == whole["instability"]
    assert spread["spindle_speed_rpm"] == whole["spindle_speed_rpm"]
    assert spread["resolved"] == whole["resolved"]
    assert set(spread) == set(whole)


def test_the_parts_are_consecutive_and_cover_every_speed_once(one_call, spread_any_cost):
    backend = InlineBackend()
    spread = stability_lobes_answer(REQUEST, backend=backend)
    parts = backend.speeds()
    assert len(parts) == len(backend.parts) == 2 * SDM_PARTS_PER_SLOT
    assert all(p.size >= SDM_MIN_SPEEDS_PER_PART for p in parts)
    np.testing.assert_array_equal(np.concatenate(parts), one_call.nominal.spindle_speed_rpm)
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


#: The README's robust example made cheaper (two teeth at a/D = 0.05, 24 speeds, 12 draws): its
#: reduced model solves the nominal modes at four damping levels on a 52-speed stretched grid.
ROBUST_REQUEST = {**json.loads((REPO / "examples" / "lobes-robust.json").read_text()),
                  "teeth": 2, "radial_immersion": 0.05, "uncertainty": {"draws": 12, "seed": 1},
                  "spindle_speed_rpm": {"start": 4000, "stop": 24000, "count": 24}}
#: The reduced model's diagrams are bracketed to 5e-3 (``robust_sdm``), unchecked: the robust limits
#: of two ways of solving them differ by at most two brackets.
ROBUST_AGREE_RTOL = 2 * 5e-3


def test_robust_limits_share_their_diagrams_speeds_with_every_damping_level_together(monkeypatch):
    whole = stability_lobes_answer(ROBUST_REQUEST)
    monkeypatch.setattr(analyses, "SDM_MIN_SPREAD_COST", 0.0)
    monkeypatch.setattr(analyses, "SDM_MIN_SPEEDS_PER_PART", 16)
    backend = InlineBackend(slots=2)
    spread = stability_lobes_answer(ROBUST_REQUEST, backend=backend)
    levels = {which for part in backend.parts for which, _ in part}
    assert len(levels) > 1 and len(backend.parts) == 3  # the 52-speed grid in three slices of >= 16
    assert all({which for which, _ in part} == levels for part in backend.parts)  # every level in every part
    grid = np.concatenate(backend.speeds(0))
    assert grid.size > ROBUST_REQUEST["spindle_speed_rpm"]["count"] and np.all(np.diff(grid) > 0)
    for level in levels:
        np.testing.assert_array_equal(np.concatenate(backend.speeds(level)), grid)
    a, b = spread.robust.depth_limit_m, whole.robust.depth_limit_m
    assert np.array_equal(np.isnan(a), np.isnan(b))
    ok = np.isfinite(b)
    assert np.max(np.abs(a[ok] / b[ok] - 1.0)) <= ROBUST_AGREE_RTOL
    assert not np.array_equal(a[ok], b[ok])  # solved apart
    np.testing.assert_array_equal(spread.nominal.depth_limit_m, whole.nominal.depth_limit_m)  # 24 speeds: one call


def test_models_with_grids_of_any_size_are_spread_together_and_joined_each_on_its_own(monkeypatch, spread_any_cost):
    """Slices are taken model by model: a short grid has fewer of them (its last parts hold only the
    longer grids), and a grid cut in fewer slices than asked leaves no empty part behind."""
    from rcsa.analysis.lobes import semi_discretization as sd
    from rcsa.analysis.lobes.modal_model import ModalModel

    models = [ModalModel.of([922.0], [0.011], [1 / 0.03993], [0]), ModalModel.of([1400.0], [0.02], [20.0], [0])]
    speeds = [np.linspace(5000.0, 25000.0, 100), np.array([8000.0, 16000.0])]
    settings = {"teeth": 2, "tangential_coefficient_n_m2": 6e8, "radial_ratio": 1 / 3, "radial_immersion": 0.05,
                "milling": "down", "min_depth_search_max_m": [0.01, 0.02]}
    whole = sd.solve_diagrams_here(models, speeds, settings)
    backend = InlineBackend(slots=2)
    spread = analyses.spread_sdm_diagrams(backend)
    assert spread is not None
    apart = spread(models, speeds, settings)
    assert [len(part) for part in backend.parts] == [2, 2, 1]  # 100 speeds in three slices, 2 in two
    for a, b, s in zip(apart, whole, speeds, strict=True):
        assert a.modal_model is b.modal_model is not None
        np.testing.assert_array_equal(a.spindle_speed_rpm, s)
        assert a.depth_search_max_m == b.depth_search_max_m
        assert_same_answers({**a.to_dict(), "depth_limit_m": a.depth_limit_m.tolist()},
                            {**b.to_dict(), "depth_limit_m": b.depth_limit_m.tolist()}, apart=a is apart[0])
    monkeypatch.setattr(sd, "speed_parts", lambda s, c, n: [np.asarray(s, dtype=float)])  # one slice each
    backend = InlineBackend(slots=2)
    analyses.spread_sdm_diagrams(backend)(models, speeds, settings)
    assert [len(part) for part in backend.parts] == [2]
