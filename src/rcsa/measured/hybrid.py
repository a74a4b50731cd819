"""Measured spindles: from a stored measurement to the spindle-side receptance of an assembly.

A stored measurement (``contract.md`` "Measured spindles") is one direction of a spindle,
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

from typing import Any, Protocol

import numpy as np

from rcsa.errors import DamagedError, InputError, NotFoundError
from rcsa.measured.artifact_identification import (
    artifact_from_meta,
    identify_exact,
    identify_finite_difference,
)
from rcsa.measured.store import Measurement
from rcsa.model.contract import MeasuredSpindleSpec
from rcsa.model.spindle_side import BaseResolver, MeasuredBase

__all__ = ["DEFAULT_EFFECTIVE_LENGTH_M", "MeasurementSource", "base_resolver", "cantilever_rotations", "measured_base"]

DEFAULT_EFFECTIVE_LENGTH_M = 0.2


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
        geometry = artifact_from_meta(m.meta.artifact)
        artifact_d = geometry.diameter_m
        frfs = dict(m.frfs)
        if artifact_method == "exact":
            s, info = identify_exact(geometry, m.meta.points_m, m.frequency_hz, frfs)
        elif artifact_method == "finite_difference":
            s, info = identify_finite_difference(geometry, m.meta.points_m, m.frequency_hz, frfs)
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
    return MeasuredBase(plane=plane, receptance=_interpolate(m.frequency_hz, s, f), alternatives=alternatives,
                        notes=tuple(notes), report=report, artifact_diameter_m=artifact_d)


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
