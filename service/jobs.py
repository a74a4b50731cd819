"""Service side of work that may become a job: the one answer, and how a job is shown over HTTP.

Whether a batch, library or sync is answered at once or queued is decided by
:func:`rcsa.app.jobs.answer_or_queue` (size against ``RCSA_ASYNC_BATCH_THRESHOLD``, or
``Prefer: respond-async``); the job runners run the same :func:`rcsa.app.jobs.run_work`.
Here: the ``Prefer`` header, the ``202 Accepted`` answer, the links a sync report carries,
who a job belongs to (:func:`caller`, a :class:`JobCaller`), whose runners it shares (:func:`pool`: a keyed caller's own; every anonymous caller
shares one pool, which runs at most ``RCSA_JOB_MAX_RUNNING_PER_CALLER`` jobs at once, so
anonymous jobs never hold every runner; jobs are claimed round-robin across pools), and the
public JSON of a job.

**Jobs are private.** A job is readable (status, result, the list of one's jobs) only by
whoever submitted it: the same API key, or — for an anonymous caller — whoever holds its
**job token**: the ``202`` of an anonymous submission carries one (header ``X-Job-Token`` and
``job_token`` in the body; a new one unless the request sent its own), and the caller sends it
back in ``X-Job-Token`` to read the job and to submit further jobs under the same token (so
``GET /v1/jobs`` lists them together). Only the token's SHA-256 is stored. Everyone else gets
``404``, as for a job that does not exist (:func:`own_job`). Quotas stay per key or per
anonymous address (one caller may have at most ``RCSA_JOB_MAX_UNFINISHED_PER_CALLER``
unfinished jobs, ``429`` beyond), whatever tokens an address holds.
"""

from __future__ import annotations

import hashlib
import re
import secrets
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Annotated, Any

from fastapi import Header
from starlette.requests import Request
from starlette.responses import Response

from rcsa.app import budget
from rcsa.app.analyses import validate
from rcsa.app.jobs import Outcome, Work, answer_or_queue
from rcsa.app.results import Format
from rcsa.errors import InputError
from rcsa.infra.api_keys import Principal
from rcsa.infra.job_queue import Job, QuotaExceeded

from .errors import ProblemError
from .responses import json_response, result_response
from .state import AppState

__all__ = ["ANONYMOUS_POOL", "JOB_TOKEN_HEADER", "JobCaller", "JobTokenHeader", "accepted", "answer", "caller",
           "compute", "job_document", "own_job", "pool", "present", "wants_async"]

#: The header an anonymous caller's job token travels in (both ways).
JOB_TOKEN_HEADER = "X-Job-Token"
_TOKEN = re.compile(r"^[A-Za-z0-9_-]{32,128}$")
JobTokenHeader = Annotated[str | None, Header(alias=JOB_TOKEN_HEADER, description=(
    "Anonymous callers: the job token of the 202 that started your job(s) (32-128 characters of A-Z a-z 0-9 _ -). "
    "Needed to read an anonymous job (404 without it); sent with a submission, the new job joins the same token. "
    "Callers with an API key do not need it: their jobs are the key's."))]


@dataclass(frozen=True)
class JobCaller:
    """Who submits or reads a job.

    Attributes
    ----------
    owner : str
        Whose quota it counts in: the API key's id, or ``anonymous@<client address>``.
    access : str
        Who may read the job: ``key:<key id>``, or ``token:<SHA-256 of the job token>``.
    token : str or None
        An anonymous caller's job token (sent, or made now), to hand back in a ``202``.
    """

    owner: str
    access: str
    token: str | None = None


