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
from rcsa.measured.importers import (
    measurement_from_contract,
    measurement_to_contract,
    read_contract_json,
    read_csv,
    read_cutpro,
    read_tap,
    read_uff,
)
from rcsa.measured.store import Measurement, MeasurementMeta, Provenance, is_measurement_id
from rcsa.measured.store import paths as P
from rcsa.measured.store.schema import frf_unit
from rcsa.model import fields
from rcsa.model.assembly import build_model
from rcsa.model.contract import parse_assembly
from rcsa.physics.elimination import tip_receptance
from rcsa.reference import ra1

__all__ = [
    "DEMO_SPINDLE_ID",
    "FORMATS",
    "IMPORT_OPTIONS",
    "META_FIELDS",
    "check_store",
    "delete_measurement",
    "demo_measurement",
    "format_from_name",
    "import_measurement",
    "list_measurements",
    "measurement_document",
    "measurement_hdf5",
    "measurement_summary",
    "read_measurement",
    "parse_points",
    "parse_roles",
    "rebuild_catalogue",
    "seed_demo",
    "store_measurement",
    "store_measurement_once",
]

#: Import formats: UFF 58, CSV/TSV table, CutPro ``.frf``, the contract's JSON, raw tap.
FORMATS = ("uff", "csv", "frf", "json", "tap")
_BY_SUFFIX = {".uff": "uff", ".unv": "uff", ".csv": "csv", ".tsv": "csv", ".frf": "frf", ".json": "json"}
#: Metadata of a measurement (``contract.md`` "Measured spindles").
META_FIELDS = ("spindle_id", "direction", "plane", "kind", "machine", "notes", "points_m", "artifact")
#: Importer options, with the formats they apply to.
IMPORT_OPTIONS: dict[str, tuple[str, ...]] = {
    "units": ("uff", "csv", "frf"),
    "columns": ("csv", "tap"),
    "frequency_unit": ("csv",),
    "phase_unit": ("csv",),
    "roles": ("uff",),
    "scalar_direction": ("uff",),
    "drop_nonpositive": ("uff", "csv", "frf", "json"),
    "sensor_mass_kg": FORMATS,
    "force_unit": ("tap",),
    "response_unit": ("tap",),
    "sample_rate_hz": ("tap",),
    "force_window_s": ("tap",),
    "exponential_tau_s": ("tap",),
    "max_frequency_hz": ("tap",),
}
#: Spindle id of the demo measurement (RA-1's analytical spindle-nose receptance).
DEMO_SPINDLE_ID = "demo-ra1"
_DEMO_MARKER = ".demo-seeded"
_MAX_PAGE = 1000


def format_from_name(file_name: str, fmt: str | None = None) -> str:
    """The import format: ``fmt`` if given, else from the file name's suffix.

    Raises
    ------
    InputError
        Field ``format``: unknown format, or a suffix that does not say.
    """
    form = (fmt or _BY_SUFFIX.get(Path(file_name or "").suffix.lower(), "")).strip().lower()
    if form not in FORMATS:
        given = f"{fmt!r} is not a format; " if fmt else f"cannot tell the format of {file_name or 'the upload'!r}; "
        raise InputError("format", given + f"say which: one of {', '.join(FORMATS)}")
    return form


def parse_roles(text: str | Mapping[str, Any] | None) -> dict[str, tuple[int, int]] | None:
    """UFF roles ``"h11=1:1,h21=2:1,h22=2:2"`` (or a mapping name → [rsp, ref]) as a dict."""
    if text is None or text == "":
        return None
    if isinstance(text, Mapping):
        items = [f"{k}={v[0]}:{v[1]}" if isinstance(v, list | tuple) and len(v) == 2 else f"{k}=?"
                 for k, v in text.items()]
    elif isinstance(text, str):
        items = text.split(",")
    else:
        raise InputError("roles", "write NAME=RESPONSE_NODE:REFERENCE_NODE,..., e.g. h11=1:1,h21=2:1")
    roles = {}
    for item in items:
        name, sep, nodes = item.partition("=")
        rsp, sep2, ref = nodes.partition(":")
        try:
            if not (sep and sep2):
                raise ValueError
            roles[name.strip()] = (int(rsp), int(ref))
        except ValueError:
            raise InputError("roles", f"{item!r}: write NAME=RESPONSE_NODE:REFERENCE_NODE, e.g. h21=2:1") from None
    return roles


