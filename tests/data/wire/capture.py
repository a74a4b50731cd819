"""Capture the wire bytes rcsa wrote before the array-to-bytes encoder (issue 22), as golden files.

Run once, from the repository root, on the code *before* the change (commit 27bdf14):
``.venv/bin/python tests/data/wire/capture.py``. It writes ``*.json.gz`` beside itself:

* ``ra1-cli.json.gz``: ``rcsa predict`` of RA-1 on 100:5000:25 Hz (stdout, indented);
* ``ra1-rest.json.gz``: ``POST /v1/tool-point-frf`` of the same (compact);
* ``ra1-hybrid-rest.json.gz``: the same holder and tool on RA-1's spindle receptance stored as a
  measurement (modal fit, ``natural_frequencies_sd_hz``, a null static stiffness);
* ``ra1-uncertainty-rest.json.gz``: RA-1 with a 20-draw uncertainty band;
* ``batch-rest.json.gz``: ``POST /v1/tool-point-frf/batch`` of ``examples/batch.json`` plus a
  refused combination (per-combination error kept);
* ``library-cli.json.gz``: ``rcsa library predict examples/fusion-library.json`` (ok, skipped);
* ``library-export.json.gz``: ``rcsa library export`` (JSON) of that library after a sync.

``tests/model/test_wire_bytes.py`` decodes each, re-encodes the document with today's encoder
and compares the bytes exactly (formatting, key order, null policy), independently of the
physics' last bits.
"""

from __future__ import annotations

import copy
import gzip
import json
import os
import sys
import tempfile
import warnings
from pathlib import Path

from typer.testing import CliRunner

HERE = Path(__file__).resolve().parent
REPO = HERE.parents[2]
GRID = {"start_hz": 100.0, "stop_hz": 5000.0, "step_hz": 25.0}


def main() -> None:
    tmp = Path(tempfile.mkdtemp(prefix="rcsa-golden-"))
    os.environ["RCSA_STORE"] = str(tmp / "store")
    from rcsa.cli import app
    from rcsa.reference import ra1
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        from fastapi.testclient import TestClient
    from service.config import Settings
    from service.main import create_app

    from rcsa.app.measurements import demo_measurement
    from rcsa.measured.importers import measurement_to_contract

    out: dict[str, bytes] = {}
    runner = CliRunner()
    assembly = tmp / "ra1.json"
    assembly.write_text(json.dumps(ra1(GRID)))
    r = runner.invoke(app, ["predict", str(assembly)])
    assert r.exit_code == 0, r.stderr
    out["ra1-cli"] = r.stdout_bytes
    r = runner.invoke(app, ["library", "predict", str(REPO / "examples/fusion-library.json"), "--spindle",
                            str(REPO / "examples/ra1.json"), "--frequency", "100:5000:25", "-q"])
    assert r.exit_code == 0, r.stderr
    out["library-cli"] = r.stdout_bytes
    r = runner.invoke(app, ["library", "sync", str(REPO / "examples/fusion-library.json"), "--spindle",
                            str(REPO / "examples/ra1.json"), "--frequency", "100:5000:25", "-q",
                            "--library-id", "golden"])
    assert r.exit_code == 0, r.stderr
    export = tmp / "golden.json"
    r = runner.invoke(app, ["library", "export", "golden", "-o", str(export)])
    assert r.exit_code == 0, r.stderr
    out["library-export"] = export.read_bytes()

    key = "golden-write-key-0123456789abcdef"
    settings = Settings(store=tmp / "store2", api_keys=f"{key}:write", seed_demo=False, access_log=False)
    with TestClient(create_app(settings)) as client:
        r = client.post("/v1/tool-point-frf", json=ra1(GRID))
        assert r.status_code == 200, r.text
        out["ra1-rest"] = r.content
        r = client.post("/v1/tool-point-frf", json={**ra1(GRID), "uncertainty": {"draws": 20, "seed": 1}})
        assert r.status_code == 200, r.text
        out["ra1-uncertainty-rest"] = r.content
        spindle = measurement_to_contract(demo_measurement(GRID))
        spindle = {k: v for k, v in spindle.items() if k not in ("id", "source", "created_utc")}
        r = client.post("/v1/measurements", json=spindle, headers={"X-API-Key": key})
        assert r.status_code == 201, r.text
        r = client.post("/v1/tool-point-frf", json={**ra1(GRID), "spindle": {"measurement_id": r.json()["id"]}})
        assert r.status_code == 200, r.text
        out["ra1-hybrid-rest"] = r.content
        batch = {**json.loads((REPO / "examples/batch.json").read_text()), "frequency": GRID}
        bad = copy.deepcopy(batch["combinations"][0])
        bad["id"] = "bad-stickout"
        bad["tool"]["stickout_m"] = -0.01
        batch["combinations"].insert(1, bad)
        r = client.post("/v1/tool-point-frf/batch", json=batch)
        assert r.status_code == 200, r.text
        out["batch-rest"] = r.content
    for name, data in out.items():
        (HERE / f"{name}.json.gz").write_bytes(gzip.compress(data, mtime=0))
        print(f"{name}: {len(data)} bytes", file=sys.stderr)


if __name__ == "__main__":
    main()
