"""One measurement ↔ one HDF5 file (h5py only here).

File layout (every group and dataset has ``schema`` and ``schema_version`` attributes)::

    /                       schema="rcsa.measurement", schema_version=1, id, created_utc,
                            software_version, spindle_id, machine, direction, plane, kind,
                            notes, convention, points_m (float64[], artifact_frfs only),
                            artifact_json, source_format, source_file, source_sha256,
                            original_quantity, original_units, conversions_json,
                            sensor_mass_kg (only if corrected), n_frequencies,
                            frequency_min_hz, frequency_max_hz, frf_names_json
    /frf                    NXdata group: NX_class="NXdata", signal=<first FRF>,
                            axes=["frequency_hz"], frequency_hz_indices=0
    /frf/frequency_hz       float64 (nfreq,), units="Hz"
    /frf/<name>             complex128 (nfreq,), units e.g. "m/N", quantity="receptance"
    /coherence/<name>       float64 (nfreq,), units="1" (only FRFs with a known coherence)

Datasets are chunked, gzip-compressed (lossless), shuffled and Fletcher-32 checksummed, so
a flipped bit on disk is reported rather than returned. Values round-trip bit-exactly.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import h5py
import numpy as np

from rcsa.errors import InputError, StoreError
from rcsa.infra.atomic_files import fsync_file
from rcsa.measured.store import schema as S
from rcsa.measured.store.measurement import (
    Measurement,
    MeasurementInfo,
    MeasurementMeta,
    Provenance,
    freeze_json,
    thaw_json,
)

__all__ = ["read_info_file", "read_measurement_file", "write_measurement_file"]

_DATASET_OPTS: dict[str, Any] = {
    "chunks": True,
    "compression": "gzip",
    "shuffle": True,
    "fletcher32": True,
}


def _tag(obj: h5py.HLObject, schema: str) -> None:
    obj.attrs["schema"] = schema
    obj.attrs["schema_version"] = S.SCHEMA_VERSION


def write_measurement_file(path: Path, m: Measurement) -> None:
    """Write ``m`` (which must carry its ``id`` and ``created_utc``) to a new file ``path``.

    The caller writes to a temporary name and renames it into place (see
    :class:`~rcsa.measured.store.MeasurementStore`); this function closes and fsyncs the file.
    """
    if m.id is None or m.created_utc is None:
        raise StoreError(
            "internal: a measurement is written only once it has an id and a creation time"
        )
    meta, prov = m.meta, m.provenance
    with h5py.File(path, "w") as f:
        _tag(f, S.MEASUREMENT_SCHEMA)
        a = f.attrs
        a["id"] = m.id
        a["created_utc"] = m.created_utc
        a["software_version"] = m.software_version or ""
        for key in ("spindle_id", "machine", "direction", "plane", "kind", "notes"):
            a[key] = getattr(meta, key)
        a["convention"] = S.CONVENTION
        if meta.points_m is not None:
            a["points_m"] = np.asarray(meta.points_m, dtype=np.float64)
        a["artifact_json"] = (
            json.dumps(thaw_json(meta.artifact)) if meta.artifact is not None else ""
        )
        for key in (
            "source_format",
            "source_file",
            "source_sha256",
            "original_quantity",
            "original_units",
        ):
            a[key] = getattr(prov, key)
        a["conversions_json"] = json.dumps(list(prov.conversions))
        if prov.sensor_mass_kg is not None:
            a["sensor_mass_kg"] = float(prov.sensor_mass_kg)
        a["n_frequencies"] = m.n_frequencies
        a["frequency_min_hz"] = float(m.frequency_hz[0])
        a["frequency_max_hz"] = float(m.frequency_hz[-1])
        a["frf_names_json"] = json.dumps(list(m.frfs))

        g = f.create_group("frf")
        _tag(g, S.FRF_GROUP_SCHEMA)
        g.attrs["NX_class"] = "NXdata"
        g.attrs["signal"] = next(iter(m.frfs))
        g.attrs["axes"] = ["frequency_hz"]
        g.attrs["frequency_hz_indices"] = 0
        d = g.create_dataset("frequency_hz", data=m.frequency_hz, dtype=np.float64, **_DATASET_OPTS)
        _tag(d, S.FREQUENCY_SCHEMA)
        d.attrs["units"] = "Hz"
        for name, values in m.frfs.items():
            d = g.create_dataset(name, data=values, dtype=np.complex128, **_DATASET_OPTS)
            _tag(d, S.FRF_SCHEMA)
            d.attrs["units"] = S.frf_unit(name)
            d.attrs["quantity"] = "receptance"
        if m.coherence:
            c = f.create_group("coherence")
            _tag(c, S.COHERENCE_GROUP_SCHEMA)
            for name, values in m.coherence.items():
                d = c.create_dataset(name, data=values, dtype=np.float64, **_DATASET_OPTS)
                _tag(d, S.COHERENCE_SCHEMA)
                d.attrs["units"] = "1"
    fsync_file(path)


def _check_schema(obj: h5py.HLObject, expected: str, where: str) -> None:
    schema = obj.attrs.get("schema")
    version = obj.attrs.get("schema_version")
    if schema is None or version is None:
        raise StoreError(f"{where}: no schema/schema_version attributes; not written by rcsa")
    if isinstance(schema, bytes):
        schema = schema.decode("utf-8", "replace")
    if schema != expected:
        raise StoreError(f"{where}: foreign schema {schema!r}, expected {expected!r}")
    if int(version) not in S.SUPPORTED_VERSIONS:
        raise StoreError(
            f"{where}: schema {schema} version {int(version)} is not supported by this rcsa "
            f"(reads versions {sorted(S.SUPPORTED_VERSIONS)}); upgrade rcsa"
        )


def _open(path: Path) -> h5py.File:
    try:
        return h5py.File(path, "r", locking="best-effort")
    except FileNotFoundError:
        raise
    except OSError as e:
        raise StoreError(f"{path.name}: not a readable HDF5 file ({e})") from None


def _str(attrs: h5py.AttributeManager, key: str, where: str) -> str:
    if key not in attrs:
        raise StoreError(f"{where}: attribute {key!r} is missing")
    v = attrs[key]
    return v.decode("utf-8") if isinstance(v, bytes) else str(v)


def _meta_and_provenance(f: h5py.File, where: str) -> tuple[MeasurementMeta, Provenance]:
    a = f.attrs
    artifact_json = _str(a, "artifact_json", where)
    meta = MeasurementMeta(
        spindle_id=_str(a, "spindle_id", where),
        direction=_str(a, "direction", where),
        plane=_str(a, "plane", where),
        kind=_str(a, "kind", where),
        machine=_str(a, "machine", where),
        points_m=tuple(float(x) for x in a["points_m"]) if "points_m" in a else None,
        artifact=freeze_json(json.loads(artifact_json), "artifact") if artifact_json else None,
        notes=_str(a, "notes", where),
    )
    prov = Provenance(
        source_format=_str(a, "source_format", where),
        source_file=_str(a, "source_file", where),
        source_sha256=_str(a, "source_sha256", where),
        original_quantity=_str(a, "original_quantity", where),
        original_units=_str(a, "original_units", where),
        conversions=tuple(json.loads(_str(a, "conversions_json", where))),
        sensor_mass_kg=float(a["sensor_mass_kg"]) if "sensor_mass_kg" in a else None,
    )
    return meta, prov


def read_info_file(path: Path) -> MeasurementInfo:
    """Read only the metadata of a measurement file (cheap: attributes, no arrays)."""
    where = Path(path).name
    with _open(path) as f:
        _check_schema(f, S.MEASUREMENT_SCHEMA, where)
        try:
            meta, prov = _meta_and_provenance(f, where)
            a = f.attrs
            return MeasurementInfo(
                id=_str(a, "id", where),
                created_utc=_str(a, "created_utc", where),
                software_version=_str(a, "software_version", where),
                meta=meta,
                provenance=prov,
                frf_names=tuple(json.loads(_str(a, "frf_names_json", where))),
                n_frequencies=int(a["n_frequencies"]),
                frequency_min_hz=float(a["frequency_min_hz"]),
                frequency_max_hz=float(a["frequency_max_hz"]),
            )
        except (InputError, KeyError, ValueError, TypeError) as e:
            raise StoreError(f"{where}: inconsistent metadata ({e})") from None


def read_measurement_file(path: Path) -> Measurement:
    """Read a whole measurement file, checking every object's schema.

    Raises
    ------
    FileNotFoundError
        The file does not exist (the store turns this into ``NotFoundError``).
    StoreError
        The file is not HDF5, has a foreign or newer schema, or is inconsistent.
    """
    where = Path(path).name
    with _open(path) as f:
        _check_schema(f, S.MEASUREMENT_SCHEMA, where)
        try:
            meta, prov = _meta_and_provenance(f, where)
            if "frf" not in f:
                raise StoreError(f"{where}: group /frf is missing")
            g = f["frf"]
            _check_schema(g, S.FRF_GROUP_SCHEMA, f"{where}:/frf")
            _check_schema(g["frequency_hz"], S.FREQUENCY_SCHEMA, f"{where}:/frf/frequency_hz")
            freq = g["frequency_hz"][()]
            frfs = {}
            for name in json.loads(_str(f.attrs, "frf_names_json", where)):
                _check_schema(g[name], S.FRF_SCHEMA, f"{where}:/frf/{name}")
                frfs[name] = g[name][()]
            coherence = {}
            if "coherence" in f:
                c = f["coherence"]
                _check_schema(c, S.COHERENCE_GROUP_SCHEMA, f"{where}:/coherence")
                for name in c:
                    _check_schema(c[name], S.COHERENCE_SCHEMA, f"{where}:/coherence/{name}")
                    coherence[name] = c[name][()]
            return Measurement(
                frequency_hz=freq,
                frfs=frfs,
                meta=meta,
                provenance=prov,
                coherence=coherence,
                id=_str(f.attrs, "id", where),
                created_utc=_str(f.attrs, "created_utc", where),
                software_version=_str(f.attrs, "software_version", where),
            )
        except (InputError, KeyError, ValueError, TypeError) as e:
            raise StoreError(f"{where}: inconsistent content ({e})") from None
        except OSError as e:  # e.g. a Fletcher-32 checksum mismatch
            raise StoreError(f"{where}: data cannot be read ({e})") from None
