"""Batches cut into chunks that can be computed anywhere: everything a chunk needs travels with it.

Large work (a batch job, a tool library, a sync) is computed in chunks of tools: each chunk is
one call of :func:`rcsa.model.batch.predict_batch` on a slice of the combinations. A chunk is
run by a backend (:mod:`rcsa.infra.compute_backends`): in this process, or on a Dask cluster whose
workers share nothing with the service but the network. So a chunk carries its inputs **by
content**:

* :class:`Shared` — sent once per run: the shared part of the batch request (grid, spindle,
  materials, ...), the measured spindle's base receptance **already resolved** here from the
  store (arrays, never a store path), the line limit, and the model fingerprint the results
  will be filed under (a worker running another model version refuses the chunk rather than
  file its results under the wrong key);
* the chunk itself — its list of combinations.

Results come back to the caller, which writes them (result cache, job result file).

How the work is cut depends on the request only (:func:`chunk_size`, :func:`chunk_ranges`),
never on the backend: the same chunks give the same bytes on every backend. (The exact
natural frequencies of a chunk's tools are bisected together; their last bits — far below
the 1e-11 bisection tolerance — depend on which tools share a chunk, which is why the cut is
fixed by the request.)
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from rcsa.errors import InputError, RcsaError
from rcsa.libraries.results_cache import model_fingerprint
from rcsa.measured.hybrid import MeasurementSource, base_resolver
from rcsa.model import batch as batches
from rcsa.model.bounds import MAX_BATCH_COMBINATIONS, MAX_FREQUENCY_LINES
from rcsa.model.contract import MeasuredSpindleSpec
from rcsa.model.spindle_side import BaseResolver, MeasuredBase

__all__ = [
    "CHUNK_TOOL_LINES",
    "MAX_CHUNK_TOOLS",
    "MIN_CHUNK_TOOLS",
    "Shared",
    "chunk_ranges",
    "chunk_size",
    "compute_chunk",
    "prepare_shared",
    "resolver_of",
    "run_chunk",
]

#: Tool-lines (tools × frequency lines) per chunk: bounds a chunk's results in memory
#: (~72 bytes per tool-line: 250 000 → 18 MB) and its run time (a second or two).
CHUNK_TOOL_LINES = 250_000
#: Fewest and most tools per chunk. The natural frequencies of a chunk's tools are bisected in
#: lockstep at a cost per chunk, so small chunks cost more per tool (25 tools: twice the
#: time per tool of 250).
MIN_CHUNK_TOOLS, MAX_CHUNK_TOOLS = 10, 250


def chunk_size(n_lines: int) -> int:
    """Tools per chunk on a grid of ``n_lines`` lines (:data:`CHUNK_TOOL_LINES`, clamped)."""
    return int(min(MAX_CHUNK_TOOLS, max(MIN_CHUNK_TOOLS, CHUNK_TOOL_LINES // max(int(n_lines), 1))))


def chunk_ranges(n: int, size: int) -> list[tuple[int, int]]:
    """``(start, stop)`` of consecutive chunks of at most ``size`` of ``n`` items."""
    size = max(int(size), 1)
    return [(start, min(start + size, n)) for start in range(0, n, size)]


def resolver_of(store: MeasurementSource | None) -> BaseResolver:
    """Looks measured spindles up in ``store``; without one, a measured spindle is refused."""
    if store is not None:
        return base_resolver(store)

    def refuse(spindle: MeasuredSpindleSpec, frequency_hz: np.ndarray) -> MeasuredBase:
        raise InputError("spindle.measurement_id", "a measured spindle needs a measurement store")

    return refuse


def _shipped(base: MeasuredBase) -> BaseResolver:
    """A resolver that answers with a base resolved elsewhere (no store needed)."""

    def resolve(spindle: MeasuredSpindleSpec, frequency_hz: np.ndarray) -> MeasuredBase:
        if base.receptance.shape[0] != np.asarray(frequency_hz).size:
            raise InputError("frequency", "the shipped spindle receptance does not match the grid")
        return base

    return resolve


@dataclass(frozen=True)
class Shared:
    """What every chunk of one batch shares, by content (picklable, no store, no paths).

    Attributes
    ----------
    common : dict
        The batch request without its combinations (JSON-ready).
    base : MeasuredBase or None
        The measured spindle's base receptance on the grid (None for an analytical spindle).
    max_lines : int
    fingerprint : str
        :func:`rcsa.libraries.results_cache.model_fingerprint` of the caller.
    n_lines : int
        Frequency lines of the grid.
    """

    common: dict[str, Any]
    base: MeasuredBase | None
    max_lines: int
    fingerprint: str
    n_lines: int


def prepare_shared(batch: Mapping[str, Any], *, store: MeasurementSource | None = None,
                   max_lines: int = MAX_FREQUENCY_LINES,
                   max_combinations: int = MAX_BATCH_COMBINATIONS) -> tuple[list[Any], Shared]:
    """Check a batch request as :func:`~rcsa.model.batch.predict_batch` does and resolve its spindle.

    Returns
    -------
    combinations : list
        The batch's combinations, to be cut into chunks.
    shared : Shared

    Raises
    ------
    InputError
        Exactly the errors :func:`~rcsa.model.batch.predict_batch` raises for the whole
        request (a bad combination is not an error: it gets its own ``error`` result).
    """
    combos, _, common = batches.parse_batch(batch, max_lines=max_lines, max_combinations=max_combinations)
    base = None
    if isinstance(common.spindle, MeasuredSpindleSpec):
        base = resolver_of(store)(common.spindle, common.frequency_hz)
    return combos, Shared({k: v for k, v in batch.items() if k != "combinations"}, base, int(max_lines),
                          model_fingerprint(), int(common.frequency_hz.size))


def compute_chunk(batch: Mapping[str, Any], *, base: MeasuredBase | None = None,
                  store: MeasurementSource | None = None, max_lines: int = MAX_FREQUENCY_LINES
                  ) -> list[dict[str, Any]]:
    """Results of a batch request's combinations, in order (:func:`~rcsa.model.batch.predict_batch`).

    A measured spindle is taken from ``base`` when given (resolved by the caller), else looked
    up in ``store``. The one place a chunk computes; tests count or stub calls here.
    """
    n = len(batch["combinations"])
    resolve = _shipped(base) if base is not None else resolver_of(store)
    results: list[dict[str, Any]] = batches.predict_batch(batch, resolve_base=resolve, max_lines=max_lines,
                                                          max_combinations=max(n, 1), arrays="numpy")["results"]
    return results


def run_chunk(compute: Any, combinations: list[Any], shared: Shared) -> list[dict[str, Any]]:
    """One chunk: ``compute({**shared.common, "combinations": combinations}, base=..., max_lines=...)``.

    Runs wherever the backend runs it (here, or on a cluster worker).

    Raises
    ------
    RcsaError
        This process runs another model than the one the results will be filed under.
    """
    if model_fingerprint() != shared.fingerprint:
        raise RcsaError(f"this worker runs model {model_fingerprint()[:12]}, the service "
                                  f"{shared.fingerprint[:12]}: install the same rcsa version on every worker")
    return list(compute({**shared.common, "combinations": combinations}, base=shared.base,
                        max_lines=shared.max_lines))
