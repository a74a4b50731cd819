"""Content-addressed cache of computed tool-point results (derived data, safe to delete).

A result is filed under the SHA-256 of everything that determines it (``ecosystem.md``
§3.4), never under a tool or library id:

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
* the model: ``rcsa.__version__`` and :func:`model_fingerprint`, the SHA-256 of the source of
  every module that determines a prediction (:data:`MODEL_SOURCES`), so any change to the
  physics gives new keys by itself — no version number to remember to bump.

Layout (under the cache directory, normally ``<store>/libraries/results``)::

    <key[:2]>/<key>.npz     one uncompressed numpy archive per result: ``frequency_hz`` and the
                            complex128 tool-point receptances ``h, l, n, p`` (ok results), and
                            ``meta`` (UTF-8 JSON of every other field, ``status`` included)

Files are written to ``tmp/`` (a sibling given to :class:`ResultCache`), fsynced and renamed
into place, so a reader never sees half a result and a writer killed at any moment leaves at
worst a stray temporary file. Two processes writing the same key write the same content; the
second rename just replaces the first. Files are never modified afterwards.
"""

from __future__ import annotations

import contextlib
import functools
import hashlib
import json
import math
import os
import secrets
import time
from collections.abc import Iterable, Iterator, Mapping
from importlib import resources
from importlib.resources.abc import Traversable
from pathlib import Path
from typing import Any

import numpy as np
import orjson

from rcsa._version import __version__
from rcsa.errors import StoreError
from rcsa.infra.atomic_files import fsync_dir
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
    "shared_part",
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


def _fingerprint(package: Traversable) -> str:
    digest = hashlib.sha256(b"rcsa.model-fingerprint/1\0")
    files = [f for source in MODEL_SOURCES for f in _source_files(package.joinpath(*source.split("/")), source)]
    if not files:
        raise FileNotFoundError(f"no model source under {package}")
    for rel, file in sorted(files, key=lambda f: f[0]):
        data = file.read_bytes()
        digest.update(rel.encode() + b"\0" + len(data).to_bytes(8, "little"))
        digest.update(data)
    return digest.hexdigest()


@functools.cache
def _installed_fingerprint() -> str:
    return _fingerprint(resources.files("rcsa"))


def model_fingerprint(root: str | os.PathLike[str] | None = None) -> str:
    """SHA-256 (hex) of the source of every module that determines a prediction.

    The files of :data:`MODEL_SOURCES`, sorted by their path relative to the package, each
    hashed with its path and length. Any edit to one of them (a physics change, a fixed bug)
    changes the fingerprint, and with it every :func:`result_key`, so stale results are
    never served.

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


class ResultCache:
    """Computed results filed by :func:`result_key`; safe for several processes and crashes.

    Parameters
    ----------
    directory : str or os.PathLike
        Where the result files live (created on first use).
    tmp : str or os.PathLike
        Where files are written before being renamed into place (same file system).
    """

    def __init__(self, directory: str | os.PathLike[str], tmp: str | os.PathLike[str]) -> None:
        self.directory = Path(directory)
        self.tmp = Path(tmp)
        self.directory.mkdir(parents=True, exist_ok=True)
        self.tmp.mkdir(parents=True, exist_ok=True)

    def __repr__(self) -> str:
        return f"ResultCache({str(self.directory)!r})"

    def path(self, key: str) -> Path:
        """The file of ``key`` (whether or not it exists)."""
        if len(key) != 64 or not all(c in "0123456789abcdef" for c in key):
            raise ValueError(f"not a result key: {key!r}")
        return self.directory / key[:2] / f"{key}.npz"

    def __contains__(self, key: object) -> bool:
        return isinstance(key, str) and self.path(key).is_file()

    def get(self, key: str) -> dict[str, Any]:
        """The stored result document (numpy arrays for the long arrays).

        Raises
        ------
        KeyError
            Not in the cache.
        StoreError
            The file is unreadable.
        """
        try:
            with np.load(self.path(key), allow_pickle=False) as npz:
                meta = orjson.loads(npz["meta"].tobytes())
                doc = {"status": meta.pop("status", "ok")}
                if "frequency_hz" in npz.files:
                    doc["frequency_hz"] = npz["frequency_hz"]
                    doc["tool_point"] = {k: complex_to_wire(npz[k], arrays="numpy") for k in _ARRAYS if k in npz.files}
                doc.update(meta)
        except FileNotFoundError:
            raise KeyError(key) from None
        except (OSError, ValueError, KeyError, orjson.JSONDecodeError) as exc:
            raise StoreError(f"unreadable cached result {key}: {exc}") from None
        return doc

    def status(self, key: str) -> str:
        """``status`` of a stored result (``ok`` or ``error``) without loading its arrays."""
        try:
            with np.load(self.path(key), allow_pickle=False) as npz:
                return str(orjson.loads(npz["meta"].tobytes()).get("status", "ok"))
        except FileNotFoundError:
            raise KeyError(key) from None
        except (OSError, ValueError, KeyError, orjson.JSONDecodeError) as exc:
            raise StoreError(f"unreadable cached result {key}: {exc}") from None

    def put_many(self, items: Iterable[tuple[str, Mapping[str, Any]]]) -> int:
        """Store results (``(key, result document)`` pairs); return how many were written.

        Each file is complete and on stable storage under its final name when this returns.
        """
        token = f"{os.getpid()}-{secrets.token_hex(4)}"
        dirs: set[Path] = set()
        n = 0
        for key, doc in items:
            final = self.path(key)
            final.parent.mkdir(exist_ok=True)
            tmp = self.tmp / f"{key}.{token}.npz.tmp"
            try:
                with open(tmp, "wb") as fh:
                    np.savez(fh, **_encode(doc))
                    fh.flush()
                    os.fsync(fh.fileno())
                os.replace(tmp, final)
            except OSError as exc:
                with contextlib.suppress(OSError):
                    tmp.unlink()
                raise StoreError(f"could not write a cached result to {self.directory}: {exc}") from None
            dirs.add(final.parent)
            n += 1
        for d in dirs:
            fsync_dir(d)
        return n

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


def _encode(doc: Mapping[str, Any]) -> dict[str, np.ndarray]:
    """Split a result document into arrays and a JSON ``meta`` (see the module docstring)."""
    meta = {k: v for k, v in doc.items() if k not in ("id", "frequency_hz", "tool_point")}
    out: dict[str, np.ndarray] = {}
    if "frequency_hz" in doc:
        out["frequency_hz"] = np.asarray(doc["frequency_hz"], dtype=np.float64)
        for k, v in (doc.get("tool_point") or {}).items():
            out[k] = complex_from_wire(v, f"tool_point.{k}", out["frequency_hz"].size, finite=False)
    out["meta"] = np.frombuffer(orjson.dumps(meta, option=orjson.OPT_SERIALIZE_NUMPY), dtype=np.uint8)
    return out
