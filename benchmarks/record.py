"""What a benchmark writes: its figures in ``benchmarks/results/NAME.json``, with the machine and its load.

Every published figure comes from such a file (``scripts/render_figures.py`` renders the
documents' numbers from them; ``tests/test_figures_rendered.py`` fails when a document and its
JSON disagree). A record holds the benchmark's own figures under ``figures`` and, beside them,
what they were measured on: the CPU, the cores, Python and numpy, the load average when the run
started and ended (the VM is shared: say the load honestly), the git commit and the command.
"""

from __future__ import annotations

import datetime
import json
import os
import platform
import subprocess
import sys
from pathlib import Path
from typing import Any

import numpy as np

RESULTS = Path(__file__).resolve().parent / "results"


def machine() -> dict[str, Any]:
    """The CPU model, its cores, memory, Python and numpy (what the figures were measured on)."""
    model = "unknown CPU"
    memory_gb = None
    try:
        model = next(line.split(":", 1)[1].strip() for line in Path("/proc/cpuinfo").read_text().splitlines()
                     if line.startswith("model name"))
        kb = next(int(line.split()[1]) for line in Path("/proc/meminfo").read_text().splitlines()
                  if line.startswith("MemTotal"))
        memory_gb = round(kb / 2**20, 1)
    except (OSError, StopIteration, ValueError):
        pass
    return {"cpu": model, "cores": os.cpu_count(), "memory_gb": memory_gb, "python": platform.python_version(),
            "numpy": np.__version__, "platform": platform.platform()}


def load_average() -> list[float]:
    """The 1, 5 and 15-minute load averages now."""
    return [round(x, 2) for x in os.getloadavg()]


def _commit() -> str | None:
    try:
        out = subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True, text=True, check=True,
                             cwd=Path(__file__).resolve().parent)
        dirty = subprocess.run(["git", "status", "--porcelain", "--untracked-files=no"], capture_output=True,
                               text=True, check=True, cwd=Path(__file__).resolve().parent).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        return None
    return out.stdout.strip() + ("+changes" if dirty else "")


def record(figures: dict[str, Any], *, load_start: list[float]) -> dict[str, Any]:
    """The JSON record of a run: ``figures`` and what they were measured on."""
    return {"figures": figures, "machine": machine(), "load_average_start": load_start,
            "load_average_end": load_average(), "commit": _commit(),
            "command": " ".join([Path(sys.argv[0]).as_posix(), *sys.argv[1:]]) if sys.argv[0] else "",
            "written_utc": datetime.datetime.now(datetime.UTC).strftime("%Y-%m-%dT%H:%M:%SZ")}


def write(name: str, figures: dict[str, Any], *, load_start: list[float], out: Path | None = None) -> Path:
    """Write ``figures`` as ``benchmarks/results/NAME.json`` (or ``out``) and say where on stderr."""
    path = out or RESULTS / f"{name}.json"
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(record(figures, load_start=load_start), indent=1, sort_keys=False) + "\n")
    print(f"figures written to {path}", file=sys.stderr)
    return path
