"""The in-memory measured spindle FRF: what importers return and the store keeps.

A :class:`Measurement` is one direction of one spindle (or spindle + holder), expressed as
complex receptances in the contract's units (m/N, 1/N, rad/N, rad/(N·m)) and conventions
(``docs/physics.md`` §2.1) on a strictly increasing frequency axis in Hz. It is immutable: a
frozen dataclass whose arrays are read-only copies and whose mappings are read-only views.
"""

from __future__ import annotations

import math
import re
from collections.abc import Mapping
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Any

import numpy as np

from rcsa.errors import InputError
from rcsa.measured.store.schema import ARTIFACT_FRF_NAME, DIRECTIONS, KINDS, PLANES
from rcsa.model import fields
from rcsa.model.bounds import MAX_COHERENCE
from rcsa.physics.receptance import Receptance, check_frequency_hz

__all__ = [
    "Measurement",
    "MeasurementInfo",
    "MeasurementMeta",
    "Provenance",
    "freeze_json",
    "thaw_json",
]

_EMPTY: Mapping[str, np.ndarray] = MappingProxyType({})
_SHA256 = re.compile(r"^[0-9a-f]{64}$")


def freeze_json(value: Any, field_name: str) -> Any:
    """Deep-freeze a JSON-like value (dict → read-only mapping, list → tuple).

    Raises :class:`InputError` for anything JSON cannot carry (NaN, non-string keys, objects).
    """
    if isinstance(value, Mapping):
        out = {}
        for k, v in value.items():
            if not isinstance(k, str):
                raise InputError(field_name, f"keys must be strings, got {k!r}")
            out[k] = freeze_json(v, f"{field_name}.{k}")
        return MappingProxyType(out)
    if isinstance(value, list | tuple):
        return tuple(freeze_json(v, f"{field_name}[{i}]") for i, v in enumerate(value))
    if isinstance(value, bool) or value is None or isinstance(value, str):
        return value
    if isinstance(value, int | float | np.integer | np.floating):
        if not math.isfinite(float(value)):
            raise InputError(field_name, "must be a finite number")
        return value.item() if isinstance(value, np.generic) else value
    raise InputError(
        field_name, f"must be JSON data (object, list, string, number), got {type(value).__name__}"
    )


def thaw_json(value: Any) -> Any:
    """Inverse of :func:`freeze_json`: plain dicts and lists, ready for ``json.dumps``."""
    if isinstance(value, Mapping):
        return {k: thaw_json(v) for k, v in value.items()}
    if isinstance(value, tuple | list):
        return [thaw_json(v) for v in value]
    return value


def _text(value: object, field_name: str, *, required: bool, max_len: int) -> str:
    if not isinstance(value, str):
        raise InputError(field_name, f"must be a string, got {type(value).__name__}")
    if required and not value.strip():
        raise InputError(field_name, "must not be empty")
    if len(value) > max_len:
        raise InputError(field_name, f"must be at most {max_len} characters")
    if any(ord(c) < 32 and c not in "\t\n" for c in value):
        raise InputError(field_name, "must not contain control characters")
    return value


def _check_artifact(artifact: Mapping[str, Any]) -> None:
    """Light checks of a contract-like artifact description (see :class:`MeasurementMeta`)."""
    for key in ("diameter_m", "stickout_m"):
        if key not in artifact:
            raise InputError(f"artifact.{key}", "is required for kind 'artifact_frfs'")
    for key, v in artifact.items():
        if key.endswith("_m") and not isinstance(v, Mapping | tuple):
            if key in ("diameter_m", "stickout_m", "length_m"):
                fields.number(v, f"artifact.{key}", gt=0.0)
            elif isinstance(v, bool) or not isinstance(v, int | float) or not 0 <= v < math.inf:
                raise InputError(f"artifact.{key}", f"must be a finite length >= 0 m, got {v!r}")
    d, bore = float(artifact["diameter_m"]), artifact.get("inner_diameter_m", 0.0)
    if isinstance(bore, int | float) and bore >= d:
        raise InputError("artifact.inner_diameter_m", "must be smaller than artifact.diameter_m")
    if "length_m" in artifact and float(artifact["length_m"]) < float(artifact["stickout_m"]):
        raise InputError("artifact.length_m", "must be >= artifact.stickout_m")


