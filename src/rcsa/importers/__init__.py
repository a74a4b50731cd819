"""Importers of measured FRFs: every format is converted at the edge to complex receptance
in m/N (1/N, rad/N, rad/(N·m) for rotations) vs Hz, in the contract's conventions, and
returned as an immutable :class:`rcsa.store.Measurement` ready for ``MeasurementStore.put``.

Units are never guessed; a file that cannot be read raises :class:`rcsa.errors.InputError`
(naming the field) and nothing is stored.
"""

from __future__ import annotations

from .contract_json import measurement_from_contract, measurement_to_contract, read_contract_json
from .csv_table import read_csv
from .cutpro import read_cutpro
from .sensor import add_sensor_mass, correct_sensor_mass, remove_sensor_mass
from .tap import h1_estimate, read_tap
from .uff58 import read_uff
from .units import FrfUnit, parse_frf_unit, to_receptance

__all__ = [
    "FrfUnit",
    "add_sensor_mass",
    "correct_sensor_mass",
    "h1_estimate",
    "measurement_from_contract",
    "measurement_to_contract",
    "parse_frf_unit",
    "read_contract_json",
    "read_csv",
    "read_cutpro",
    "read_tap",
    "read_uff",
    "remove_sensor_mass",
    "to_receptance",
]
