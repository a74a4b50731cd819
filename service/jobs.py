"""Service side of background jobs: the handlers, and the 202 / status answers.

The durable job store and the runner live in :mod:`rcsa.infra.job_queue` (SQLite in the store
directory, atomic claims, heartbeats, resume after a restart). Here: what a ``batch`` and a
``library`` job compute (the same :mod:`rcsa` calls as the synchronous routes), and how a
job is shown over HTTP.
"""

from __future__ import annotations

from typing import Any

from starlette.responses import Response

from rcsa.app import libraries as library_api
from rcsa.infra.job_queue import Handler, Job

from .responses import json_response
from .state import AppState

__all__ = ["accepted", "handlers", "job_document", "wants_async"]


def handlers(state: AppState) -> dict[str, Handler]:
    """The job kinds this service runs: ``batch`` and ``library``."""
    s, m = state.settings, state.metrics

    def batch(request: dict[str, Any], progress: Any) -> tuple[Any, dict[str, Any]]:
        with m.timed("batch"):
            out = library_api.run_entries(request, store=state.reader, max_lines=s.max_frequency_lines,
                                          max_combinations=s.max_batch_combinations, progress=progress,
                                          arrays="numpy")
        m.frfs.labels("batch").inc(out["summary"]["ok"])
        return out, out["summary"]

    def library(request: dict[str, Any], progress: Any) -> tuple[Any, dict[str, Any]]:
        with m.timed("library"):
            out = library_api.run_library_request(request, store=state.reader, max_lines=s.max_frequency_lines,
                                                  max_combinations=s.max_batch_combinations,
                                                  progress=progress, arrays="numpy")
        m.frfs.labels("library").inc(out["summary"]["ok"])
        return out, out["summary"]

    return {"batch": batch, "library": library}


def job_document(job: Job) -> dict[str, Any]:
    """The public JSON of a job, with its status and result URLs."""
    return {**job.to_dict(), "status_url": f"/v1/jobs/{job.id}",
            "result_url": f"/v1/jobs/{job.id}/result" if job.status == "succeeded" else None}


def wants_async(prefer: str | None) -> bool:
    """Whether a ``Prefer`` header (RFC 7240) asks for ``respond-async``."""
    return any(p.split(";")[0].strip().lower() == "respond-async" for p in (prefer or "").split(","))


def accepted(state: AppState, job: Job, *, preference_applied: bool) -> Response:
    """``202 Accepted`` with ``Location`` (the job) and ``Retry-After``."""
    headers = {"Location": f"/v1/jobs/{job.id}", "Retry-After": str(state.settings.retry_after_s)}
    if preference_applied:
        headers["Preference-Applied"] = "respond-async"
    for runner in state.runners:
        runner.wake()
    return json_response(job_document(job), status_code=202, headers=headers)
