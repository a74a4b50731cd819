"""Chunk functions the process-backend tests send to worker processes (importable there by name;
standard library only, so that a worker starts in a fraction of a second)."""

from __future__ import annotations

import os
import signal
import time
from typing import Any


def scaled(chunk: list[int], factor: int) -> list[int]:
    """Every item times ``factor``."""
    return [factor * x for x in chunk]


def process_id(chunk: Any, shared: Any) -> int:
    """The process the chunk ran in."""
    return os.getpid()


def refusing(chunk: int, shared: Any) -> int:
    """Raises for a negative chunk (as a chunk with bad input would)."""
    if chunk < 0:
        raise ValueError(f"chunk {chunk} is negative")
    return chunk


def dying(chunk: int, shared: Any) -> int:
    """Kills its own worker for chunk 1 (as the OOM killer would, mid-chunk)."""
    if chunk == 1:
        os.kill(os.getpid(), signal.SIGKILL)
    return chunk


def sleeping(chunk: float, shared: Any) -> int:
    """Sleeps ``chunk`` seconds, then answers its process id."""
    time.sleep(chunk)
    return os.getpid()


def _refuse_to_load() -> None:
    raise TypeError("this result cannot be rebuilt here")


class Unreadable:
    """A result that pickles in the worker but cannot be unpickled by the caller."""

    def __reduce__(self) -> tuple[Any, ...]:
        return (_refuse_to_load, ())


def unreadable(chunk: int, shared: Any) -> Any:
    """Answers chunk 1 with a result the caller cannot read back."""
    return Unreadable() if chunk == 1 else chunk
