"""Operations endpoints: ``/healthz`` (alive), ``/readyz`` (store writable, jobs, compute cluster), ``/metrics``."""

from __future__ import annotations

import contextlib
import os
import secrets
from pathlib import Path

from fastapi import APIRouter
from starlette.responses import Response

from ..deps import StateDep
from ..metrics import CONTENT_TYPE_LATEST
from ..responses import json_response
from ..routing import ServiceRoute
from ..schemas import Health, Ready

router = APIRouter(tags=["operations"], route_class=ServiceRoute)


@router.get("/healthz", response_model=Health, summary="Liveness")
def get_health() -> Response:
    """The process answers (nothing else is checked)."""
    return json_response({"status": "ok"})


@router.get("/readyz", response_model=Ready, summary="Readiness",
            responses={503: {"model": Ready, "description": "Not ready (see checks)."}})
def get_readiness(state: StateDep) -> Response:
    """Ready when the store accepts a write (a probe file written and deleted), the job table
    answers, this process's job runners are alive and the compute backend can compute (a
    configured Dask scheduler answers and has a worker); ``503`` otherwise, each check saying
    why."""
    checks = {"store": _probe_store(Path(state.store.path))}
    try:
        state.jobs.counts()
        checks["jobs"] = "ok"
    except Exception as exc:  # any failure of the job table means not ready
        checks["jobs"] = f"error: {type(exc).__name__}"
    if state.settings.job_workers:
        alive = all(r.alive for r in state.runners) and bool(state.runners)
        checks["job_runner"] = "ok" if alive else "error: job runner thread stopped"
    backend = state.bench.backend
    if getattr(backend, "name", "local") != "local":
        checks["compute"] = backend.ready(timeout_s=min(2.0, state.settings.dask_connect_timeout_s))
    ready = all(v == "ok" for v in checks.values())
    return json_response({"status": "ready" if ready else "not ready", "checks": checks},
                         status_code=200 if ready else 503)


def _probe_store(root: Path) -> str:
    probe = root / f".readyz-{os.getpid()}-{secrets.token_hex(4)}"
    try:
        with open(probe, "wb") as fh:
            fh.write(b"ok")
            fh.flush()
            os.fsync(fh.fileno())
        probe.unlink()
        return "ok"
    except OSError as exc:
        with contextlib.suppress(OSError):
            probe.unlink()
        return f"error: store not writable ({exc.strerror or exc})"


@router.get("/metrics", summary="Prometheus metrics", response_class=Response,
            responses={200: {"content": {CONTENT_TYPE_LATEST: {"schema": {"type": "string"}}},
                             "description": "Prometheus text exposition."}})
def get_metrics(state: StateDep) -> Response:
    """Request counts and latencies by route and status, FRFs computed, compute seconds,
    imports and import failures by format, jobs finished (all processes in multi-process mode)."""
    return Response(state.metrics.exposition(), media_type=CONTENT_TYPE_LATEST)
