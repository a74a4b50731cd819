"""Exports of a stored library's results for other software: HDF5, and a zip of UFF 58 files.

Both take the document of :meth:`rcsa.libraries.sync.LibraryStore.results` and return bytes.

HDF5 (``application/x-hdf5``; every group and dataset carries ``schema`` and
``schema_version``)::

    /                    schema="rcsa.library-results", schema_version=1, library_id, revision,
                         synced_utc, exported_utc, source, library_sha256, model_version,
                         software_version, convention, tools_json (every tool: id, index,
                         status, reason, error, group)
    /frequency_hz        float64 (n,), units="Hz"
    /tools/<name>        one NXdata group per ok tool (name: the tool id, percent-encoded where
                         HDF5 needs it; attribute ``id`` holds it verbatim): signal="h",
                         axes=["frequency_hz"]; attributes index, description, number, teeth,
                         tool_type, natural_frequencies_hz, static_stiffness_n_m, result_sha256
    /tools/<name>/frequency_hz   hard link to /frequency_hz
    /tools/<name>/h, l, n, p     complex128 (n,) (h5py's compound {r, i}), units and
                                 quantity="receptance"

UFF (``application/zip``): ``index.json`` (id → file, description, T number, teeth) and one
``<tool>.uff`` per ok tool, written with pyuff: a dataset 164 (SI units: m, N, K) then a
dataset 58 — function type 4 (FRF), response and reference node 1 direction +X (the tool
tip), ordinate displacement (8) over force (13), abscissa frequency (18) in Hz, complex
double values of the tool-point receptance h in m/N (ASCII, about 13 significant digits).
"""

from __future__ import annotations

import io
import json
import os
import re
import tempfile
import zipfile
from collections.abc import Mapping
from pathlib import Path
from typing import Any, BinaryIO
from urllib.parse import quote

import numpy as np
import orjson

from rcsa._version import __version__
from rcsa.infra.clock import utc_now_iso
from rcsa.model.wire import CONVENTION, RECEPTANCE_UNITS, complex_from_wire

__all__ = ["HDF5_SCHEMA", "PARQUET_EXTRA", "SCHEMAS", "Hdf5Results", "ParquetResults", "ResultsWriter", "hdf5_writer",
           "library_hdf5", "library_uff_zip", "parquet_available", "parquet_writer", "split_result",
           "tool_file_names"]

HDF5_SCHEMA = "rcsa.library-results"
SCHEMA_VERSION = 1
#: Schema name of each kind of result document in a binary file.
SCHEMAS = {"library-results": HDF5_SCHEMA, "batch": "rcsa.batch-results", "library": "rcsa.library-prediction"}
#: The optional extra that installs pyarrow (Parquet results).
PARQUET_EXTRA = "parquet"
#: Rows of a Parquet row group (at least; whole results are never split).
PARQUET_ROW_GROUP = 1 << 17


def _group_name(tool_id: str) -> str:
    name = quote(tool_id, safe="")
    return name.replace(".", "%2E") if set(name) <= {"."} else name


def tool_file_names(ids: list[str]) -> list[str]:
    """File names (without suffix) for tool ids: safe characters only, unique.

    Examples
    --------
    >>> tool_file_names(["T1", "a/b", "a:b"])
    ['T1', 'a_b', 'a_b~2']
    """
    out, seen = [], set()
    for tool_id in ids:
        base = re.sub(r"[^A-Za-z0-9._-]", "_", tool_id).lstrip(".") or "tool"
        name, k = base, 1
        while name.lower() in seen:
            k += 1
            name = f"{base}~{k}"
        seen.add(name.lower())
        out.append(name)
    return out


def split_result(result: Mapping[str, Any]) -> tuple[dict[str, Any], dict[str, np.ndarray]]:
    """A result's long arrays (one value per frequency line) apart from everything else.

    Parameters
    ----------
    result : mapping
        One entry of a batch or library result (any status).

    Returns
    -------
    fields : dict
        The result in its JSON key order, with ``frequency_hz``, each ``tool_point``
        receptance and each ``uncertainty.h_magnitude_m_n`` percentile replaced by ``None``
        (where a binary file holds them); everything else as it is.
    arrays : dict of str to numpy.ndarray
        ``h``, ``l``, ``n``, ``p`` (complex128, those present) and ``h_magnitude_<p>_m_n``
        (float64), bit for bit the JSON's numbers.
    """
    fields = dict(result)
    arrays: dict[str, np.ndarray] = {}
    if result.get("status") != "ok" or "tool_point" not in result:
        return fields, arrays
    ident = result.get("id")
    fields["frequency_hz"] = None
    fields["tool_point"] = dict.fromkeys(result["tool_point"])
    for name, pair in result["tool_point"].items():
        arrays[name] = complex_from_wire(pair, f"{ident}.tool_point.{name}", finite=False)
    band = result.get("uncertainty")
    if isinstance(band, Mapping) and isinstance(band.get("h_magnitude_m_n"), Mapping):
        fields["uncertainty"] = {**band, "h_magnitude_m_n": dict.fromkeys(band["h_magnitude_m_n"])}
        for p, values in band["h_magnitude_m_n"].items():
            arrays[f"h_magnitude_{p}_m_n"] = np.array(values, dtype=np.float64)
    return fields, arrays


