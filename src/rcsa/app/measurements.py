"""Measurements as the CLI (``rcsa store ...``) and the REST service see them.

One place decides how an uploaded file becomes a stored measurement (format from the name
or stated, metadata from options or form fields, importer options), how a measurement is
shown (the contract's JSON form plus a peak summary), how the store is listed page by page,
and the demo measurement a fresh store is seeded with. Both doors call these functions and
add nothing but their own input and output handling.
"""

from __future__ import annotations

import base64
import binascii
import json
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import Any

import filelock
import numpy as np

from rcsa.app.inputs import decode_json
from rcsa.errors import ConflictError, InputError, NotFoundError, StoreError
from rcsa.infra.atomic_files import atomic_write_bytes
from rcsa.measured.importers import measurement_from_contract, measurement_to_contract
from rcsa.measured.importers.registry import (
    FORMATS,
    IMPORT_OPTIONS,
    META_FIELDS,
    format_from_name,
    read_upload,
)
from rcsa.measured.store import Measurement, MeasurementMeta, Provenance, is_measurement_id
from rcsa.measured.store import paths as P
from rcsa.measured.store.schema import frf_unit
from rcsa.model import fields
from rcsa.model.reference import ra1_spindle_receptance

__all__ = [
    "DEMO_SPINDLE_ID",
    "FORMATS",
    "IMPORT_OPTIONS",
    "META_FIELDS",
    "check_store",
    "delete_measurement",
    "demo_measurement",
    "import_measurement",
    "list_measurements",
    "measurement_document",
    "measurement_hdf5",
    "measurement_summary",
    "read_measurement",
    "rebuild_catalogue",
    "seed_demo",
    "store_measurement",
    "store_measurement_once",
    "upload_format",
]

#: Spindle id of the demo measurement (RA-1's analytical spindle-nose receptance).
DEMO_SPINDLE_ID = "demo-ra1"
_DEMO_MARKER = ".demo-seeded"
_MAX_PAGE = 1000


def upload_format(file_name: str, fmt: str | None = None) -> str:
    """What an upload is, for messages and metrics: its import format, or ``"unknown"``.

    The format is ``fmt`` if given, else the file name's suffix (as the importers decide,
    :func:`rcsa.measured.importers.registry.format_from_name`); unlike reading the file,
    this never raises.

    Examples
    --------
    >>> upload_format("tip.csv"), upload_format("tip.dat"), upload_format("tip.dat", "tap")
    ('csv', 'unknown', 'tap')
    """
    try:
        return format_from_name(file_name, fmt)
    except InputError:
        return "unknown"


def _artifact(value: Any) -> Any:
    """An artifact given as JSON text (a form field or option) as a mapping."""
    if isinstance(value, str) and value.strip():
        doc = decode_json(value, path="artifact", what="artifact")
        if not isinstance(doc, dict):
            raise InputError("artifact", "must be a JSON object")
        return doc
    return value


def import_measurement(
    data: bytes,
    *,
    file_name: str = "",
    fmt: str | None = None,
    metadata: Mapping[str, Any] | None = None,
    options: Mapping[str, Any] | None = None,
    extra_taps: Sequence[bytes] = (),
) -> Measurement:
    """Read an uploaded measurement file (not yet stored), every field as text or value.

    The importer registry (:func:`rcsa.measured.importers.registry.read_upload`) with what
    the doors add: metadata and options arrive as form fields or command-line text, and an
    ``artifact`` given as JSON text is decoded under the request policy
    (:func:`rcsa.app.inputs.decode_json`).

    Parameters
    ----------
    data : bytes
        The file's content.
    file_name : str
        Its name (recorded in the provenance; its suffix gives the format unless ``fmt``).
    fmt : {"uff", "csv", "frf", "json", "tap"}, optional
    metadata : mapping, optional
        :data:`META_FIELDS` (``points_m`` as a list or ``"0,0.025"``, ``artifact`` as an
        object or JSON text).
    options : mapping, optional
        :data:`IMPORT_OPTIONS`, strings accepted.
    extra_taps : sequence of bytes
        Further tap files averaged with ``data`` (format ``tap`` only).

    Returns
    -------
    rcsa.measured.store.Measurement

    Raises
    ------
    InputError
        Naming the field: unknown format or option, missing metadata, unreadable file.
    """
    meta = dict(metadata or {})
    if "artifact" in meta:
        meta["artifact"] = _artifact(meta["artifact"])
    return read_upload(data, file_name=file_name, fmt=fmt, metadata=meta, options=options, extra_taps=extra_taps)


