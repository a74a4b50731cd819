"""Answer now or queue a job: one decision and one job handler for batches, libraries and syncs.

Three kinds of work may take long: a batch of combinations (``batch``), a whole tool library
(``library``) and a library sync (``library-sync``). Each is first *prepared*
(:mod:`rcsa.app.libraries`: read, checked, sized — every input error is raised before
anything is queued), giving a :class:`Work`. Then :func:`answer_or_queue` decides: work that
is big (more results to compute than the caller's threshold) or that the caller asked to run
in the background is queued in the durable job store (:mod:`rcsa.infra.job_queue`); the rest
is run at once by :func:`run_work`. A job runner calls the very same :func:`run_work`
(:func:`job_handlers`), so a job's result is exactly what the immediate answer would have been.
A batch or library job writes its result as it is computed (:func:`stream_work`: one result
after the other into the job's result file, never the whole document in memory); its bytes
are those :func:`run_work`'s document would serialise to.

Where the work runs — the measurement source, the library store, the size limits, the
compute backend (this process, or a Dask cluster: :mod:`rcsa.infra.compute_backends`, which
the doors use directly) and who is told about computations (metrics) — is a
:class:`Workbench`. Work answered at once is computed
in the calling process; jobs and the CLI use the workbench's backend. Either way the work is
cut into the same chunks, so the results are the same bytes.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Iterator, Mapping
from contextlib import AbstractContextManager, contextmanager
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, BinaryIO, Literal, Protocol

from rcsa.app.analyses import ANALYSIS_KINDS, run_analysis
from rcsa.app.results import RESULT_FORMAT_FIELD, binary_writer, json_bytes
from rcsa.app.stores import library_store
from rcsa.errors import InputError
from rcsa.infra.compute_backends import Backend, LocalBackend
from rcsa.infra.job_queue import Handler, Job, JobStore, StreamedResult
from rcsa.libraries.library_prediction import EntryResults, iter_entries, run_entries
from rcsa.libraries.sync import LibraryStore, SyncPlan, run_sync
from rcsa.measured.hybrid import MeasurementSource
from rcsa.model.bounds import MAX_BATCH_COMBINATIONS, MAX_FREQUENCY_LINES

__all__ = [
    "JOBS_DIRECTORY",
    "JOB_KINDS",
    "Kind",
    "Observer",
    "Outcome",
    "Work",
    "Workbench",
    "analysis_job_handlers",
    "answer_or_queue",
    "job_handlers",
    "job_store",
    "run_work",
    "stream_work",
    "write_entries",
]

#: What may run as a job: batches, libraries and syncs (:data:`JOB_KINDS`), and single
#: computations a caller asked to run in the background (:data:`rcsa.app.analyses.ANALYSIS_KINDS`,
#: handlers from :func:`analysis_job_handlers`).
Kind = Literal["batch", "library", "library-sync", "prediction", "lobes", "effects", "identification", "diagnosis"]
JOB_KINDS: tuple[Kind, ...] = ("batch", "library", "library-sync")
#: Sub-directory of the store holding the job queue.
JOBS_DIRECTORY = "jobs"


class Observer(Protocol):
    """Who is told about computations (the service's metrics); every method may do nothing."""

    def timed(self, operation: str) -> AbstractContextManager[None]:
        """Time one computation of ``operation`` (a :data:`Kind`)."""
        ...

    def computed(self, operation: str, n: int) -> None:
        """``n`` tool-point FRFs were computed by ``operation``."""
        ...


class _Unobserved:
    @contextmanager
    def timed(self, operation: str) -> Iterator[None]:
        yield

    def computed(self, operation: str, n: int) -> None:
        return None


@dataclass(frozen=True)
class Workbench:
    """Where work runs.

    Attributes
    ----------
    store : MeasurementSource or None
        Where measured spindles are read (a store, or a cache in front of one); None refuses
        measured spindles.
    store_path : path or None
        The store directory, whose ``libraries`` a sync keeps (needed by syncs only).
    max_lines : int
        Most frequency lines per request.
    max_combinations : int
        Most combinations (tools to predict) per request.
    observer : Observer
        Told about every computation (default: nobody).
    backend : Backend
        Where jobs (and the CLI) compute their chunks (default: this process).
    """

    store: MeasurementSource | None
    store_path: str | os.PathLike[str] | None = None
    max_lines: int = MAX_FREQUENCY_LINES
    max_combinations: int = MAX_BATCH_COMBINATIONS
    observer: Observer = field(default_factory=_Unobserved)
    backend: Backend = field(default_factory=LocalBackend)

    @property
    def libraries(self) -> LibraryStore:
        """The stored libraries of :attr:`store_path` (:func:`rcsa.app.stores.library_store`)."""
        if self.store_path is None:
            raise InputError("library_id", "stored libraries need a store directory")
        return library_store(self.store_path)


@dataclass(frozen=True)
class Work:
    """Prepared work: checked, JSON-ready (so it can be queued), and sized.

    Attributes
    ----------
    kind : {"batch", "library", "library-sync"}
    request : dict
        What :func:`run_work` runs (and a job stores).
    size : int
        Results it computes (a sync: only those not in the result cache).
    plan : SyncPlan or None
        A sync's plan, already made while preparing it (saves making it twice).
    check : callable or None
        Checks the computation makes itself as it starts (the grid, spindle and materials
        the combinations share): run before queuing, so that a bad request is refused at
        once instead of becoming a failed job.
    """

    kind: Kind
    request: dict[str, Any]
    size: int
    plan: SyncPlan | None = None
    check: Callable[[], None] | None = None

    def should_queue(self, *, respond_async: bool, async_threshold: int) -> bool:
        """Queue it when it computes more than ``async_threshold`` results or the caller asks.

        A library with no tool to predict is answered at once: there is nothing to wait for.
        """
        if self.kind == "library" and self.size == 0:
            return False
        if self.kind in ANALYSIS_KINDS:  # one computation: a job only when asked for
            return respond_async
        return respond_async or self.size > async_threshold


@dataclass(frozen=True)
class Outcome:
    """What running work gave.

    Attributes
    ----------
    kind : str
    document : dict
        The result: a batch or library result (one entry per item), or a sync report.
    summary : dict
        Small counts kept with a job (``ok``/``skipped``/``error``; a sync adds ``added``,
        ``changed``, ``unchanged``, ``removed`` and ``computed``).
    computed : int
        Tool-point FRFs computed.
    """

    kind: str
    document: dict[str, Any]
    summary: dict[str, Any]
    computed: int


def run_work(bench: Workbench, kind: str, request: Mapping[str, Any], *,
             progress: Callable[[int, int], None] | None = None, plan: SyncPlan | None = None,
             backend: Backend | None = None) -> Outcome:
    """Run a batch, library or sync request now (the immediate answer and every job).

    Parameters
    ----------
    bench : Workbench
    kind : {"batch", "library", "library-sync"}
    request : mapping
        :attr:`Work.request`.
    progress : callable, optional
        ``progress(done, total)`` as results are computed.
    plan : SyncPlan, optional
        A sync's plan when the caller already has it.
    backend : Backend, optional
        Where the chunks are computed (default: the workbench's).

    Raises
    ------
    InputError
        An unknown kind, or a request the computation refuses.
    ComputeUnavailable
        The cluster cannot be reached or went away.
    """
    backend = backend if backend is not None else bench.backend
    with bench.observer.timed(kind):
        if kind in ("batch", "library"):
            document = run_entries(request, store=bench.store, max_lines=bench.max_lines,
                                   max_combinations=bench.max_combinations, progress=progress, arrays="numpy",
                                   backend=backend)
            summary = dict(document["summary"])
            computed = int(summary["ok"])
        elif kind == "library-sync":
            report = run_sync(bench.libraries, request, store=bench.store, max_lines=bench.max_lines,
                              progress=progress, plan=plan, backend=backend)
            document = report.to_dict()
            summary = {**document["counts"], **report.summary, "computed": report.computed}
            computed = report.computed
        elif kind in ANALYSIS_KINDS:
            document = run_analysis(kind, request, store=bench.store, max_lines=bench.max_lines, backend=backend)
            summary, computed = {}, 1
        else:
            raise InputError("kind", f"no work of kind {kind!r} (known: {', '.join(JOB_KINDS)})")
    bench.observer.computed(kind, computed)
    return Outcome(kind, document, summary, computed)


def stream_work(bench: Workbench, kind: str, request: Mapping[str, Any], *,
                progress: Callable[[int, int], None] | None = None,
                backend: Backend | None = None) -> StreamedResult:
    """A batch or library request as a result written while it is computed (for jobs).

    ``write(fh)`` writes the JSON document :func:`run_work` would answer — the same bytes —
    one result at a time, and returns the summary. At most a chunk's results (a window of
    them on a cluster) are held in memory, and no serialisation holds the interpreter for
    longer than one result takes. A request whose ``result_format`` (:data:`RESULT_FORMAT_FIELD`)
    is ``hdf5`` or ``parquet`` is written in that form instead, result by result too
    (:func:`rcsa.app.results.binary_writer`); ``fh`` must then be readable and seekable.

    Raises
    ------
    InputError
        A kind other than ``batch`` or ``library``.
    """
    if kind not in ("batch", "library"):
        raise InputError("kind", f"only batch and library results are streamed, not {kind!r}")
    backend = backend if backend is not None else bench.backend
    fmt = request.get(RESULT_FORMAT_FIELD, "json")

    def write(fh: BinaryIO) -> dict[str, Any]:
        with bench.observer.timed(kind):
            started = iter_entries(request, store=bench.store, max_lines=bench.max_lines,
                                   max_combinations=bench.max_combinations, progress=progress, backend=backend)
            summary = write_entries(fh, started, fmt, kind)
        bench.observer.computed(kind, int(summary.get("ok", 0)))
        return summary

    return StreamedResult(write)


def write_entries(fh: BinaryIO, started: EntryResults, fmt: str = "json", kind: str = "batch") -> dict[str, Any]:
    """Write a started batch or library result to ``fh`` result by result, in a form; its summary.

    Parameters
    ----------
    fh : binary file
        Readable and seekable for HDF5.
    started : EntryResults
        :func:`rcsa.libraries.library_prediction.iter_entries` of the request.
    fmt : {"json", "hdf5", "parquet"}
        JSON: the bytes :func:`json_bytes` gives the whole document.
    kind : {"batch", "library"}
        What the document is (a binary file's schema).
    """
    return _write_json(fh, started) if fmt == "json" else _write_binary(fh, started, fmt, kind)


def _write_json(fh: BinaryIO, started: EntryResults) -> dict[str, Any]:
    """Write ``{**head, "results": [...], "summary": {...}}`` as :func:`json_bytes` would, result by result."""
    fh.write(b"{")
    for name, value in started.head.items():
        fh.write(json_bytes(name) + b":" + json_bytes(value) + b",")
    fh.write(b'"results":[')
    counts: dict[str, int] = {}
    results = started.results
    try:
        for i, result in enumerate(results):
            if i:
                fh.write(b",")
            fh.write(json_bytes(result))
            counts[result["status"]] = counts.get(result["status"], 0) + 1
    finally:
        close = getattr(results, "close", None)
        if close is not None:
            close()  # stops the chunks still in flight when writing failed
    summary = started.summary(counts)
    fh.write(b'],"summary":' + json_bytes(summary) + b"}")
    return summary


def _write_binary(fh: BinaryIO, started: EntryResults, fmt: str, kind: str) -> dict[str, Any]:
    """Write the same document as :func:`_write_json` in a binary form, result by result."""
    counts: dict[str, int] = {}
    results = started.results
    with binary_writer(fmt, fh, kind) as writer:  # type: ignore[arg-type]
        writer.head(started.head)
        try:
            for result in results:
                writer.result(result)
                counts[result["status"]] = counts.get(result["status"], 0) + 1
        finally:
            close = getattr(results, "close", None)
            if close is not None:
                close()
        summary = started.summary(counts)
        writer.summary(summary)
    return summary


def answer_or_queue(bench: Workbench, jobs: JobStore, work: Work, *, respond_async: bool, async_threshold: int,
                    reuse_unfinished: bool = False, owner: str | None = None,
                    max_unfinished: int | None = None, pool: str | None = None,
                    access: str | None = None) -> Job | Outcome:
    """Queue ``work`` as a job (:meth:`Work.should_queue`), or run it now.

    Parameters
    ----------
    bench : Workbench
    jobs : JobStore
    work : Work
    respond_async : bool
        The caller asks for a job whatever the size.
    async_threshold : int
        Work computing more results than this is queued.
    reuse_unfinished : bool
        A retried submission: return the owner's unfinished job of the same request, if
        any, instead of queuing it twice (:meth:`JobStore.submit`).
    owner : str, optional
        Who asks.
    max_unfinished : int, optional
        Most queued or running jobs one owner may have.
    pool : str, optional
        Whose runners the job shares (jobs are claimed fairly across pools and the running
        cap counts per pool; default: the owner's own).
    access : str, optional
        Who may read the job (:meth:`rcsa.infra.job_queue.JobStore.get`).

    Returns
    -------
    Job or Outcome
        The queued job, or the outcome of running it now (computed in this process).

    Raises
    ------
    InputError
        The request is refused (before anything is queued).
    QuotaExceeded
        The owner has ``max_unfinished`` unfinished jobs already.
    """
    if work.should_queue(respond_async=respond_async, async_threshold=async_threshold):
        if work.check is not None:
            work.check()
        return jobs.submit(work.kind, work.request, reuse_unfinished=reuse_unfinished, owner=owner,
                           max_unfinished=max_unfinished, pool=pool, access=access)
    return run_work(bench, work.kind, work.request, plan=work.plan, backend=LocalBackend())


def job_handlers(bench: Workbench, present: Callable[[Outcome], dict[str, Any]] | None = None
                 ) -> dict[str, Handler]:
    """The job runner's handlers: one per :data:`JOB_KINDS`.

    Batches and libraries are streamed (:func:`stream_work`); a sync runs :func:`run_work`
    (its result is a small report). All compute on the workbench's backend.

    Parameters
    ----------
    bench : Workbench
    present : callable, optional
        Turns a sync's outcome into the result document its job stores (default: its
        ``document``); the service adds its links there, as in its immediate answers.
    """
    def handler(kind: str) -> Handler:
        def run(request: dict[str, Any], progress: Callable[[int, int], None]) -> tuple[Any, dict[str, Any] | None]:
            if kind in ("batch", "library"):
                return stream_work(bench, kind, request, progress=progress), None
            outcome = run_work(bench, kind, request, progress=progress)
            return (present(outcome) if present is not None else outcome.document), outcome.summary

        return run

    return {kind: handler(kind) for kind in JOB_KINDS}


def analysis_job_handlers(bench: Workbench) -> dict[str, Handler]:
    """The job runner's handlers of single computations queued on request
    (:data:`rcsa.app.analyses.ANALYSIS_KINDS`), all :func:`run_work`."""
    def handler(kind: str) -> Handler:
        def run(request: dict[str, Any], progress: Callable[[int, int], None]) -> tuple[Any, dict[str, Any]]:
            outcome = run_work(bench, kind, request, progress=progress)
            return outcome.document, outcome.summary

        return run

    return {kind: handler(kind) for kind in ANALYSIS_KINDS}


def job_store(store_path: str | os.PathLike[str], *, stale_after_s: float = 60.0, max_attempts: int = 3,
              max_result_bytes: int | None = None) -> JobStore:
    """The job queue of the store at ``store_path`` (``<store>/jobs``)."""
    return JobStore(Path(store_path) / JOBS_DIRECTORY, stale_after_s=stale_after_s, max_attempts=max_attempts,
                    max_result_bytes=max_result_bytes)
