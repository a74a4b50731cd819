"""Result documents as bytes: the contract's JSON written straight from arrays, or HDF5 / Parquet.

**JSON.** Every result the CLI prints, the service answers, a job streams to disk or a
library export writes goes through :func:`json_bytes`: orjson with numpy arrays serialised
directly (``OPT_SERIALIZE_NUMPY``: no Python list, no Python float per value). The bytes are
those of today's path — ``Prediction.to_dict()`` (lists) then orjson — exactly: the same
shortest round-trip float text (``1e-6``, ``1e+16``, ``-0.0``), the same key order, and the
same null policy (NaN and ±inf are ``null``, as orjson writes a non-finite Python float);
``tests/app/test_results.py`` holds them to golden files captured before the change.
A :class:`~rcsa.model.prediction.Prediction` may be given as it is (its
``to_dict(arrays="numpy")`` is written); so may non-contiguous float arrays (copied once).

**Binary.** Batches, library predictions and a stored library's results may be written as
HDF5 (h5py, a core dependency) or as an Apache Parquet table (pyarrow, the optional extra
``rcsa[parquet]``), chosen by media type (REST ``Accept``) or by file suffix (CLI ``-o``):
:data:`FORMATS`, :func:`format_of_suffix`, :func:`write_result`. Their layouts and the
bit-exactness rules are in :mod:`rcsa.libraries.exports`.
"""

from __future__ import annotations

import io
import os
import secrets
from collections.abc import Mapping
from pathlib import Path
from typing import Any, BinaryIO, Literal

import numpy as np
import orjson

from rcsa.errors import InputError
from rcsa.infra.atomic_files import atomic_write_bytes
from rcsa.libraries.exports import (
    PARQUET_EXTRA,
    ResultsWriter,
    hdf5_writer,
    parquet_available,
    parquet_writer,
)
from rcsa.model.prediction import Prediction

__all__ = ["FORMATS", "JSON_MEDIA", "MEDIA_TYPES", "PARQUET_EXTRA", "RESULT_FORMAT_FIELD", "Format", "binary_writer", "encode_result",
           "format_of_suffix", "json_bytes", "missing_extra", "require_format", "write_document", "write_result"]

#: A result form: the contract's JSON, HDF5, or a Parquet table.
Format = Literal["json", "hdf5", "parquet"]
#: The JSON media type.
JSON_MEDIA = "application/json"
#: Media type of each form (``Accept`` on REST).
MEDIA_TYPES: dict[Format, str] = {"json": JSON_MEDIA, "hdf5": "application/x-hdf5",
                                  "parquet": "application/vnd.apache.parquet"}
#: Field of a batch or library work request naming the form its job writes (absent: JSON).
RESULT_FORMAT_FIELD = "result_format"
#: File suffixes of each form (``-o`` on the CLI).
FORMATS: dict[str, Format] = {".json": "json", ".h5": "hdf5", ".hdf5": "hdf5", ".parquet": "parquet"}

_OPTIONS = orjson.OPT_SERIALIZE_NUMPY


def _default(value: Any) -> Any:
    """What orjson cannot write itself: a strided float array, a numpy scalar."""
    if isinstance(value, np.ndarray) and value.dtype.kind in "fiub":
        return np.ascontiguousarray(value)
    if isinstance(value, np.generic) and value.dtype.kind in "fiub":
        return value.item()
    raise TypeError(f"cannot write a {type(value).__name__} as JSON")


def json_bytes(document: Any, *, indent: bool = False) -> bytes:
    """The contract's JSON of a result document, written straight from its arrays.

    Parameters
    ----------
    document : dict, list or Prediction
        A result document whose long arrays may be numpy arrays (``to_dict(arrays="numpy")``);
        a Prediction is written as its ``to_dict(arrays="numpy")``.
    indent : bool
        Two-space indentation (what the CLI prints); compact otherwise (REST, jobs, exports).

    Returns
    -------
    bytes
        UTF-8 JSON, no trailing newline; non-finite numbers as ``null``.

    Examples
    --------
    >>> json_bytes({"h": {"real": np.array([1e-6, np.nan]), "imag": np.array([-0.0, 2.5])}})
    b'{"h":{"real":[1e-6,null],"imag":[-0.0,2.5]}}'
    """
    if isinstance(document, Prediction):  # a dataclass, which orjson would write field by field
        document = document.to_dict(arrays="numpy")
    return orjson.dumps(document, default=_default, option=_OPTIONS | (orjson.OPT_INDENT_2 if indent else 0))