#: Metadata of a file read only for its data (a tool-point tap test has no spindle to name).
_READ_DEFAULTS = {"spindle_id": "tap-test", "direction": "x", "plane": "spindle_nose"}


def read_measurement(data: bytes, *, file_name: str = "", fmt: str | None = None,
                     metadata: Mapping[str, Any] | None = None, options: Mapping[str, Any] | None = None,
                     extra_taps: Sequence[bytes] = ()) -> dict[str, Any]:
    """Read a measurement file into the contract's JSON form, without storing it.

    The same importers, units and checks as :func:`import_measurement` (what ``rcsa store
    import`` and ``POST /v1/measurements`` store); for files read only for their data, such
    as a tool point's tap tests sent on to a diagnosis. ``spindle_id``, ``direction`` and
    ``plane`` may be left out (``tap-test``, ``x``, ``spindle_nose``; a UFF file's own
    direction is kept).

    Parameters
    ----------
    data : bytes
        The file's content.
    file_name : str
        Its name (its suffix gives the format unless ``fmt``).
    fmt : {"uff", "csv", "frf", "json", "tap"}, optional
    metadata : mapping, optional
        As for :func:`import_measurement`.
    options : mapping, optional
        As for :func:`import_measurement` (``units``, ``columns``, ...).
    extra_taps : sequence of bytes
        Further tap files averaged with ``data`` (format ``tap`` only).

    Returns
    -------
    dict
        ``frequency_hz``, ``h`` (and the other receptances), ``coherence`` when the file has
        one, ``units``, ``source`` (format, conversions), ``summary`` and the metadata.

    Raises
    ------
    InputError
        As :func:`import_measurement`.
    """
    form = format_from_name(file_name, fmt)
    given = {k: v for k, v in (metadata or {}).items() if v is not None and v != ""}
    defaults = {k: v for k, v in _READ_DEFAULTS.items() if not (k == "direction" and form == "uff")}
    if form != "json":
        given = {**defaults, **given}
    m = import_measurement(data, file_name=file_name, fmt=form, metadata=given, options=options,
                           extra_taps=extra_taps)
    out = {k: v for k, v in measurement_to_contract(m).items() if k not in ("id", "created_utc", "software_version")}
    out["summary"] = measurement_summary(m)
    return out


def measurement_from_document(doc: Mapping[str, Any], *, drop_nonpositive: bool = False,
                              sensor_mass_kg: float | None = None) -> Measurement:
    """A measurement from the contract's JSON form, already parsed (a JSON request body)."""
    return measurement_from_contract(doc, drop_nonpositive=drop_nonpositive, sensor_mass_kg=sensor_mass_kg)


def measurement_summary(m: Any) -> dict[str, Any]:
    """Peak of each FRF: ``{name: {"units", "max_magnitude", "frequency_at_max_hz"}}``."""
    out = {}
    for name, v in m.frfs.items():
        i = int(np.argmax(np.abs(v)))
        out[name] = {"units": frf_unit(name), "max_magnitude": float(np.abs(v[i])),
                     "frequency_at_max_hz": float(m.frequency_hz[i])}
    return out


def measurement_document(store: Any, measurement_id: str, *, include_data: bool = True) -> dict[str, Any]:
    """A stored measurement in the contract's JSON form, with its metadata and a summary.

    Raises
    ------
    NotFoundError
    """
    m = store.get(measurement_id)
    out = measurement_to_contract(m, include_data=include_data)
    out["summary"] = measurement_summary(m)
    return out


