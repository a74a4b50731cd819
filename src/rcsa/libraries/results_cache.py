"""Content-addressed cache of computed tool-point results (derived data, safe to delete).

A result is filed under the SHA-256 of everything that determines it (``docs/architecture.md``
"Durable storage"), never under a tool or library id:

* the canonical JSON (:func:`canonical_json`: sorted keys, integers written as floats,
  ``-0.0`` as ``0.0``) of the combination (``holder``, ``tool``, ``joints``; its ``id`` left
  out, so a renamed tool keeps its result);
* the shared part of the request: the spindle, with a stored measurement named by the hash
  of its *content* (:func:`measurement_sha256`: frequency lines, receptances, plane, kind,
  points, artifact), not by its id; ``materials``, ``beam_theory``, ``shear_coefficient``
  and ``natural_frequencies`` (defaults filled in, so "left out" and "the default" agree);
  and, only when the request has one, its ``uncertainty`` option with every default filled in
  (:func:`rcsa.model.uncertainty.parse_uncertainty`: draws, seed, every tolerance), so a band
  is never served for another option and results without one keep their keys;
* the frequency grid as computed (SHA-256 of the float64 lines), so ``{start, stop, step}``
  and the same lines given as ``values_hz`` share results;
* the model: ``rcsa.__version__`` and :func:`model_fingerprint`, the SHA-256 of the *meaning*
  of every module that determines a prediction (:data:`MODEL_SOURCES`): its syntax tree
  without docstrings, comments or layout. Any change to what the physics computes gives new
  keys by itself — no version number to remember to bump — while a docstring, a comment or a
  reformatted line keeps every stored result.

Layout (under the cache directory, normally ``<store>/libraries/results``)::

    results.sqlite          one row per result (WAL, ``synchronous=FULL``): ``status``, ``meta``
                            (UTF-8 JSON of every other field), the float64 ``frequency_hz`` and
                            the complex128 tool-point receptances ``h, l, n, p`` as raw
                            little-endian bytes (ok results)

A chunk of results is written in one transaction (:meth:`ResultCache.put_many`): one durable
write per chunk, and a writer killed at any moment leaves either the whole chunk or none of
it. Rows are inserted ``OR IGNORE``: the same key always holds the same content, so a second
writer (a resumed sync, a retried chunk, another process) writes nothing twice. Rows are never
modified afterwards.
"""

from __future__ import annotations

import ast
import contextlib
import functools
import hashlib
import json
import math
import os
import sqlite3
import time
from collections.abc import Iterable, Iterator, Mapping
from contextlib import closing
from importlib import resources
from importlib.resources.abc import Traversable
from pathlib import Path
from typing import Any

import numpy as np
import orjson

from rcsa._version import __version__
from rcsa.errors import StoreError
from rcsa.infra.clock import utc_now_iso
from rcsa.infra.sqlite import connect, transaction
from rcsa.model.uncertainty import parse_uncertainty
from rcsa.model.wire import complex_from_wire, complex_to_wire

__all__ = [
    "MODEL_SOURCES",
    "RESULT_KEY_SCHEMA",
    "ResultCache",
    "canonical_json",
    "frequency_sha256",
    "measurement_sha256",
    "model_fingerprint",
    "result_key",
    "result_keys",
    "shared_part",
    "source_meaning",
]

#: What determines a computed result, relative to the ``rcsa`` package directory: all of the
#: physics and the model (segments, chain, solver, contract parsing, assembly building,
#: prediction) and, for measured spindles, the hybrid coupling and the artifact
#: identification. Every ``.py`` file under a directory counts.
MODEL_SOURCES = ("physics", "model", "measured/hybrid.py", "measured/artifact_identification.py")

#: Version of the key's own layout (bump if the set of hashed fields changes).
RESULT_KEY_SCHEMA = "rcsa.result-key/2"

