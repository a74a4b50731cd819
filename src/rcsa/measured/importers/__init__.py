"""Importers of measured FRFs: every format is converted at the edge to complex receptance
in m/N (1/N, rad/N, rad/(N·m) for rotations) vs Hz, in the contract's conventions, and
returned as an immutable :class:`rcsa.measured.store.Measurement` ready for ``MeasurementStore.put``.

Units are never guessed; a file that cannot be read raises :class:`rcsa.errors.InputError`
(naming the field) and nothing is stored. What a file says is used and checked: a CSV
header's columns and units (:mod:`~rcsa.measured.importers.header`), a UFF's response
direction and dataset types, a tap file's time stamps; what the caller declares must agree
with it. Every array meets the plausibility bounds of :mod:`~rcsa.measured.importers.bounds`,
and a truncated file is refused, never read as a shorter measurement.

:func:`read_any` reads a file of any of these formats (the registry of
:mod:`~rcsa.measured.importers.registry`: format from the suffix or stated, metadata and
importer options by name).
"""

from __future__ import annotations

from rcsa.measured.importers.contract_json import (
    measurement_from_contract,
    measurement_to_contract,
    read_contract_json,
)
from rcsa.measured.importers.csv_table import read_csv
from rcsa.measured.importers.cutpro import read_cutpro
from rcsa.measured.importers.registry import read_any
from rcsa.measured.importers.sensor import add_sensor_mass, correct_sensor_mass, remove_sensor_mass
from rcsa.measured.importers.tap import h1_estimate, read_tap
from rcsa.measured.importers.uff58 import read_uff
from rcsa.measured.importers.units import FrfUnit, parse_frf_unit, to_receptance

__all__ = [
    "FrfUnit",
    "add_sensor_mass",
    "correct_sensor_mass",
    "h1_estimate",
    "measurement_from_contract",
    "measurement_to_contract",
    "parse_frf_unit",
    "read_any",
    "read_contract_json",
    "read_csv",
    "read_cutpro",
    "read_tap",
    "read_uff",
    "remove_sensor_mass",
    "to_receptance",
]
