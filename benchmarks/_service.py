"""What the service benchmarks share: a real ``rcsa serve --workers N`` on loopback, its worker
processes and their memory (the records are written by ``record.write``).

``start_service`` runs the command a user runs (``rcsa serve``: preflight, then uvicorn with the
service's HTTP protocol, its connection limits and timeouts) on a free port with a temporary
store and the given keys; ``workers(proc)`` are the uvicorn worker processes (children of the
serving process, which is uvicorn's supervisor and respawns a worker that dies), and
``memory_mb(pid)`` reads a worker's resident memory now (``VmRSS``) and at its peak (``VmHWM``)
from ``/proc`` (Linux).
"""

from __future__ import annotations

import os
import signal
import socket
import subprocess
import sys
import time
from collections.abc import Mapping
from pathlib import Path

import httpx

REPO = Path(__file__).resolve().parents[1]


def rcsa(store: Path, *args: str) -> subprocess.CompletedProcess:
    """Run the CLI ``rcsa ARGS`` on the store ``store`` (as an operator would), output captured."""
    return subprocess.run([sys.executable, "-c", "from rcsa.cli import main; main()", *args], cwd=REPO,
                          env={**os.environ, "RCSA_STORE": str(store)}, capture_output=True, text=True)


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def start_service(tmp: Path, *, workers: int = 2, env: Mapping[str, str] | None = None,
                  args: tuple[str, ...] = ()) -> tuple[subprocess.Popen, str, Path]:
    """``rcsa serve --workers N`` on a free port with the store ``tmp/store``: the process, its base
    URL and its log, once ``/readyz`` answers and every worker has started."""
    port = free_port()
    prom = tmp / "prom"
    prom.mkdir(exist_ok=True)
    full = {**os.environ, "RCSA_STORE": str(tmp / "store"), "RCSA_SEED_DEMO": "false", "RCSA_ACCESS_LOG": "false",
            "PROMETHEUS_MULTIPROC_DIR": str(prom), **(env or {})}
    log = tmp / "service.log"
    with log.open("w") as out:
        proc = subprocess.Popen([sys.executable, "-c", "from rcsa.cli import main; main()", "serve", "--host",
                                 "127.0.0.1", "--port", str(port), "--workers", str(workers), *args],
                                cwd=REPO, env=full, stdout=out, stderr=subprocess.STDOUT)
    base = f"http://127.0.0.1:{port}"
    for _ in range(1200):
        if proc.poll() is not None:
            raise SystemExit("rcsa serve exited:\n" + log.read_text())
        try:
            if httpx.get(base + "/readyz", timeout=5).status_code == 200 and \
                    log.read_text().count("Application startup complete.") >= workers:
                return proc, base, log
        except httpx.TransportError:
            pass
        time.sleep(0.25)
    proc.kill()
    raise SystemExit("rcsa serve did not become ready:\n" + log.read_text())


def stop_service(proc: subprocess.Popen) -> int:
    """SIGINT, then SIGKILL after a minute; the exit status."""
    proc.send_signal(signal.SIGINT)
    try:
        return proc.wait(timeout=60)
    except subprocess.TimeoutExpired:
        proc.kill()
        return proc.wait()


def workers(proc: subprocess.Popen) -> list[int]:
    """Pids of the worker processes of a serving ``rcsa serve`` (its children that run uvicorn)."""
    found = []
    for entry in Path("/proc").iterdir():
        if not entry.name.isdigit():
            continue
        try:
            status = (entry / "status").read_text()
        except OSError:
            continue
        fields = dict(line.split(":", 1) for line in status.splitlines() if ":" in line)
        if fields.get("PPid", "").strip() == str(proc.pid) and "VmRSS" in fields:
            cmdline = (entry / "cmdline").read_bytes()
            if b"spawn_main" in cmdline:  # not the resource tracker
                found.append(int(entry.name))
    return sorted(found)


def memory_mb(pid: int) -> dict[str, float]:
    """``{"rss_mb", "peak_rss_mb"}`` of a process now (empty when it is gone)."""
    try:
        status = (Path("/proc") / str(pid) / "status").read_text()
    except OSError:
        return {}
    fields = dict(line.split(":", 1) for line in status.splitlines() if ":" in line)
    return {"rss_mb": int(fields["VmRSS"].split()[0]) / 1024, "peak_rss_mb": int(fields["VmHWM"].split()[0]) / 1024}
