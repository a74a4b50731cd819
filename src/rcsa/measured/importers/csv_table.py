"""CSV/TSV FRF tables with declared columns and units.

The column declaration is a comma-separated list, one token per column of the file:

* ``f`` (also ``freq``, ``frequency``): the frequency, in ``frequency_unit`` (Hz default);
* ``re``, ``im`` or ``mag``, ``phase`` (aliases ``real``, ``imag``, ``abs``, ``magnitude``,
  ``arg``): the FRF, in ``units``; phase in ``phase_unit`` (must be declared);
* ``coh``: its coherence (0…1);
* ``_`` (or ``skip``): a column to ignore.

FRF tokens may be prefixed by the receptance name, ``h21.re``; without a prefix they
belong to ``h`` (``direct_frf``). Examples: ``f,re,im`` (default), ``f,mag,phase``,
``f,h11.re,h11.im,h21.re,h21.im,h22.re,h22.im``. Delimiters: comma, semicolon, tab or
spaces (detected per line; decimal commas are not supported). Header lines before the
data and ``#``/``%`` comment lines are skipped.
"""

from __future__ import annotations

import os

import numpy as np

from rcsa.errors import InputError
from rcsa.measured.importers._common import decode_text, finish, numeric_rows, read_source
from rcsa.measured.importers.units import (
    frequency_factor_to_hz,
    parse_frf_unit,
    phase_factor_to_rad,
)
from rcsa.measured.store.measurement import Measurement, MeasurementMeta, Provenance

__all__ = ["parse_columns", "read_csv"]

_ROLES = {
    "f": "f", "freq": "f", "frequency": "f", "frequency_hz": "f",
    "re": "re", "real": "re", "im": "im", "imag": "im",
    "mag": "mag", "abs": "mag", "magnitude": "mag", "phase": "phase", "arg": "phase",
    "coh": "coh", "coherence": "coh", "_": "skip", "skip": "skip", "-": "skip",
}  # fmt: skip


def parse_columns(spec: str, kind: str) -> list[tuple[str, str]]:
    """Parse a column declaration into ``(name, role)`` per column (name '' for f and skip)."""
    if not isinstance(spec, str) or not spec.strip():
        raise InputError("columns", "declare the columns, e.g. 'f,re,im' or 'f,mag,phase'")
    out: list[tuple[str, str]] = []
    for tok in (t.strip().lower() for t in spec.split(",")):
        name, _, role = tok.rpartition(".")
        if role not in _ROLES:
            raise InputError(
                "columns", f"unknown column {tok!r}; use f, re, im, mag, phase, coh or _"
            )
        role = _ROLES[role]
        if role in ("f", "skip"):
            if name:
                raise InputError("columns", f"{tok!r}: only FRF columns take a name prefix")
        elif not name:
            if kind != "direct_frf":
                raise InputError(
                    "columns", f"kind {kind!r} needs named FRF columns, e.g. h11.re,h11.im"
                )
            name = "h"
        if (name, role) in out and role != "skip":
            raise InputError("columns", f"{tok!r} is declared twice")
        out.append((name, role))
    if sum(r == "f" for _, r in out) != 1:
        raise InputError("columns", "declare exactly one frequency column 'f'")
    for name in {n for n, r in out if n}:
        roles = {r for n, r in out if n == name}
        if not ({"re", "im"} <= roles or {"mag", "phase"} <= roles) or (
            {"re", "im"} & roles and {"mag", "phase"} & roles
        ):
            raise InputError(
                "columns", f"{name!r} needs either re and im, or mag and phase columns"
            )
    return out


def read_csv(
    source: str | os.PathLike[str] | bytes,
    meta: MeasurementMeta,
    *,
    units: str | None,
    columns: str = "f,re,im",
    frequency_unit: str = "Hz",
    phase_unit: str | None = None,
    delimiter: str | None = None,
    drop_nonpositive: bool = False,
    sensor_mass_kg: float | None = None,
    file_name: str = "",
) -> Measurement:
    """Import an FRF table.

    Parameters
    ----------
    source : path or bytes
        The file (or its bytes, e.g. an upload; then ``file_name`` names it).
    meta : MeasurementMeta
    units : str
        FRF unit, required (e.g. ``"um/N"``, ``"m/s^2/N"``, ``"g/N"``); see
        :mod:`rcsa.measured.importers.units`. A ``point_receptance`` table must be in SI
        (``m/N``; l, n, p then in 1/N, rad/N, rad/(N·m)).
    columns : str
        Column declaration (module docstring).
    frequency_unit : {"Hz", "kHz", "rad/s"}
    phase_unit : {"deg", "rad"}, optional
        Required when a phase column is declared.
    delimiter : str, optional
        Forced delimiter; default detects comma, semicolon or whitespace per line.
    drop_nonpositive : bool
        Drop rows at f <= 0 Hz instead of refusing the file.
    sensor_mass_kg : float, optional
        Remove this accelerometer mass (driving point, ``direct_frf`` only).
    file_name : str
        Name recorded in provenance when ``source`` is bytes.

    Returns
    -------
    Measurement
        Receptances in m/N vs Hz (contract conventions).
    """
    cols = parse_columns(columns, meta.kind)
    unit = parse_frf_unit(units)
    if meta.kind == "point_receptance" and (
        unit.quantity != "receptance" or unit.factor_to_si != 1.0
    ):
        raise InputError("units", "a point_receptance table must be in SI: declare units='m/N'")
    f_factor = frequency_factor_to_hz(frequency_unit)
    ph_factor = phase_factor_to_rad(phase_unit) if any(r == "phase" for _, r in cols) else None
    data, name, sha = read_source(source, file_name)
    rows, lines = numeric_rows(decode_text(data), delimiter=delimiter)
    for row, ln in zip(rows, lines, strict=True):
        if len(row) != len(cols):
            raise InputError(
                "columns",
                f"line {ln} has {len(row)} values but {len(cols)} columns are declared ({columns!r})",
            )
    table = np.array(rows, dtype=float)
    col = {key: table[:, i] for i, key in enumerate(cols)}
    freq = col[("", "f")] * f_factor
    values, coherence = {}, {}
    for nm in sorted({n for n, _ in cols if n}):
        if (nm, "re") in col:
            v = col[(nm, "re")] + 1j * col[(nm, "im")]
        else:
            v = col[(nm, "mag")] * np.exp(1j * ph_factor * col[(nm, "phase")])
        values[nm] = v * unit.factor_to_si
        if (nm, "coh") in col:
            coherence[nm] = col[(nm, "coh")]
    steps = []
    if unit.factor_to_si != 1.0:
        steps.append(f"scaled {unit.text} -> SI by {unit.factor_to_si:.17g}")
    if f_factor != 1.0:
        steps.append(f"frequency {frequency_unit} -> Hz by {f_factor:.17g}")
    prov = Provenance(
        source_format="csv",
        source_file=name,
        source_sha256=sha,
        original_quantity=unit.quantity,
        original_units=unit.text,
        conversions=tuple(steps),
    )
    return finish(
        freq,
        values,
        quantity=unit.quantity,
        meta=meta,
        provenance=prov,
        coherence=coherence,
        lines=lines,
        drop_nonpositive=drop_nonpositive,
        sensor_mass_kg=sensor_mass_kg,
    )