def parse_points(value: str | Sequence[float] | None) -> tuple[float, ...] | None:
    """Artifact point positions from ``"0,0.025"``, ``"[0, 0.025]"`` or a list, m."""
    if value is None or value == "":
        return None
    if isinstance(value, str):
        text = value.strip()
        try:
            items = decode_json(text, path="points_m") if text.startswith("[") else text.split(",")
            if not isinstance(items, list):
                raise ValueError
            return tuple(float(x) for x in items)
        except (ValueError, TypeError):
            raise InputError("points_m", f"{value!r}: write comma-separated metres, e.g. 0,0.025") from None
    if isinstance(value, Sequence) and all(isinstance(x, int | float) and not isinstance(x, bool) for x in value):
        return tuple(float(x) for x in value)
    raise InputError("points_m", "must be a list of positions in metres")


def _parse_artifact(value: str | Mapping[str, Any] | None) -> Mapping[str, Any] | None:
    if value is None or value == "":
        return None
    if isinstance(value, Mapping):
        return value
    if not isinstance(value, str):
        raise InputError("artifact", "must be a JSON object")
    doc = decode_json(value, path="artifact", what="artifact")
    if not isinstance(doc, dict):
        raise InputError("artifact", "must be a JSON object")
    return doc


def _float(value: Any, field: str) -> float | None:
    """A number from an option or form field; None when left out or empty."""
    return None if value is None or value == "" else fields.number(value, field, text=True)


