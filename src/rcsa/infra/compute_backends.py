"""Where chunks of work run: in this process, or on a Dask cluster (optional).

A *backend* runs a given pure function over chunks: ``backend.map(fn, chunks, shared=s)``
yields ``(i, fn(chunks[i], s))`` for every chunk. What a chunk is, and what ``fn`` computes,
is the caller's business; nothing here knows the domain.

* :class:`LocalBackend` (the default) runs the chunks one after the other in the calling
  thread. It needs nothing beyond the standard library.
* :class:`ProcessBackend` runs them in worker processes of this machine (the standard
  library's process pool, started with ``spawn``: safe beside the threads of a server or a
  progress bar). The pool starts when a map first has two chunks or more — a map of one chunk
  runs in the calling thread, so small work pays no start-up — and lives until
  :meth:`~ProcessBackend.close`. Like a cluster's workers, the processes share nothing with
  the caller: ``fn`` must be importable by name, and a script that builds one must guard its
  main code with ``if __name__ == "__main__":`` (a spawned process imports the main module).
* :class:`DaskBackend` runs them as tasks on a Dask cluster (``pip install 'rcsa[dask]'``;
  ``dask.distributed`` is imported here only, when one is built). The workers share nothing
  with the caller but the network: ``fn``, each chunk and ``shared`` travel by value
  (pickled), and the results come back to the caller. ``shared`` is sent once per
  :meth:`~DaskBackend.map` as a task of its own, so the scheduler can recompute it if the
  worker holding it dies. At most ``window`` chunks are in flight (results wait at the
  caller in bounded memory); ``ordered=False`` hands results over as they finish.

Faults on a cluster:

* a worker that dies mid-chunk (killed, out of memory) is noticed by the scheduler, which
  runs the chunk again on another worker (Dask's ``allowed-failures``, 3 by default; a
  chunk that keeps killing its workers fails with :class:`ChunkFailed`); a chunk that
  *raises* is retried ``retries`` times, then its exception is raised here;
* the scheduler going away cancels the chunks in flight: :meth:`DaskBackend.map` raises
  :class:`ComputeUnavailable` naming the scheduler, never waits for ever; the next
  :meth:`~DaskBackend.map` connects again;
* a scheduler that cannot be reached when the backend is built (or reconnected) raises
  :class:`ComputeUnavailable` after ``connect_timeout_s``.

``on_wait``, called about every ``poll_s`` while a map waits for results, lets the caller
stop it (e.g. a job's time limit or a lost claim): whatever it raises cancels the chunks
still in flight and propagates. A :class:`ProcessBackend` stops its workers the same way (it
terminates them: a time limit set in the caller does not reach another process), and a
worker process that dies mid-chunk fails the map with :class:`ChunkFailed`.
"""

from __future__ import annotations

import contextlib
import itertools
import logging
import multiprocessing
import os
import secrets
import threading
import time
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait
from concurrent.futures.process import BrokenProcessPool
from typing import Any, Protocol

from rcsa.errors import RcsaError

__all__ = ["DASK_WORKER_ENVIRON", "Backend", "ChunkFailed", "ComputeUnavailable", "DaskBackend", "LocalBackend",
           "ProcessBackend", "compute_backend", "cores_available"]

log = logging.getLogger("rcsa.infra.compute_backends")

#: The environment a Dask nanny should give the workers it starts (Dask's config
#: ``distributed.nanny.pre-spawn-environ``; ``docker-compose.yml`` sets the same through
#: ``DASK_DISTRIBUTED__NANNY__PRE_SPAWN_ENVIRON``). Dask's default trims freed memory above
#: 64 KiB back to the system at once, so numpy's large temporaries are mapped and unmapped
#: again and again: a chatter-safe recommendation of 100 tools on two workers took 47 s
#: (37 s of it system time) against 30 s with 128 MiB. The three thread counts are Dask's own.
DASK_WORKER_ENVIRON: dict[str, int] = {"MALLOC_TRIM_THRESHOLD_": 128 * 2**20, "OMP_NUM_THREADS": 1,
                                       "MKL_NUM_THREADS": 1, "OPENBLAS_NUM_THREADS": 1}

#: ``fn(chunk, shared) -> result``: a module-level function (or a ``functools.partial`` of one)
#: so that a cluster's workers can import it.
ChunkFunction = Callable[[Any, Any], Any]


class ComputeUnavailable(RcsaError):
    """The compute cluster cannot be reached, or went away while work was running on it."""

    #: How a job that fails with it is reported (problem ``title`` and ``status``).
    title = "Compute cluster unavailable"
    http_status = 503