_ARRAYS = ("h", "l", "n", "p")
_DEFAULTS = {"beam_theory": "timoshenko", "shear_coefficient": "hutchinson", "natural_frequencies": True}
_SHARED = ("materials", "beam_theory", "shear_coefficient", "natural_frequencies")
_TMP_MAX_AGE_S = 3600.0


def _normalise(value: Any) -> Any:
    """Numbers as floats (``-0.0`` → ``0.0``), tuples as lists, mapping keys as strings."""
    if isinstance(value, bool) or value is None or isinstance(value, str):
        return value
    if isinstance(value, int | float | np.integer | np.floating):
        x = float(value)
        if not math.isfinite(x):
            raise ValueError(f"canonical JSON has no place for {x!r}")
        return x + 0.0  # -0.0 + 0.0 == 0.0
    if isinstance(value, Mapping):
        return {str(k): _normalise(v) for k, v in value.items()}
    if isinstance(value, list | tuple | np.ndarray):
        return [_normalise(v) for v in value]
    raise TypeError(f"not JSON data: {type(value).__name__}")


def canonical_json(value: Any) -> bytes:
    """Canonical UTF-8 JSON of a JSON-like value: sorted keys, no spaces, numbers as floats.

    ``{"a": 1}`` and ``{"a": 1.0}`` give the same bytes, as do ``0.0`` and ``-0.0``; floats
    are written in Python's shortest round-trip form.

    Examples
    --------
    >>> canonical_json({"b": [1, -0.0], "a": {"y": 2.5, "x": True}})
    b'{"a":{"x":true,"y":2.5},"b":[1.0,0.0]}'
    """
    return json.dumps(_normalise(value), sort_keys=True, separators=(",", ":"), ensure_ascii=False,
                      allow_nan=False).encode()


def frequency_sha256(frequency_hz: np.ndarray) -> str:
    """SHA-256 (hex) of a frequency grid's float64 little-endian lines."""
    return hashlib.sha256(np.ascontiguousarray(frequency_hz, dtype="<f8").tobytes()).hexdigest()


def measurement_sha256(measurement: Any, *, coherence: bool = False) -> str:
    """SHA-256 (hex) of what a stored measurement contributes to a prediction.

    Covers the frequency lines, every receptance (name and complex128 values), and the
    metadata the coupling reads (``plane``, ``kind``, ``points_m``, ``artifact``); not its id,
    dates, names or notes. Two uploads of the same data hash the same.

    Parameters
    ----------
    measurement : rcsa.measured.store.Measurement
    coherence : bool
        Also the stored coherences (name and float64 values): what an uncertainty band's
        noise draws read.
    """
    digest = hashlib.sha256(b"rcsa.measurement-content/1\0")
    if coherence:
        digest.update(b"coherence\0")
        for name in sorted(measurement.coherence):
            digest.update(b"\0" + name.encode() + b"\0")
            digest.update(np.ascontiguousarray(measurement.coherence[name], dtype="<f8").tobytes())
    digest.update(np.ascontiguousarray(measurement.frequency_hz, dtype="<f8").tobytes())
    for name in sorted(measurement.frfs):
        digest.update(b"\0" + name.encode() + b"\0")
        digest.update(np.ascontiguousarray(measurement.frfs[name], dtype="<c16").tobytes())
    meta = measurement.meta
    artifact = None if meta.artifact is None else _thaw(meta.artifact)
    digest.update(canonical_json({"plane": meta.plane, "kind": meta.kind,
                                  "points_m": None if meta.points_m is None else list(meta.points_m),
                                  "artifact": artifact}))
    return digest.hexdigest()