def caller(who: Principal, request: Request, *, new_token: bool = True) -> JobCaller:
    """Who the caller is for jobs (module docstring); an anonymous caller without a token gets a
    new one (``new_token``; a read needs the one it was given).

    Raises
    ------
    InputError
        An ``X-Job-Token`` that is not a token this service could have made (field ``X-Job-Token``).
    """
    if who.scope is not None:
        return JobCaller(who.key_id, f"key:{who.key_id}")
    host = request.client.host if request.client is not None else "unknown"
    token = request.headers.get(JOB_TOKEN_HEADER)
    if token is None:
        token = secrets.token_urlsafe(32) if new_token else ""
    elif not _TOKEN.match(token):
        raise InputError(JOB_TOKEN_HEADER, "must be the job token of a 202 answer (32-128 characters of A-Z a-z 0-9 "
                                           "_ -)")
    return JobCaller(f"anonymous@{host}", "token:" + hashlib.sha256(token.encode()).hexdigest(), token or None)


def own_job(state: AppState, job_id: str, who: Principal, request: Request) -> Job:
    """The caller's job ``job_id``.

    Raises
    ------
    NotFoundError
        No such job, or someone else's (``404`` either way: another caller's job ids are not
        confirmed to exist).
    """
    return state.jobs.get(job_id, access=caller(who, request, new_token=False).access)


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
           headers: Mapping[str, str] | None = None, owner: JobCaller | None = None, result_format: Format = "json"
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
                                 reuse_unfinished=idempotency_key is not None,
                                 owner=owner.owner if owner else None, access=owner.access if owner else None,
                                 max_unfinished=state.settings.job_max_unfinished_per_caller,
                                 pool=pool(owner.owner if owner else None))
    except QuotaExceeded as exc:
        raise too_many_jobs(state, exc) from None
    if isinstance(result, Job):
        return accepted(state, result, preference_applied=asked, token=owner.token if owner else None)
    if result.kind in ("batch", "library"):
        return result_response(result.document, result_format, result.kind, headers=headers)
    created = result.kind == "library-sync" and result.document.get("revision") == 1  # its first sync made it
    return json_response(present(result), status_code=201 if created else 200, headers=headers)


def too_many_jobs(state: AppState, exc: QuotaExceeded) -> ProblemError:
    """The ``429`` of a caller at its quota of unfinished jobs."""
    return ProblemError(429, f"{exc}; poll the jobs you have (GET /v1/jobs) and submit again when one has finished",
                        slug="too-many-jobs", title="Too many unfinished jobs",
                        headers={"Retry-After": str(max(state.settings.retry_after_s, 5))})


def submit(state: AppState, kind: str, request: Mapping[str, Any], owner: JobCaller, *, reuse_unfinished: bool,
           preference_applied: bool) -> Response:
    """Queue a job of ``kind`` for ``owner`` (quota and pool as for :func:`answer`): its ``202``."""
    try:
        job = state.jobs.submit(kind, request, reuse_unfinished=reuse_unfinished, owner=owner.owner,
                                access=owner.access, max_unfinished=state.settings.job_max_unfinished_per_caller,
                                pool=pool(owner.owner))
    except QuotaExceeded as exc:
        raise too_many_jobs(state, exc) from None
    return accepted(state, job, preference_applied=preference_applied, token=owner.token)


def compute(state: AppState, kind: str, request: Mapping[str, Any], *, prefer: str | None,
            run: Callable[[], Response], owner: JobCaller | None = None) -> Response:
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


def accepted(state: AppState, job: Job, *, preference_applied: bool, token: str | None = None) -> Response:
    """``202 Accepted`` with ``Location`` (the job) and ``Retry-After``; an anonymous caller's
    job token in ``X-Job-Token`` and ``job_token``."""
    headers = {"Location": f"/v1/jobs/{job.id}", "Retry-After": str(state.settings.retry_after_s)}
    if preference_applied:
        headers["Preference-Applied"] = "respond-async"
    document = job_document(job)
    if token is not None:
        headers[JOB_TOKEN_HEADER] = token
        document["job_token"] = token
    for runner in state.runners:
        runner.wake()
    return json_response(document, status_code=202, headers=headers)
