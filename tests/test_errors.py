"""Every error rcsa raises on purpose crosses a process boundary as itself (``rcsa.errors``).

A chunk or a lobes part raises in a worker process or on a Dask worker; the caller must get the
same class, message and attributes, not a failure to unpickle the error (the standard
exception pickling calls ``cls(message)``, which errors with several parameters refuse) that a
process pool reports as a dead worker.
"""

from __future__ import annotations

import pickle

import pytest

from rcsa.app.budget import SYNC, BudgetExceeded, estimate
from rcsa.errors import (
    ConflictError,
    DamagedError,
    FrequencyMismatch,
    InputError,
    MalformedInput,
    NotFoundError,
    RcsaError,
    StoreError,
    TimeLimitExceeded,
)
from rcsa.infra.compute_backends import ChunkFailed, ComputeUnavailable, ProcessBackend
from rcsa.reference import ra1

ERRORS = [InputError("teeth", "must be >= 1"), InputError("", "the request must be a JSON object"),
          MalformedInput("", "not JSON"), FrequencyMismatch("frf_y", "another grid"),
          NotFoundError("measurement", "m-1"), ConflictError("job", "j-1", "deleted"), StoreError("unreadable"),
          DamagedError("measurement", "m-2", "bad checksum"), TimeLimitExceeded(2.5),
          ComputeUnavailable("no scheduler"), ChunkFailed("chunk 1 of 2")]


@pytest.mark.parametrize("error", ERRORS, ids=lambda e: type(e).__name__)
def test_an_error_pickles_as_itself(error):
    back = pickle.loads(pickle.dumps(error))
    assert type(back) is type(error) and str(back) == str(error) and back.args == error.args
    assert vars(back) == vars(error)


def test_a_budget_refusal_pickles_with_its_cost():
    error = BudgetExceeded(estimate("prediction", ra1()), SYNC, "sync", "frequency")
    back = pickle.loads(pickle.dumps(error))
    assert type(back) is BudgetExceeded and str(back) == str(error) and back.field == "frequency"
    assert back.cost == error.cost and back.limits == error.limits and back.mode == "sync"


def _raise_input_error(chunk: int, shared: object) -> None:
    raise InputError(f"chunks[{chunk}]", "refused in the worker")


def test_an_input_error_in_a_worker_process_reaches_the_caller_as_itself():
    backend = ProcessBackend(2)
    try:
        with pytest.raises(InputError, match=r"chunks\[\d\]: refused in the worker") as caught:
            list(backend.map(_raise_input_error, [0, 1]))
    finally:
        backend.close()
    assert isinstance(caught.value, RcsaError) and caught.value.rule == "refused in the worker"