def _thaw(value: Any) -> Any:
    if isinstance(value, Mapping):
        return {k: _thaw(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [_thaw(v) for v in value]
    return value


def shared_part(batch: Mapping[str, Any], measurement_sha: str | None) -> dict[str, Any]:
    """The part of a batch request every combination's key shares (see the module docstring).

    Parameters
    ----------
    batch : mapping
        A batch request (``spindle``, ``frequency``, ``materials``, …; ``combinations`` ignored).
    measurement_sha : str or None
        :func:`measurement_sha256` of the spindle's measurement when it is a stored one.
    """
    spindle = dict(batch.get("spindle") or {})
    if "measurement_id" in spindle:
        spindle.pop("measurement_id")
        spindle["measurement_sha256"] = measurement_sha
    out = {"spindle": spindle, "materials": batch.get("materials") or {}}
    for name in _SHARED[1:]:
        value = batch.get(name)
        out[name] = _DEFAULTS[name] if value is None else value
    if batch.get("uncertainty") is not None:
        option = parse_uncertainty(batch["uncertainty"], measured_spindle=measurement_sha is not None)
        assert option is not None  # not None: given
        out["uncertainty"] = option.to_dict()
    return out


def _source_files(node: Traversable, rel: str) -> Iterator[tuple[str, Traversable]]:
    """``(relative path, file)`` of every ``.py`` file at or under ``node`` (bytecode caches skipped)."""
    if node.is_file():
        if node.name.endswith(".py"):
            yield rel, node
    elif node.is_dir() and node.name != "__pycache__":
        for child in node.iterdir():
            yield from _source_files(child, f"{rel}/{child.name}")


_DOCUMENTED = (ast.Module, ast.ClassDef, ast.FunctionDef, ast.AsyncFunctionDef)


def _is_docstring(statement: ast.stmt) -> bool:
    return isinstance(statement, ast.Expr) and isinstance(statement.value, ast.Constant) \
        and isinstance(statement.value.value, str)


def _canonical(node: Any) -> str:
    """A syntax tree written out field by field, docstrings left out, the same on every Python.

    Positions are not written (they are attributes, not fields), nor are empty fields (a field
    a newer Python adds, such as ``type_params``, is empty in code that does not use it), nor
    the first statement of a module, class or function body when it is a string (its
    docstring).
    """
    if isinstance(node, ast.AST):
        fields = []
        for name in sorted(node._fields):
            value = getattr(node, name, None)
            if name == "body" and isinstance(node, _DOCUMENTED) and value and _is_docstring(value[0]):
                value = value[1:]
            if value is None or value == [] or (name == "kind" and isinstance(node, ast.Constant)):
                continue
            fields.append(f"{name}={_canonical(value)}")
        return f"{type(node).__name__}({','.join(fields)})"
    if isinstance(node, list):
        return "[" + ",".join([_canonical(v) for v in node]) + "]"
    return f"{type(node).__name__}:{node!r}"


def source_meaning(source: str | bytes) -> bytes:
    """What a module's source means to the interpreter: its syntax tree, docstrings left out.

    Comments, blank lines, layout and docstrings do not change it; any change to a name, a
    number, an operator or a statement does.

    Parameters
    ----------
    source : str or bytes
        Python source.

    Examples
    --------
    >>> documented = "def f(x):\\n    'Twice x.'\\n    return 2 * x  # doubled\\n"
    >>> source_meaning(documented) == source_meaning("def f(x): return 2*x")
    True
    >>> source_meaning("def f(x): return 2*x") == source_meaning("def f(x): return 3*x")
    False
    """
    return _canonical(ast.parse(source)).encode()


def _fingerprint(package: Traversable) -> str:
    digest = hashlib.sha256(b"rcsa.model-fingerprint/2\0")
    files = [f for source in MODEL_SOURCES for f in _source_files(package.joinpath(*source.split("/")), source)]
    if not files:
        raise FileNotFoundError(f"no model source under {package}")
    for rel, file in sorted(files, key=lambda f: f[0]):
        data = source_meaning(file.read_bytes())
        digest.update(rel.encode() + b"\0" + len(data).to_bytes(8, "little"))
        digest.update(data)
    return digest.hexdigest()


@functools.cache
def _installed_fingerprint() -> str:
    return _fingerprint(resources.files("rcsa"))


def model_fingerprint(root: str | os.PathLike[str] | None = None) -> str:
    """SHA-256 (hex) of what every module that determines a prediction means.

    The files of :data:`MODEL_SOURCES`, sorted by their path relative to the package, each
    hashed with its path as :func:`source_meaning` (its syntax tree without docstrings). Any
    change to the code (a physics change, a fixed bug) changes the fingerprint, and with it
    every :func:`result_key`, so stale results are never served; a change to a docstring or
    a comment changes nothing, so stored results stay valid.

    Parameters
    ----------
    root : str or os.PathLike, optional
        A directory holding the ``rcsa`` package's files (``src/rcsa``). Default: the
        installed package, read once per process.

    Returns
    -------
    str
        64 hex digits.
    """
    if root is None:
        return _installed_fingerprint()
    return _fingerprint(Path(root))


def result_key(combination: Mapping[str, Any], shared: Mapping[str, Any], frequency_sha: str) -> str:
    """The cache key (SHA-256 hex) of one combination's result.

    Parameters
    ----------
    combination : mapping
        ``{"id", "holder", "tool", "joints"}`` as in a batch request (``id`` is ignored).
    shared : mapping
        :func:`shared_part` of the request.
    frequency_sha : str
        :func:`frequency_sha256` of the computed grid.
    """
    doc = {"schema": RESULT_KEY_SCHEMA, "model_fingerprint": model_fingerprint(), "rcsa_version": __version__,
           "combination": {k: v for k, v in combination.items() if k != "id"},
           "shared": shared, "frequency_sha256": frequency_sha}
    return hashlib.sha256(canonical_json(doc)).hexdigest()


def result_keys(combinations: Iterable[Mapping[str, Any]], shared: Mapping[str, Any], frequency_sha: str
                ) -> list[str]:
    """:func:`result_key` of many combinations sharing ``shared`` (the same keys, faster).

    The canonical JSON of the shared part is written once and spliced into each key's
    document (sorted keys: ``combination`` comes first, ``shared`` last), and the canonical
    JSON of each value of a combination (its holder, tool, joints) is remembered by its
    exact JSON text, so a holder shared by a thousand tools is normalised once.
    """
    doc = {"schema": RESULT_KEY_SCHEMA, "model_fingerprint": model_fingerprint(), "rcsa_version": __version__,
           "frequency_sha256": frequency_sha}
    middle = canonical_json(doc)[1:-1]  # "frequency_sha256":...,"schema":...: between combination and shared
    tail = b',' + middle + b',"shared":' + canonical_json(shared) + b'}'
    memo: dict[bytes, bytes] = {}

    def value_json(value: Any) -> bytes:
        try:
            text = orjson.dumps(value, option=orjson.OPT_SORT_KEYS)
        except TypeError:  # numpy values and the like: no shortcut
            return canonical_json(value)
        found = memo.get(text)
        if found is None:
            found = memo[text] = canonical_json(value)
        return found

    keys = []
    for combination in combinations:
        parts = sorted((str(k), v) for k, v in combination.items() if k != "id")
        body = b",".join(canonical_json(k) + b":" + value_json(v) for k, v in parts)
        keys.append(hashlib.sha256(b'{"combination":{' + body + b'}' + tail).hexdigest())
    return keys


class ResultCache:
    """Computed results filed by :func:`result_key`; safe for several processes and crashes.

    Results live as rows of one SQLite database (``results.sqlite`` in ``directory``, WAL,
    ``synchronous=FULL``): :meth:`put_many` writes a whole chunk of results in **one
    transaction**, so a chunk costs one durable write (one log sync) instead of one
    ``fsync`` per result file. Rows are inserted ``OR IGNORE`` by key — a result is content,
    so a second writer of the same key (a resumed sync, a retried chunk, another process)
    changes nothing and nothing is ever stored twice.

    Parameters
    ----------
    directory : str or os.PathLike
        Where the results live (created on first use).
    tmp : str or os.PathLike
        Scratch directory beside it (temporary files of writers that died are removed by
        :meth:`clean_tmp`).
    """

    def __init__(self, directory: str | os.PathLike[str], tmp: str | os.PathLike[str]) -> None:
        self.directory = Path(directory)
        self.tmp = Path(tmp)
        self.directory.mkdir(parents=True, exist_ok=True)
        self.tmp.mkdir(parents=True, exist_ok=True)
        self.database = self.directory / "results.sqlite"
        with closing(self._connect()) as con:
            con.executescript(_SCHEMA)

    def __repr__(self) -> str:
        return f"ResultCache({str(self.directory)!r})"

    def _connect(self) -> sqlite3.Connection:
        # FULL: a library commit references these rows as soon as put_many returns
        try:
            con = connect(self.database, synchronous="FULL", timeout_s=_BUSY_TIMEOUT_S)
            con.execute(f"PRAGMA journal_size_limit={_WAL_LIMIT_BYTES}")
        except sqlite3.Error as exc:
            raise StoreError(f"cannot open the result cache {self.database}: {exc}") from None
        return con

    def __contains__(self, key: object) -> bool:
        return isinstance(key, str) and not self.missing([key])

    def missing(self, keys: Iterable[str]) -> set[str]:
        """The keys of ``keys`` that have no stored result (one query per 500 keys)."""
        wanted = list(dict.fromkeys(keys))
        for key in wanted:
            _check_key(key)
        found: set[str] = set()
        with closing(self._connect()) as con:
            for start in range(0, len(wanted), _KEYS_PER_QUERY):
                part = wanted[start:start + _KEYS_PER_QUERY]
                found.update(r[0] for r in con.execute(
                    f"SELECT key FROM results WHERE key IN ({','.join('?' * len(part))})", part))
        return {k for k in wanted if k not in found}

    def get(self, key: str) -> dict[str, Any]:
        """The stored result document (numpy arrays for the long arrays).

        Raises
        ------
        KeyError
            Not in the cache.
        StoreError
            The stored result is unreadable.
        """
        _check_key(key)
        with closing(self._connect()) as con:
            row = con.execute(f"SELECT {_ROW} FROM results WHERE key = ?", (key,)).fetchone()
        if row is None:
            raise KeyError(key)
        try:
            return _decode(row)
        except (ValueError, orjson.JSONDecodeError) as exc:
            raise StoreError(f"unreadable cached result {key}: {exc}") from None

    def status(self, key: str) -> str:
        """``status`` of a stored result (``ok`` or ``error``) without loading its arrays."""
        return str(self.statuses([key])[key]["status"])

    def statuses(self, keys: Iterable[str]) -> dict[str, dict[str, Any]]:
        """``{key: {"status", "error"}}`` of stored results, without loading their arrays.

        Raises
        ------
        KeyError
            One of the keys is not in the cache.
        """
        wanted = list(dict.fromkeys(keys))
        out: dict[str, dict[str, Any]] = {}
        with closing(self._connect()) as con:
            for start in range(0, len(wanted), _KEYS_PER_QUERY):
                part = wanted[start:start + _KEYS_PER_QUERY]
                for key, status, meta in con.execute(
                        f"SELECT key, status, meta FROM results WHERE key IN ({','.join('?' * len(part))})", part):
                    out[key] = {"status": status, "error": orjson.loads(meta).get("error")}
        for key in wanted:
            if key not in out:
                raise KeyError(key)
        return out

    def put_many(self, items: Iterable[tuple[str, Mapping[str, Any]]]) -> int:
        """Store results (``(key, result document)`` pairs) in one transaction; return how many
        were new (a key already stored is left as it is: same key, same content).

        Every result is on stable storage when this returns (one log sync for all of them).
        """
        rows = [(key, *_encode(doc)) for key, doc in items]
        for row in rows:
            _check_key(row[0])
        if not rows:
            return 0
        now = utc_now_iso()
        try:
            with closing(self._connect()) as con, transaction(con):
                before = con.total_changes
                con.executemany(f"INSERT OR IGNORE INTO results ({_COLUMNS}) VALUES ({','.join('?' * 9)})",
                                [(*row, now) for row in rows])
                return con.total_changes - before
        except sqlite3.Error as exc:
            raise StoreError(f"could not write cached results to {self.database}: {exc}") from None

    def clean_tmp(self, older_than_s: float = _TMP_MAX_AGE_S) -> int:
        """Remove temporary files left by writers that died (older than ``older_than_s``)."""
        cutoff, n = time.time() - older_than_s, 0
        with os.scandir(self.tmp) as it:
            for e in it:
                with contextlib.suppress(OSError):
                    if e.name.endswith(".tmp") and e.stat().st_mtime < cutoff:
                        os.unlink(e.path)
                        n += 1
        return n


_SCHEMA = """
CREATE TABLE IF NOT EXISTS results (
    key           TEXT PRIMARY KEY,
    status        TEXT NOT NULL,
    meta          TEXT NOT NULL,
    frequency_hz  BLOB,
    h             BLOB,
    l             BLOB,
    n             BLOB,
    p             BLOB,
    created_utc   TEXT NOT NULL
);
"""
_COLUMNS = "key, status, meta, frequency_hz, h, l, n, p, created_utc"
_ROW = "status, meta, frequency_hz, h, l, n, p"
_KEYS_PER_QUERY = 500
_BUSY_TIMEOUT_S = 60.0
_WAL_LIMIT_BYTES = 64 * 1024 * 1024


def _check_key(key: str) -> None:
    if not isinstance(key, str) or len(key) != 64 or not all(c in "0123456789abcdef" for c in key):
        raise ValueError(f"not a result key: {key!r}")


def _encode(doc: Mapping[str, Any]) -> tuple[str, str, bytes | None, bytes | None, bytes | None, bytes | None,
                                           bytes | None]:
    """A result document as a row: status, ``meta`` (UTF-8 JSON of every other field) and the
    float64 lines and complex128 receptances as little-endian bytes (None where absent)."""
    meta = {k: v for k, v in doc.items() if k not in ("id", "status", "frequency_hz", "tool_point")}
    blobs: dict[str, bytes | None] = dict.fromkeys(("frequency_hz", *_ARRAYS))
    if "frequency_hz" in doc:
        f = np.ascontiguousarray(doc["frequency_hz"], dtype="<f8")
        blobs["frequency_hz"] = f.tobytes()
        for k, v in (doc.get("tool_point") or {}).items():
            blobs[k] = np.ascontiguousarray(complex_from_wire(v, f"tool_point.{k}", f.size, finite=False),
                                            dtype="<c16").tobytes()
    h, l_, n, p = (blobs[k] for k in _ARRAYS)
    return (str(doc.get("status", "ok")), orjson.dumps(meta, option=orjson.OPT_SERIALIZE_NUMPY).decode(),
            blobs["frequency_hz"], h, l_, n, p)


def _decode(row: tuple[Any, ...]) -> dict[str, Any]:
    status, meta, frequency, *arrays = row
    doc: dict[str, Any] = {"status": status}
    if frequency is not None:
        doc["frequency_hz"] = np.frombuffer(frequency, dtype="<f8").copy()
        doc["tool_point"] = {k: complex_to_wire(np.frombuffer(a, dtype="<c16"), arrays="numpy")
                             for k, a in zip(_ARRAYS, arrays, strict=True) if a is not None}
    doc.update(orjson.loads(meta))
    return doc