def _same_bits(a: np.ndarray, b: np.ndarray) -> bool:
    """Whether two arrays hold the same bits (NaN equal to the same NaN, -0.0 not +0.0)."""
    return a.shape == b.shape and a.dtype == b.dtype and bool(np.array_equal(a.view(np.uint64), b.view(np.uint64)))


def _json(value: Any) -> str:
    return orjson.dumps(value, option=orjson.OPT_SERIALIZE_NUMPY).decode()


class ResultsWriter:
    """Writes one result document (head, results one by one, summary) to a binary file.

    Use as a context manager; call :meth:`head` once, :meth:`result` for every result in
    order, :meth:`summary` once. Every ok result must be on the grid of the first.
    """

    def __init__(self, kind: str) -> None:
        if kind not in SCHEMAS:
            raise ValueError(f"unknown result kind {kind!r} (known: {', '.join(SCHEMAS)})")
        self.kind = kind
        self.frequency_hz: np.ndarray | None = None
        self.fields: list[dict[str, Any]] = []
        self.index: list[dict[str, Any]] = []
        self.head_doc: dict[str, Any] = {}
        self.summary_doc: dict[str, Any] = {}

    def __enter__(self) -> ResultsWriter:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close(failed=exc[0] is not None)

    def head(self, head: Mapping[str, Any]) -> None:
        """The document's fields before ``results`` (a library's ``library``; none for a batch)."""
        self.head_doc = dict(head)

    def result(self, result: Mapping[str, Any]) -> None:
        """One result, in order."""
        fields, arrays = split_result(result)
        ok = bool(arrays)
        if ok:
            f = np.array(result["frequency_hz"], dtype=np.float64)
            if self.frequency_hz is None:
                self.frequency_hz = f
            elif not _same_bits(f, self.frequency_hz):
                raise ValueError(f"result {result.get('id')!r} is on another frequency grid than the first")
        self.fields.append(fields)
        self.index.append({"id": result.get("id"), "index": result.get("index"), "status": result.get("status"),
                           "reason": result.get("reason"), "error": result.get("error"),
                           "group": self._write(len(self.fields) - 1, result, arrays) if ok else None})

    def summary(self, summary: Mapping[str, Any]) -> None:
        """The document's ``summary``."""
        self.summary_doc = dict(summary)

    def _write(self, position: int, result: Mapping[str, Any], arrays: dict[str, np.ndarray]) -> str | None:
        raise NotImplementedError

    def close(self, failed: bool = False) -> None:
        """Finish the file (its index and metadata); on failure only release it."""
        raise NotImplementedError


def _hdf5_fields(kind: str, head: Mapping[str, Any]) -> dict[str, Any]:
    """Root attributes of the file (those of a stored library's export since schema version 1)."""
    a: dict[str, Any] = {"schema": SCHEMAS[kind], "schema_version": SCHEMA_VERSION, "kind": kind,
                         "exported_utc": utc_now_iso(), "software_version": __version__, "convention": CONVENTION}
    if kind == "library-results":
        lib = head["library"]
        a.update({"library_id": lib["id"], "revision": int(lib["revision"]), "synced_utc": lib["synced_utc"],
                  "source": lib.get("source") or "", "library_sha256": lib.get("library_sha256") or "",
                  "model_version": str(lib.get("model_version") or ""),
                  "software_version": lib.get("software_version") or __version__})
    elif kind == "library":
        lib = head.get("library") or {}
        a.update({"source": lib.get("source") or "", "library_sha256": lib.get("library_sha256") or ""})
    return a