@dataclass(frozen=True, slots=True)
class MeasurementMeta:
    """What the person who measured declares about a measurement.

    Parameters
    ----------
    spindle_id : str
        Spindle (or spindle + holder) identifier, e.g. ``"mc1-hsk63"``.
    direction : {"x", "y"}
        Machine direction of this measurement.
    plane : {"spindle_nose", "holder_tip"}
        Coupling plane the receptances belong to (docs/contract.md "Measured spindles").
    kind : {"point_receptance", "artifact_frfs", "direct_frf"}
        Which receptances are present: ``h, l, n, p``; ``h11, h21, h22`` (+ optional
        ``hij``); or ``h`` alone.
    machine : str, optional
        Machine tool name.
    points_m : tuple of float, optional
        ``artifact_frfs`` only (and required there): positions of the measurement points
        1, 2, … in m, measured from the artifact tip toward the spindle, strictly increasing.
    artifact : mapping, optional
        Contract-like artifact description, required for ``artifact_frfs``:
        ``diameter_m`` (blank diameter), ``stickout_m`` (holder face to blank tip), and
        where known ``length_m``, ``inner_diameter_m``, ``material`` (a name or a material
        dict of the contract) and ``holder`` (a contract holder dict or a description).
    notes : str, optional
    """

    spindle_id: str
    direction: str
    plane: str
    kind: str
    machine: str = ""
    points_m: tuple[float, ...] | None = None
    artifact: Mapping[str, Any] | None = None
    notes: str = ""

    def __post_init__(self) -> None:
        _text(self.spindle_id, "spindle_id", required=True, max_len=128)
        _text(self.machine, "machine", required=False, max_len=128)
        _text(self.notes, "notes", required=False, max_len=10_000)
        for name, allowed in (("direction", DIRECTIONS), ("plane", PLANES), ("kind", KINDS)):
            if getattr(self, name) not in allowed:
                raise InputError(
                    name, f"must be one of {', '.join(allowed)}; got {getattr(self, name)!r}"
                )
        if self.artifact is not None:
            if not isinstance(self.artifact, Mapping):
                raise InputError("artifact", "must be an object (dict)")
            object.__setattr__(self, "artifact", freeze_json(self.artifact, "artifact"))
        if self.kind == "artifact_frfs":
            if self.points_m is None:
                raise InputError("points_m", "is required for kind 'artifact_frfs'")
            if self.artifact is None:
                raise InputError("artifact", "is required for kind 'artifact_frfs'")
            _check_artifact(self.artifact)
        elif self.points_m is not None:
            raise InputError("points_m", "is only meaningful for kind 'artifact_frfs'")
        if self.points_m is not None:
            pts = np.asarray(self.points_m, dtype=float)
            if pts.ndim != 1 or pts.size < 2 or not np.all(np.isfinite(pts)) or np.any(pts < 0):
                raise InputError("points_m", "must list at least two finite positions >= 0 m")
            if np.any(np.diff(pts) <= 0):
                raise InputError(
                    "points_m",
                    "must be strictly increasing (from the artifact tip toward the spindle)",
                )
            if self.artifact is not None and pts[-1] > float(self.artifact["stickout_m"]):
                raise InputError(
                    "points_m",
                    "points must lie on the artifact's stickout (<= artifact.stickout_m)",
                )
            object.__setattr__(self, "points_m", tuple(float(x) for x in pts))


@dataclass(frozen=True, slots=True)
class Provenance:
    """Where the numbers came from and what was done to them on import.

    Parameters
    ----------
    source_format : str
        ``"uff58"``, ``"csv"``, ``"cutpro_frf"``, ``"contract_json"``, ``"tap"`` or ``"api"``.
    source_file : str
        Base name of the imported file ('' when none).
    source_sha256 : str
        sha256 (hex) of the imported file's bytes ('' when none).
    original_quantity : {"receptance", "mobility", "accelerance"}
    original_units : str
        Units the file carried, e.g. ``"um/N"``, ``"g/N"``.
    conversions : tuple of str
        Human-readable steps applied, in order.
    sensor_mass_kg : float or None
        Accelerometer mass removed from the driving-point FRF, kg (None: not corrected).
    """

    source_format: str = "api"
    source_file: str = ""
    source_sha256: str = ""
    original_quantity: str = "receptance"
    original_units: str = "m/N"
    conversions: tuple[str, ...] = ()
    sensor_mass_kg: float | None = None

    def __post_init__(self) -> None:
        _text(self.source_format, "source_format", required=True, max_len=64)
        _text(self.source_file, "source_file", required=False, max_len=1024)
        if self.source_sha256 and not _SHA256.match(self.source_sha256):
            raise InputError("source_sha256", "must be 64 lowercase hex digits")
        if self.original_quantity not in ("receptance", "mobility", "accelerance"):
            raise InputError("original_quantity", "must be receptance, mobility or accelerance")
        object.__setattr__(self, "conversions", tuple(str(c) for c in self.conversions))
        if self.sensor_mass_kg is not None:
            object.__setattr__(
                self, "sensor_mass_kg", fields.number(self.sensor_mass_kg, "sensor_mass_kg", gt=0.0)
            )


