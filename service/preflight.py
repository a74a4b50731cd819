"""The service's start-up, tried once before any worker starts: ``python -m service.preflight``.

A uvicorn with several workers whose workers fail at start-up stops, but exits 0 (uvicorn
0.54: the supervisor returns normally), so a container or a process manager would not know.
``rcsa serve`` and the Docker image therefore run this first: the settings are read from the
``RCSA_*`` environment, the app's own start-up runs once (the store opened or created, the
job table, a Dask scheduler reached when one is configured), ``/readyz`` is asked (the store
takes a write, the job table answers), and everything is shut down again. Exit status 0 when
the service can start; 1 with one line naming the problem otherwise.
"""

from __future__ import annotations

import asyncio
import json
import sys
from typing import Any

from pydantic import ValidationError

from .config import Settings
from .main import create_app

__all__ = ["check", "main"]


class StartupError(RuntimeError):
    """The service cannot start here; the message says why."""


def check(settings: Settings | None = None) -> None:
    """Start the app once, ask ``/readyz``, stop it.

    Parameters
    ----------
    settings : Settings, optional
        Default: read from the ``RCSA_*`` environment.

    Raises
    ------
    StartupError
        A setting is invalid, the start-up failed (store, job table, Dask scheduler) or the
        started app is not ready; the message names the setting or the failed check.
    """
    try:
        settings = settings if settings is not None else Settings()
    except ValidationError as exc:
        raise StartupError("invalid setting: " + "; ".join(_setting_error(e) for e in exc.errors())) from exc
    app = create_app(settings)
    try:
        status, body = asyncio.run(_start_and_ask_ready(app))
    except StartupError:
        raise
    except Exception as exc:  # whatever stops the start-up is reported, with its type
        raise StartupError(f"start-up failed: {type(exc).__name__}: {exc}") from exc
    if status != 200:
        raise StartupError(f"not ready (/readyz {status}): {body}")


def _setting_error(error: Any) -> str:
    name = "RCSA_" + "_".join(str(part) for part in error["loc"]).upper()
    return f"{name}: {error['msg']}"


async def _start_and_ask_ready(app: Any) -> tuple[int, str]:
    async with app.router.lifespan_context(app):
        return await _get(app, "/readyz")


async def _get(app: Any, path: str) -> tuple[int, str]:
    """One GET through the ASGI interface (no server, no socket): ``(status, body)``."""
    scope = {"type": "http", "asgi": {"version": "3.0"}, "http_version": "1.1", "method": "GET",
             "scheme": "http", "path": path, "raw_path": path.encode(), "query_string": b"",
             "root_path": "", "headers": [(b"host", b"preflight")], "client": ("127.0.0.1", 0),
             "server": ("preflight", 80), "state": {}}
    sent: dict[str, Any] = {"status": 0, "body": b""}

    async def receive() -> dict[str, Any]:
        return {"type": "http.request", "body": b"", "more_body": False}

    async def send(message: dict[str, Any]) -> None:
        if message["type"] == "http.response.start":
            sent["status"] = message["status"]
        elif message["type"] == "http.response.body":
            sent["body"] += message.get("body", b"")

    await app(scope, receive, send)
    body = sent["body"].decode(errors="replace")
    try:
        body = json.dumps(json.loads(body).get("checks", body))
    except (ValueError, AttributeError):
        pass
    return sent["status"], body


def main() -> int:
    """Run :func:`check` on the environment's settings; ``0`` if the service can start, else ``1``.

    Returns
    -------
    int
        The exit status.
    """
    try:
        check()
    except StartupError as exc:
        sys.stderr.write(f"rcsa: the service cannot start: {exc}\n")
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