class Hdf5Results(ResultsWriter):
    """HDF5 form of a result document (layout in the module docstring), written result by result.

    Parameters
    ----------
    target : binary file or path
        A seekable binary file (e.g. a job's result file, ``io.BytesIO``) or a path.
    kind : {"library-results", "batch", "library"}
    """

    def __init__(self, target: BinaryIO | str | os.PathLike[str], kind: str) -> None:
        import h5py

        super().__init__(kind)
        self.file = h5py.File(target, "w")
        self.tools = self.file.create_group("tools")
        self.names: set[str] = set()
        self.fd: Any = None

    def _write(self, position: int, result: Mapping[str, Any], arrays: dict[str, np.ndarray]) -> str:
        if self.fd is None:
            self.fd = fd = self.file.create_dataset("frequency_hz", data=self.frequency_hz)
            fd.attrs["schema"], fd.attrs["schema_version"], fd.attrs["units"] = \
                "rcsa.frequency_hz", SCHEMA_VERSION, "Hz"
        name, k = _group_name(str(result.get("id"))), 1
        while name in self.names:  # ids of a batch need not be unique
            k += 1
            name = f"{_group_name(str(result.get('id')))}~{k}"
        self.names.add(name)
        g = self.tools.create_group(name)
        ga = g.attrs
        ga["schema"], ga["schema_version"] = "rcsa.tool_point", SCHEMA_VERSION
        ga["NX_class"], ga["signal"], ga["axes"], ga["frequency_hz_indices"] = "NXdata", "h", ["frequency_hz"], 0
        ga["id"] = str(result.get("id"))
        ga["result"] = position
        ga["index"] = int(result.get("index") or 0)
        for attr in ("description", "tool_type"):
            ga[attr] = result.get(attr) or ""
        for attr in ("number", "teeth"):
            ga[attr] = -1 if result.get(attr) is None else int(result[attr])
        modes = result.get("natural_frequencies_hz")
        ga["natural_frequencies_hz"] = np.asarray([] if modes is None else modes, dtype=np.float64)
        stiffness = result.get("static_stiffness_n_m")
        ga["static_stiffness_n_m"] = np.nan if stiffness is None else float(stiffness)
        ga["result_sha256"] = result.get("result_sha256") or ""
        g["frequency_hz"] = self.fd
        for key, values in arrays.items():
            if key == "n" and "l" in arrays and _same_bits(values, arrays["l"]):
                g["n"] = g["l"]  # reciprocity: the same bits, stored once (a hard link)
                continue
            d = g.create_dataset(key, data=values)
            if key in RECEPTANCE_UNITS:
                d.attrs["schema"], d.attrs["schema_version"] = "rcsa.frf", SCHEMA_VERSION
                d.attrs["units"], d.attrs["quantity"] = RECEPTANCE_UNITS[key], "receptance"
            else:
                d.attrs["units"], d.attrs["quantity"] = "m/N", "percentile of |h| over the uncertainty draws"
        return f"/tools/{name}"

    def close(self, failed: bool = False) -> None:
        """Write the index and the JSON fields, and close the file."""
        try:
            if not failed:
                if self.fd is None:
                    self.file.create_dataset("frequency_hz", data=np.zeros(0))
                for key, value in _hdf5_fields(self.kind, self.head_doc).items():
                    self.file.attrs[key] = value
                self.file.attrs["tools_json"] = json.dumps(self.index)
                self.file.attrs["head_json"] = _json(self.head_doc)
                self.file.attrs["summary_json"] = _json(self.summary_doc)
                self.file.create_dataset("results_json", data=_json(self.fields))
        finally:
            self.file.close()


def hdf5_writer(target: BinaryIO | str | os.PathLike[str], kind: str) -> Hdf5Results:
    """An :class:`Hdf5Results` writer (a context manager).

    Parameters
    ----------
    target : binary file or path
    kind : {"library-results", "batch", "library"}
    """
    return Hdf5Results(target, kind)


def parquet_available() -> bool:
    """Whether pyarrow (the extra ``rcsa[parquet]``) is installed."""
    import importlib.util

    return importlib.util.find_spec("pyarrow") is not None


