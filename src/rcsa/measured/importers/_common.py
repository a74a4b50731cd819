"""Shared importer steps: read a file once (bytes + sha256), parse numeric text, validate,
convert to receptance and build the :class:`~rcsa.measured.store.Measurement`."""

from __future__ import annotations

import dataclasses
import hashlib
import os
from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np

from rcsa.errors import InputError
from rcsa.measured.importers._table import COMMENTS as _COMMENTS
from rcsa.measured.importers._table import cut_column
from rcsa.measured.importers.bounds import check_frequency, check_magnitudes
from rcsa.measured.importers.bounds import row_label as _where
from rcsa.measured.importers.sensor import correct_sensor_mass
from rcsa.measured.importers.units import to_receptance
from rcsa.measured.store.measurement import Measurement, MeasurementMeta, Provenance
from rcsa.model.bounds import MAX_FREQUENCY_LINES, MAX_JSON_NUMBER
from rcsa.model.input_policy import check_count, check_numbers

__all__ = ["decode_text", "finish", "numeric_rows", "read_source", "split_line"]


def read_source(
    source: str | os.PathLike[str] | bytes, file_name: str = ""
) -> tuple[bytes, str, str]:
    """Read a whole file (or take uploaded bytes); return ``(bytes, name, sha256 hex)``.

    ``file_name`` overrides the recorded name (the only name bytes have). Raises
    :class:`InputError` (field ``file``) when the file cannot be read.
    """
    if isinstance(source, bytes | bytearray):
        data = bytes(source)
        return data, file_name, hashlib.sha256(data).hexdigest()
    p = Path(source)
    try:
        data = p.read_bytes()
    except FileNotFoundError:
        raise InputError("file", f"{p}: no such file") from None
    except OSError as e:
        raise InputError("file", f"cannot read {p}: {e.strerror or e}") from None
    return data, file_name or p.name, hashlib.sha256(data).hexdigest()


def decode_text(data: bytes) -> str:
    """UTF-8 (with or without BOM), else Latin-1 (old analyser exports write ``µ`` that way)."""
    try:
        return data.decode("utf-8-sig")
    except UnicodeDecodeError:
        return data.decode("latin-1")


def split_line(line: str, delimiter: str | None) -> list[str]:
    """Split a data line: the given delimiter, else comma, else semicolon, else whitespace."""
    if delimiter is None:
        delimiter = "," if "," in line else ";" if ";" in line else None
    if delimiter is None:
        return line.split()
    return [t.strip() for t in line.split(delimiter)]


def numeric_rows(
    text: str, *, delimiter: str | None = None, leading: int | None = None,
    max_rows: int = MAX_FREQUENCY_LINES,
) -> tuple[list[list[float]], list[int]]:
    """Rows of numbers from a text table, with the 1-based line number of each row.

    Blank lines and lines starting with ``#``, ``%``, ``//`` or ``!`` are skipped anywhere;
    lines that are not numbers are skipped before the first data row (a header) and refused
    after it. With ``leading=k`` only the first k tokens of a line must be numbers and the
    rest is ignored (CutPro's first line carries labels after its first triple). A file
    that ends without a newline in a last row that is short, or whose last value is written
    shorter than the same column in the other rows, is refused as truncated
    (:mod:`rcsa.measured.importers._table`). Every number meets the input policy
    (:func:`rcsa.model.input_policy.check_numbers`: finite, magnitude at most 1e30) and a
    file has at most ``max_rows`` rows.
    """
    rows: list[list[float]] = []
    lines: list[int] = []
    tokens: list[list[str]] = []
    raw_lines = text.splitlines()
    last = next((i for i in range(len(raw_lines), 0, -1) if raw_lines[i - 1].strip()), 0)
    open_end = not text.endswith(("\n", "\r"))
    for ln, raw in enumerate(raw_lines, 1):
        s = raw.strip()
        if not s or s.startswith(_COMMENTS):
            continue
        toks = split_line(s, delimiter)
        if leading is not None:
            toks = toks[:leading]
        try:
            vals = [float(t) for t in toks]
        except ValueError:
            if not rows:
                continue  # header line
            cut = (
                "; the file ends there without a newline: it looks truncated"
                if (ln == last and open_end)
                else ""
            )
            raise InputError(
                "file", f"line {ln} is not a row of numbers: {s[:80]!r}{cut}"
            ) from None
        if not all(-MAX_JSON_NUMBER <= v <= MAX_JSON_NUMBER for v in vals):
            check_numbers([vals], "file", lines=[ln], columns=None)
        rows.append(vals)
        lines.append(ln)
        tokens.append(toks)
        if len(rows) > max_rows:
            check_count(len(rows), "file", max_rows, "rows of numbers (the file goes on past line "
                                                     f"{ln})")
    if not rows:
        raise InputError("file", "no rows of numbers found")
    if open_end and len(rows) > 2 and lines[-1] == last:
        if len(rows[-1]) < len(rows[-2]):
            raise InputError(
                "columns",
                f"the last line {lines[-1]} has {len(rows[-1])} of {len(rows[-2])} values and no "
                "newline: the file looks truncated (cut mid-row)",
            )
        j = cut_column(tokens[-1], tokens[-50:-1])
        if j is not None:
            raise InputError(
                "file",
                f"the last line {lines[-1]} ends without a newline and its value "
                f"{tokens[-1][j]!r} is written shorter than every other row's "
                f"({tokens[-2][j]!r}): the file looks truncated (cut mid-number)",
            )
    return rows, lines


