"""Shared test helpers: relative tolerances and the receptance comparison.

Receptances span 1e-9 … 1e-3 in their units, so every comparison is relative, with an
absolute floor scaled to the magnitude of the expected data (never numpy's default atol).
"""

from __future__ import annotations

import os
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
#: The shared data beside the repository (CI's layout); ``RCSA_SHARED_DATA`` points elsewhere
#: (e.g. a work tree whose shared directory is not its sibling). Never copied into the repo.
SHARED_DATA = Path(os.environ.get("RCSA_SHARED_DATA") or REPO.parent / "shared" / "data")


def manual_pages() -> list[Path]:
    """The manual's pages, ``docs/*.md``, in the order of ``mkdocs.yml``'s ``nav`` (reading order)."""
    import yaml

    def walk(node: object) -> list[str]:
        if isinstance(node, str):
            return [node]
        if isinstance(node, dict):
            return [page for value in node.values() for page in walk(value)]
        if isinstance(node, list):
            return [page for item in node for page in walk(item)]
        return []

    config = yaml.safe_load((REPO / "mkdocs.yml").read_text(encoding="utf-8"))
    return [REPO / config.get("docs_dir", "docs") / page for page in walk(config["nav"])]


#: algebraic identities evaluated in double precision (a few hundred flops per entry)
RTOL_ALGEBRA = 1e-10
#: golden values regenerated from this implementation
RTOL_GOLDEN = 1e-8


def assert_receptance_close(actual: np.ndarray, expected: np.ndarray, rtol: float,
                            atol_scale: float = 1e-12, err_msg: str = "") -> None:
    """``|actual − expected| <= rtol·|expected| + atol_scale·max|expected|`` elementwise."""
    expected = np.asarray(expected)
    atol = atol_scale * float(np.max(np.abs(expected)))
    np.testing.assert_allclose(actual, expected, rtol=rtol, atol=atol, err_msg=err_msg)


def max_error_of_peak(actual: np.ndarray, expected: np.ndarray) -> float:
    """``max|actual − expected| / max|expected|`` — the error measure of ``docs/physics.md`` §4.6."""
    return float(np.max(np.abs(np.asarray(actual) - expected)) / np.max(np.abs(expected)))


#: how many times the log of a starting uvicorn is read, 0.1 s apart, for the port it bound
BIND_ATTEMPTS = 1200


def stop_uvicorn(proc: subprocess.Popen) -> None:
    """SIGINT a server started by :func:`start_uvicorn`, and SIGKILL it if it is not gone in a minute."""
    proc.send_signal(signal.SIGINT)
    try:
        proc.wait(timeout=60)
    except subprocess.TimeoutExpired:
        proc.kill()


def start_uvicorn(args: list[str], env: dict[str, str], log_path: Path,
                  workers: int = 1) -> tuple[subprocess.Popen, str]:
    """Start ``python -m uvicorn ARGS --host 127.0.0.1 --port 0``: the process and its base URL,
    once all ``workers`` have logged "Application startup complete.".

    Port 0 lets the kernel pick a free port at the moment uvicorn binds it, and the port is
    read back from uvicorn's "Uvicorn running on" line. A port chosen in advance (bound,
    closed, then handed to the server) can be taken in between by any process on a shared
    machine — another suite's server, whose ``/readyz`` then answers for ours while ours
    failed to bind. Counts attempts, not seconds; fails with the log if uvicorn exits first.
    """
    with log_path.open("w") as log:
        proc = subprocess.Popen([sys.executable, "-m", "uvicorn", *args, "--host", "127.0.0.1", "--port", "0"],
                                cwd=REPO, env=env, stdout=log, stderr=subprocess.STDOUT)
    for _ in range(BIND_ATTEMPTS):
        text = log_path.read_text()
        found = re.search(r"Uvicorn running on http://127\.0\.0\.1:(\d+)", text)
        if found and text.count("Application startup complete.") >= workers:
            return proc, f"http://127.0.0.1:{found.group(1)}"
        if proc.poll() is not None:
            break
        time.sleep(0.1)
    proc.kill()
    proc.wait()
    raise AssertionError("uvicorn did not bind a port:\n" + log_path.read_text())