class ParquetResults(ResultsWriter):
    """Apache Parquet form of a result document: one row per ok result and frequency line.

    Columns: ``result`` (int32, the result's position in ``results``), ``id`` (dictionary
    string), ``frequency_hz``, ``<r>_real`` and ``<r>_imag`` for each receptance ``r`` of
    ``tool_point`` (float64; ``n_*`` null where ``n`` equals ``l`` bit for bit, as
    reciprocity makes it, and ``l_*`` then holds it), and ``h_magnitude_<p>_m_n`` with an
    uncertainty band. The file's key-value metadata holds ``rcsa.schema``, ``rcsa.head``,
    ``rcsa.results`` (every result's other fields, in order: :func:`split_result`),
    ``rcsa.summary``, ``rcsa.convention`` and ``rcsa.units`` (JSON).

    Parameters
    ----------
    target : binary file or path
    kind : {"library-results", "batch", "library"}
    compression : str
        Parquet codec of the float columns (byte-stream-split encoded).
    """

    def __init__(self, target: BinaryIO | str | os.PathLike[str], kind: str, compression: str = "zstd") -> None:
        super().__init__(kind)
        self.target = target
        self.compression = compression
        self.writer: Any = None
        self.names: list[str] | None = None
        self.pending: list[tuple[int, str, dict[str, np.ndarray]]] = []
        self.rows = 0

    def _write(self, position: int, result: Mapping[str, Any], arrays: dict[str, np.ndarray]) -> None:
        names = list(arrays)
        if self.names is None:
            self.names = names
        elif names != self.names:
            raise ValueError(f"result {result.get('id')!r} has the arrays {names}, the first had {self.names}")
        self.pending.append((position, str(result.get("id")), arrays))
        self.rows += arrays[names[0]].size
        if self.rows >= PARQUET_ROW_GROUP:
            self._flush()
        return None

    def _flush(self) -> None:
        import pyarrow as pa
        import pyarrow.parquet as pq

        if not self.pending:
            return
        assert self.frequency_hz is not None and self.names is not None
        m = self.frequency_hz.size
        ids = [ident for _, ident, _ in self.pending]
        columns: dict[str, Any] = {
            "result": pa.array(np.repeat(np.array([p for p, _, _ in self.pending], dtype=np.int32), m)),
            "id": pa.DictionaryArray.from_arrays(np.repeat(np.arange(len(ids), dtype=np.int32), m), pa.array(ids)),
            "frequency_hz": pa.array(np.tile(self.frequency_hz, len(ids))),
        }
        for key in self.names:
            parts = [a[key] for _, _, a in self.pending]
            if key in RECEPTANCE_UNITS:
                stacked = np.concatenate(parts)
                real, imag = np.ascontiguousarray(stacked.real), np.ascontiguousarray(stacked.imag)
                if key == "n" and "l" in self.names:
                    same = np.repeat([_same_bits(a["n"], a["l"]) for _, _, a in self.pending], m)
                    columns["n_real"] = pa.array(real, mask=same)
                    columns["n_imag"] = pa.array(imag, mask=same)
                else:
                    columns[f"{key}_real"], columns[f"{key}_imag"] = pa.array(real), pa.array(imag)
            else:
                columns[key] = pa.array(np.concatenate(parts))
        table = pa.table(columns)
        if self.writer is None:
            floats = [c for c in table.column_names if c not in ("result", "id", "frequency_hz")]
            self.writer = pq.ParquetWriter(self.target, table.schema, compression=self.compression,
                                           use_dictionary=["id", "frequency_hz"], write_statistics=["result"],
                                           column_encoding=dict.fromkeys(floats, "BYTE_STREAM_SPLIT"))
        self.writer.write_table(table, row_group_size=max(self.rows, 1))
        self.pending, self.rows = [], 0

    def close(self, failed: bool = False) -> None:
        """Write the last rows and the metadata, and close the file."""
        import pyarrow as pa
        import pyarrow.parquet as pq

        if failed:
            if self.writer is not None:
                self.writer.close()
            return
        self._flush()
        if self.writer is None:  # no ok result: the columns of a prediction, no rows
            schema = pa.schema([("result", pa.int32()), ("id", pa.dictionary(pa.int32(), pa.string())),
                                ("frequency_hz", pa.float64())])
            self.writer = pq.ParquetWriter(self.target, schema)
        self.writer.add_key_value_metadata({
            "rcsa.schema": _json({"schema": SCHEMAS[self.kind], "schema_version": SCHEMA_VERSION, "kind": self.kind,
                                  "software_version": __version__, "exported_utc": utc_now_iso()}),
            "rcsa.head": _json(self.head_doc), "rcsa.results": _json(self.fields),
            "rcsa.summary": _json(self.summary_doc), "rcsa.convention": CONVENTION,
            "rcsa.units": _json({**RECEPTANCE_UNITS, "frequency_hz": "Hz", "h_magnitude_*_m_n": "m/N"})})
        self.writer.close()


