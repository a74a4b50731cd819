"""CutPro-style ``.frf`` text: one direction per file, ``freq  real  imag`` per line.

Assumed units (from the public MATLAB writer ``Matlab2CutPro.m`` of github.com/leekunhwee/Dynamics):
frequency in Hz, real and imaginary parts of the receptance in **m/N**. That writer puts
the labels ``Freq Hz Real m/N Imag Real`` after the first triple on the first line, so only
the first three numbers of each line are read. A file in other units must be declared
(``units="mm/N"``); if the file itself names an FRF unit that differs from the one in
effect, the import is refused rather than guessed.
"""

from __future__ import annotations

import os

import numpy as np

from rcsa.errors import InputError
from rcsa.measured.importers._common import decode_text, finish, numeric_rows, read_source
from rcsa.measured.importers.units import parse_frf_unit
from rcsa.measured.store.measurement import Measurement, MeasurementMeta, Provenance

__all__ = ["CUTPRO_DEFAULT_UNITS", "read_cutpro"]

CUTPRO_DEFAULT_UNITS = "m/N"


def _units_named_in(text: str) -> set[float]:
    """SI factors of every receptance unit spelled out in the file (e.g. the 'm/N' label)."""
    found = set()
    for tok in text.split():
        if "/" in tok:
            try:
                u = parse_frf_unit(tok)
            except InputError:
                continue
            found.add(u.factor_to_si)
    return found


def read_cutpro(
    source: str | os.PathLike[str] | bytes,
    meta: MeasurementMeta,
    *,
    units: str | None = None,
    drop_nonpositive: bool = False,
    sensor_mass_kg: float | None = None,
    file_name: str = "",
) -> Measurement:
    """Import a CutPro-style ``.frf`` file (a ``direct_frf``).

    Parameters
    ----------
    source : path or bytes
    meta : MeasurementMeta
        ``meta.kind`` must be ``direct_frf``.
    units : str, optional
        FRF unit if not the CutPro default m/N (receptance units only).
    drop_nonpositive, sensor_mass_kg, file_name :
        As in :func:`rcsa.measured.importers.read_csv`.
    """
    if meta.kind != "direct_frf":
        raise InputError(
            "kind", f"a CutPro .frf file holds one FRF: kind must be direct_frf, not {meta.kind!r}"
        )
    data, name, sha = read_source(source, file_name)
    text = decode_text(data)
    declared = units is not None
    unit = parse_frf_unit(units if declared else CUTPRO_DEFAULT_UNITS)
    if unit.quantity != "receptance":
        raise InputError(
            "units", f"CutPro .frf files hold receptance; {unit.text!r} is {unit.quantity}"
        )
    named = _units_named_in(text)
    if named and named != {unit.factor_to_si}:
        raise InputError(
            "units",
            f"the file names a receptance unit that differs from {unit.text}"
            + ("" if declared else " (the CutPro default)")
            + "; declare the file's unit, e.g. units='mm/N'",
        )
    rows, lines = numeric_rows(text, leading=3)
    for row, ln in zip(rows, lines, strict=True):
        if len(row) != 3:
            raise InputError(
                "columns", f"line {ln} has {len(row)} values; a .frf line is freq real imag"
            )
    table = np.array(rows, dtype=float)
    prov = Provenance(
        source_format="cutpro_frf",
        source_file=name,
        source_sha256=sha,
        original_quantity="receptance",
        original_units=unit.text
        if declared
        else f"{CUTPRO_DEFAULT_UNITS} (CutPro convention, assumed)",
        conversions=(f"scaled {unit.text} -> m/N by {unit.factor_to_si:.17g}",)
        if unit.factor_to_si != 1
        else (),
    )
    return finish(
        table[:, 0],
        {"h": (table[:, 1] + 1j * table[:, 2]) * unit.factor_to_si},
        quantity="receptance",
        meta=meta,
        provenance=prov,
        lines=lines,
        drop_nonpositive=drop_nonpositive,
        sensor_mass_kg=sensor_mass_kg,
    )
