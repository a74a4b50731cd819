"""The REST service: ``create_app(settings=None)`` builds the FastAPI application.

Run it with ``rcsa serve`` (uvicorn, ``service.main:create_app --factory``), or
``uvicorn --factory service.main:create_app --workers 2``: every process opens the same
store safely (immutable measurement files under a write lock, SQLite in WAL mode for the
catalogue and the jobs), seeds a fresh store once with the demo measurement, and runs a
job-runner thread that claims queued jobs atomically.
"""

from __future__ import annotations

import logging
import threading
from collections.abc import AsyncIterator
from contextlib import asynccontextmanager
from typing import Any

from fastapi import FastAPI
from fastapi.concurrency import run_in_threadpool
from fastapi.openapi.utils import get_openapi
from pydantic.json_schema import models_json_schema
from starlette.middleware.gzip import GZipMiddleware

from rcsa._version import __version__
from rcsa.app.jobs import Workbench, analysis_job_handlers, job_handlers, job_store
from rcsa.app.keys import key_ring
from rcsa.app.measurements import seed_demo
from rcsa.app.presets import recommend_job_handlers
from rcsa.app.stores import CachedMeasurements, open_store
from rcsa.errors import RcsaError
from rcsa.infra.compute_backends import compute_backend
from rcsa.infra.job_queue import Job, JobRunner

from . import schemas
from .config import Settings
from .errors import install_error_handlers
from .jobs import present
from .metrics import Metrics
from .middleware import RequestContextMiddleware, configure_logging
from .openapi_doc import (
    document_job_token,
    mark_anonymous_operations,
    operation_id,
    write_operations,
)
from .routes import ROUTERS
from .state import AppState, ensure_state

__all__ = ["create_app"]

log = logging.getLogger("service")

DESCRIPTION = """\
Tool-point FRFs of machine-tool spindle–holder–tool assemblies by exact Timoshenko receptance
coupling, on modelled or measured (hybrid) spindles; batches, Fusion tool libraries, stored
measurements and stability lobes.

* SI units on the wire; every numeric field name ends in its unit (`_m`, `_hz`, `_n_m`, ...).
  Complex arrays are `{"real": [...], "imag": [...]}`.
* Errors are `application/problem+json` (RFC 9457) with a `detail` to act on and `errors[]`
  naming each offending field.
* Auth: header `X-API-Key`. Every operation that changes the store needs a key with scope
  `write` (created on the server with `rcsa keys create --scope write`): {writes}. Reads and
  computations are anonymous unless `RCSA_ANONYMOUS_READ=false`.
* Jobs are private: readable only with the API key that started them, or — anonymous — with the
  job token of their `202` (`X-Job-Token`); `404` for anyone else. `GET /v1/jobs` lists yours.
* Large batches and libraries answer `202 Accepted` with `Location: /v1/jobs/{id}`; poll it,
  then GET its `result_url`. `Prefer: respond-async` always makes a job.
* POSTs that store or start something (measurement uploads, batches, libraries) accept an
  `Idempotency-Key`: a retry with the same key and request gets the first answer again
  (same status and body); the same key with another request is a 422; a retry while the
  first is still running (or its job is) is a 409 with `Retry-After`.
* Stored libraries: `POST /v1/libraries/{id}:sync` computes only new or changed tools and
  reports `added`, `changed`, `unchanged`, `removed` tool ids; `GET /v1/libraries/{id}/results`
  gives the results again as JSON, HDF5, Parquet or a zip of UFF 58 files.
* Batch and library results may be asked for as HDF5 (`Accept: application/x-hdf5`) or Apache
  Parquet (`Accept: application/vnd.apache.parquet`, when the server has `rcsa[parquet]`): the
  same numbers as the JSON to the last bit.
* Every response carries `X-Request-ID` (yours if you sent one).
"""

#: Models used by routes that read their body themselves (documented via openapi_extra).
_EXTRA_MODELS = (schemas.Problem, schemas.MeasurementUpload, schemas.LibraryPredictionRequest,
                 schemas.BatchResult, schemas.LibraryResult)