def parquet_writer(target: BinaryIO | str | os.PathLike[str], kind: str) -> ParquetResults:
    """A :class:`ParquetResults` writer (needs pyarrow: the extra ``rcsa[parquet]``).

    Parameters
    ----------
    target : binary file or path
    kind : {"library-results", "batch", "library"}
    """
    return ParquetResults(target, kind)


def library_hdf5(results: Mapping[str, Any]) -> bytes:
    """The library's results as one HDF5 file (layout in the module docstring).

    The document of :meth:`rcsa.libraries.sync.LibraryStore.results`, written by
    :class:`Hdf5Results` (kind ``library-results``).
    """
    buffer = io.BytesIO()
    with hdf5_writer(buffer, "library-results") as writer:
        writer.head({k: v for k, v in results.items() if k not in ("results", "summary")})
        for r in results["results"]:
            writer.result(r)
        writer.summary(results["summary"])
    return buffer.getvalue()


def library_uff_zip(results: Mapping[str, Any]) -> bytes:
    """A zip of one UFF 58 file per ok tool (tool-point h) and ``index.json``."""
    import pyuff

    lib = results["library"]
    ok = [r for r in results["results"] if r["status"] == "ok"]
    names = tool_file_names([r["id"] for r in ok])
    buffer = io.BytesIO()
    with tempfile.TemporaryDirectory(prefix="rcsa-uff-") as tmp, \
            zipfile.ZipFile(buffer, "w", compression=zipfile.ZIP_DEFLATED) as zf:
        index = []
        for r, name in zip(ok, names, strict=True):
            f = np.asarray(r["frequency_hz"], dtype=np.float64)
            h = complex_from_wire(r["tool_point"]["h"], f"{r['id']}.tool_point.h", finite=False)
            steps = np.diff(f)
            even = f.size > 1 and bool(np.allclose(steps, steps[0], rtol=1e-9, atol=0.0))
            units = pyuff.prepare_164(units_code=1, units_description="SI", temp_mode=2, length=1.0, force=1.0,
                                      temp=1.0, temp_offset=273.15)
            d58 = pyuff.prepare_58(
                binary=0, id1=f"tool-point h {r['id']}"[:80], id2=(r.get("description") or "")[:80],
                id3=f"library {lib['id']} revision {lib['revision']}"[:80], id4=lib.get("synced_utc", "")[:80],
                id5=f"rcsa {__version__} model {lib.get('model_version')}"[:80],
                func_type=4, ver_num=0, load_case_id=0, rsp_ent_name="tooltip", rsp_node=1, rsp_dir=1,
                ref_ent_name="tooltip", ref_node=1, ref_dir=1, ord_data_type=6, num_pts=int(f.size),
                abscissa_spacing=1 if even else 0, abscissa_min=float(f[0]),
                abscissa_inc=float(steps[0]) if even else 0.0, z_axis_value=0.0,
                abscissa_spec_data_type=18, abscissa_len_unit_exp=0, abscissa_force_unit_exp=0,
                abscissa_temp_unit_exp=0, abscissa_axis_units_lab="Hz",
                ordinate_spec_data_type=8, ordinate_len_unit_exp=1, ordinate_force_unit_exp=0,
                ordinate_temp_unit_exp=0, ordinate_axis_units_lab="m",
                orddenom_spec_data_type=13, orddenom_len_unit_exp=0, orddenom_force_unit_exp=1,
                orddenom_temp_unit_exp=0, orddenom_axis_units_lab="N",
                z_axis_spec_data_type=0, z_axis_len_unit_exp=0, z_axis_force_unit_exp=0, z_axis_temp_unit_exp=0,
                z_axis_axis_units_lab="NONE", data=h, x=f)
            path = Path(tmp) / f"{name}.uff"
            pyuff.UFF(str(path)).write_sets([units, d58], mode="overwrite")
            zf.write(path, f"{name}.uff")
            index.append({"id": r["id"], "file": f"{name}.uff", "index": r.get("index"),
                          "description": r.get("description"), "number": r.get("number"), "teeth": r.get("teeth"),
                          "quantity": "receptance h (tool tip, +X/+X)", "units": "m/N", "result_sha256":
                          r.get("result_sha256")})
        zf.writestr("index.json", json.dumps({"library_id": lib["id"], "revision": lib["revision"],
                                              "synced_utc": lib.get("synced_utc"), "tools": index}, indent=1))
    return buffer.getvalue()