class ChunkFailed(RcsaError):
    """A chunk could not be computed on the cluster (it killed its workers again and again)."""

    title = "Job failed on the compute cluster"
    http_status = 500


class Backend(Protocol):
    """Runs a function over chunks (:class:`LocalBackend`, :class:`DaskBackend`)."""

    name: str

    def map(self, fn: ChunkFunction, chunks: Sequence[Any], *, shared: Any = None, ordered: bool = True,
            on_wait: Callable[[], None] | None = None) -> Iterator[tuple[int, Any]]:
        """``(i, fn(chunks[i], shared))`` for every chunk (in chunk order when ``ordered``).

        Parameters
        ----------
        fn : callable
            ``fn(chunk, shared) -> result``, importable by name where it runs.
        chunks : sequence
            The chunks.
        shared : object, optional
            What every chunk needs besides itself (sent once).
        ordered : bool
            Yield in chunk order (else as chunks finish).
        on_wait : callable, optional
            Called while waiting for results; whatever it raises stops the map.

        Yields
        ------
        tuple of (int, object)
            A chunk's index and ``fn``'s result for it.
        """
        ...

    def describe(self) -> dict[str, Any]:
        """JSON-ready description (name, address, workers) for logs and health checks."""
        ...

    def ready(self, timeout_s: float = 2.0) -> str:
        """``"ok"`` when chunks can be computed now, else why not (a readiness check)."""
        ...

    def close(self) -> None:
        """Release connections (idempotent)."""
        ...


def _hand_over(ready: dict[int, Any], next_out: int, ordered: bool) -> list[tuple[int, Any]]:
    """The results a map can hand over now, taken out of ``ready`` (chunk index → result): in chunk
    order from ``next_out`` while they are consecutive when ``ordered``, else all of them.

    >>> ready = {0: "a", 2: "c"}
    >>> _hand_over(ready, 0, True), ready
    ([(0, 'a')], {2: 'c'})
    """
    if not ordered:
        return [(i, ready.pop(i)) for i in sorted(ready)]
    out: list[tuple[int, Any]] = []
    while next_out + len(out) in ready:
        i = next_out + len(out)
        out.append((i, ready.pop(i)))
    return out


def _windowed(n: int, window: int, submit: Callable[[int], None], in_flight: Callable[[], int],
              finished: Callable[[], dict[int, Any]], idle: Callable[[], None], ordered: bool
              ) -> Iterator[tuple[int, Any]]:
    """The loop of a pool's map: at most ``window`` chunks submitted or waiting to be handed over
    (``submit(i)`` sends chunk ``i``; ``in_flight()`` counts those sent and not finished), the
    results ``finished()`` returns (chunk index → result; it may wait a little) handed over by
    :func:`_hand_over`, and ``idle()`` called whenever a round finished nothing."""
    ready: dict[int, Any] = {}
    submitted = next_out = 0
    while next_out < n:
        while submitted < n and in_flight() + len(ready) < window:  # results wait in bounded memory
            submit(submitted)
            submitted += 1
        done = finished()
        ready.update(done)
        for item in _hand_over(ready, next_out, ordered):
            yield item
            next_out += 1
        if not done and next_out < n:
            idle()


def _nothing() -> None:
    """An ``idle`` that does nothing (a map without ``on_wait``)."""


class LocalBackend:
    """Runs every chunk in the calling thread, in order."""

    name = "local"

    def map(self, fn: ChunkFunction, chunks: Sequence[Any], *, shared: Any = None, ordered: bool = True,
            on_wait: Callable[[], None] | None = None) -> Iterator[tuple[int, Any]]:
        """``(i, fn(chunks[i], shared))`` for every chunk, computed here one after the other
        (parameters: :meth:`Backend.map`)."""
        for i, chunk in enumerate(chunks):
            yield i, fn(chunk, shared)

    def describe(self) -> dict[str, Any]:
        """``{"backend": "local"}``."""
        return {"backend": "local"}

    def ready(self, timeout_s: float = 2.0) -> str:
        """Always ``"ok"``: this process computes."""
        return "ok"

    def close(self) -> None:
        """Nothing to release."""
        return None

    def __repr__(self) -> str:
        return "LocalBackend()"


