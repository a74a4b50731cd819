"""Chunk functions the Dask tests send to their cluster's workers (importable there by name)."""

from __future__ import annotations

import os
import signal
import time
from typing import Any

from rcsa.libraries.chunks import compute_chunk

#: A file path: the first chunk to find it absent creates it and kills its worker process.
KILL_MARKER = "RCSA_TEST_KILL_MARKER"


def compute_chunk_killing_its_worker_once(batch: Any, **kwargs: Any) -> list[dict[str, Any]]:
    """:func:`rcsa.libraries.chunks.compute_chunk`, but the first call kills its own process."""
    marker = os.environ.get(KILL_MARKER)
    if marker:
        try:
            fd = os.open(marker, os.O_CREAT | os.O_EXCL | os.O_WRONLY)
        except FileExistsError:
            pass
        else:
            os.close(fd)
            os.kill(os.getpid(), signal.SIGKILL)  # as the OOM killer would, mid-chunk
    return compute_chunk(batch, **kwargs)


def compute_chunk_slowly(batch: Any, **kwargs: Any) -> list[dict[str, Any]]:
    """A chunk that takes 30 s (long enough to lose the scheduler while it runs)."""
    time.sleep(30)
    return compute_chunk(batch, **kwargs)
