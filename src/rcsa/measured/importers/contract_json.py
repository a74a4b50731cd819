"""The contract's JSON form of a measurement (docs/contract.md "Measured spindles"), both ways.

Upload form::

    {"spindle_id": "mc1-hsk63", "direction": "x", "plane": "spindle_nose",
     "kind": "point_receptance", "frequency_hz": [...],
     "h": {"real": [...], "imag": [...]}, "l": {...}, "n": {...}, "p": {...}}

Optional fields: ``machine``, ``notes``, ``points_m`` and ``artifact`` (``artifact_frfs``),
``coherence`` (a list for ``h`` alone, or ``{"h21": [...], ...}``). Values are SI
(receptance m/N, l 1/N, n rad/N, p rad/(N·m)) in the contract's conventions. What
:func:`measurement_to_contract` adds (``id``, ``created_utc``, ``source`` …) is accepted
back, so an exported measurement can be imported again (it gets a new id).
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from typing import Any

import numpy as np

from rcsa.errors import InputError
from rcsa.measured.importers._common import finish, read_source
from rcsa.measured.store.measurement import Measurement, MeasurementMeta, Provenance
from rcsa.measured.store.schema import ARTIFACT_FRF_NAME, CONVENTION, frf_unit
from rcsa.model.bounds import MAX_FREQUENCY_LINES
from rcsa.model.input_policy import check_count, load_json
from rcsa.model.wire import complex_from_wire, complex_to_wire, number_list

__all__ = ["measurement_from_contract", "measurement_to_contract", "read_contract_json"]

_META_KEYS = (
    "spindle_id",
    "direction",
    "plane",
    "kind",
    "machine",
    "notes",
    "points_m",
    "artifact",
)
#: Fields written by measurement_to_contract / MeasurementInfo.to_dict that an upload may carry back.
_OUTPUT_ONLY = frozenset(
    {"id", "created_utc", "software_version", "source", "frfs", "n_frequencies", "frequency_min_hz",
     "frequency_max_hz", "units", "convention", "summary"}
)  # fmt: skip


def _numbers(value: Any, field: str) -> np.ndarray:
    return number_list(value, field, finite=False)  # non-finite values are refused by Measurement


def _complex(value: Any, field: str) -> np.ndarray:
    return complex_from_wire(value, field, finite=False)


def _frf_keys(kind: Any, doc: Mapping[str, Any]) -> list[str]:
    if kind == "point_receptance":
        return ["h", "l", "n", "p"]
    if kind == "direct_frf":
        return ["h"]
    if kind == "artifact_frfs":
        return sorted(k for k in doc if ARTIFACT_FRF_NAME.match(k))
    raise InputError(
        "kind", f"must be one of point_receptance, artifact_frfs, direct_frf; got {kind!r}"
    )


def measurement_from_contract(
    doc: Mapping[str, Any],
    *,
    overrides: Mapping[str, Any] | None = None,
    drop_nonpositive: bool = False,
    sensor_mass_kg: float | None = None,
    file_name: str = "",
    source_sha256: str = "",
) -> Measurement:
    """Build a measurement from the contract's JSON form (already parsed).

    Parameters
    ----------
    doc : mapping
        The JSON object.
    overrides : mapping, optional
        Metadata given alongside (CLI options, form fields): fills fields the document
        lacks; a value that contradicts the document is refused.
    drop_nonpositive, sensor_mass_kg :
        As in :func:`rcsa.measured.importers.read_csv`.
    file_name, source_sha256 : str
        Provenance of the document, if it came from a file.
    """
    if not isinstance(doc, Mapping):
        raise InputError("", "a measurement must be a JSON object")
    doc = dict(doc)
    for key, value in (overrides or {}).items():
        if value is None:
            continue
        if key in doc and doc[key] != value:
            raise InputError(key, f"the document says {doc[key]!r} but {value!r} was given")
        doc[key] = value
    for key in ("spindle_id", "direction", "plane", "kind", "frequency_hz"):
        if key not in doc:
            raise InputError(key, "is required")
    if isinstance(doc["frequency_hz"], list):  # the input policy's row count
        check_count(len(doc["frequency_hz"]), "frequency_hz", MAX_FREQUENCY_LINES, "frequency lines")
    frf_keys = _frf_keys(doc["kind"], doc)
    unknown = sorted(
        set(doc) - set(_META_KEYS) - _OUTPUT_ONLY - set(frf_keys) - {"frequency_hz", "coherence"}
    )
    if unknown:
        raise InputError(unknown[0], f"unknown field for kind {doc['kind']!r}")
    missing = [k for k in frf_keys if k not in doc]
    if missing:
        raise InputError(missing[0], f"is required for kind {doc['kind']!r}")
    points = doc.get("points_m")
    meta = MeasurementMeta(
        spindle_id=doc["spindle_id"],
        direction=doc["direction"],
        plane=doc["plane"],
        kind=doc["kind"],
        machine=doc.get("machine") or "",
        points_m=tuple(_numbers(points, "points_m")) if points is not None else None,
        artifact=doc.get("artifact"),
        notes=doc.get("notes") or "",
    )
    coherence_doc = doc.get("coherence")
    if isinstance(coherence_doc, list) and frf_keys == ["h"]:
        coherence_doc = {"h": coherence_doc}
    if coherence_doc is not None and not isinstance(coherence_doc, Mapping):
        raise InputError(
            "coherence", "must be a list (for h alone) or an object of lists by FRF name"
        )
    coherence = {k: _numbers(v, f"coherence.{k}") for k, v in (coherence_doc or {}).items()}
    steps, prior_mass = [], None
    src = doc.get("source")
    if isinstance(src, Mapping):  # re-import of an export: keep what was done to the numbers
        steps.append(
            f"re-imported rcsa export {doc.get('id', '')} (originally {src.get('format')} {src.get('file')!r})"
        )
        steps.extend(str(c) for c in src.get("conversions") or ())
        prior_mass = src.get("sensor_mass_kg")
    prov = Provenance(
        source_format="contract_json",
        source_file=file_name,
        source_sha256=source_sha256,
        conversions=tuple(steps),
        sensor_mass_kg=prior_mass,
    )
    return finish(
        _numbers(doc["frequency_hz"], "frequency_hz"),
        {k: _complex(doc[k], k) for k in frf_keys},
        quantity="receptance",
        meta=meta,
        provenance=prov,
        coherence=coherence,
        drop_nonpositive=drop_nonpositive,
        sensor_mass_kg=sensor_mass_kg,
    )


def read_contract_json(
    source: str | os.PathLike[str] | bytes,
    *,
    overrides: Mapping[str, Any] | None = None,
    drop_nonpositive: bool = False,
    sensor_mass_kg: float | None = None,
    file_name: str = "",
) -> Measurement:
    """Import a measurement JSON file (or bytes); see :func:`measurement_from_contract`."""
    data, name, sha = read_source(source, file_name)
    doc = load_json(data, path="file", what=f"{name or 'the upload'}")
    return measurement_from_contract(
        doc,
        overrides=overrides,
        drop_nonpositive=drop_nonpositive,
        sensor_mass_kg=sensor_mass_kg,
        file_name=name,
        source_sha256=sha,
    )


def measurement_to_contract(m: Measurement, *, include_data: bool = True) -> dict[str, Any]:
    """The contract JSON form of ``m`` plus its stored metadata (``id``, ``source`` …).

    Floats are written as Python floats, which ``json`` round-trips exactly.
    """
    out = m.info().to_dict()
    out["units"] = {name: frf_unit(name) for name in m.frfs} | {"frequency_hz": "Hz"}
    out["convention"] = CONVENTION
    if include_data:
        out["frequency_hz"] = m.frequency_hz.tolist()
        for name, v in m.frfs.items():
            out[name] = complex_to_wire(v)
        if m.coherence:
            out["coherence"] = {k: v.tolist() for k, v in m.coherence.items()}
    return out
