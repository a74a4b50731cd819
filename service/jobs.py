"""Service side of work that may become a job: the one answer, and how a job is shown over HTTP.

Whether a batch, library or sync is answered at once or queued is decided by
:func:`rcsa.app.jobs.answer_or_queue` (size against ``RCSA_ASYNC_BATCH_THRESHOLD``, or
``Prefer: respond-async``); the job runners run the same :func:`rcsa.app.jobs.run_work`.
Here: the ``Prefer`` header, the ``202 Accepted`` answer, the links a sync report carries,
who a job belongs to (:func:`caller`: its API key, or an anonymous client's address — one
caller may have at most ``RCSA_JOB_MAX_UNFINISHED_PER_CALLER`` unfinished jobs, ``429``
beyond), whose runners it shares (:func:`pool`: a keyed caller's own; every anonymous caller
shares one pool, which runs at most ``RCSA_JOB_MAX_RUNNING_PER_CALLER`` jobs at once, so
anonymous jobs never hold every runner; jobs are claimed round-robin across pools), and the
public JSON of a job.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import Any

from starlette.requests import Request
from starlette.responses import Response

from rcsa.app import budget
from rcsa.app.analyses import validate
from rcsa.app.jobs import Outcome, Work, answer_or_queue
from rcsa.app.results import Format
from rcsa.infra.api_keys import Principal
from rcsa.infra.job_queue import Job, QuotaExceeded

from .errors import ProblemError
from .responses import json_response, result_response
from .state import AppState

__all__ = ["ANONYMOUS_POOL", "accepted", "answer", "caller", "compute", "job_document", "pool", "present",
           "wants_async"]


def caller(who: Principal, request: Request) -> str:
    """Whose job it is: the API key's id, or ``anonymous@<client address>``."""
    if who.scope is not None:
        return who.key_id
    host = request.client.host if request.client is not None else "unknown"
    return f"anonymous@{host}"


#: The pool of every anonymous caller's jobs.
ANONYMOUS_POOL = "anonymous"


def pool(owner: str | None) -> str | None:
    """Whose runners a job of ``owner`` shares: :data:`ANONYMOUS_POOL` for anonymous callers,
    else None (the owner's own)."""
    return ANONYMOUS_POOL if owner is not None and owner.startswith("anonymous@") else None


def wants_async(prefer: str | None) -> bool:
    """Whether a ``Prefer`` header (RFC 7240) asks for ``respond-async``."""
    return any(p.split(";")[0].strip().lower() == "respond-async" for p in (prefer or "").split(","))


def present(outcome: Outcome) -> dict[str, Any]:
    """The document the service answers (and a job stores) for an outcome: a sync report
    gets the links of its library."""
    if outcome.kind != "library-sync":
        return outcome.document
    base = f"/v1/libraries/{outcome.document['library_id']}"
    return {**outcome.document, "library_url": base, "results_url": base + "/results"}


def answer(state: AppState, work: Work, *, prefer: str | None, idempotency_key: str | None,
           headers: Mapping[str, str] | None = None, owner: str | None = None, result_format: Format = "json"
           ) -> Response:
    """Run ``work`` now (``200`` with its document) or queue it for ``owner`` (``202``, :func:`accepted`).

    A batch or library answered now is sent in ``result_format`` (JSON, HDF5 or Parquet: the
    client's ``Accept``, :func:`service.responses.result_form`); a job writes that form itself
    (the work request names it).

    A request with an ``Idempotency-Key`` may be a retry whose first answer was lost: its
    submission reuses the unfinished job of the same request instead of queuing it twice.
    An owner with too many unfinished jobs gets ``429`` with ``Retry-After``.
    """
    asked = wants_async(prefer)
    queued = work.should_queue(respond_async=asked, async_threshold=state.settings.async_batch_threshold)
    if work.kind in ("batch", "library", "library-sync"):  # the compute budget, before any work
        budget.check_work(work.kind, work.request, work.size, mode="job" if queued else "sync")
    try:
        result = answer_or_queue(state.bench, state.jobs, work, respond_async=asked,
                                 async_threshold=state.settings.async_batch_threshold,
                                 reuse_unfinished=idempotency_key is not None, owner=owner,
                                 max_unfinished=state.settings.job_max_unfinished_per_caller, pool=pool(owner))
    except QuotaExceeded as exc:
        raise ProblemError(429, f"{exc}; poll the jobs you have (GET /v1/jobs/{{id}}) and submit again when one has "
                                "finished", slug="too-many-jobs", title="Too many unfinished jobs",
                           headers={"Retry-After": str(max(state.settings.retry_after_s, 5))}) from None
    if isinstance(result, Job):
        return accepted(state, result, preference_applied=asked)
    if result.kind in ("batch", "library"):
        return result_response(result.document, result_format, result.kind, headers=headers)
    return json_response(present(result), headers=headers)


def compute(state: AppState, kind: str, request: Mapping[str, Any], *, prefer: str | None,
            run: Callable[[], Response], owner: str | None = None) -> Response:
    """One computation (:data:`rcsa.app.analyses.ANALYSIS_KINDS`) under the compute budget.

    The request's estimated cost (:func:`rcsa.app.budget.check`) must fit the limits of a
    synchronous request, unless ``Prefer: respond-async`` asks for a job: then the job
    limits apply, the request is validated and queued (``202``, :func:`accepted`), and the
    job's result is what ``run`` would have answered, queued for ``owner`` (:func:`caller`,
    for per-caller quotas). Otherwise ``run()`` answers now.
    """
    asked = wants_async(prefer)
    budget.check(kind, request, mode="job" if asked else "sync")
    if not asked:
        return run()
    validate(kind, request, store=state.reader)
    return answer(state, Work(kind, dict(request), 1), prefer=prefer, idempotency_key=None,  # type: ignore[arg-type]
                  owner=owner)


def job_document(job: Job) -> dict[str, Any]:
    """The public JSON of a job, with its status and result URLs."""
    return {**job.to_dict(), "status_url": f"/v1/jobs/{job.id}",
            "result_url": f"/v1/jobs/{job.id}/result" if job.has_result else None}


def accepted(state: AppState, job: Job, *, preference_applied: bool) -> Response:
    """``202 Accepted`` with ``Location`` (the job) and ``Retry-After``."""
    headers = {"Location": f"/v1/jobs/{job.id}", "Retry-After": str(state.settings.retry_after_s)}
    if preference_applied:
        headers["Preference-Applied"] = "respond-async"
    for runner in state.runners:
        runner.wake()
    return json_response(job_document(job), status_code=202, headers=headers)