def measurement_hdf5(store: Any, measurement_id: str) -> bytes:
    """The stored HDF5 file of a measurement, as bytes (``Accept: application/x-hdf5``).

    Raises
    ------
    NotFoundError
    """
    if not is_measurement_id(measurement_id):
        raise NotFoundError("measurement", str(measurement_id))
    try:
        return (Path(store.path) / P.MEASUREMENTS / f"{measurement_id}.h5").read_bytes()
    except FileNotFoundError:
        raise NotFoundError("measurement", measurement_id) from None
    except OSError as e:
        raise StoreError(f"cannot read measurement {measurement_id}: {e.strerror or e}") from None


def _encode_cursor(info: Any) -> str:
    raw = json.dumps([info.created_utc or "", info.id or ""]).encode()
    return base64.urlsafe_b64encode(raw).decode().rstrip("=")


def _decode_cursor(cursor: str) -> tuple[str, str]:
    try:
        raw = base64.urlsafe_b64decode(cursor + "=" * (-len(cursor) % 4))
        created, ident = json.loads(raw)
        if not isinstance(created, str) or not isinstance(ident, str):
            raise ValueError
        return created, ident
    except (ValueError, TypeError, binascii.Error, UnicodeDecodeError):
        raise InputError("cursor", "is not a cursor this service handed out; start again without it") from None


def list_measurements(store: Any, *, limit: int = 100, cursor: str | None = None,
                      **filters: str | None) -> dict[str, Any]:
    """One page of the stored measurements' metadata, oldest first.

    Parameters
    ----------
    store : MeasurementStore
        The store to list.
    limit : int
        Items per page, 1…1000.
    cursor : str, optional
        ``next_cursor`` of the previous page (opaque). Pages stay consistent while
        measurements are added (they come last) or deleted.
    **filters
        ``spindle_id``, ``machine``, ``direction``, ``plane``, ``kind`` (exact match).

    Returns
    -------
    dict
        ``{"items": [metadata...], "next_cursor": str | None}``.
    """
    fields.integer(limit, "limit", ge=1, le=_MAX_PAGE)
    infos = store.list(filters.pop("spindle_id", None), **filters)
    if cursor:
        after = _decode_cursor(cursor)
        infos = [i for i in infos if (i.created_utc or "", i.id or "") > after]
    page = infos[:limit]
    more = len(infos) > limit
    out: dict[str, Any] = {"items": [i.to_dict() for i in page], "next_cursor": _encode_cursor(page[-1]) if more
                           else None}
    damaged = store.damaged() if hasattr(store, "damaged") else []
    if damaged:  # left out of the items: unreadable files, so that a listing never fails on one
        out["damaged"] = damaged
    return out


def delete_measurement(store: Any, measurement_id: str) -> dict[str, str]:
    """Delete a measurement; return ``{"deleted": id}``.

    Raises
    ------
    NotFoundError
    """
    store.delete(measurement_id)
    return {"deleted": measurement_id}


def store_measurement(store: Any, measurement: Any) -> dict[str, Any]:
    """Put a measurement in the store; return its metadata (with the new ``id``)."""
    info: dict[str, Any] = store.info(store.put(measurement)).to_dict()
    return info