def finish(
    frequency_hz: np.ndarray,
    values: Mapping[str, np.ndarray],
    *,
    quantity: str,
    meta: MeasurementMeta,
    provenance: Provenance,
    coherence: Mapping[str, np.ndarray] | None = None,
    lines: Sequence[int] | None = None,
    drop_nonpositive: bool = False,
    sensor_mass_kg: float | None = None,
    bound_hint: str = "",
) -> Measurement:
    """Validate, drop 0 Hz rows if asked, convert to receptance and build the measurement.

    Every array is checked: finite values only, frequencies > 0, strictly increasing and at
    most :data:`~rcsa.measured.importers.bounds.MAX_FREQUENCY_HZ`, and every receptance
    within :data:`~rcsa.measured.importers.bounds.BOUNDS_BY_UNIT` once converted (so a unit
    mix-up of a factor 1e6 is refused, not stored).

    Parameters
    ----------
    frequency_hz : numpy.ndarray, shape (nfreq,)
        Hz, as read.
    values : mapping of str to numpy.ndarray, each shape (nfreq,)
        FRFs in SI of ``quantity`` (m/N, (m/s)/N or (m/s²)/N), complex.
    quantity : {"receptance", "mobility", "accelerance"}
    meta, provenance :
        Metadata; ``provenance.conversions`` gets the steps taken here appended.
    coherence : mapping of str to numpy.ndarray, optional
    lines : sequence of int, optional
        Source line of each row, for error messages.
    drop_nonpositive : bool
        Drop rows at f <= 0 Hz (e.g. the 0 Hz bin) instead of refusing them.
    sensor_mass_kg : float, optional
        Remove this accelerometer mass from the driving-point FRF (direct_frf only).
    bound_hint : str
        Advice appended when a magnitude is out of bounds (importer-specific).
    """
    f = np.asarray(frequency_hz, dtype=float)
    vals = {k: np.asarray(v, dtype=np.complex128) for k, v in values.items()}
    coh = {k: np.asarray(v, dtype=float) for k, v in (coherence or {}).items()}
    for name, arr in (
        ("frequency_hz", f),
        *vals.items(),
        *(("coherence." + k, v) for k, v in coh.items()),
    ):
        if arr.shape != f.shape:
            raise InputError(name, f"has {arr.size} values but frequency_hz has {f.size}")
        bad = np.flatnonzero(~np.isfinite(arr))
        if bad.size:
            raise InputError(name, f"{_where(int(bad[0]), lines)} is NaN or infinite")
    steps = list(provenance.conversions)
    nonpos = np.flatnonzero(f <= 0)
    if nonpos.size:
        if not drop_nonpositive:
            raise InputError(
                "frequency_hz",
                f"{_where(int(nonpos[0]), lines)} is at {f[nonpos[0]]:g} Hz; receptances are singular at 0 Hz. "
                "Remove such rows or ask to drop them (drop_nonpositive=True, CLI --drop-nonpositive)",
            )
        keep = f > 0
        steps.append(f"dropped {nonpos.size} row(s) at f <= 0 Hz")
        lines = [ln for ln, k in zip(lines, keep, strict=True) if k] if lines is not None else None
        f = f[keep]
        vals = {k: v[keep] for k, v in vals.items()}
        coh = {k: v[keep] for k, v in coh.items()}
    if f.size == 0:
        raise InputError("frequency_hz", "no rows at f > 0 Hz")
    dec = np.flatnonzero(np.diff(f) <= 0)
    if dec.size:
        i = int(dec[0]) + 1
        raise InputError(
            "frequency_hz",
            f"must be strictly increasing: {_where(i, lines)} has {f[i]:g} Hz after {f[i - 1]:g} Hz",
        )
    if quantity == "mobility":
        steps.append("mobility -> receptance: H = Y/(i w)")
    elif quantity == "accelerance":
        steps.append("accelerance -> receptance: H = -A/w^2")
    check_frequency(f, lines)
    with np.errstate(over="ignore", invalid="ignore"):
        frfs = {k: to_receptance(f, v, quantity) for k, v in vals.items()}
    for k, v in frfs.items():
        bad = np.flatnonzero(~np.isfinite(v))
        if bad.size:  # finite in the file's quantity, overflowed on conversion
            raise InputError(
                k, f"{_where(int(bad[0]), lines)} overflows on conversion to receptance"
            )
        check_magnitudes(k, v, f, lines=lines, read_as=provenance.original_units, hint=bound_hint)
    m = Measurement(
        frequency_hz=f,
        frfs=frfs,
        meta=meta,
        provenance=dataclasses.replace(provenance, conversions=tuple(steps)),
        coherence=coh,
    )
    if sensor_mass_kg is not None:
        m = correct_sensor_mass(m, sensor_mass_kg)
    return m
