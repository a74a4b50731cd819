"""``rcsa serve [--host HOST] [--port PORT] [--workers N] [--dask-scheduler tcp://HOST:8786]``.

The connection limits of the server (uvicorn's) are options with environment defaults, so that
the Docker image sets them by ``RCSA_*`` variables: ``--limit-concurrency`` (connections and
requests in flight per worker; beyond, a request is answered 503 at once),
``--timeout-keep-alive`` (an idle keep-alive connection is closed) and the largest request head
(``--max-head-bytes``: request line and headers, h11's ``max_incomplete_event_size``; beyond, 400).
The head's and the body's read timeouts are the service's own settings
(``RCSA_HEADER_TIMEOUT_S``, ``RCSA_BODY_TIMEOUT_S``, ``RCSA_BODY_MIN_RATE_BYTES_S``).
"""

from __future__ import annotations

import os
import subprocess
import sys
import tempfile
from typing import Annotated

import typer


def register(app: typer.Typer) -> None:
    """Add the ``serve`` command to ``app``."""

    @app.command(short_help="Run the REST service and its web view.")
    def serve(
        host: Annotated[str, typer.Option(help="Interface to bind.")] = "127.0.0.1",
        port: Annotated[int, typer.Option(help="TCP port.")] = 8000,
        workers: Annotated[int, typer.Option(help="Worker processes (all share one store safely).")] = 1,
        dask_scheduler: Annotated[str | None, typer.Option(
            help="Run batch, library and sync jobs on this Dask cluster (tcp://HOST:8786; needs "
                 "pip install 'rcsa[dask]'). Default: RCSA_DASK_SCHEDULER, else in the service.")] = None,
        limit_concurrency: Annotated[int, typer.Option(
            min=1, envvar="RCSA_LIMIT_CONCURRENCY",
            help="Connections and requests in flight per worker; beyond, a request is answered 503 at once.")] = 100,
        timeout_keep_alive: Annotated[int, typer.Option(
            min=1, envvar="RCSA_TIMEOUT_KEEP_ALIVE_S",
            help="Seconds an idle keep-alive connection is kept open.")] = 5,
        max_head_bytes: Annotated[int, typer.Option(
            min=1024, envvar="RCSA_MAX_HEAD_BYTES",
            help="Largest request head (request line and headers), bytes; beyond, 400.")] = 16384,
    ) -> None:
        """Run the REST service (uvicorn) with the store from RCSA_STORE or the default location.

        The settings, the store and the Dask scheduler are checked once first (the service's
        own start-up, python -m service.preflight): a service that cannot start exits 1 with
        the reason instead of leaving its workers to fail (uvicorn then exits 0).
        """
        if dask_scheduler:
            os.environ["RCSA_DASK_SCHEDULER"] = dask_scheduler  # read by every worker process's settings
        # its request must not count in the workers' shared metrics
        env = {k: v for k, v in os.environ.items() if k != "PROMETHEUS_MULTIPROC_DIR"}
        if subprocess.run([sys.executable, "-m", "service.preflight"], env=env, check=False).returncode:
            raise typer.Exit(1)
        # uvicorn: only for this command (``rcsa --help`` and the others do without it)
        import uvicorn

        if workers > 1 and not os.environ.get("PROMETHEUS_MULTIPROC_DIR"):
            # one /metrics over all worker processes (prometheus-client multi-process mode)
            os.environ["PROMETHEUS_MULTIPROC_DIR"] = tempfile.mkdtemp(prefix="rcsa-metrics-")

        # service.http: uvicorn's HTTP protocol with TCP_NODELAY on every connection (a multi-worker
        # uvicorn leaves Nagle on: ~40 ms per small response on a keep-alive connection)
        uvicorn.run("service.main:create_app", factory=True, host=host, port=port, workers=workers,
                    http="service.http:NoDelayHTTPProtocol", log_level="info", limit_concurrency=limit_concurrency,
                    timeout_keep_alive=timeout_keep_alive, h11_max_incomplete_event_size=max_head_bytes)
