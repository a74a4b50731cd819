"""The service, with crash points for tests: ``uvicorn --factory tests.service._crashing_app:create_app``.

A worker SIGKILLs itself at a named point when it finds the marker file
``$RCSA_TEST_CRASH_DIR/<point>`` (taken atomically by a rename, so exactly one process
crashes once per marker). Points: ``before-put`` (the measurement's id is recorded, nothing
written), ``after-put`` (the file is committed, the answer not yet kept) and
``after-complete`` (the answer is kept, not yet sent). Without markers it is the service.
"""

from __future__ import annotations

import os
import signal
from pathlib import Path
from typing import Any

from service.idempotency import IdempotencyStore
from service.main import create_app as _create_app

from rcsa.measured.store.store import MeasurementStore


def _crash_at(point: str) -> None:
    directory = Path(os.environ["RCSA_TEST_CRASH_DIR"])
    try:
        os.rename(directory / point, directory / f"{point}.taken-by-{os.getpid()}")
    except FileNotFoundError:
        return
    os.kill(os.getpid(), signal.SIGKILL)


def create_app() -> Any:
    """The service app, with :class:`MeasurementStore.put` and the idempotency store's
    ``complete`` wrapped by crash points."""
    put, complete = MeasurementStore.put, IdempotencyStore.complete

    def crashing_put(self: MeasurementStore, measurement: Any, **kwargs: Any) -> str:
        _crash_at("before-put")
        mid = put(self, measurement, **kwargs)
        _crash_at("after-put")
        return mid

    def crashing_complete(self: IdempotencyStore, *args: Any, **kwargs: Any) -> bool:
        done = complete(self, *args, **kwargs)
        _crash_at("after-complete")
        return done

    MeasurementStore.put = crashing_put  # type: ignore[method-assign]
    IdempotencyStore.complete = crashing_complete  # type: ignore[method-assign]
    return _create_app()
