"""Independent readers of rcsa's binary result files (HDF5, Parquet) back into the JSON document.

Written from the layout documented in :mod:`rcsa.libraries.exports` with h5py and pyarrow only
(no rcsa code), so a round trip ``document → file → document`` checks the writers against the
documentation: the rebuilt document must serialise to the very bytes of the original.
"""

from __future__ import annotations

import gzip
import io
import json
from pathlib import Path
from typing import Any

import numpy as np
import orjson

WIRE = Path(__file__).resolve().parent / "data" / "wire"


def golden(name: str) -> bytes:
    """The bytes of a golden file in ``tests/data/wire`` (captured before the encoder change)."""
    return gzip.decompress((WIRE / f"{name}.json.gz").read_bytes())


def as_numpy(value: Any) -> Any:
    """A decoded JSON document with every list of more than one float as a float64 array."""
    if isinstance(value, dict):
        return {k: as_numpy(v) for k, v in value.items()}
    if isinstance(value, list):
        if len(value) > 1 and all(type(v) is float for v in value):
            return np.array(value, dtype=np.float64)
        return [as_numpy(v) for v in value]
    return value


def _fill(result: dict[str, Any], frequency_hz: np.ndarray, get: Any) -> None:
    result["frequency_hz"] = frequency_hz
    for name in result["tool_point"]:
        z = get(name)
        result["tool_point"][name] = {"real": np.ascontiguousarray(z.real), "imag": np.ascontiguousarray(z.imag)}
    band = result.get("uncertainty")
    if isinstance(band, dict) and isinstance(band.get("h_magnitude_m_n"), dict):
        for p in band["h_magnitude_m_n"]:
            band["h_magnitude_m_n"][p] = get(f"h_magnitude_{p}_m_n")


def read_hdf5(data: bytes) -> dict[str, Any]:
    """An HDF5 result file as the JSON document it was written from (``n_is_l``: ``l``'s row)."""
    import h5py

    with h5py.File(io.BytesIO(data), "r") as f:
        fields = json.loads(f["results_json"][()])
        frequency_hz = f["frequency_hz"][()]
        tool_point = f.get("tool_point")
        band = f.get("uncertainty")
        for row, position in enumerate(f["result"][()]):

            def get(name: str, row: int = row) -> np.ndarray:
                if name.startswith("h_magnitude_"):
                    return band[name][row]
                if name == "n" and tool_point["n_is_l"][row]:
                    name = "l"
                return tool_point[name][row]

            _fill(fields[int(position)], frequency_hz, get)
        return {**json.loads(f.attrs["head_json"]), "results": fields, "summary": json.loads(f.attrs["summary_json"])}


def read_parquet(data: bytes) -> dict[str, Any]:
    """A Parquet result file as the JSON document it was written from (``n`` null: ``l``'s bits)."""
    import pyarrow.parquet as pq

    table = pq.read_table(io.BytesIO(data))
    meta = pq.read_metadata(io.BytesIO(data)).metadata
    fields = json.loads(meta[b"rcsa.results"])
    columns = {name: table.column(name) for name in table.column_names}
    position = columns["result"].to_numpy()

    def column(name: str, rows: np.ndarray) -> np.ndarray:
        return columns[name].to_numpy(zero_copy_only=False)[rows]

    for pos in np.unique(position):
        rows = position == pos

        def get(name: str, rows: np.ndarray = rows) -> np.ndarray:
            if name.startswith("h_magnitude_"):
                return column(name, rows)
            re, im = column(f"{name}_real", rows), column(f"{name}_imag", rows)
            if name == "n":
                null = columns["n_real"].is_null().to_numpy(zero_copy_only=False)[rows]
                re, im = np.where(null, column("l_real", rows), re), np.where(null, column("l_imag", rows), im)
            z = np.empty(re.size, dtype=np.complex128)
            z.real, z.imag = re, im
            return z

        _fill(fields[int(pos)], column("frequency_hz", rows), get)
    return {**json.loads(meta[b"rcsa.head"]), "results": fields, "summary": json.loads(meta[b"rcsa.summary"])}


def compact(document: Any) -> bytes:
    """Today's JSON path for a document with arrays (orjson, numpy serialised)."""
    return orjson.dumps(document, option=orjson.OPT_SERIALIZE_NUMPY)