def store_measurement_once(store: Any, measurement: Any, *, recorded_id: str | None,
                           record: Callable[[str], None]) -> dict[str, Any]:
    """Store a measurement at most once across retries of one request (crash consistency).

    The id is chosen first and made durable by ``record`` (e.g. with the request's
    idempotency key) before the file is written under it. A retry whose earlier attempt
    died passes the id it recorded (``recorded_id``): if that attempt's file was committed,
    its metadata is the answer (no second copy); if not, the measurement is written under
    that id now (nothing lost).

    Parameters
    ----------
    store : MeasurementStore
    measurement : Measurement
    recorded_id : str or None
        The id an earlier attempt of the same request recorded, if any.
    record : callable
        ``record(id)``: durably note the id before the write (raises to stop).

    Returns
    -------
    dict
        The stored measurement's metadata.

    Raises
    ------
    ConflictError
        The measurement an earlier attempt stored was deleted since.
    """
    if recorded_id is not None:
        if recorded_id in store:
            kept: dict[str, Any] = store.info(recorded_id).to_dict()
            return kept
        if store.was_deleted(recorded_id):
            raise ConflictError("measurement", recorded_id, "was stored by an earlier attempt of this request and "
                                                            "deleted since; send the upload with a new key")
        mid = recorded_id
    else:
        mid = store.new_id()
        record(mid)
    stored: dict[str, Any] = store.info(store.put(measurement, measurement_id=mid)).to_dict()
    return stored


def check_store(store: Any) -> dict[str, Any]:
    """Verify every measurement file and the catalogue (``rcsa store check``); changes nothing.

    See :meth:`rcsa.measured.store.MeasurementStore.verify` for the report.
    """
    report: dict[str, Any] = store.verify()
    return report


def rebuild_catalogue(store: Any) -> dict[str, Any]:
    """Make the catalogue again from the files (``rcsa store rebuild``).

    Returns
    -------
    dict
        ``store``, ``ok`` (no damaged file), ``measurements`` (listed after the rebuild) and
        ``damaged`` (ids of files that cannot be read completely, checksums included; those
        whose metadata cannot be read are left out of the catalogue; see :func:`check_store`).
    """
    n = store.rebuild_index()
    damaged = sorted({str(p["id"]) for p in store.verify()["problems"] if p["problem"] in ("damaged", "misnamed")})
    return {"store": str(store.path), "ok": not damaged, "measurements": n, "damaged": damaged}


def demo_measurement(frequency: Mapping[str, float] | None = None) -> Measurement:
    """RA-1's analytical spindle-nose receptance as a ``point_receptance`` measurement.

    Spindle id :data:`DEMO_SPINDLE_ID`, plane ``spindle_nose``, direction ``x``, on
    1…10 000 Hz in 1 Hz steps by default
    (:func:`rcsa.model.reference.ra1_spindle_receptance`), so that a fresh user can try a
    hybrid prediction (``"spindle": {"measurement_id": ...}``) with RA-1's holder and tool at
    once.
    """
    r = ra1_spindle_receptance(dict(frequency) if frequency is not None else None)
    meta = MeasurementMeta(spindle_id=DEMO_SPINDLE_ID, direction="x", plane="spindle_nose",
                           kind="point_receptance", machine="RA-1 (analytical demo)",
                           notes="Demo data: the analytical spindle-nose receptance of the RA-1 reference "
                                 "spindle (rcsa.reference.ra1), not a measurement. Try a hybrid prediction "
                                 "with RA-1's holder and tool on it.")
    prov = Provenance(source_format="api", conversions=("computed by rcsa.physics.elimination.tip_receptance of RA-1's spindle",))
    return Measurement(frequency_hz=r.frequency_hz, frfs={"h": r.h, "l": r.l, "n": r.n, "p": r.p},
                       meta=meta, provenance=prov)


def seed_demo(store: Any) -> str | None:
    """Seed an empty store with :func:`demo_measurement`, once in the store's life.

    Idempotent and safe when several processes start together: under a file lock, a store
    that was seeded before (marker file ``.demo-seeded``) or is not empty is left alone.

    Returns
    -------
    str or None
        The new measurement's id, or None when nothing was done.
    """
    root = Path(store.path)
    marker = root / _DEMO_MARKER
    try:
        with filelock.FileLock(str(root / ".demo-seed.lock"), timeout=60):
            if marker.exists():
                return None
            mid = None
            if not store.list():
                mid = store.put(demo_measurement())
            atomic_write_bytes(marker, ((mid or "store was not empty") + "\n").encode())
            return mid
    except filelock.Timeout:
        raise StoreError(f"another process holds the demo-seeding lock of {root}") from None