def cores_available() -> int:
    """The CPU cores this process may run on (its affinity mask where the platform has one)."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # not Linux
        return max(1, os.cpu_count() or 1)


#: What a worker process sets before it imports numpy: one BLAS thread per process, as on a
#: cluster's workers (``DASK_WORKER_ENVIRON``), so that N processes do not each start N threads.
#: (It takes effect because a spawned worker imports numpy only with its first chunk — unless
#: the caller's main module imports it itself; then the caller's own setting holds.)
_WORKER_THREADS_ENVIRON = {k: str(v) for k, v in DASK_WORKER_ENVIRON.items() if k.endswith("_NUM_THREADS")}


def _start_worker() -> None:
    """A worker process's initializer: :data:`_WORKER_THREADS_ENVIRON` (what the caller set is kept)."""
    for key, value in _WORKER_THREADS_ENVIRON.items():
        os.environ.setdefault(key, value)


def _broken_pool_reason(exc: BrokenProcessPool, i: int, n: int) -> str:
    """Why a process pool broke while chunk ``i`` of ``n`` ran: a result the caller could not read
    back (the pool keeps the reader's error, a quoted traceback, as the cause: its last line is
    said), else a worker that died."""
    lines = str(exc.__cause__ or "").replace("'''", "").strip().splitlines()
    if lines:
        return (f"the result of chunk {i + 1} of {n} could not be read back from its worker process "
                f"({lines[-1].strip()}); the work was stopped")
    return (f"a worker process died while chunk {i + 1} of {n} was running (killed, or out of memory); "
            "the work was stopped")


class ProcessBackend:
    """Runs chunks in ``workers`` processes of this machine (module docstring).

    Parameters
    ----------
    workers : int
        Worker processes (>= 1; 1 computes in the calling thread, as :class:`LocalBackend`).
    poll_s : float
        How often a waiting map looks at its chunks and calls ``on_wait``, s.
    window : int, optional
        Most chunks in flight per map (submitted, or computed and not yet handed over; default
        twice the workers), so that results wait at the caller in bounded memory.

    Examples
    --------
    >>> import operator
    >>> backend = ProcessBackend(2)
    >>> sorted(backend.map(operator.mul, [1, 2, 3], shared=10))
    [(0, 10), (1, 20), (2, 30)]
    >>> backend.close()
    """

    name = "processes"

    def __init__(self, workers: int, *, poll_s: float = 0.05, window: int | None = None) -> None:
        if int(workers) < 1:
            raise ValueError(f"a process backend needs at least one worker process, not {workers}")
        self.workers = int(workers)
        self.poll_s = float(poll_s)
        self.window = max(1, int(window)) if window is not None else 2 * self.workers
        self._lock = threading.Lock()
        self._pool: ProcessPoolExecutor | None = None

    def __repr__(self) -> str:
        return f"ProcessBackend({self.workers})"

    def _executor(self) -> ProcessPoolExecutor:
        with self._lock:
            if self._pool is None:
                self._pool = ProcessPoolExecutor(self.workers, mp_context=multiprocessing.get_context("spawn"),
                                                 initializer=_start_worker)
            return self._pool

    def _stop_workers(self) -> None:
        """Cancel what waits and terminate the workers (a chunk in a worker cannot be interrupted
        otherwise); the next map starts a new pool."""
        with self._lock:
            pool, self._pool = self._pool, None
        if pool is None:
            return
        processes = list((getattr(pool, "_processes", None) or {}).values())  # the standard pool keeps them here
        pool.shutdown(wait=False, cancel_futures=True)
        for process in processes:
            with contextlib.suppress(Exception):
                process.terminate()
        for process in processes:
            with contextlib.suppress(Exception):
                process.join(5.0)

    def map(self, fn: ChunkFunction, chunks: Sequence[Any], *, shared: Any = None, ordered: bool = True,
            on_wait: Callable[[], None] | None = None) -> Iterator[tuple[int, Any]]:
        """``(i, fn(chunks[i], shared))`` for every chunk, computed in the worker processes
        (``shared`` is sent with every chunk; parameters: :meth:`Backend.map`)."""
        n = len(chunks)
        if n <= 1 or self.workers == 1:  # no process to start for one chunk
            yield from LocalBackend().map(fn, chunks, shared=shared, ordered=ordered)
            return
        pool = self._executor()
        index: dict[Future[Any], int] = {}
        pending: set[Future[Any]] = set()

        def submit(i: int) -> None:
            future = pool.submit(fn, chunks[i], shared)
            index[future] = i
            pending.add(future)

        def finished() -> dict[int, Any]:
            done, still = wait(pending, timeout=self.poll_s, return_when=FIRST_COMPLETED)
            pending.intersection_update(still)
            out = {}
            for future in done:
                i = index.pop(future)
                try:
                    out[i] = future.result()
                except BrokenProcessPool as exc:
                    raise ChunkFailed(_broken_pool_reason(exc, i, n)) from None
            return out

        finished_cleanly = False
        try:
            yield from _windowed(n, self.window, submit, lambda: len(pending), finished,
                                 on_wait if on_wait is not None else _nothing, ordered)
            finished_cleanly = True
        finally:
            if not finished_cleanly:  # raised, or the caller stopped early: stop what still runs
                self._stop_workers()

    def describe(self) -> dict[str, Any]:
        """``{"backend": "processes", "workers": N}``."""
        return {"backend": self.name, "workers": self.workers}

    def ready(self, timeout_s: float = 2.0) -> str:
        """Always ``"ok"``: this machine computes."""
        return "ok"

    def close(self) -> None:
        """Stop the worker processes (idempotent; the next map starts them again)."""
        with self._lock:
            pool, self._pool = self._pool, None
        if pool is not None:
            pool.shutdown(wait=True, cancel_futures=True)