def format_of_suffix(path: str | os.PathLike[str], field: str = "out",
                     allowed: tuple[Format, ...] = ("json", "hdf5", "parquet")) -> Format:
    """The result form a file name asks for by its suffix.

    Raises
    ------
    InputError
        Naming ``field``: a suffix of no allowed form.
    """
    fmt = FORMATS.get(Path(path).suffix.lower())
    if fmt is None or fmt not in allowed:
        suffixes = ", ".join(s for s, f in FORMATS.items() if f in allowed)
        raise InputError(field, f"{path}: the file name must end in {suffixes}")
    return fmt


def missing_extra(fmt: str) -> str | None:
    """What to install for a result form, or None when it is available (Parquet needs pyarrow)."""
    if fmt == "parquet" and not parquet_available():
        return f"Parquet results need pyarrow, the extra rcsa[{PARQUET_EXTRA}] (pip install 'rcsa[{PARQUET_EXTRA}]')"
    return None


def require_format(fmt: Format) -> None:
    """Refuse a form whose optional library is not installed (Parquet without pyarrow).

    Raises
    ------
    InputError
        Field ``format``, naming the extra to install.
    """
    missing = missing_extra(fmt)
    if missing is not None:
        raise InputError("format", missing)


def binary_writer(fmt: Format, fh: BinaryIO | str | os.PathLike[str], kind: str) -> ResultsWriter:
    """A writer of one result document in a binary form, result by result (for streaming jobs).

    Parameters
    ----------
    fmt : {"hdf5", "parquet"}
    fh : binary file or path
        Where to write (seekable for HDF5).
    kind : {"batch", "library", "library-results"}
        What the document is (its schema name).
    """
    require_format(fmt)
    if fmt == "hdf5":
        return hdf5_writer(fh, kind)
    if fmt == "parquet":
        return parquet_writer(fh, kind)
    raise InputError("format", f"{fmt!r} is not a binary result form (hdf5, parquet)")


def encode_result(document: Mapping[str, Any], fmt: Format, kind: str) -> bytes:
    """A whole result document (``{head..., "results": [...], "summary"}``) as bytes of a form.

    Parameters
    ----------
    document : mapping
        A batch result, library prediction or stored library's results.
    fmt : {"json", "hdf5", "parquet"}
    kind : {"batch", "library", "library-results"}
    """
    if fmt == "json":
        return json_bytes(document)
    buffer = io.BytesIO()
    write_document(binary_writer(fmt, buffer, kind), document)
    return buffer.getvalue()


def write_document(writer: ResultsWriter, document: Mapping[str, Any]) -> None:
    """Give a binary writer a whole document and close it."""
    with writer:
        writer.head({k: v for k, v in document.items() if k not in ("results", "summary")})
        for result in document["results"]:
            writer.result(result)
        writer.summary(document["summary"])


def write_result(document: Mapping[str, Any], path: str | os.PathLike[str], kind: str, *,
                 indent: bool = False) -> Format:
    """Write a result document to ``path`` in the form its suffix names (atomically).

    Parameters
    ----------
    document : mapping
    path : path
        ``.json``, ``.h5``/``.hdf5`` or ``.parquet``.
    kind : {"batch", "library", "library-results"}
    indent : bool
        JSON only: indented as the CLI prints it.

    Returns
    -------
    str
        The form written.

    Raises
    ------
    InputError
        A suffix of no form, or Parquet without pyarrow.
    OSError
        The file cannot be written.
    """
    fmt = format_of_suffix(path)
    if fmt == "json":
        atomic_write_bytes(Path(path), json_bytes(document, indent=indent) + (b"\n" if indent else b""))
        return fmt
    require_format(fmt)
    final = Path(path)
    tmp = final.with_name(f".{final.name}.{os.getpid()}.{secrets.token_hex(4)}.tmp")
    try:  # written in place result by result (no copy of the file in memory), then renamed
        with open(tmp, "w+b") as fh:
            write_document(binary_writer(fmt, fh, kind), document)
            fh.flush()
            os.fsync(fh.fileno())
        os.replace(tmp, final)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise
    return fmt
