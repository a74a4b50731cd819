"""Dask backend benchmark: one library sync computed here, then on a LocalCluster of 2 workers.

Run: ``.venv/bin/python benchmarks/bench_dask.py [--tools 10000] [--frequency 2.5:5000:2.5]
[--workers 2]`` (needs ``pip install 'rcsa[dask]'``; takes minutes: it is a benchmark, not a
test). The library is :func:`bench_sync.synthetic_library` (distinct Fusion tools on RA-1's
analytical spindle), 2 000 lines by default. Each run syncs it into a fresh store:

* ``local``: the embedded path — chunks computed one after the other in this process;
* ``dask``: a ``distributed.LocalCluster`` (worker processes, one thread each, loopback):
  the chunks run on the workers, their results come back here and are written here.

Printed and written to ``benchmarks/results/dask.json``: wall and CPU time of each run, the
per-chunk cost (model time of a chunk here; task compute time on a worker from Dask's task
stream), what a chunk costs besides computing it (moving its results to the service, writing
them into the result cache: one transaction per chunk), the fixed costs (import, keys, plan,
commit, cluster start), and the expected time on N machines from these measurements. Both
runs must give bit-identical stored results (checked).

On this machine the workers share 2 cores with the service process (which receives and
writes ~1.4 GB of results) and with whatever else runs: the cluster cannot beat the local path
here. The point is the measured per-chunk cost and overheads, from which the scaling follows.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import statistics
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np
import orjson

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "benchmarks"))

from bench_sync import synthetic_library  # noqa: E402
from rcsa.cli.library_cmd import parse_frequency_option  # noqa: E402
from rcsa.infra.compute_backends import DaskBackend, LocalBackend  # noqa: E402
from rcsa.libraries import chunks  # noqa: E402
from rcsa.libraries import sync as library_sync  # noqa: E402
from rcsa.reference import ra1  # noqa: E402


class _Timed:
    """Records the time of every chunk computed in this process and of every cache write."""

    def __init__(self) -> None:
        self.compute: list[float] = []
        self.write: list[float] = []
        self._compute = library_sync.compute_chunk
        self._put_many = library_sync.ResultCache.put_many

    def __enter__(self) -> _Timed:
        timed = self

        def compute(batch: Any, **kwargs: Any) -> Any:
            t0 = time.perf_counter()
            out = timed._compute(batch, **kwargs)
            timed.compute.append(time.perf_counter() - t0)
            return out

        def put_many(cache: Any, items: Any) -> int:
            t0 = time.perf_counter()
            out = timed._put_many(cache, items)
            timed.write.append(time.perf_counter() - t0)
            return out

        library_sync.compute_chunk = compute  # type: ignore[assignment]
        library_sync.ResultCache.put_many = put_many  # type: ignore[method-assign]
        return self

    def __exit__(self, *exc: object) -> None:
        library_sync.compute_chunk = self._compute  # type: ignore[assignment]
        library_sync.ResultCache.put_many = self._put_many  # type: ignore[method-assign]


def _stats(values: list[float]) -> dict[str, float]:
    if not values:
        return {"n": 0}
    return {"n": len(values), "sum_s": sum(values), "mean_s": statistics.fmean(values),
            "p50_s": statistics.median(values), "max_s": max(values)}


def sync_once(directory: Path, library: bytes, settings: dict, backend: Any) -> dict[str, Any]:
    """One first sync into a fresh store, its phases timed."""
    libs = library_sync.LibraryStore(directory / "libraries")
    c0, t0 = time.process_time(), time.perf_counter()
    request = library_sync.sync_request("bench", library, **settings)
    t1 = time.perf_counter()
    plan = library_sync.plan_sync(libs, request)
    t2 = time.perf_counter()
    arrivals: list[float] = []
    with _Timed() as timed:
        report = library_sync.run_sync(libs, request, plan=plan, backend=backend,
                                       progress=lambda d, t: arrivals.append(time.perf_counter()))
    t3 = time.perf_counter()
    assert report.summary["ok"] == len(plan.keys), report.summary
    return {"wall_s": t3 - t0, "cpu_s": time.process_time() - c0, "import_s": t1 - t0, "plan_s": t2 - t1,
            "compute_and_write_s": t3 - t2, "chunks": len(timed.write), "computed": report.computed,
            "chunk_compute_here": _stats(timed.compute), "chunk_write_here": _stats(timed.write),
            "libs": libs}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--tools", type=int, default=10_000)
    parser.add_argument("--frequency", default="2.5:5000:2.5", help="START:STOP:STEP, Hz (default 2 000 lines)")
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--out", type=Path, default=ROOT / "benchmarks" / "results" / "dask.json")
    args = parser.parse_args()

    import distributed

    grid = parse_frequency_option(args.frequency)
    assembly = ra1(grid)
    settings = {"spindle": assembly["spindle"], "frequency": grid, "joints": assembly["joints"]}
    library = orjson.dumps(synthetic_library(args.tools))
    n_lines = int(round((grid["stop_hz"] - grid["start_hz"]) / grid["step_hz"])) + 1
    print(f"{args.tools} tools x {n_lines} lines, {chunks.chunk_size(n_lines)} tools per chunk; load average "
          f"{os.getloadavg()[0]:.1f} on {os.cpu_count()} cores", flush=True)

    figures: dict[str, Any] = {"machine": {"cpus": os.cpu_count(), "python": platform.python_version(),
                                           "platform": platform.platform()},
                               "tools": args.tools, "lines": n_lines, "tools_per_chunk": chunks.chunk_size(n_lines),
                               "load_average_start": os.getloadavg()[0]}
    with tempfile.TemporaryDirectory(prefix="rcsa-bench-dask-") as tmp:
        local = sync_once(Path(tmp) / "local", library, settings, LocalBackend())
        print(f"local: {local['wall_s']:.1f} s wall, {local['cpu_s']:.1f} s CPU; {local['chunks']} chunks, "
              f"compute {local['chunk_compute_here']['mean_s']:.2f} s per chunk (p50 "
              f"{local['chunk_compute_here']['p50_s']:.2f}, max {local['chunk_compute_here']['max_s']:.2f}), "
              f"write {local['chunk_write_here']['mean_s'] * 1e3:.0f} ms per chunk; import {local['import_s']:.2f} s, "
              f"plan {local['plan_s']:.2f} s", flush=True)

        t0 = time.perf_counter()
        cluster = distributed.LocalCluster(n_workers=args.workers, threads_per_worker=1, processes=True,
                                           host="127.0.0.1", dashboard_address="127.0.0.1:0", silence_logs=40)
        backend = DaskBackend(cluster.scheduler_address)
        cluster_start = time.perf_counter() - t0
        try:
            with distributed.get_task_stream(client=backend.client) as stream:
                remote = sync_once(Path(tmp) / "dask", library, settings, backend)
            tasks = [t for t in stream.data if "rcsa-chunk" in str(t.get("key", ""))]
        finally:
            backend.close()
            cluster.close()
        compute = [sum(s["stop"] - s["start"] for s in t["startstops"] if s["action"] == "compute") for t in tasks]
        moving = [sum(s["stop"] - s["start"] for s in t["startstops"] if s["action"] != "compute") for t in tasks]
        worker_compute = _stats(compute)
        print(f"dask ({args.workers} workers, cluster start {cluster_start:.1f} s): {remote['wall_s']:.1f} s wall, "
              f"{remote['cpu_s']:.1f} s CPU in the service process; {len(tasks)} chunk tasks, compute on a worker "
              f"{worker_compute['mean_s']:.2f} s per chunk (p50 {worker_compute['p50_s']:.2f}, max "
              f"{worker_compute['max_s']:.2f}); transfer/deserialise on workers {statistics.fmean(moving) * 1e3:.0f} "
              f"ms per chunk; write here {remote['chunk_write_here']['mean_s'] * 1e3:.0f} ms per chunk", flush=True)

        a, b = local["libs"].results("bench"), remote["libs"].results("bench")
        same = all(np.array_equal(x["tool_point"][k]["real"], y["tool_point"][k]["real"])
                   and np.array_equal(x["tool_point"][k]["imag"], y["tool_point"][k]["imag"])
                   and x["natural_frequencies_hz"] == y["natural_frequencies_hz"]
                   for x, y in zip(a["results"], b["results"], strict=True) for k in "hlnp")
        assert same, "the cluster's results differ from the local ones"
        print("stored results bit-identical: yes", flush=True)
        result_mb = sum(p.stat().st_size for p in (Path(tmp) / "dask" / "libraries" / "results").iterdir()) / 1e6

    # fixed costs paid by the service whatever the cluster; per-chunk costs that spread over N
    fixed = remote["import_s"] + remote["plan_s"]
    per_chunk_service = remote["chunk_write_here"]["mean_s"]
    chunks_n = len(tasks)
    work = worker_compute["sum_s"]
    work_here = local["chunk_compute_here"]["sum_s"]  # the same chunks, computed in one uncontended process
    service_bound = chunks_n * per_chunk_service  # beyond this, results arrive faster than one process writes them
    scaling = {n: fixed + max(work / n, service_bound) for n in (1, 2, 4, 8, 16, 32)}
    scaling_here = {n: fixed + max(work_here / n, service_bound) for n in (1, 2, 4, 8, 16, 32)}
    overhead = remote["compute_and_write_s"] - work / args.workers
    print(f"overhead of the cluster run beyond its workers' compute / {args.workers}: {overhead:.1f} s "
          f"({overhead / max(remote['compute_and_write_s'], 1e-9):.0%} of it)")
    print("expected first sync on N machines of this speed (1 worker thread each), fixed "
          f"{fixed:.1f} s + max(compute {work:.0f} s / N, writing {chunks_n} x {per_chunk_service * 1e3:.0f} ms):")
    print("   " + ", ".join(f"N={n}: {t:.0f} s" for n, t in scaling.items()))
    print(f"  the same with the chunk cost measured in this process ({work_here:.0f} s for all chunks):")
    print("   " + ", ".join(f"N={n}: {t:.0f} s" for n, t in scaling_here.items()))
    for run in (local, remote):
        run.pop("libs")
    figures.update({"local": local, "dask": {**remote, "workers": args.workers, "cluster_start_s": cluster_start,
                                             "chunk_compute_on_worker": worker_compute,
                                             "chunk_transfer_on_worker": _stats(moving),
                                             "overhead_s": overhead},
                    "result_cache_mb": result_mb, "bit_identical": same,
                    "expected_wall_s_on_n_machines": scaling,
                    "expected_wall_s_on_n_machines_with_local_chunk_cost": scaling_here,
                    "service_write_bound_s": service_bound, "load_average_end": os.getloadavg()[0]})
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(figures, indent=1) + "\n")
    print(f"figures written to {args.out}")


if __name__ == "__main__":
    main()
