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
from rcsa.app.results import MEDIA_TYPES, RESULT_FORMAT_FIELD

from ..bodies import require_json
from ..deps import StateDep
from ..errors import ProblemError
from ..idempotency import IDEMPOTENCY_PROBLEMS, IdempotencyKeyHeader, IdempotentRoute
from ..jobs import JobTokenHeader, answer, caller, job_document, own_job
from ..responses import accepted_entry, body_limit, json_response, negotiate, problems, result_form
from ..schemas import BatchRequest, BatchResult, JobPage, JobStatus
from ..security import ReadAccess

router = APIRouter(prefix="/v1", tags=["batches and jobs"], route_class=IdempotentRoute)

JobId = Annotated[str, Path(description="Job id from the Location header of a 202 answer.",
                            examples=["j-0123456789abcdef0123456789abcdef"])]
PreferHeader = Annotated[str | None, Header(description="respond-async: always answer 202 with a job.")]
ToolPointQuery = Annotated[str | None, Query(pattern=r"^[hlnp](,[hlnp]){0,3}$", description=(
    "Receptances to return in each result's tool_point, e.g. h (a third of the size); default h,l,n,p."))]
ResultAccept = Annotated[str | None, Header(alias="accept", description=(
    "The result's form: application/json (default), application/x-hdf5 or application/vnd.apache.parquet "
    "(the server needs the extra rcsa[parquet]); the same numbers to the last bit. A job writes the form asked "
    "for when it was submitted."))]
#: OpenAPI ``content`` of a result that may be binary.
BINARY_RESULT = {MEDIA_TYPES["hdf5"]: {"schema": {"type": "string", "format": "binary"}},
                 MEDIA_TYPES["parquet"]: {"schema": {"type": "string", "format": "binary"}}}


@router.post("/tool-point-frf/batch", dependencies=[Depends(require_json)], response_model=BatchResult,
             openapi_extra=body_limit("batch"), responses={
    200: {"description": "The results (BatchResult), or the same as HDF5 or Parquet (Accept).", "content": BINARY_RESULT},
    **accepted_entry("Queued as a job; poll Location."), **problems(401, 406, 413, 415, 422),
    **problems(429), **IDEMPOTENCY_PROBLEMS}, summary="Tool-point FRFs of many combinations")
def predict_batch(body: BatchRequest, request: Request, state: StateDep, who: ReadAccess, prefer: PreferHeader = None,
                  tool_point: ToolPointQuery = None, idempotency_key: IdempotencyKeyHeader = None,
                  accept: ResultAccept = None) -> Response:
    """One result per combination, in input order, each with its own ``status``.

    The spindle (and each distinct spindle + holder) is condensed once and reused. A bad
    combination gets ``status: error`` with the offending field and never fails the others.
    With ``Idempotency-Key``, a retry gets the first answer (the same job, for a large batch).
    """
    fmt = result_form(accept)
    batch, refused = body.to_request()
    work = prepare_batch(state.bench, batch, refused, tool_point.split(",") if tool_point else None, fmt)
    return answer(state, work, prefer=prefer, idempotency_key=idempotency_key, owner=caller(who, request),
                  result_format=fmt)


@router.get("/jobs", response_model=JobPage, responses=problems(401, 422), summary="List your jobs")
def list_jobs(request: Request, state: StateDep, who: ReadAccess, _token: JobTokenHeader = None,
              limit: Annotated[int, Query(ge=1, le=1000, description="Items per page.")] = 100,
              cursor: Annotated[str | None, Query(max_length=1000, description="next_cursor of the previous page.")]
              = None) -> Response:
    """Your jobs, newest first, a page at a time (``limit`` + ``cursor``): those of your API key,
    or — anonymous — those of your ``X-Job-Token`` (none without one). Nobody else's."""
    mine = caller(who, request, new_token=False)
    jobs, next_cursor = state.jobs.page(mine.access, limit=limit, cursor=cursor) if mine.token or who.scope \
        else ([], None)
    return json_response({"items": [job_document(j) for j in jobs], "next_cursor": next_cursor})


@router.get("/jobs/{job_id}", response_model=JobStatus, responses=problems(401, 404), summary="Job status")
def get_job(job_id: JobId, request: Request, state: StateDep, who: ReadAccess, _token: JobTokenHeader = None
            ) -> Response:
    """Status and progress of one of your jobs; ``result_url`` once it has succeeded (``404``
    for a job that is not yours)."""
    job = own_job(state, job_id, who, request)
    headers = {} if job.finished else {"Retry-After": str(state.settings.retry_after_s)}
    return json_response(job_document(job), headers=headers)


@router.get("/jobs/{job_id}/result", response_class=FileResponse, responses={
    200: {"description": "The job's result: a batch result (BatchResult) or a library result (LibraryResult), "
                         "or the same as HDF5 or Parquet when the job was submitted with that Accept.",
          "content": {"application/json": {"schema": {"oneOf": [{"$ref": "#/components/schemas/BatchResult"},
                                                                {"$ref": "#/components/schemas/LibraryResult"}]}},
                      **BINARY_RESULT}},
    **problems(401, 404, 406, 409, 410)}, summary="Result of a finished job")
def get_job_result(job_id: JobId, request: Request, state: StateDep, who: ReadAccess, _token: JobTokenHeader = None,
                   accept: Annotated[str | None, Header(description=(
                       "Any Accept that allows the form the job wrote (the Accept of the POST that started it: "
                       "JSON, HDF5 or Parquet); 406 otherwise."))] = None) -> Response:
    """The result document of a succeeded job (``409`` while it runs or when it failed; ``410``
    once it was deleted to keep the kept results within their disk budget).

    The file is sent in pieces as it is read (and ranges of it on request), never loaded whole,
    in the form the job was asked for when it was submitted (JSON unless its POST's ``Accept``
    named HDF5 or Parquet).
    """
    job = own_job(state, job_id, who, request)
    if job.status == "succeeded" and job.result_evicted_utc is not None:
        raise ProblemError(410, f"the result of job {job_id} was deleted on {job.result_evicted_utc} to keep the kept "
                                "job results within their disk budget (oldest first); submit the job again",
                           slug="job-result-evicted", title="Job result deleted", extra={"job": job_document(job)})
    if job.status == "succeeded":
        written = state.jobs.request(job_id).get(RESULT_FORMAT_FIELD, "json") if job.kind in ("batch", "library") \
            else "json"
        media = MEDIA_TYPES[written]
        negotiate(accept, (media,), f"the result of job {job_id} (written as asked when it was submitted)")
        suffix = {"hdf5": ".h5", "parquet": ".parquet"}.get(written)
        return FileResponse(state.jobs.result_path(job_id), media_type=media,
                            filename=f"{job_id}{suffix}" if suffix else None)
    if job.status == "failed":
        error = job.error or {}
        raise ProblemError(409, f"job {job_id} failed: {error.get('detail', 'see its status')}", slug="job-failed",
                           title="Job failed", errors=error.get("errors"), extra={"job": job_document(job)})
    raise ProblemError(409, f"job {job_id} is {job.status} ({job.progress:.0%} done); poll /v1/jobs/{job_id}",
                       slug="job-not-finished", title="Job not finished",
                       headers={"Retry-After": str(state.settings.retry_after_s), "Location": f"/v1/jobs/{job_id}"})