def import_measurement(
    data: bytes,
    *,
    file_name: str = "",
    fmt: str | None = None,
    metadata: Mapping[str, Any] | None = None,
    options: Mapping[str, Any] | None = None,
    extra_taps: Sequence[bytes] = (),
):
    """Read an uploaded measurement file (not yet stored).

    Parameters
    ----------
    data : bytes
        The file's content.
    file_name : str
        Its name (recorded in the provenance; its suffix gives the format unless ``fmt``).
    fmt : {"uff", "csv", "frf", "json", "tap"}, optional
    metadata : mapping, optional
        :data:`META_FIELDS`: ``spindle_id``, ``direction``, ``plane`` (required except for
        JSON, which may carry them), ``kind`` (default ``direct_frf``), ``machine``,
        ``notes``, ``points_m`` (list or ``"0,0.025"``) and ``artifact`` (object or JSON text).
    options : mapping, optional
        :data:`IMPORT_OPTIONS`, strings accepted (form fields): ``units`` (e.g. ``"um/N"``),
        ``columns``, ``frequency_unit``, ``phase_unit``, ``roles`` (``"h11=1:1,..."``),
        ``scalar_direction`` (UFF), ``drop_nonpositive``, ``sensor_mass_kg`` and the tap
        options. UFF files may leave ``direction`` out: the file's is used.
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
    form = format_from_name(file_name, fmt)
    meta_in = dict(metadata or {})
    unknown = sorted(set(meta_in) - set(META_FIELDS))
    if unknown:
        raise InputError(unknown[0], f"unknown metadata field (allowed: {', '.join(META_FIELDS)})")
    opts = {k: v for k, v in (options or {}).items() if v is not None and v != ""}
    for key in opts:
        if key not in IMPORT_OPTIONS:
            raise InputError(key, f"unknown import option (allowed: {', '.join(IMPORT_OPTIONS)})")
        if form not in IMPORT_OPTIONS[key] and not (key == "drop_nonpositive" and not fields.boolean(opts[key], key, text=True)):
            raise InputError(key, f"does not apply to format {form!r}")
    if extra_taps and form != "tap":
        raise InputError("file", f"several files can only be averaged for format 'tap', not {form!r}")
    given = {k: v for k, v in meta_in.items() if v is not None and v != ""}
    if "points_m" in given:
        given["points_m"] = parse_points(given["points_m"])
    if "artifact" in given:
        given["artifact"] = _parse_artifact(given["artifact"])
    common = {"sensor_mass_kg": _float(opts.get("sensor_mass_kg"), "sensor_mass_kg"), "file_name": file_name}
    drop = fields.boolean(opts.get("drop_nonpositive", False), "drop_nonpositive", text=True)
    if form == "json":
        overrides = {k: (list(v) if isinstance(v, tuple) else v) for k, v in given.items()}
        return read_contract_json(data, overrides=overrides, drop_nonpositive=drop, **common)
    for key in ("spindle_id", "direction", "plane"):
        if key not in given and not (key == "direction" and form == "uff"):  # UFF: the file says
            raise InputError(key, f"is required for format {form!r}")
    given.setdefault("kind", "direct_frf")
    if form == "uff":
        return read_uff(data, given, roles=parse_roles(opts.get("roles")), units=opts.get("units"),
                        scalar_direction=opts.get("scalar_direction"), drop_nonpositive=drop, **common)
    meta = MeasurementMeta(**given)
    if form == "csv":
        return read_csv(data, meta, units=opts.get("units"), columns=opts.get("columns"),  # default: the header
                        frequency_unit=opts.get("frequency_unit"), phase_unit=opts.get("phase_unit"),
                        drop_nonpositive=drop, **common)
    if form == "frf":
        return read_cutpro(data, meta, units=opts.get("units"), drop_nonpositive=drop, **common)
    if drop:
        raise InputError("drop_nonpositive", "a tap FFT always drops its 0 Hz bin; leave the option out")
    for key in ("force_unit", "response_unit"):
        if not opts.get(key):
            raise InputError(key, "is required for format 'tap' (e.g. N and m/s^2)")
    return read_tap(
        [data, *extra_taps], meta, force_unit=opts["force_unit"], response_unit=opts["response_unit"],
        columns=opts.get("columns") or "t,force,response",
        sample_rate_hz=_float(opts.get("sample_rate_hz"), "sample_rate_hz"),
        force_window_s=_float(opts.get("force_window_s"), "force_window_s"),
        exponential_tau_s=_float(opts.get("exponential_tau_s"), "exponential_tau_s"),
        max_frequency_hz=_float(opts.get("max_frequency_hz"), "max_frequency_hz"), **common)


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
                              sensor_mass_kg: float | None = None):
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
    return store.info(store.put(measurement)).to_dict()


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
            return store.info(recorded_id).to_dict()
        if store.was_deleted(recorded_id):
            raise ConflictError("measurement", recorded_id, "was stored by an earlier attempt of this request and "
                                                            "deleted since; send the upload with a new key")
        mid = recorded_id
    else:
        mid = store.new_id()
        record(mid)
    return store.info(store.put(measurement, measurement_id=mid)).to_dict()


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


def demo_measurement(frequency: Mapping[str, float] | None = None):
    """RA-1's analytical spindle-nose receptance as a ``point_receptance`` measurement.

    Spindle id :data:`DEMO_SPINDLE_ID`, plane ``spindle_nose``, direction ``x``, on
    1…10 000 Hz in 1 Hz steps by default, so that a fresh user can try a hybrid prediction
    (``"spindle": {"measurement_id": ...}``) with RA-1's holder and tool at once.
    """
    spec = parse_assembly(ra1(dict(frequency or {"start_hz": 1.0, "stop_hz": 10000.0, "step_hz": 1.0})))
    r = tip_receptance(build_model(spec).spindle, 2.0 * np.pi * spec.frequency_hz)
    meta = MeasurementMeta(spindle_id=DEMO_SPINDLE_ID, direction="x", plane="spindle_nose",
                           kind="point_receptance", machine="RA-1 (analytical demo)",
                           notes="Demo data: the analytical spindle-nose receptance of the RA-1 reference "
                                 "spindle (rcsa.reference.ra1), not a measurement. Try a hybrid prediction "
                                 "with RA-1's holder and tool on it.")
    prov = Provenance(source_format="api", conversions=("computed by rcsa.physics.elimination.tip_receptance of RA-1's spindle",))
    return Measurement(frequency_hz=spec.frequency_hz,
                       frfs={"h": r[:, 0, 0], "l": r[:, 0, 1], "n": r[:, 1, 0], "p": r[:, 1, 1]},
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
