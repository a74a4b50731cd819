"""Result files for other software: HDF5 and Parquet (batches, libraries), a zip of UFF 58 files.

A batch result, a library prediction or a stored library's results
(:meth:`rcsa.libraries.sync.LibraryStore.results`) — ``{head..., "results": [...], "summary"}``
— is written result by result (:class:`ResultsWriter`; jobs stream it to disk). Every number is
the JSON's to the last bit: the long arrays (``frequency_hz``, each ``tool_point`` receptance,
an uncertainty band's ``h_magnitude_m_n`` percentiles) are stored as float64 / complex128, and
everything else of every result — errors, skipped entries, natural frequencies, peaks, notes,
modal fits — as JSON (:func:`split_result`), so a reader can rebuild the JSON document exactly.
Tool-point receptances are symmetric (reciprocity: ``n`` equals ``l`` bit for bit on the
analytical model), so ``n`` is stored only where it differs from ``l``.

HDF5 (``application/x-hdf5``, schema version 2; one row per ok result)::

    /                     schema ("rcsa.batch-results", "rcsa.library-prediction" or
                          "rcsa.library-results"), schema_version=2, kind, exported_utc,
                          software_version, convention, head_json, summary_json; a stored
                          library's also library_id, revision, synced_utc, source,
                          library_sha256, model_version
    /frequency_hz         float64 (m,), units="Hz"
    /result               int32 (k,): each row's position in the document's results
    /id                   str (k,): each row's id
    /tool_point/h, l, n, p          complex128 (k, m), units, quantity="receptance"
    /tool_point/n_is_l              bool (k,): that row of n is l's (and not stored)
    /uncertainty/h_magnitude_<p>_m_n float64 (k, m), with an uncertainty band
    /results_json         str: JSON list of every result's other fields, in order
    /index_json           str: JSON list of (id, index, status, reason, error, row)

Parquet (``application/vnd.apache.parquet``, the extra ``rcsa[parquet]``): one row per ok result
and line, see :class:`ParquetResults`.

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

import numpy as np
import orjson

from rcsa._version import __version__
from rcsa.infra.clock import utc_now_iso
from rcsa.model.wire import CONVENTION, RECEPTANCE_UNITS, complex_from_wire

__all__ = ["HDF5_SCHEMA", "PARQUET_EXTRA", "SCHEMAS", "Hdf5Results", "ParquetResults", "ResultsWriter", "hdf5_writer",
           "library_hdf5", "library_uff_zip", "parquet_available", "parquet_writer", "split_result",
           "tool_file_names"]

HDF5_SCHEMA = "rcsa.library-results"
#: 2: one row per ok result in stacked datasets (1: one group per tool), and every field kept.
SCHEMA_VERSION = 2
#: Schema name of each kind of result document in a binary file.
SCHEMAS = {"library-results": HDF5_SCHEMA, "batch": "rcsa.batch-results", "library": "rcsa.library-prediction"}
#: The optional extra that installs pyarrow (Parquet results).
PARQUET_EXTRA = "parquet"
#: Rows of a Parquet row group (at least; whole results are never split).
PARQUET_ROW_GROUP = 1 << 17


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


def split_result(result: Mapping[str, Any], pairs: bool = False) -> tuple[dict[str, Any], dict[str, np.ndarray]]:
    """A result's long arrays (one value per frequency line) apart from everything else.

    Parameters
    ----------
    result : mapping
        One entry of a batch or library result (any status).
    pairs : bool
        Receptances as ``<r>_real`` and ``<r>_imag`` float64 arrays (the JSON's own arrays
        when they are already float64) instead of complex128 ``<r>``.

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
        if pairs:
            arrays[f"{name}_real"], arrays[f"{name}_imag"] = _pair(pair, f"{ident}.tool_point.{name}")
        else:
            arrays[name] = _complex(pair, f"{ident}.tool_point.{name}")
    band = result.get("uncertainty")
    if isinstance(band, Mapping) and isinstance(band.get("h_magnitude_m_n"), Mapping):
        fields["uncertainty"] = {**band, "h_magnitude_m_n": dict.fromkeys(band["h_magnitude_m_n"])}
        for p, values in band["h_magnitude_m_n"].items():
            arrays[f"h_magnitude_{p}_m_n"] = np.array(values, dtype=np.float64)
    return fields, arrays


