"""Results on the wire (issue 22): JSON bytes of a prediction, and a large batch as JSON, HDF5, Parquet.

Run: ``.venv/bin/python benchmarks/bench_wire.py`` (``--tools 100`` for a quick run). Prints, in
one process, median wall times with the machine's load:

* **JSON of one prediction.** ``rcsa.predict`` of RA-1 at 10 000 lines (the yardstick; cold, as in
  ``bench_engine.py``: no spindle side kept from the call before), then its
  JSON bytes three ways: ``to_dict()`` (lists) + the standard library's ``json.dumps``;
  ``to_dict()`` (lists) + orjson (what the CLI did); and ``rcsa.app.results.json_bytes`` of the
  Prediction (arrays straight to bytes: what the CLI, REST, jobs and exports do now), compact and
  indented. Target: ≤ 0.3× the prediction.
* **A 1 000 × 20 000-line batch** (RA-1's spindle, holder and joints, stickouts 40–90 mm,
  ``natural_frequencies: false``; computed once, not timed): written to disk result by result as
  a job writes it, fsynced, as JSON (the job's writer), HDF5 and Parquet. Bytes and write times.
  Targets: binary ≤ ⅓ of the JSON's bytes, ≥ 5× faster to write.

The files go to a temporary directory (``--dir``; 3.7 GB of JSON at the full size) and are
deleted afterwards. The figures are written to ``benchmarks/results/wire.json``.
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import statistics
import sys
import tempfile
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import orjson

import rcsa
from rcsa.app import predictions
from rcsa.app.jobs import write_entries
from rcsa.app.results import json_bytes
from rcsa.libraries.library_prediction import EntryResults
from rcsa.model.batch import predict_batch
from rcsa.reference import ra1
from record import load_average, write


def median_s(fn: Callable[[], object], repeats: int) -> float:
    fn()
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return statistics.median(times)


def load() -> str:
    one, five, fifteen = os.getloadavg()
    return f"load average {one:.2f}, {five:.2f}, {fifteen:.2f} on {os.cpu_count()} cores"


def prediction_section(repeats: int) -> dict[str, float]:
    doc = ra1({"start_hz": 1.0, "stop_hz": 10000.0, "step_hz": 1.0})
    result = rcsa.predict(doc)
    t_predict = median_s(lambda: rcsa.predict(doc), repeats)
    rows = {
        "to_dict() lists + json.dumps (standard library)": lambda: json.dumps(result.to_dict()).encode(),
        "to_dict() lists + orjson (the CLI before)": lambda: orjson.dumps(result.to_dict()),
        "json_bytes(prediction), compact (REST, jobs, exports)": lambda: json_bytes(result),
        "json_bytes(prediction), indented (the CLI)": lambda: json_bytes(result, indent=True),
    }
    assert json_bytes(result) == orjson.dumps(result.to_dict())  # the same bytes as before
    print(f"RA-1 at 10 000 lines, one prediction ({load()})")
    print(f"  rcsa.predict, cold (the yardstick)                         {t_predict * 1e3:7.1f} ms")
    out = {"predict_ms": t_predict * 1e3}
    for name, fn in rows.items():
        t = median_s(fn, repeats)
        out[name] = t * 1e3
        print(f"  {name:57s}{t * 1e3:7.1f} ms   {t / t_predict:5.2f}x the prediction")
    print(f"  ({len(json_bytes(result)) / 1e6:.2f} MB compact)")
    return out


def batch_results(tools: int, lines: int) -> dict[str, Any]:
    step = 5000.0 / lines
    grid = {"start_hz": step, "stop_hz": 5000.0, "step_hz": step}
    doc = ra1(grid)
    combos = [{"id": f"T{i:04d}", "holder": doc["holder"], "joints": doc["joints"],
               "tool": {**doc["tool"], "stickout_m": 0.040 + 0.05 * i / tools}} for i in range(tools)]
    return predict_batch({"frequency": grid, "spindle": doc["spindle"], "combinations": combos,
                          "natural_frequencies": False}, arrays="numpy")


def _started(document: dict[str, Any]) -> EntryResults:
    def results() -> Iterator[dict[str, Any]]:
        yield from document["results"]

    return EntryResults({}, results(), ("ok", "error"))


def write_timed(path: Path, write: Callable[[Any], object]) -> float:
    t0 = time.perf_counter()
    with open(path, "w+b") as fh:  # as the job runner opens its result file
        write(fh)
        fh.flush()
        os.fsync(fh.fileno())
    return time.perf_counter() - t0


def batch_section(tools: int, lines: int, directory: Path, repeats: int) -> dict[str, Any]:
    t0 = time.perf_counter()
    document = batch_results(tools, lines)
    print(f"{tools} tools x {lines} lines, computed in {time.perf_counter() - t0:.1f} s (not timed below; {load()})")
    writers = {
        "JSON (the job's writer)": (".json", lambda fh: write_entries(fh, _started(document), "json", "batch")),
        "HDF5": (".h5", lambda fh: write_entries(fh, _started(document), "hdf5", "batch")),
        "Parquet (uncompressed)": (".parquet",
                                              lambda fh: write_entries(fh, _started(document), "parquet", "batch")),
    }
    out: dict[str, Any] = {"tools": tools, "lines": lines}
    json_s = json_bytes_n = None
    for name, (suffix, writer) in writers.items():
        path = directory / f"batch{suffix}"
        times = [write_timed(path, writer) for _ in range(repeats)]
        t, size = statistics.median(times), path.stat().st_size
        path.unlink()
        if json_s is None:
            json_s, json_bytes_n = t, size
            print(f"  {name:36s} {size / 1e9:6.3f} GB  written in {t:6.2f} s")
        else:
            print(f"  {name:36s} {size / 1e9:6.3f} GB  written in {t:6.2f} s   {size / json_bytes_n:5.3f}x the JSON's "
                  f"bytes, {json_s / t:4.1f}x faster")
        out[name] = {"bytes": size, "write_s": t}
    print(f"  ({load()})")
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--tools", type=int, default=1000)
    parser.add_argument("--lines", type=int, default=20000)
    parser.add_argument("--repeats", type=int, default=7)
    parser.add_argument("--batch-repeats", type=int, default=1)
    parser.add_argument("--dir", type=Path, default=None, help="where the batch files are written")
    parser.add_argument("--skip-batch", action="store_true")
    parser.add_argument("--out", type=Path, default=None, help="the JSON (default benchmarks/results/wire.json)")
    args = parser.parse_args()
    begin = load_average()
    print(f"python {sys.version.split()[0]}, orjson {orjson.__version__}")
    predictions.SIDES.size = 0  # cold predictions, the yardstick of bench_engine.py
    figures: dict[str, Any] = {"prediction": {**prediction_section(args.repeats), "load_average": load_average()},
                               "repeats": args.repeats}
    if not args.skip_batch:
        directory = Path(tempfile.mkdtemp(prefix="rcsa-wire-", dir=args.dir))
        try:
            figures["batch"] = {**batch_section(args.tools, args.lines, directory, args.batch_repeats),
                                "load_average": load_average()}
        finally:
            shutil.rmtree(directory, ignore_errors=True)
    write("wire", figures, load_start=begin, out=args.out)


if __name__ == "__main__":
    main()
