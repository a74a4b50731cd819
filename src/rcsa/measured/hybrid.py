"""Measured spindles: from a stored measurement to the spindle-side receptance of an assembly.

A stored measurement (``docs/contract.md`` "Measured spindles") is one direction of a spindle,
at the plane ``spindle_nose`` (holder and tool are coupled to it) or ``holder_tip`` (it
contains its holder and clamping; only the tool is coupled). By kind:

* ``point_receptance`` — the full 2×2 as given (``l`` and ``n`` averaged: reciprocity);
* ``artifact_frfs`` — identified by the exact three-FRF method (:mod:`rcsa.measured.artifact_identification`),
  finite differences only as a labelled fallback (``"artifact_method": "finite_difference"``);
* ``direct_frf`` — only ``h``; rotations estimated with the equivalent-cantilever relation
  below, and the prediction labelled with that estimate's uncertainty.

Rotations for ``direct_frf`` (a justified estimate, not a measurement): near the nose a
spindle deflects like the free end of a cantilever of effective length ``L`` (tip load:
w = FL³/3EI, ψ = FL²/2EI; tip moment: ψ = ML/EI), so ``N = 3H/(2L)`` and ``P = 3H/L²``
(``PH/N² = 4/3``). RA-1's analytical spindle gives ``N/H = 6.5 /m`` (L ≈ 0.23 m) and
``PH/N² = 1.55`` at low frequency. ``L`` defaults to 0.2 m and the prediction is repeated
at L/2 and 2L; the spread of the tool-point ``h`` is reported as the uncertainty.

The requested band must lie inside the measured one: it is interpolated (linearly, per
real and imaginary part; exact where grid lines coincide), never extrapolated.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any, Protocol

import numpy as np

from rcsa.errors import DamagedError, InputError, NotFoundError
from rcsa.measured.artifact_identification import (
    ArtifactGeometry,
    artifact_from_meta,
    identify_exact,
    identify_exact_many,
    identify_finite_difference,
)
from rcsa.measured.store import Measurement
from rcsa.model.contract import MeasuredSpindleSpec
from rcsa.model.spindle_side import BaseResolver, MeasuredBase

__all__ = ["ASSUMED_N_AVERAGES", "DEFAULT_EFFECTIVE_LENGTH_M", "MeasurementSource", "base_resolver",
           "cantilever_rotations", "measured_base"]

DEFAULT_EFFECTIVE_LENGTH_M = 0.2
#: Impacts assumed averaged when a stored coherence is turned into a noise level (the store
#: keeps no count of averages): σ = √(1−γ²)/(|γ|√(2·5)), Bendat & Piersol 2010, Table 9.6.
ASSUMED_N_AVERAGES = 5.0
# Relative noise floor: a coherence of exactly 1 must not make a line infinitely precise.
_MIN_NOISE_REL = 1e-4


class MeasurementSource(Protocol):
    """Where stored measurements are read: a :class:`~rcsa.measured.store.MeasurementStore`,
    or anything with its ``get`` (e.g. the service's cache in front of one)."""

    def get(self, measurement_id: str) -> Measurement:
        """The stored measurement; raises :class:`~rcsa.errors.NotFoundError` if absent."""
        ...


def cantilever_rotations(h: np.ndarray, effective_length_m: float) -> np.ndarray:
    """2×2 receptance from ``h`` alone: ``[[H, 3H/2L], [3H/2L, 3H/L²]]``, shape (nfreq, 2, 2)."""
    out = np.empty((h.size, 2, 2), dtype=complex)
    beta = 1.5 / effective_length_m
    out[:, 0, 0] = h
    out[:, 0, 1] = out[:, 1, 0] = beta * h
    out[:, 1, 1] = 3.0 * h / effective_length_m**2
    return out


def _interpolate(f_from: np.ndarray, values: np.ndarray, f_to: np.ndarray) -> np.ndarray:
    if f_from.shape == f_to.shape and np.array_equal(f_from, f_to):
        return values
    flat = values.reshape(f_from.size, -1)
    out = np.empty((f_to.size, flat.shape[1]), dtype=complex)
    for j in range(flat.shape[1]):  # a loop over the four entries, not over frequency
        out[:, j] = np.interp(f_to, f_from, flat[:, j].real) + 1j * np.interp(f_to, f_from, flat[:, j].imag)
    return out.reshape((f_to.size, *values.shape[1:]))


def _noise_rel(m: Measurement, name: str, f: np.ndarray) -> np.ndarray | None:
    """Relative noise sd per line (per real and imaginary part) of FRF ``name`` from its coherence."""
    c = m.coherence.get(name)
    if c is None:
        return None
    g2 = np.clip(np.interp(f, m.frequency_hz, c), 1e-3, 1.0)
    out: np.ndarray = np.maximum(np.sqrt(1.0 - g2) / (np.sqrt(g2) * np.sqrt(2.0 * ASSUMED_N_AVERAGES)), _MIN_NOISE_REL)
    return out


def _noise_summary(sd: Mapping[str, np.ndarray | None], default_noise_rel: float) -> dict[str, Any]:
    known = {k: float(np.median(v)) for k, v in sd.items() if v is not None}
    unknown = sorted(k for k, v in sd.items() if v is None)
    return {"from_coherence": sorted(known), "median_relative_sd": known,
            "n_averages_assumed": ASSUMED_N_AVERAGES if known else None,
            "default_relative_sd": default_noise_rel if unknown else None, "without_coherence": unknown}


def _complex_noise(rng: np.random.Generator, shape: tuple[int, ...]) -> np.ndarray:
    e = rng.standard_normal((2, *shape))
    out: np.ndarray = e[0] + 1j * e[1]
    return out


@dataclass(frozen=True)
class _EntryNoise:
    """Independent relative noise on the stored FRFs of a point receptance (h; l = n; p) or of h alone.

    ``direct_frf``: one draw of h's noise scales the whole estimated 2×2 (its rotations are
    h times fixed factors).
    """

    receptance: np.ndarray              # (nfreq, 2, 2)
    sd: Mapping[str, np.ndarray | None]  # per stored FRF, (nfreq,) or None (no coherence)

    def draw(self, rng: np.random.Generator, n: int, default_noise_rel: float) -> np.ndarray:
        """See :meth:`rcsa.model.spindle_side.BaseUncertainty.draw`."""
        nf = self.receptance.shape[0]

        def sd(name: str) -> np.ndarray:
            v = self.sd[name]
            return np.full(nf, default_noise_rel) if v is None else v

        if set(self.sd) == {"h"}:
            drawn: np.ndarray = self.receptance * (1.0 + sd("h")[:, None, None]
                                                   * _complex_noise(rng, (n, nf))[..., None, None])
            return drawn
        out = np.array(np.broadcast_to(self.receptance, (n, *self.receptance.shape)))
        ln = 0.5 * (sd("l") + sd("n"))
        out[..., 0, 0] *= 1.0 + sd("h") * _complex_noise(rng, (n, nf))
        cross = 1.0 + ln * _complex_noise(rng, (n, nf))
        out[..., 0, 1] *= cross
        out[..., 1, 0] *= cross
        out[..., 1, 1] *= 1.0 + sd("p") * _complex_noise(rng, (n, nf))
        return out

    def summary(self, default_noise_rel: float) -> dict[str, Any]:
        """See :meth:`rcsa.model.spindle_side.BaseUncertainty.summary`."""
        return {"propagation": "relative noise on each stored FRF" if len(self.sd) > 1 else
                "relative noise on h, carried by the estimated rotations",
                **_noise_summary(self.sd, default_noise_rel)}


@dataclass(frozen=True)
class _ArtifactNoise:
    """Noise on the artifact FRFs pushed through the exact identification (its conditioning included)."""

    receptance: np.ndarray               # (nfreq, 2, 2), the identified base receptance
    geometry: ArtifactGeometry
    points_m: tuple[float, ...]
    frequency_hz: np.ndarray
    frfs: Mapping[str, np.ndarray]       # h11, h21, h22 on frequency_hz
    sd: Mapping[str, np.ndarray | None]
    condition_number: np.ndarray         # (nfreq,)

    def draw(self, rng: np.random.Generator, n: int, default_noise_rel: float) -> np.ndarray:
        """See :meth:`rcsa.model.spindle_side.BaseUncertainty.draw`."""
        nf = self.frequency_hz.size
        noisy = {}
        for name, v in self.frfs.items():
            s = self.sd[name]
            sd = np.full(nf, default_noise_rel) if s is None else s
            noisy[name] = v * (1.0 + sd * _complex_noise(rng, (n, nf)))
        centre = identify_exact_many(self.geometry, self.points_m, self.frequency_hz, self.frfs)
        drawn = identify_exact_many(self.geometry, self.points_m, self.frequency_hz, noisy)
        out: np.ndarray = self.receptance + (drawn - centre)
        return out

    def summary(self, default_noise_rel: float) -> dict[str, Any]:
        """See :meth:`rcsa.model.spindle_side.BaseUncertainty.summary`."""
        c = self.condition_number
        return {"propagation": "noise on h11, h21, h22 re-identified by the exact three-FRF method",
                **_noise_summary(self.sd, default_noise_rel),
                "condition_number": {"median": float(np.median(c)), "p90": float(np.quantile(c, 0.9)),
                                     "max": float(np.max(c)),
                                     "at_frequency_hz": float(self.frequency_hz[int(np.argmax(c))])}}


def measured_base(measurement_id: str, frequency_hz: np.ndarray, store: MeasurementSource, *,
                  artifact_method: str = "exact",
                  effective_length_m: float = DEFAULT_EFFECTIVE_LENGTH_M) -> MeasuredBase:
    """The spindle-side receptance of a stored measurement on the requested grid.

    Parameters
    ----------
    measurement_id : str
    frequency_hz : numpy.ndarray, shape (nfreq,)
        Requested grid; must lie inside the measured band.
    store : MeasurementSource
        Where the measurement is looked up.
    artifact_method : {"exact", "finite_difference"}
    effective_length_m : float
        Equivalent-cantilever length for ``direct_frf`` rotations, m.

    Returns
    -------
    MeasuredBase
    """
    field_name = "spindle.measurement_id"
    try:
        m = store.get(measurement_id)
    except NotFoundError:
        raise InputError(field_name, f"no stored measurement {measurement_id!r}") from None
    except DamagedError as exc:
        raise InputError(field_name, f"the stored measurement {measurement_id} is damaged and cannot be used "
                                     f"({exc.reason}); upload it again, or choose another") from None
    f = np.asarray(frequency_hz, dtype=float)
    lo, hi = float(m.frequency_hz[0]), float(m.frequency_hz[-1])
    if f[0] < lo * (1 - 1e-12) or f[-1] > hi * (1 + 1e-12):
        raise InputError("frequency", f"the requested band {f[0]:g}–{f[-1]:g} Hz lies outside the measured band "
                                      f"{lo:g}–{hi:g} Hz of {measurement_id}; extrapolation is refused")
    kind, plane = m.meta.kind, m.meta.plane
    report: dict[str, Any] = {"id": measurement_id, "kind": kind, "plane": plane, "spindle_id": m.meta.spindle_id,
                              "direction": m.meta.direction}
    notes: list[str] = []
    alternatives: tuple[np.ndarray, ...] = ()
    artifact_d = None
    if kind == "point_receptance":
        s = m.receptance().values
        asym = float(np.max(np.abs(s[:, 0, 1] - s[:, 1, 0])) / max(np.max(np.abs(s[:, 0, 1])), 1e-300))
        s = s.copy()
        s[:, 0, 1] = s[:, 1, 0] = 0.5 * (s[:, 0, 1] + s[:, 1, 0])
        report["method"] = "as_given"
        report["l_n_asymmetry"] = asym
    elif kind == "artifact_frfs":
        points = m.meta.points_m
        assert m.meta.artifact is not None and points is not None  # required for the kind (MeasurementMeta)
        geometry = artifact_from_meta(m.meta.artifact)
        artifact_d = geometry.diameter_m
        frfs = dict(m.frfs)
        if artifact_method == "exact":
            s, info = identify_exact(geometry, points, m.frequency_hz, frfs)
        elif artifact_method == "finite_difference":
            s, info = identify_finite_difference(geometry, points, m.frequency_hz, frfs)
            notes.append("spindle receptance identified by the finite-difference fallback (P = N²/H): biased")
        else:
            raise InputError("spindle.artifact_method", "must be 'exact' or 'finite_difference'")
        info = dict(info)
        cond = np.asarray(info.pop("condition_number", []))
        if cond.size:
            info["condition_number"] = _interpolate(m.frequency_hz, cond.astype(complex), f).real.tolist()
        report.update(info)
    else:  # direct_frf
        h = np.asarray(m.frfs["h"])
        s = cantilever_rotations(h, effective_length_m)
        alternatives = tuple(_interpolate(m.frequency_hz, cantilever_rotations(h, x), f)
                             for x in (effective_length_m / 2, effective_length_m * 2))
        report["method"] = "equivalent_cantilever_rotations"
        report["effective_length_m"] = [effective_length_m / 2, effective_length_m, effective_length_m * 2]
        notes.append("only h was measured: rotational receptances are estimated (equivalent cantilever, "
                     f"L = {effective_length_m:g} m, bounds L/2 and 2L); see 'uncertainty'")
    interpolated = not (m.frequency_hz.shape == f.shape and np.array_equal(m.frequency_hz, f))
    report["interpolated"] = interpolated
    if interpolated:
        notes.append(f"measured spindle interpolated from its own grid ({m.frequency_hz.size} lines) to the request")
    receptance = _interpolate(m.frequency_hz, s, f)
    return MeasuredBase(plane=plane, receptance=receptance, alternatives=alternatives,
                        notes=tuple(notes), report=report, artifact_diameter_m=artifact_d,
                        uncertainty=_uncertainty(m, f, receptance, artifact_method),
                        effective_length_m=effective_length_m if kind == "direct_frf" else None)


def _uncertainty(m: Measurement, f: np.ndarray, receptance: np.ndarray, artifact_method: str
                 ) -> _EntryNoise | _ArtifactNoise | None:
    """The measurement's own noise model on the grid ``f`` (None for the finite-difference fallback)."""
    kind = m.meta.kind
    if kind == "point_receptance":
        return _EntryNoise(receptance, {k: _noise_rel(m, k, f) for k in ("h", "l", "n", "p")})
    if kind == "direct_frf":
        return _EntryNoise(receptance, {"h": _noise_rel(m, "h", f)})
    if artifact_method != "exact":
        return None
    assert m.meta.artifact is not None and m.meta.points_m is not None  # required for the kind (MeasurementMeta)
    geometry = artifact_from_meta(m.meta.artifact)
    frfs = {k: _interpolate(m.frequency_hz, np.asarray(m.frfs[k]), f) for k in ("h11", "h21", "h22")}
    _, info = identify_exact(geometry, m.meta.points_m, f, frfs)
    return _ArtifactNoise(receptance, geometry, m.meta.points_m, f, frfs, {k: _noise_rel(m, k, f) for k in frfs},
                          np.asarray(info["condition_number"]))


def base_resolver(store: MeasurementSource) -> BaseResolver:
    """A :data:`~rcsa.model.spindle_side.BaseResolver` that looks measured spindles up in ``store``.

    Parameters
    ----------
    store : MeasurementSource

    Returns
    -------
    callable
        ``resolve(spindle_spec, frequency_hz) -> MeasuredBase``.
    """

    def resolve(spindle: MeasuredSpindleSpec, frequency_hz: np.ndarray) -> MeasuredBase:
        return measured_base(spindle.measurement_id, frequency_hz, store, artifact_method=spindle.artifact_method,
                             effective_length_m=spindle.effective_length_m)

    return resolve