def _complex(pair: Any, field: str) -> np.ndarray:
    """``{"real", "imag"}`` as complex128: one copy when both are float64 arrays (results rcsa made)."""
    if isinstance(pair, Mapping) and set(pair) == {"real", "imag"}:
        re, im = pair["real"], pair["imag"]
        if isinstance(re, np.ndarray) and isinstance(im, np.ndarray) and re.dtype == im.dtype == np.float64 \
                and re.ndim == im.ndim == 1 and re.shape == im.shape:
            out = np.empty(re.shape, dtype=np.complex128)
            out.real, out.imag = re, im
            return out
    return complex_from_wire(pair, field, finite=False)


def _pair(pair: Any, field: str) -> tuple[np.ndarray, np.ndarray]:
    """``{"real", "imag"}`` as two float64 arrays (no copy when they already are)."""
    if isinstance(pair, Mapping) and set(pair) == {"real", "imag"}:
        re, im = pair["real"], pair["imag"]
        if isinstance(re, np.ndarray) and isinstance(im, np.ndarray) and re.dtype == im.dtype == np.float64 \
                and re.ndim == im.ndim == 1 and re.shape == im.shape:
            return np.ascontiguousarray(re), np.ascontiguousarray(im)
    z = complex_from_wire(pair, field, finite=False)
    return np.ascontiguousarray(z.real), np.ascontiguousarray(z.imag)


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

    #: Receptances as real and imaginary float64 arrays (see :func:`split_result`).
    pairs = False

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
        fields, arrays = split_result(result, self.pairs)
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
                           "row": self._write(len(self.fields) - 1, result, arrays) if ok else None})

    def summary(self, summary: Mapping[str, Any]) -> None:
        """The document's ``summary``."""
        self.summary_doc = dict(summary)

    def _write(self, position: int, result: Mapping[str, Any], arrays: dict[str, np.ndarray]) -> int | None:
        """Store an ok result's arrays; its row in the file's stacked arrays (None: found by column)."""
        raise NotImplementedError

    def close(self, failed: bool = False) -> None:
        """Finish the file (its index and metadata); on failure only release it."""
        raise NotImplementedError


def _hdf5_fields(kind: str, head: Mapping[str, Any]) -> dict[str, Any]:
    """Root attributes of the file."""
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


#: Bytes of one chunk of a stacked dataset, at most (whole rows; one row when a row is larger).
HDF5_CHUNK_BYTES = 1 << 18


