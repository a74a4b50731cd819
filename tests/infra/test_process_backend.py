"""Worker processes of this machine as a compute backend (:class:`rcsa.infra.compute_backends.ProcessBackend`).

Results equal the in-process ones, in order or as they finish; a chunk that raises, a worker that
dies and a caller that stops waiting (a time limit) each stop the map and leave no worker running;
one chunk runs in the caller (no process started); the pockets of a tool library computed in two
processes are the ones computed here.
"""

from __future__ import annotations

import functools
import os

import pytest

from rcsa.infra.compute_backends import (
    ChunkFailed,
    LocalBackend,
    ProcessBackend,
    compute_backend,
    cores_available,
)
from tests.infra import process_helpers as helpers


@pytest.fixture
def backend():
    b = ProcessBackend(2, poll_s=0.02)
    yield b
    b.close()


def _alive(pids: set[int]) -> set[int]:
    """The processes of ``pids`` still running (a zombie counts as gone)."""
    alive = set()
    for pid in pids:
        try:
            with open(f"/proc/{pid}/stat") as f:
                state = f.read().rsplit(")", 1)[1].split()[0]
        except FileNotFoundError:
            continue
        if state not in ("Z", "X"):
            alive.add(pid)
    return alive


def _workers(backend: ProcessBackend) -> set[int]:
    pool = backend._pool
    return set() if pool is None else set(pool._processes)


def test_results_equal_the_in_process_ones_in_order_and_as_they_finish(backend):
    chunks = [[1, 2], [3], [4, 5, 6], [7]]
    here = list(LocalBackend().map(helpers.scaled, chunks, shared=3))
    assert list(backend.map(helpers.scaled, chunks, shared=3)) == here
    assert sorted(backend.map(helpers.scaled, chunks, shared=3, ordered=False)) == here
    assert backend.describe() == {"backend": "processes", "workers": 2}
    narrow = ProcessBackend(2, window=1)  # one chunk in flight at a time: the same results
    try:
        assert list(narrow.map(helpers.scaled, chunks, shared=3)) == here
        assert sorted(narrow.map(helpers.scaled, chunks, shared=3, ordered=False)) == here
    finally:
        narrow.close()


def test_chunks_run_in_other_processes_and_one_chunk_runs_here(backend):
    pids = {pid for _, pid in backend.map(helpers.process_id, [None] * 4)}
    assert os.getpid() not in pids and 1 <= len(pids) <= 2
    assert list(backend.map(helpers.process_id, [None])) == [(0, os.getpid())]


def test_a_chunk_that_raises_stops_the_map_with_its_error(backend):
    with pytest.raises(ValueError, match="chunk -1 is negative"):
        list(backend.map(helpers.refusing, [1, -1, 2, 3]))
    assert list(backend.map(helpers.refusing, [4, 5])) == [(0, 4), (1, 5)]  # a new pool answers


def test_a_worker_that_dies_fails_the_map_and_the_next_map_works(backend):
    with pytest.raises(ChunkFailed, match="worker process died"):
        list(backend.map(helpers.dying, [0, 1, 2]))
    assert list(backend.map(helpers.dying, [0, 2])) == [(0, 0), (1, 2)]


def test_a_result_that_cannot_be_read_back_says_so_not_that_a_worker_died(backend):
    with pytest.raises(ChunkFailed, match="could not be read back .*this result cannot be rebuilt here"):
        list(backend.map(helpers.unreadable, [0, 1, 2]))
    assert list(backend.map(helpers.unreadable, [0, 2])) == [(0, 0), (1, 2)]


def test_a_caller_that_stops_waiting_terminates_the_workers(backend):
    class Stop(Exception):
        pass

    started: set[int] = set()

    def on_wait():  # as a time limit does: raise once the workers are busy
        started.update(_workers(backend))
        if len(started) == 2:
            raise Stop

    with pytest.raises(Stop):
        for _ in backend.map(helpers.sleeping, [600.0, 600.0], on_wait=on_wait):
            pass  # never: both chunks sleep for ten minutes
    assert len(started) == 2 and not _alive(started)  # terminated, not left to sleep
    assert not _workers(backend)  # the pool was dropped; the next map starts another
    assert len(list(backend.map(helpers.sleeping, [0.0, 0.0]))) == 2


def test_compute_backend_picks_processes_by_the_worker_count():
    assert isinstance(compute_backend(None), LocalBackend)
    assert isinstance(compute_backend(None, workers=1), LocalBackend)
    two = compute_backend(None, workers=2)
    assert isinstance(two, ProcessBackend) and two.workers == 2
    auto = compute_backend(None, workers=0)
    assert auto.workers == cores_available() if cores_available() > 1 else isinstance(auto, LocalBackend)
    with pytest.raises(ValueError, match="workers"):
        compute_backend(None, workers=-1)
    with pytest.raises(ValueError, match="at least one"):
        ProcessBackend(0)


@pytest.mark.slow
def test_chatter_safe_pockets_in_two_processes_equal_the_ones_computed_here(backend):
    """Issue 29: a library's pockets found by two worker processes (a chunk of tools each) are the
    pockets found in this process, with progress over the chunks."""
    from rcsa.libraries.recommend import pockets_on
    from tests.infra.pocket_cases import pocket_case

    cuts, settings = pocket_case(4)
    seen = []
    there = pockets_on(backend, tools_per_chunk=2)(cuts, settings, lambda d, t: seen.append((d, t)))
    here = pockets_on(LocalBackend(), tools_per_chunk=2)(cuts, settings)
    assert [a.pocket for a in there] == [b.pocket for b in here] and all(a.pocket for a in there)
    assert seen == [(0, 4), (2, 4), (4, 4)]


def test_the_partial_helper_is_importable_by_a_worker(backend):
    """``fn`` may be a partial of a module-level function (it is pickled by reference)."""
    fn = functools.partial(helpers.scaled)
    assert list(backend.map(fn, [[1], [2]], shared=5)) == [(0, [5]), (1, [10])]