def _identity(value: Any) -> Any:
    """The task that holds a map's shared part on the cluster."""
    return value


class DaskBackend:
    """Runs chunks as tasks on the Dask cluster of the scheduler at ``address``.

    Parameters
    ----------
    address : str
        The scheduler, e.g. ``tcp://127.0.0.1:8786``.
    connect_timeout_s : float
        How long to try to reach the scheduler before :class:`ComputeUnavailable`, s.
    retries : int
        Extra tries of a chunk that raises (a worker that dies is handled by the scheduler,
        see the module docstring).
    window : int, optional
        Most chunks in flight per map; default twice the cluster's worker threads (at least 2).
    poll_s : float
        How often a waiting map looks at its chunks and calls ``on_wait``, s.

    Raises
    ------
    ComputeUnavailable
        The scheduler cannot be reached within ``connect_timeout_s``, or ``dask.distributed``
        is not installed.
    """

    name = "dask"

    def __init__(self, address: str, *, connect_timeout_s: float = 10.0, retries: int = 3,
                 window: int | None = None, poll_s: float = 0.05) -> None:
        self.address = str(address)
        self.connect_timeout_s = float(connect_timeout_s)
        self.retries = int(retries)
        self.window = window
        self.poll_s = float(poll_s)
        self._lock = threading.Lock()
        self._client: Any = None
        self._connect()

    def __repr__(self) -> str:
        return f"DaskBackend({self.address!r})"

    def _connect(self) -> Any:
        try:  # only here: the embedded default needs no Dask installed
            from distributed import Client
        except ImportError:
            raise ComputeUnavailable(f"a Dask scheduler ({self.address}) is configured but dask.distributed is not "
                                     "installed: pip install 'rcsa[dask]'") from None
        with self._lock:
            if self._client is not None and self._client.status == "running":
                return self._client
            if self._client is not None:
                with contextlib.suppress(Exception):
                    self._client.close(timeout=1)
                self._client = None
            try:
                self._client = Client(self.address, timeout=self.connect_timeout_s, set_as_default=False)
            except (OSError, TimeoutError, ValueError) as exc:
                raise ComputeUnavailable(f"cannot reach the Dask scheduler at {self.address} within "
                                         f"{self.connect_timeout_s:g} s ({exc}); start it, or unset "
                                         "RCSA_DASK_SCHEDULER to compute locally") from None
            return self._client

    @property
    def client(self) -> Any:
        """The ``distributed.Client`` (connected again if the scheduler was lost)."""
        return self._connect()

    def describe(self) -> dict[str, Any]:
        """The scheduler's address and its workers and threads (or the error reaching it)."""
        try:
            threads = self.client.nthreads()
        except Exception as exc:  # a health check must not raise
            return {"backend": "dask", "scheduler": self.address, "error": str(exc)}
        return {"backend": "dask", "scheduler": self.address, "workers": len(threads),
                "threads": int(sum(threads.values()))}

    def ready(self, timeout_s: float = 2.0) -> str:
        """``"ok"`` when the scheduler answers within ``timeout_s`` and has a worker, else why not.

        Never raises and never waits longer than about ``timeout_s`` (the answer is read
        from a helper thread; a connection lost since is tried again with that timeout).
        """
        def probe() -> str:
            client = self._client
            if client is None or client.status != "running":
                try:
                    from distributed import Client
                except ImportError:
                    return "error: dask.distributed is not installed"
                with self._lock:
                    if self._client is not None:
                        with contextlib.suppress(Exception):
                            self._client.close(timeout=1)
                    self._client = None
                    try:
                        self._client = Client(self.address, timeout=timeout_s, set_as_default=False)
                    except (OSError, TimeoutError, ValueError) as exc:
                        return f"error: the Dask scheduler at {self.address} does not answer ({exc})"
                client = self._client
            workers = client.nthreads()
            return "ok" if workers else f"error: the Dask scheduler at {self.address} has no worker"

        result: list[str] = []
        thread = threading.Thread(target=lambda: result.append(_quietly(probe, self.address)), daemon=True,
                                  name="rcsa-dask-ready")
        thread.start()
        thread.join(timeout_s + 1.0)
        return result[0] if result else f"error: the Dask scheduler at {self.address} did not answer within " \
                                        f"{timeout_s:g} s"

    def close(self) -> None:
        """Close the connection to the scheduler (idempotent; the cluster keeps running)."""
        with self._lock:
            if self._client is not None:
                with contextlib.suppress(Exception):
                    self._client.close(timeout=5)
                self._client = None

    def map(self, fn: ChunkFunction, chunks: Sequence[Any], *, shared: Any = None, ordered: bool = True,
            on_wait: Callable[[], None] | None = None) -> Iterator[tuple[int, Any]]:
        """``(i, fn(chunks[i], shared))`` for every chunk, computed as tasks on the cluster
        (parameters: :meth:`Backend.map`)."""
        from distributed.client import FutureCancelledError
        from distributed.scheduler import KilledWorker

        client = self.client
        n = len(chunks)
        if n == 0:
            return
        window = self.window or max(2, 2 * int(sum(client.nthreads().values())))
        token = secrets.token_hex(6)
        shared_future = client.submit(_identity, shared, key=f"rcsa-shared-{token}", pure=False)
        pending: dict[int, Any] = {}

        def submit(i: int) -> None:
            pending[i] = client.submit(fn, chunks[i], shared_future, retries=self.retries,
                                       key=f"rcsa-chunk-{token}-{i}", pure=False)

        def finished() -> dict[int, Any]:
            out = {}
            for i in [i for i, f in pending.items() if f.done()]:
                future = pending.pop(i)
                try:
                    out[i] = future.result()
                except FutureCancelledError:
                    raise ComputeUnavailable(f"lost the Dask scheduler at {self.address} while chunk {i + 1} of "
                                             f"{n} was running (client {client.status}); the work was "
                                             "stopped, submit it again once the cluster is back") from None
                except KilledWorker as exc:
                    raise ChunkFailed(f"chunk {i + 1} of {n} killed every Dask worker it ran on ({exc}); it "
                                      "may need more memory than a worker has") from None
                finally:
                    future.release()
            return out

        def idle() -> None:
            if client.status not in ("running", "connecting"):
                raise ComputeUnavailable(f"lost the Dask scheduler at {self.address} (client "
                                         f"{client.status}); the work was stopped")
            if on_wait is not None:
                on_wait()
            time.sleep(self.poll_s)

        try:
            yield from _windowed(n, window, submit, lambda: len(pending), finished, idle, ordered)
        finally:
            leftover = list(itertools.chain(pending.values(), [shared_future]))
            if leftover and client.status == "running":
                with contextlib.suppress(Exception):
                    client.cancel(leftover)


def _quietly(probe: Callable[[], str], address: str) -> str:
    try:
        return probe()
    except Exception as exc:  # a readiness check reports, it does not raise
        return f"error: the Dask scheduler at {address} is unavailable ({type(exc).__name__}: {exc})"


def compute_backend(scheduler: str | None, *, connect_timeout_s: float = 10.0, retries: int = 3,
                    workers: int = 1) -> Backend:
    """A :class:`DaskBackend` on ``scheduler`` when one is given, else a :class:`ProcessBackend` of
    ``workers`` processes (0: :func:`cores_available`), else (one worker) a :class:`LocalBackend`.

    Raises
    ------
    ComputeUnavailable
        The scheduler cannot be reached (or Dask is not installed).
    """
    if scheduler:
        backend = DaskBackend(scheduler, connect_timeout_s=connect_timeout_s, retries=retries)
        log.info("computing on the Dask cluster at %s: %s", scheduler, backend.describe())
        return backend
    workers = cores_available() if int(workers) == 0 else int(workers)
    if workers < 0:
        raise ValueError(f"workers must be >= 0 (0: one per core), not {workers}")
    return ProcessBackend(workers) if workers > 1 else LocalBackend()