def _frf_names_ok(kind: str, names: set[str], points_m: tuple[float, ...] | None) -> None:
    if kind == "point_receptance" and names != {"h", "l", "n", "p"}:
        raise InputError(
            "frfs", f"kind 'point_receptance' needs exactly h, l, n, p; got {sorted(names)}"
        )
    if kind == "direct_frf" and names != {"h"}:
        raise InputError("frfs", f"kind 'direct_frf' needs exactly h; got {sorted(names)}")
    if kind == "artifact_frfs":
        bad = sorted(n for n in names if not ARTIFACT_FRF_NAME.match(n))
        if bad:
            raise InputError(
                "frfs", f"artifact FRFs are named h<response><excitation>, e.g. h21; got {bad}"
            )
        missing = sorted({"h11", "h21", "h22"} - names)
        if missing:
            raise InputError(
                "frfs", f"kind 'artifact_frfs' needs at least h11, h21, h22; missing {missing}"
            )
        top = max(int(c) for n in names for c in n[1:])
        if points_m is not None and top > len(points_m):
            raise InputError(
                "points_m", f"the FRFs use point {top} but points_m lists {len(points_m)} points"
            )


@dataclass(frozen=True, slots=True, eq=False)
class Measurement:
    """One measured spindle direction: receptances vs frequency, and its metadata.

    Parameters
    ----------
    frequency_hz : array_like, shape (nfreq,)
        Strictly increasing frequencies > 0, Hz.
    frfs : mapping of str to array_like, each shape (nfreq,)
        Complex receptances in the contract's units (see :mod:`rcsa.measured.store.schema`),
        named per ``meta.kind``.
    meta : MeasurementMeta
    provenance : Provenance, optional
    coherence : mapping of str to array_like, each shape (nfreq,), optional
        Coherence (0…1) of the FRF of the same name, where known.
    id, created_utc, software_version : str or None
        Set by the store on :meth:`~rcsa.measured.store.MeasurementStore.put`; ``None`` before.
    """

    frequency_hz: np.ndarray
    frfs: Mapping[str, np.ndarray]
    meta: MeasurementMeta
    provenance: Provenance = field(default_factory=Provenance)
    coherence: Mapping[str, np.ndarray] = field(default_factory=lambda: _EMPTY)
    id: str | None = None
    created_utc: str | None = None
    software_version: str | None = None

    def __post_init__(self) -> None:
        f = check_frequency_hz(self.frequency_hz)
        object.__setattr__(self, "frequency_hz", f)
        if not isinstance(self.meta, MeasurementMeta):
            raise InputError("meta", "must be a MeasurementMeta")
        if not isinstance(self.provenance, Provenance):
            raise InputError("provenance", "must be a Provenance")
        if not isinstance(self.frfs, Mapping):
            raise InputError("frfs", "must map names to complex arrays")
        _frf_names_ok(self.meta.kind, set(self.frfs), self.meta.points_m)
        frfs = {}
        for name in sorted(self.frfs):
            v = np.array(self.frfs[name], dtype=np.complex128)
            if v.shape != f.shape:
                raise InputError(name, f"has shape {v.shape}, frequency_hz has {f.shape}")
            if not np.all(np.isfinite(v)):
                raise InputError(name, "contains NaN or infinite values")
            v.flags.writeable = False
            frfs[name] = v
        object.__setattr__(self, "frfs", MappingProxyType(frfs))
        coh = {}
        for name in sorted(self.coherence or {}):
            if name not in frfs:
                raise InputError(f"coherence.{name}", "names no FRF of this measurement")
            c = np.array(self.coherence[name], dtype=np.float64)
            if c.shape != f.shape:
                raise InputError(
                    f"coherence.{name}", f"has shape {c.shape}, frequency_hz has {f.shape}"
                )
            if not np.all(np.isfinite(c)) or np.any(c < 0) or np.any(c > MAX_COHERENCE):
                raise InputError(f"coherence.{name}", "must be finite numbers between 0 and 1")
            c.flags.writeable = False
            coh[name] = c
        object.__setattr__(self, "coherence", MappingProxyType(coh))

    @property
    def n_frequencies(self) -> int:
        """Number of frequency points."""
        return int(self.frequency_hz.size)

    @property
    def omega_rad_s(self) -> np.ndarray:
        """Angular frequency, rad/s, shape (nfreq,)."""
        return 2.0 * np.pi * self.frequency_hz

    def receptance(self) -> Receptance:
        """The 2×2 point receptance of a ``point_receptance`` measurement."""
        if self.meta.kind != "point_receptance":
            raise InputError(
                "kind", f"only a point_receptance has a 2x2 receptance, this is {self.meta.kind!r}"
            )
        r = self.frfs
        return Receptance.from_hlnp(self.frequency_hz, r["h"], r["l"], r["n"], r["p"])

    def info(self) -> MeasurementInfo:
        """The cheap metadata summary :meth:`~rcsa.measured.store.MeasurementStore.list` returns."""
        return MeasurementInfo(
            id=self.id,
            created_utc=self.created_utc,
            software_version=self.software_version,
            meta=self.meta,
            provenance=self.provenance,
            frf_names=tuple(self.frfs),
            n_frequencies=self.n_frequencies,
            frequency_min_hz=float(self.frequency_hz[0]),
            frequency_max_hz=float(self.frequency_hz[-1]),
        )


