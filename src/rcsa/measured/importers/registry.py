"""Which importer reads a file, and with which metadata and options: the one registry.

A measurement file is read by the importer of its format — UFF 58 (``uff``), a CSV/TSV table
(``csv``), CutPro ``.frf`` (``frf``), the contract's JSON (``json``) or raw tap signals
(``tap``) — chosen from the stated format or the file name's suffix, with the metadata a
stored measurement needs (:data:`META_FIELDS`) and the importer options that apply to that
format (:data:`IMPORT_OPTIONS`; an option that does not apply is refused, not ignored).
Library users call :func:`read_any` on a path; the application layer calls
:func:`read_upload` on an upload's bytes (``rcsa store import``, ``POST /v1/measurements``).

>>> from rcsa.measured.importers import read_any
>>> m = read_any("examples/measurement.csv", spindle_id="mc1", direction="x",
...              plane="spindle_nose")                                   # doctest: +SKIP
>>> m.frfs["h"].shape                                                    # doctest: +SKIP
(196,)
"""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

from rcsa.errors import InputError
from rcsa.measured.importers.contract_json import read_contract_json
from rcsa.measured.importers.csv_table import read_csv
from rcsa.measured.importers.cutpro import read_cutpro
from rcsa.measured.importers.tap import read_tap
from rcsa.measured.importers.uff58 import read_uff
from rcsa.measured.store import Measurement, MeasurementMeta
from rcsa.model import fields

__all__ = ["FORMATS", "IMPORT_OPTIONS", "META_FIELDS", "format_from_name", "parse_points", "parse_roles",
           "read_any", "read_upload"]

#: Import formats: UFF 58, CSV/TSV table, CutPro ``.frf``, the contract's JSON, raw tap.
FORMATS = ("uff", "csv", "frf", "json", "tap")
_BY_SUFFIX = {".uff": "uff", ".unv": "uff", ".csv": "csv", ".tsv": "csv", ".frf": "frf", ".json": "json"}
#: Metadata of a measurement (``docs/contract.md`` "Measured spindles").
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


def format_from_name(file_name: str, fmt: str | None = None) -> str:
    """The import format: ``fmt`` if given, else from the file name's suffix.

    Raises
    ------
    InputError
        Field ``format``: unknown format, or a suffix that does not say.

    Examples
    --------
    >>> format_from_name("tip.unv"), format_from_name("x.txt", "CSV")
    ('uff', 'csv')
    """
    form = (fmt or _BY_SUFFIX.get(Path(file_name or "").suffix.lower(), "")).strip().lower()
    if form not in FORMATS:
        given = f"{fmt!r} is not a format; " if fmt else f"cannot tell the format of {file_name or 'the upload'!r}; "
        raise InputError("format", given + f"say which: one of {', '.join(FORMATS)}")
    return form


def parse_roles(text: str | Mapping[str, Any] | None) -> dict[str, tuple[int, int]] | None:
    """UFF roles ``"h11=1:1,h21=2:1,h22=2:2"`` (or a mapping name → [rsp, ref]) as a dict.

    Examples
    --------
    >>> parse_roles("h11=1:1, h21=2:1")
    {'h11': (1, 1), 'h21': (2, 1)}
    """
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
    """Artifact point positions from ``"0,0.025"``, ``"[0, 0.025]"`` or a list, m.

    Examples
    --------
    >>> parse_points("[0, 0.025]"), parse_points([0.0, 0.03])
    ((0.0, 0.025), (0.0, 0.03))
    """
    if value is None or value == "":
        return None
    if isinstance(value, str):
        text = value.strip()
        if text.startswith("[") and text.endswith("]"):
            text = text[1:-1]
        items: Sequence[Any] = [t for t in (s.strip() for s in text.split(",")) if t]
        path = "points_m"
    elif isinstance(value, Sequence) and not any(isinstance(x, bool) for x in value):
        items, path = value, "points_m"
    else:
        raise InputError("points_m", "must be a list of positions in metres")
    try:
        return tuple(fields.number(x, f"{path}[{i}]", text=True) for i, x in enumerate(items))
    except InputError:
        raise InputError("points_m", f"{value!r}: write comma-separated metres, e.g. 0,0.025") from None


def _float(value: Any, field: str) -> float | None:
    """A number from an option or form field; None when left out or empty."""
    return None if value is None or value == "" else fields.number(value, field, text=True)


