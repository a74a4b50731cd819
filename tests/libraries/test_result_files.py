"""Binary result files (:mod:`rcsa.libraries.exports`): HDF5 and Parquet, the same numbers as the JSON.

Each document is written, read back by the independent readers of ``tests/result_files.py``
(h5py and pyarrow only) and serialised again: the bytes must be those of the JSON form, so
every number survives to the last bit and every field, error and skipped entry is kept.
"""

from __future__ import annotations

import io

import h5py
import orjson
import pyarrow.parquet as pq
import pytest

from rcsa.app.predictions import predict_batch
from rcsa.app.results import encode_result, json_bytes
from rcsa.libraries import exports
from rcsa.reference import ra1
from tests.result_files import as_numpy, golden, read_hdf5, read_parquet

READERS = {"hdf5": read_hdf5, "parquet": read_parquet}
KINDS = {"batch-rest": "batch", "library-cli": "library", "library-export": "library-results"}


@pytest.mark.parametrize("fmt", ["hdf5", "parquet"])
@pytest.mark.parametrize("name", list(KINDS))
def test_round_trip_gives_the_json_bytes(name, fmt):
    document = as_numpy(orjson.loads(golden(name)))
    data = encode_result(document, fmt, KINDS[name])
    assert json_bytes(READERS[fmt](data)) == json_bytes(document)


@pytest.mark.parametrize("fmt", ["hdf5", "parquet"])
def test_a_band_and_a_lean_tool_point_round_trip(fmt):
    grid = {"start_hz": 200.0, "stop_hz": 3000.0, "step_hz": 50.0}
    doc = ra1(grid)
    request = {"frequency": grid, "spindle": doc["spindle"], "uncertainty": {"draws": 4, "seed": 3},
               "combinations": [{"id": "T1", "holder": doc["holder"], "tool": doc["tool"], "joints": doc["joints"]},
                                {"id": "T1", "holder": doc["holder"], "tool": {**doc["tool"], "stickout_m": 0.06}},
                                {"id": "bad", "holder": doc["holder"], "tool": {**doc["tool"], "diameter_m": -1}}]}
    result = predict_batch(request, arrays="numpy")
    assert [r["status"] for r in result["results"]] == ["ok", "ok", "error"]
    assert json_bytes(READERS[fmt](encode_result(result, fmt, "batch"))) == json_bytes(result)
    lean = {**result, "results": [{**r, "tool_point": {"h": r["tool_point"]["h"]}} if r["status"] == "ok" else r
                                  for r in result["results"]]}
    assert json_bytes(READERS[fmt](encode_result(lean, fmt, "batch"))) == json_bytes(lean)


def _with_n_apart(document):
    """The first ok result's n differs from its l (as a measured spindle may make it)."""
    out = orjson.loads(json_bytes(document))
    first = next(r for r in out["results"] if r["status"] == "ok")
    first["tool_point"]["n"]["real"][3] *= 1.0 + 2.0 ** -50
    return as_numpy(out)


def test_hdf5_stores_n_only_where_it_is_not_l_bit_for_bit():
    document = as_numpy(orjson.loads(golden("batch-rest")))
    with h5py.File(io.BytesIO(encode_result(document, "hdf5", "batch")), "r") as f:
        assert f.attrs["schema"] == "rcsa.batch-results" and f.attrs["schema_version"] == 2
        assert list(f["result"][()]) == [0, 2, 3] and list(f["id"].asstr()[()]) == ["T1-ra1-74mm", "T1-ra1-50mm",
                                                                                    "T7-d10"]
        assert f["tool_point/n_is_l"][()].all() and f["tool_point/h"].attrs["units"] == "m/N"
        assert f["tool_point/n"].id.get_storage_size() == 0  # no row of n written
    apart = _with_n_apart(document)
    data = encode_result(apart, "hdf5", "batch")
    with h5py.File(io.BytesIO(data), "r") as f:
        assert list(f["tool_point/n_is_l"][()]) == [False, True, True]
    assert json_bytes(read_hdf5(data)) == json_bytes(apart)


def test_parquet_leaves_n_null_only_where_it_is_l_bit_for_bit():
    document = as_numpy(orjson.loads(golden("batch-rest")))
    apart = _with_n_apart(document)
    data = encode_result(apart, "parquet", "batch")
    table = pq.read_table(io.BytesIO(data))
    null = table.column("n_real").is_null().to_numpy(zero_copy_only=False)
    first = table.column("result").to_numpy() == 0
    assert not null[first].any() and null[~first].all()
    assert json_bytes(read_parquet(data)) == json_bytes(apart)
    assert table.column_names[:3] == ["result", "id", "frequency_hz"]


def test_results_on_different_grids_are_refused():
    document = orjson.loads(golden("batch-rest"))
    document["results"][2]["frequency_hz"][0] += 1.0
    with pytest.raises(ValueError, match="another frequency grid"):
        encode_result(as_numpy(document), "hdf5", "batch")


def test_a_result_without_ok_entries_is_still_a_file():
    document = {"results": [{"id": "x", "status": "error", "error": {"field": "f", "detail": "d"}}],
                "summary": {"ok": 0, "error": 1}}
    for fmt, reader in READERS.items():
        assert json_bytes(reader(encode_result(document, fmt, "batch"))) == json_bytes(document)


def test_the_library_export_names_its_library():
    data = exports.library_hdf5(as_numpy(orjson.loads(golden("library-export"))))
    with h5py.File(io.BytesIO(data), "r") as f:
        assert f.attrs["schema"] == exports.HDF5_SCHEMA and f.attrs["library_id"] == "golden"
        assert f.attrs["revision"] == 1 and f["frequency_hz"].attrs["units"] == "Hz"
        assert list(f["id"].asstr()[()]) == ["00000000-0000-4000-8000-000000000101",
                                             "00000000-0000-4000-8000-000000000102"]
        assert f["tool_point/h"].shape == (2, f["frequency_hz"].size)