class Hdf5Results(ResultsWriter):
    """HDF5 form of a result document (layout in the module docstring), written row by row.

    Parameters
    ----------
    target : binary file or path
        A readable, seekable binary file (e.g. a job's result file, ``io.BytesIO``) or a path.
    kind : {"library-results", "batch", "library"}
    """

    def __init__(self, target: BinaryIO | str | os.PathLike[str], kind: str) -> None:
        import h5py

        super().__init__(kind)
        self.h5py = h5py
        self.file = h5py.File(target, "w")
        self.rows = 0
        self.datasets: dict[str, Any] = {}
        self.positions: list[int] = []
        self.ids: list[str] = []
        self.n_is_l: list[bool] = []

    def _dataset(self, key: str, values: np.ndarray) -> Any:
        d = self.datasets.get(key)
        if d is None:
            m = values.size
            rows = max(1, HDF5_CHUNK_BYTES // max(1, m * values.itemsize))
            parent = "tool_point" if key in RECEPTANCE_UNITS else "uncertainty"
            d = self.file.require_group(parent).create_dataset(key, shape=(0, m), maxshape=(None, m),
                                                               dtype=values.dtype, chunks=(rows, m))
            if key in RECEPTANCE_UNITS:
                d.attrs["units"], d.attrs["quantity"] = RECEPTANCE_UNITS[key], "receptance"
            else:
                d.attrs["units"], d.attrs["quantity"] = "m/N", "percentile of |h| over the uncertainty draws"
            self.datasets[key] = d
        elif d.shape[1] != values.size:
            raise ValueError(f"{key} has {values.size} values per result, the first had {d.shape[1]}")
        return d

    def _write(self, position: int, result: Mapping[str, Any], arrays: dict[str, np.ndarray]) -> int:
        row = self.rows
        if self.datasets and set(arrays) != set(self.datasets):
            raise ValueError(f"result {result.get('id')!r} has the arrays {sorted(arrays)}, the first had "
                             f"{sorted(self.datasets)}")
        same = "n" in arrays and "l" in arrays and _same_bits(arrays["n"], arrays["l"])
        for key, values in arrays.items():
            d = self._dataset(key, values)
            d.resize(row + 1, axis=0)
            if not (key == "n" and same):  # reciprocity: n is l's bits, its row stays unwritten (no storage)
                d[row] = values
        self.rows = row + 1
        self.positions.append(position)
        self.ids.append(str(result.get("id")))
        self.n_is_l.append(same)
        return row

    def close(self, failed: bool = False) -> None:
        """Write the index and the JSON fields, and close the file."""
        try:
            if not failed:
                f = self.file
                fd = f.create_dataset("frequency_hz", data=np.zeros(0) if self.frequency_hz is None
                                      else self.frequency_hz)
                fd.attrs["units"] = "Hz"
                f.create_dataset("result", data=np.array(self.positions, dtype=np.int32))
                f.create_dataset("id", data=self.ids, dtype=self.h5py.string_dtype())
                if "n" in self.datasets:
                    f["tool_point"].create_dataset("n_is_l", data=np.array(self.n_is_l, dtype=bool))
                for key, value in _hdf5_fields(self.kind, self.head_doc).items():
                    f.attrs[key] = value
                f.attrs["head_json"] = _json(self.head_doc)
                f.attrs["summary_json"] = _json(self.summary_doc)
                f.create_dataset("results_json", data=_json(self.fields))
                f.create_dataset("index_json", data=_json(self.index))
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

    Columns: ``result`` (int32, the result's position in ``results``), ``id`` (string),
    ``frequency_hz`` (these three dictionary-encoded in the file), ``<r>_real`` and ``<r>_imag`` for each receptance ``r`` of
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
        Parquet codec (``"none"``: the fastest to write, about 0.3 of the JSON's bytes;
        ``"zstd"`` about 0.2, byte-stream-split encoded, at about twice the write time).
    """

    pairs = True

    def __init__(self, target: BinaryIO | str | os.PathLike[str], kind: str, compression: str = "none") -> None:
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
        ids = pa.array([ident for _, ident, _ in self.pending])
        # the repeated columns are given dictionary-encoded, as the file stores them (nothing to hash)
        zeros, lines = np.zeros(m, dtype=np.int32), np.arange(m, dtype=np.int32)
        frequency = pa.DictionaryArray.from_arrays(lines, pa.array(self.frequency_hz))
        columns: dict[str, Any] = {
            "result": pa.chunked_array([pa.DictionaryArray.from_arrays(zeros, pa.array([p], pa.int32()))
                                        for p, _, _ in self.pending]),
            "id": pa.chunked_array([pa.DictionaryArray.from_arrays(np.full(m, j, dtype=np.int32), ids)
                                    for j in range(len(self.pending))]),
            "frequency_hz": pa.chunked_array([frequency] * len(self.pending)),
        }
        for key in self.names:
            if key.startswith("n_") and "l_real" in self.names:  # n null where it is l's bits (reciprocity)
                columns[key] = pa.chunked_array([
                    pa.nulls(m, pa.float64()) if _same_bits(a["n_real"], a["l_real"]) and
                    _same_bits(a["n_imag"], a["l_imag"]) else pa.array(a[key]) for _, _, a in self.pending])
            else:
                columns[key] = pa.chunked_array([pa.array(a[key]) for _, _, a in self.pending])
        table = pa.table(columns)
        if self.writer is None:
            floats = [c for c in table.column_names if c not in ("result", "id", "frequency_hz")]
            encoding = {} if self.compression == "none" else \
                {"column_encoding": dict.fromkeys(floats, "BYTE_STREAM_SPLIT")}
            self.writer = pq.ParquetWriter(self.target, table.schema, compression=self.compression,
                                           use_dictionary=["result", "id", "frequency_hz"],
                                           write_statistics=False, store_schema=False, **encoding)
        self.writer.write_table(table.combine_chunks() if len(self.pending) > 1 and m < 4096 else table,
                                row_group_size=max(self.rows, 1))
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
            schema = pa.schema([("result", pa.int32()), ("id", pa.string()), ("frequency_hz", pa.float64())])
            self.writer = pq.ParquetWriter(self.target, schema, store_schema=False)
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