def read_upload(
    data: bytes | str | os.PathLike[str],
    *,
    file_name: str = "",
    fmt: str | None = None,
    metadata: Mapping[str, Any] | None = None,
    options: Mapping[str, Any] | None = None,
    extra_taps: Sequence[bytes | str | os.PathLike[str]] = (),
) -> Measurement:
    """Read a measurement file by the importer of its format (not yet stored).

    Parameters
    ----------
    data : bytes or path
        The file's content, or its path.
    file_name : str
        Its name (recorded in the provenance; its suffix gives the format unless ``fmt``).
    fmt : {"uff", "csv", "frf", "json", "tap"}, optional
    metadata : mapping, optional
        :data:`META_FIELDS`: ``spindle_id``, ``direction``, ``plane`` (required except for
        JSON, which may carry them, and a UFF file's own ``direction``), ``kind`` (default
        ``direct_frf``), ``machine``, ``notes``, ``points_m`` (list or ``"0,0.025"``) and
        ``artifact`` (a mapping).
    options : mapping, optional
        :data:`IMPORT_OPTIONS`, strings accepted (form fields): ``units`` (e.g. ``"um/N"``),
        ``columns``, ``frequency_unit``, ``phase_unit``, ``roles`` (``"h11=1:1,..."``),
        ``scalar_direction`` (UFF), ``drop_nonpositive``, ``sensor_mass_kg`` and the tap
        options.
    extra_taps : sequence of bytes or paths
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
    if "artifact" in given and not isinstance(given["artifact"], Mapping):
        raise InputError("artifact", "must be a JSON object")
    sensor_mass_kg = _float(opts.get("sensor_mass_kg"), "sensor_mass_kg")
    drop = fields.boolean(opts.get("drop_nonpositive", False), "drop_nonpositive", text=True)
    if form == "json":
        overrides = {k: (list(v) if isinstance(v, tuple) else v) for k, v in given.items()}
        return read_contract_json(data, overrides=overrides, drop_nonpositive=drop, sensor_mass_kg=sensor_mass_kg,
                                  file_name=file_name)
    for key in ("spindle_id", "direction", "plane"):
        if key not in given and not (key == "direction" and form == "uff"):  # UFF: the file says
            raise InputError(key, f"is required for format {form!r}")
    given.setdefault("kind", "direct_frf")
    if form == "uff":
        return read_uff(data, given, roles=parse_roles(opts.get("roles")), units=opts.get("units"),
                        scalar_direction=opts.get("scalar_direction"), drop_nonpositive=drop,
                        sensor_mass_kg=sensor_mass_kg, file_name=file_name)
    meta = MeasurementMeta(**given)
    if form == "csv":
        return read_csv(data, meta, units=opts.get("units"), columns=opts.get("columns"),  # default: the header
                        frequency_unit=opts.get("frequency_unit"), phase_unit=opts.get("phase_unit"),
                        drop_nonpositive=drop, sensor_mass_kg=sensor_mass_kg, file_name=file_name)
    if form == "frf":
        return read_cutpro(data, meta, units=opts.get("units"), drop_nonpositive=drop, sensor_mass_kg=sensor_mass_kg,
                           file_name=file_name)
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
        max_frequency_hz=_float(opts.get("max_frequency_hz"), "max_frequency_hz"), sensor_mass_kg=sensor_mass_kg,
        file_name=file_name)


def read_any(path: str | os.PathLike[str], *, format: str | None = None,  # noqa: A002 (the option's name)
             extra_taps: Sequence[str | os.PathLike[str]] = (), **options: Any) -> Measurement:
    """Read a measurement file of any supported format into a :class:`Measurement`.

    The format is ``format`` or follows from the suffix (``.uff``/``.unv``, ``.csv``/``.tsv``,
    ``.frf``, ``.json``; raw tap signals need ``format="tap"``). Every other keyword is a
    metadata field (:data:`META_FIELDS`) or an importer option (:data:`IMPORT_OPTIONS`),
    told apart by name; an option that does not apply to the format is refused.

    Parameters
    ----------
    path : path
        The file.
    format : {"uff", "csv", "frf", "json", "tap"}, optional
    extra_taps : sequence of paths
        Further tap files averaged with ``path`` (format ``tap``).
    **options
        ``spindle_id``, ``direction``, ``plane``, ``kind``, ``machine``, ``notes``,
        ``points_m``, ``artifact``; ``units``, ``columns``, ``frequency_unit``,
        ``phase_unit``, ``roles``, ``scalar_direction``, ``drop_nonpositive``,
        ``sensor_mass_kg``, ``force_unit``, ``response_unit``, ``sample_rate_hz``,
        ``force_window_s``, ``exponential_tau_s``, ``max_frequency_hz``.

    Returns
    -------
    rcsa.measured.store.Measurement
        Receptance in m/N (rad/N, rad/(N·m) for rotations) vs Hz, ready for
        ``MeasurementStore.put``.

    Raises
    ------
    InputError
        Naming the field: unknown format or keyword, missing metadata, unreadable file.
    """
    unknown = sorted(set(options) - set(META_FIELDS) - set(IMPORT_OPTIONS))
    if unknown:
        raise InputError(unknown[0], f"neither a metadata field ({', '.join(META_FIELDS)}) nor an import "
                                     f"option ({', '.join(IMPORT_OPTIONS)})")
    metadata = {k: v for k, v in options.items() if k in META_FIELDS}
    opts = {k: v for k, v in options.items() if k in IMPORT_OPTIONS}
    return read_upload(Path(path), file_name=Path(path).name, fmt=format, metadata=metadata, options=opts,
                       extra_taps=tuple(extra_taps))
