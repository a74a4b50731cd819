"""Batches of combinations on one spindle, and the jobs that run the large ones.

``POST /v1/tool-point-frf/batch`` answers ``200`` with every result when the batch is small,
or ``202 Accepted`` (``Location: /v1/jobs/{id}``, ``Retry-After``) when it has more than
``RCSA_ASYNC_BATCH_THRESHOLD`` combinations or the request says ``Prefer: respond-async``.
"""

from __future__ import annotations

from typing import Annotated

from fastapi import APIRouter, Depends, Header, Path, Query, Request
from starlette.responses import FileResponse, Response

from rcsa.app.libraries import prepare_batch

from ..bodies import require_json
from ..deps import StateDep
from ..errors import ProblemError
from ..idempotency import IDEMPOTENCY_PROBLEMS, IdempotencyKeyHeader, IdempotentRoute
from ..jobs import answer, caller, job_document
from ..responses import body_limit, json_response, problems
from ..schemas import BatchRequest, BatchResult, JobStatus
from ..security import ReadAccess

router = APIRouter(prefix="/v1", tags=["batches and jobs"], route_class=IdempotentRoute)

JobId = Annotated[str, Path(description="Job id from the Location header of a 202 answer.",
                            examples=["j-0123456789abcdef0123456789abcdef"])]
PreferHeader = Annotated[str | None, Header(description="respond-async: always answer 202 with a job.")]
ToolPointQuery = Annotated[str | None, Query(pattern=r"^[hlnp](,[hlnp]){0,3}$", description=(
    "Receptances to return in each result's tool_point, e.g. h (a third of the size); default h,l,n,p."))]


@router.post("/tool-point-frf/batch", dependencies=[Depends(require_json)], response_model=BatchResult,
             openapi_extra=body_limit("batch"), responses={
    202: {"model": JobStatus, "description": "Queued as a job; poll Location."}, **problems(401, 413, 415, 422),
    **problems(429), **IDEMPOTENCY_PROBLEMS}, summary="Tool-point FRFs of many combinations")
def predict_batch(body: BatchRequest, request: Request, state: StateDep, who: ReadAccess, prefer: PreferHeader = None,
                  tool_point: ToolPointQuery = None, idempotency_key: IdempotencyKeyHeader = None) -> Response:
    """One result per combination, in input order, each with its own ``status``.

    The spindle (and each distinct spindle + holder) is condensed once and reused. A bad
    combination gets ``status: error`` with the offending field and never fails the others.
    With ``Idempotency-Key``, a retry gets the first answer (the same job, for a large batch).
    """
    batch, refused = body.to_request()
    work = prepare_batch(state.bench, batch, refused, tool_point.split(",") if tool_point else None)
    return answer(state, work, prefer=prefer, idempotency_key=idempotency_key, owner=caller(who, request))


@router.get("/jobs/{job_id}", response_model=JobStatus, responses=problems(401, 404), summary="Job status")
def get_job(job_id: JobId, state: StateDep, _: ReadAccess) -> Response:
    """Status and progress of a job; ``result_url`` once it has succeeded."""
    job = state.jobs.get(job_id)
    headers = {} if job.finished else {"Retry-After": str(state.settings.retry_after_s)}
    return json_response(job_document(job), headers=headers)


@router.get("/jobs/{job_id}/result", response_class=FileResponse, responses={
    200: {"description": "The job's result: a batch result (BatchResult) or a library result (LibraryResult).",
          "content": {"application/json": {"schema": {"oneOf": [{"$ref": "#/components/schemas/BatchResult"},
                                                                {"$ref": "#/components/schemas/LibraryResult"}]}}}},
    **problems(401, 404, 409, 410)}, summary="Result of a finished job")
def get_job_result(job_id: JobId, state: StateDep, _: ReadAccess) -> Response:
    """The result document of a succeeded job (``409`` while it runs or when it failed; ``410``
    once it was deleted to keep the kept results within their disk budget).

    The file is sent in pieces as it is read (and ranges of it on request), never loaded whole.
    """
    job = state.jobs.get(job_id)
    if job.status == "succeeded" and job.result_evicted_utc is not None:
        raise ProblemError(410, f"the result of job {job_id} was deleted on {job.result_evicted_utc} to keep the kept "
                                "job results within their disk budget (oldest first); submit the job again",
                           slug="job-result-evicted", title="Job result deleted", extra={"job": job_document(job)})
    if job.status == "succeeded":
        return FileResponse(state.jobs.result_path(job_id), media_type="application/json")
    if job.status == "failed":
        error = job.error or {}
        raise ProblemError(409, f"job {job_id} failed: {error.get('detail', 'see its status')}", slug="job-failed",
                           title="Job failed", errors=error.get("errors"), extra={"job": job_document(job)})
    raise ProblemError(409, f"job {job_id} is {job.status} ({job.progress:.0%} done); poll /v1/jobs/{job_id}",
                       slug="job-not-finished", title="Job not finished",
                       headers={"Retry-After": str(state.settings.retry_after_s), "Location": f"/v1/jobs/{job_id}"})