@dataclass(frozen=True, slots=True)
class MeasurementInfo:
    """Metadata of a stored measurement, without its arrays.

    Attributes
    ----------
    id, created_utc, software_version : str or None
    meta : MeasurementMeta
    provenance : Provenance
    frf_names : tuple of str
    n_frequencies : int
    frequency_min_hz, frequency_max_hz : float
        First and last frequency, Hz.
    """

    id: str | None
    created_utc: str | None
    software_version: str | None
    meta: MeasurementMeta
    provenance: Provenance
    frf_names: tuple[str, ...]
    n_frequencies: int
    frequency_min_hz: float
    frequency_max_hz: float

    @classmethod
    def from_dict(cls, d: Mapping[str, Any]) -> MeasurementInfo:
        """Inverse of :meth:`to_dict`."""
        src = d["source"]
        meta = MeasurementMeta(
            spindle_id=d["spindle_id"],
            direction=d["direction"],
            plane=d["plane"],
            kind=d["kind"],
            machine=d["machine"],
            points_m=tuple(d["points_m"]) if d["points_m"] is not None else None,
            artifact=d["artifact"],
            notes=d["notes"],
        )
        prov = Provenance(
            source_format=src["format"],
            source_file=src["file"],
            source_sha256=src["sha256"],
            original_quantity=src["original_quantity"],
            original_units=src["original_units"],
            conversions=tuple(src["conversions"]),
            sensor_mass_kg=src["sensor_mass_kg"],
        )
        return cls(
            id=d["id"],
            created_utc=d["created_utc"],
            software_version=d["software_version"],
            meta=meta,
            provenance=prov,
            frf_names=tuple(d["frfs"]),
            n_frequencies=int(d["n_frequencies"]),
            frequency_min_hz=float(d["frequency_min_hz"]),
            frequency_max_hz=float(d["frequency_max_hz"]),
        )

    def to_dict(self) -> dict[str, Any]:
        """Plain JSON-ready dict (unit-suffixed names, contract field names for the metadata)."""
        m, p = self.meta, self.provenance
        return {
            "id": self.id,
            "spindle_id": m.spindle_id,
            "machine": m.machine,
            "direction": m.direction,
            "plane": m.plane,
            "kind": m.kind,
            "frfs": list(self.frf_names),
            "n_frequencies": self.n_frequencies,
            "frequency_min_hz": self.frequency_min_hz,
            "frequency_max_hz": self.frequency_max_hz,
            "points_m": list(m.points_m) if m.points_m is not None else None,
            "artifact": thaw_json(m.artifact),
            "notes": m.notes,
            "created_utc": self.created_utc,
            "software_version": self.software_version,
            "source": {
                "format": p.source_format,
                "file": p.source_file,
                "sha256": p.source_sha256,
                "original_quantity": p.original_quantity,
                "original_units": p.original_units,
                "conversions": list(p.conversions),
                "sensor_mass_kg": p.sensor_mass_kg,
            },
        }
