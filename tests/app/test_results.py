"""The JSON encoder of results (``rcsa.app.results.json_bytes``): the wire form, byte for byte.

Golden files (``tests/data/wire``, ``capture.py``) are the bytes rcsa wrote *before* results were
written straight from arrays: the CLI's indented RA-1, the REST RA-1 (analytical, hybrid, with
an uncertainty band), a batch with a refused combination, a library prediction and a stored
library's JSON export. Each is decoded, its float lists turned into numpy arrays, and encoded
again: the bytes must be identical (float text, key order, nulls, indentation). Fresh results are
also encoded both ways (today's ``to_dict()`` lists + orjson, and the arrays) and compared.
"""

from __future__ import annotations

import json

import numpy as np
import orjson
import pytest

from rcsa.app.predictions import predict, predict_batch
from rcsa.app.results import (
    encode_result,
    format_of_suffix,
    json_bytes,
    require_format,
    write_result,
)
from rcsa.errors import InputError
from rcsa.reference import ra1
from tests.result_files import as_numpy, golden, read_hdf5

GRID = {"start_hz": 100.0, "stop_hz": 5000.0, "step_hz": 25.0}
#: relative agreement of a fresh RA-1 with the golden numbers (the physics, not the encoder):
#: an exact solver in double precision, recomputed; the last bits may move with the engine
RTOL_PHYSICS = 1e-10


@pytest.mark.parametrize("name", ["ra1-rest", "ra1-hybrid-rest", "ra1-uncertainty-rest", "batch-rest",
                                  "library-export"])
def test_compact_json_is_todays_bytes(name):
    raw = golden(name)
    document = as_numpy(orjson.loads(raw))
    assert json_bytes(document) == raw


@pytest.mark.parametrize("name", ["ra1-cli", "library-cli"])
def test_indented_json_is_what_the_cli_printed(name):
    raw = golden(name)
    assert json_bytes(as_numpy(orjson.loads(raw)), indent=True) + b"\n" == raw


def test_a_fresh_prediction_written_from_arrays_equals_the_list_path():
    result = predict(ra1(GRID))
    today = orjson.dumps(result.to_dict())  # lists of Python floats
    assert json_bytes(result) == today
    assert json_bytes(result, indent=True) == orjson.dumps(result.to_dict(), option=orjson.OPT_INDENT_2)
    fresh, kept = orjson.loads(today), orjson.loads(golden("ra1-rest"))
    assert list(fresh) == list(kept)
    for name in ("h", "l", "n", "p"):
        z = np.asarray(fresh["tool_point"][name]["real"]) + 1j * np.asarray(fresh["tool_point"][name]["imag"])
        z0 = np.asarray(kept["tool_point"][name]["real"]) + 1j * np.asarray(kept["tool_point"][name]["imag"])
        np.testing.assert_allclose(z, z0, rtol=RTOL_PHYSICS, atol=RTOL_PHYSICS * np.abs(z0).max())


def test_a_fresh_batch_written_from_arrays_equals_the_list_path():
    doc = ra1(GRID)
    request = {"frequency": GRID, "spindle": doc["spindle"], "combinations": [
        {"id": "a", "holder": doc["holder"], "tool": doc["tool"], "joints": doc["joints"]},
        {"id": "b", "holder": doc["holder"], "tool": {**doc["tool"], "stickout_m": -1.0}}]}
    arrays = predict_batch(request, arrays="numpy")
    assert json_bytes(arrays) == orjson.dumps(predict_batch(request))


def test_non_finite_numbers_are_null_as_before():
    values = np.array([1.0, np.nan, np.inf, -np.inf, -0.0, 1e-6, 1e16, 5e-324])
    assert json_bytes({"x": values}) == orjson.dumps({"x": values.tolist()}) == \
        b'{"x":[1.0,null,null,null,-0.0,1e-6,1e+16,5e-324]}'


def test_strided_arrays_and_numpy_scalars_are_written_too():
    a = np.arange(6.0)
    assert json_bytes({"a": a[::2], "b": np.float64(2.5), "c": np.int64(3), "d": np.bool_(True)}) == \
        b'{"a":[0.0,2.0,4.0],"b":2.5,"c":3,"d":true}'
    with pytest.raises(TypeError, match="not JSON serializable"):  # complex arrays travel as {real, imag}
        json_bytes({"z": np.array([1j])})


def test_suffixes_name_the_form():
    assert [format_of_suffix(p) for p in ("a.json", "a.H5", "a.hdf5", "a.parquet")] == \
        ["json", "hdf5", "hdf5", "parquet"]
    with pytest.raises(InputError, match=r"out: x\.csv: the file name must end in \.json, \.h5, \.hdf5, \.parquet"):
        format_of_suffix("x.csv")


def test_parquet_without_pyarrow_names_the_extra(monkeypatch):
    import rcsa.app.results as results

    monkeypatch.setattr(results, "parquet_available", lambda: False)
    with pytest.raises(InputError, match=r"format: Parquet results need pyarrow, the extra rcsa\[parquet\]"):
        require_format("parquet")
    require_format("hdf5")


def test_write_result_picks_the_form_by_suffix(tmp_path):
    document = as_numpy(orjson.loads(golden("batch-rest")))
    assert write_result(document, tmp_path / "b.json", "batch") == "json"
    assert (tmp_path / "b.json").read_bytes() == golden("batch-rest")
    assert write_result(document, tmp_path / "b.h5", "batch") == "hdf5"
    assert json_bytes(read_hdf5((tmp_path / "b.h5").read_bytes())) == golden("batch-rest")
    assert encode_result(document, "json", "batch") == golden("batch-rest")
    assert json.loads(json_bytes(document))["summary"] == {"ok": 3, "error": 1}