def _startup(settings: Settings, metrics: Metrics) -> AppState:
    """Open the store (creating it), seed it once, and start the job runners."""
    store = open_store(settings.store)
    if settings.seed_demo:
        try:
            seeded = seed_demo(store)
            if seeded:
                log.info("seeded the empty store %s with the demo measurement %s (spindle demo-ra1)",
                         store.path, seeded)
        except (RcsaError, OSError) as exc:
            log.warning("could not seed the store with the demo measurement: %s", exc)
    keys = key_ring(store.path, settings.api_keys.get_secret_value())
    jobs = job_store(store.path, stale_after_s=settings.job_stale_s, max_attempts=settings.job_max_attempts,
                     max_result_bytes=settings.job_results_max_bytes or None)
    purged = jobs.purge(settings.job_retention_s)  # and hourly by the runners
    if purged:
        log.info("purged %d finished jobs older than %g s", purged, settings.job_retention_s)
    if settings.job_results_max_bytes:  # a budget lowered since the last start applies at once
        jobs.evict(settings.job_results_max_bytes)
    reader = CachedMeasurements(store, settings.measurement_cache)
    # a Dask scheduler that cannot be reached stops the start-up with its address and reason
    backend = compute_backend(settings.dask_scheduler, connect_timeout_s=settings.dask_connect_timeout_s,
                              retries=settings.dask_retries)
    bench = Workbench(reader, store.path, max_lines=settings.max_frequency_lines,
                      max_combinations=settings.max_batch_combinations, observer=metrics, backend=backend)
    state = AppState(settings=settings, store=store, reader=reader, keys=keys, jobs=jobs, metrics=metrics,
                     bench=bench, runners=[])

    def finished(job: Job, seconds: float) -> None:
        metrics.jobs.labels(job.kind, job.status).inc()

    table = {**job_handlers(bench, present), **analysis_job_handlers(bench), **recommend_job_handlers(bench)}
    for _ in range(settings.job_workers):
        runner = JobRunner(jobs, table, poll_s=settings.job_poll_s, heartbeat_s=settings.job_heartbeat_s,
                           on_finish=finished, retention_s=settings.job_retention_s,
                           time_limit_s=settings.job_time_limit_s,
                           max_running_per_owner=settings.job_max_running_per_caller or None)
        runner.start()
        state.runners.append(runner)
    if not keys.configured:
        log.info("no API keys configured: writes are refused until one is created (rcsa keys create --scope write)")
    return state


def create_app(settings: Settings | None = None) -> FastAPI:
    """Build the service.

    Parameters
    ----------
    settings : Settings, optional
        Default: read from ``RCSA_*`` environment variables.

    Returns
    -------
    fastapi.FastAPI
    """
    settings = settings if settings is not None else Settings()
    metrics = Metrics()
    configure_logging(settings.access_log)

    @asynccontextmanager
    async def lifespan(app: FastAPI) -> AsyncIterator[None]:
        state = await run_in_threadpool(ensure_state, app)
        try:
            yield
        finally:
            for runner in state.runners:
                await run_in_threadpool(runner.stop, 30.0)
            await run_in_threadpool(state.bench.backend.close)

    app = FastAPI(title="rcsa — tool-point FRF service", version=__version__, description=DESCRIPTION,
                  lifespan=lifespan, separate_input_output_schemas=False, generate_unique_id_function=operation_id,
                  # /docs and /redoc with local assets (service.routes.docs): they work offline
                  docs_url=None, redoc_url=None)
    # the state is built by the lifespan, or on the first request when the app is served
    # without one (e.g. a TestClient used outside a ``with`` block)
    app.state.rcsa_factory = lambda: _startup(settings, metrics)
    app.state.rcsa_lock = threading.Lock()
    install_error_handlers(app)
    for router in ROUTERS:
        app.include_router(router)
    app.add_middleware(GZipMiddleware, minimum_size=settings.gzip_min_bytes, compresslevel=settings.gzip_level)
    app.add_middleware(RequestContextMiddleware, metrics=metrics, max_body_bytes=settings.max_body_bytes,
                       access=settings.access_log, body_timeout_s=settings.body_timeout_s,
                       body_min_rate_bytes_s=settings.body_min_rate_bytes_s)

    def openapi() -> dict[str, Any]:
        if app.openapi_schema is None:
            writes = ", ".join(f"`{w}`" for w in write_operations(app.routes))
            doc = get_openapi(title=app.title, version=app.version, description=app.description.replace("{writes}", writes),
                              routes=app.routes, separate_input_output_schemas=False)
            _, defs = models_json_schema([(m, "validation") for m in _EXTRA_MODELS],
                                         ref_template="#/components/schemas/{model}")
            components = doc.setdefault("components", {}).setdefault("schemas", {})
            for name, schema in defs.get("$defs", {}).items():
                components.setdefault(name, schema)
            mark_anonymous_operations(doc, app.routes, settings.anonymous_read)
            document_job_token(doc)
            app.openapi_schema = doc
        return app.openapi_schema

    app.openapi = openapi  # type: ignore[method-assign]
    return app


def __getattr__(name: str) -> Any:
    """``service.main.app``: an app built from the environment on first access (PEP 562).

    ``uvicorn service.main:app`` works as well as the factory form.
    """
    if name == "app":
        globals()["app"] = built = create_app()
        return built
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
