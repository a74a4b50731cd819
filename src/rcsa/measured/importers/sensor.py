"""Accelerometer mass correction of a driving-point FRF (``docs/physics.md`` §4.1).

An accelerometer of mass m on the structure is a grounded mass modification: the measured
driving-point receptance is ``H_m = H / (1 − ω² m H)``. Undoing it gives

    H = H_m / (1 + ω² m H_m)        (equivalently A = A_m / (1 − m A_m) for accelerance)

which is exact for a driving-point FRF only. Cross FRFs need the full structural-modification
inverse (the mass sits at the response point, not the excitation point), so they are refused.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from rcsa.errors import InputError
from rcsa.measured.store.measurement import Measurement
from rcsa.model.bounds import MAX_SENSOR_MASS_KG

__all__ = ["add_sensor_mass", "correct_sensor_mass", "remove_sensor_mass"]


def _mass(mass_kg: float) -> float:
    m = float(mass_kg)
    if not np.isfinite(m) or m <= 0:
        raise InputError("sensor_mass_kg", f"must be a finite mass > 0 kg, got {mass_kg!r}")
    if m > MAX_SENSOR_MASS_KG:
        raise InputError("sensor_mass_kg", f"must be <= {MAX_SENSOR_MASS_KG:g} kg (a tap-test accelerometer with its "
                                           f"mounting weighs 0.2-50 g), got {m:g}")
    return m


def remove_sensor_mass(
    frequency_hz: np.ndarray, h_measured: np.ndarray, mass_kg: float
) -> np.ndarray:
    """Driving-point receptance without the sensor: ``H_m / (1 + ω² m H_m)``.

    Parameters
    ----------
    frequency_hz : numpy.ndarray, shape (nfreq,)
        Hz.
    h_measured : numpy.ndarray, shape (nfreq,)
        Measured driving-point receptance, m/N.
    mass_kg : float
        Sensor mass (plus mounting), kg.

    Returns
    -------
    numpy.ndarray, shape (nfreq,), complex128, m/N
    """
    m = _mass(mass_kg)
    omega2 = (2.0 * np.pi * np.asarray(frequency_hz, dtype=float)) ** 2
    hm = np.asarray(h_measured, dtype=np.complex128)
    return hm / (1.0 + omega2 * m * hm)


def add_sensor_mass(frequency_hz: np.ndarray, h: np.ndarray, mass_kg: float) -> np.ndarray:
    """What a sensor of ``mass_kg`` would measure: ``H / (1 − ω² m H)`` (inverse of the above)."""
    m = _mass(mass_kg)
    omega2 = (2.0 * np.pi * np.asarray(frequency_hz, dtype=float)) ** 2
    h = np.asarray(h, dtype=np.complex128)
    out: np.ndarray = h / (1.0 - omega2 * m * h)
    return out


def correct_sensor_mass(measurement: Measurement, mass_kg: float) -> Measurement:
    """Remove the sensor mass from a ``direct_frf`` measurement and record it in provenance.

    Raises
    ------
    InputError
        The measurement is not a single driving-point FRF, or is already corrected.
    """
    m = _mass(mass_kg)
    if measurement.meta.kind != "direct_frf":
        raise InputError(
            "sensor_mass_kg",
            f"mass correction applies to a driving-point FRF (kind direct_frf), not {measurement.meta.kind!r}",
        )
    if measurement.provenance.sensor_mass_kg is not None:
        raise InputError(
            "sensor_mass_kg", "this measurement is already corrected for a sensor mass"
        )
    h = remove_sensor_mass(measurement.frequency_hz, measurement.frfs["h"], m)
    prov = dataclasses.replace(
        measurement.provenance,
        sensor_mass_kg=m,
        conversions=(
            *measurement.provenance.conversions,
            f"sensor mass {m:g} kg removed: H = Hm/(1 + w^2 m Hm)",
        ),
    )
    # a corrected copy is a new measurement: it gets its own id when stored
    return dataclasses.replace(
        measurement,
        frfs={"h": h},
        provenance=prov,
        id=None,
        created_utc=None,
        software_version=None,
    )
