"""CSV/TSV FRF tables: columns and units from the header, or declared; never guessed.

**Columns from the header.** When the line before the data names every column (e.g.
``Frequency (Hz),Magnitude (um/N),Phase (deg)``), the columns and the units written there
are used; the vocabulary is in :mod:`rcsa.measured.importers.header` (frequency in Hz/kHz/
rad/s; real/imag; magnitude linear or in dB with its reference, ``dB re 1 m/N``; phase in deg
or rad; coherence; receptance, mobility and accelerance units). A table without such a
header, or with a cell the importer does not understand, is refused with the columns it saw
and how to declare them.

**Declared columns** (``columns=``, CLI ``--columns``, form field ``columns``) win over the
header, one token per column of the file:

* ``f`` (also ``freq``, ``frequency``): the frequency, in ``frequency_unit`` (Hz default);
* ``re``, ``im`` or ``mag``, ``phase`` (aliases ``real``, ``imag``, ``abs``, ``magnitude``,
  ``arg``), or ``db``, ``phase`` for a magnitude in dB: the FRF, in ``units`` (for ``db``, the
  reference: ``units="dB re 1 m/N"``); phase in ``phase_unit``;
* ``coh``: its coherence (0…1);
* ``_`` (or ``skip``): a column to ignore.

FRF tokens may be prefixed by the receptance name, ``h21.re``; without a prefix they
belong to ``h`` (``direct_frf``). Examples: ``f,re,im``, ``f,mag,phase``,
``f,h11.re,h11.im,h21.re,h21.im,h22.re,h22.im``. A header the importer understands must
agree with the declaration (roles, names and units); a disagreement is an error, not a pick.

Delimiters: comma, semicolon, tab or spaces, one per file; decimal commas with ``;``, tab or
spaces (see :mod:`rcsa.measured.importers._table`). ``#``/``%``/``//``/``!`` lines are comments;
a commented header (``numpy.savetxt``) is used when there is no other.
"""

from __future__ import annotations

import os
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from rcsa.errors import InputError
from rcsa.measured.importers._common import decode_text, finish, read_source
from rcsa.measured.importers._table import TextTable, read_table
from rcsa.measured.importers.bounds import MAX_ABS_PHASE_RAD, row_label
from rcsa.measured.importers.header import (
    DbReference,
    HeaderCell,
    parse_db_reference,
    parse_header_cell,
)
from rcsa.measured.importers.units import (
    FrfUnit,
    frequency_factor_to_hz,
    parse_frf_unit,
    phase_factor_to_rad,
)
from rcsa.measured.store.measurement import Measurement, MeasurementMeta, Provenance
from rcsa.model.bounds import MAX_JSON_NUMBER

__all__ = ["parse_columns", "read_csv"]

_ROLES = {
    "f": "f", "freq": "f", "frequency": "f", "frequency_hz": "f",
    "re": "re", "real": "re", "im": "im", "imag": "im",
    "mag": "mag", "abs": "mag", "magnitude": "mag", "db": "db", "phase": "phase", "arg": "phase",
    "coh": "coh", "coherence": "coh", "_": "skip", "skip": "skip", "-": "skip",
}  # fmt: skip
_FRF_ROLES = ("re", "im", "mag", "db")
#: Relative agreement required between re/im and magnitude/phase columns of one FRF when a
#: file carries both: exports print 4-17 digits, so 2e-3 of |H| (plus 1e-6 of the peak near
#: zeros) admits any printing and still refuses mislabelled columns.
_BOTH_FORMS_RTOL, _BOTH_FORMS_ATOL = 2e-3, 1e-6
_DECLARE = (
    "declare them, e.g. columns='f,re,im' or 'f,mag,phase' "
    "(CLI --columns f,re,im; form field columns)"
)


def _check_structure(cols: list[tuple[str, str]], origin: str) -> None:
    """One frequency column; each FRF with re and im, or a magnitude and a phase."""
    seen: set[tuple[str, str]] = set()
    for name, role in cols:
        if role == "skip":
            continue
        if (name, role) in seen:
            what = f"{name}.{role}" if name else role
            raise InputError("columns", f"{origin}: {what!r} appears twice")
        seen.add((name, role))
    if sum(r == "f" for _, r in cols) != 1:
        raise InputError("columns", f"{origin}: needs exactly one frequency column 'f'")
    for name in sorted({n for n, r in cols if n}):
        roles = {r for n, r in cols if n == name}
        polar = {"mag", "db"} & roles
        if len(polar) > 1:
            raise InputError("columns", f"{origin}: {name!r} has a linear and a dB magnitude")
        if not ({"re", "im"} <= roles or (polar and "phase" in roles)):
            raise InputError(
                "columns", f"{origin}: {name!r} needs either re and im, or mag and phase columns"
            )


def parse_columns(spec: str, kind: str) -> list[tuple[str, str]]:
    """Parse a column declaration into ``(name, role)`` per column (name '' for f and skip)."""
    if not isinstance(spec, str) or not spec.strip():
        raise InputError("columns", "declare the columns, e.g. 'f,re,im' or 'f,mag,phase'")
    out: list[tuple[str, str]] = []
    for tok in (t.strip().lower() for t in spec.split(",")):
        name, _, role = tok.rpartition(".")
        if role not in _ROLES:
            raise InputError(
                "columns", f"unknown column {tok!r}; use f, re, im, mag, db, phase, coh or _"
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
        polar = {"mag", "db"} & roles
        if (
            not ({"re", "im"} <= roles or (len(polar) == 1 and "phase" in roles))
            or ({"re", "im"} & roles and (polar or "phase" in roles))
            or len(polar) > 1
        ):
            raise InputError(
                "columns", f"{name!r} needs either re and im, or mag (or db) and phase columns"
            )
    return out


@dataclass(frozen=True, slots=True)
class _Col:
    name: str
    role: str
    unit: str | None = None  # as written in the header
    weak: bool = False
    header: str = ""
    quantity: str | None = None  # a quantity word of the header (accelerance, ...)


def _header_names(cells: list[HeaderCell], meta: MeasurementMeta) -> dict[str, str]:
    """Header FRF name → stored name (direct_frf: the one FRF is ``h``)."""
    names = sorted({c.name for c in cells if c.role not in ("f", "skip") and c.name})
    for n in names:
        if len(n) == 3 and n[1] in "xyz":
            if n[1] != n[2] or meta.kind != "direct_frf":
                raise InputError(
                    "columns",
                    f"the header names {n.upper()}; {meta.kind} FRFs are named "
                    + ("H11, H21, ... by point" if meta.kind == "artifact_frfs" else "h, l, n, p")
                    if n[1] == n[2]
                    else f"the header names {n.upper()}, a cross-direction FRF",
                )
            if n[1] != meta.direction:
                raise InputError(
                    "direction",
                    f"the header names {n.upper()} (direction {n[1]}) but direction "
                    f"{meta.direction} was given",
                )
    if meta.kind == "direct_frf":
        if len(names) > 1:
            raise InputError(
                "columns",
                f"the header names several FRFs ({', '.join(names)}) but kind direct_frf holds "
                f"one; {_DECLARE} with '_' for the others",
            )
        return dict.fromkeys([*names, ""], "h")
    return {n: n for n in [*names, ""]}


def _from_header(table: TextTable, meta: MeasurementMeta) -> list[_Col]:
    first = ", ".join(repr(t) for t in table.tokens_last[:8])
    seen = f"{table.ncols} {table.delimiter_name}-delimited columns (last row: {first})"
    if table.header is None:
        why = (
            f"the line before the data, {table.header_text[:80]!r}, does not split into "
            f"{table.ncols} {table.delimiter_name}-delimited names"
            if table.header_text
            else "there is no header line before the data"
        )
        raise InputError("columns", f"{why}; the file has {seen}: {_DECLARE}")
    parsed = [parse_header_cell(c, meta.kind, first=(j == 0)) for j, c in enumerate(table.header)]
    problems = [f"column {j + 1} {c!r} {p}" for j, (c, p) in enumerate(zip(table.header, parsed, strict=True)) if isinstance(p, str)]  # fmt: skip
    if problems:
        raise InputError(
            "columns",
            f"cannot tell what the header (line {table.header_line}) means: "
            + "; ".join(problems)
            + f"; {_DECLARE}",
        )
    cells = [p for p in parsed if isinstance(p, HeaderCell)]
    rename = _header_names(cells, meta)
    cols = [
        _Col(
            rename[c.name] if c.role not in ("f", "skip") else "",
            c.role,
            c.unit,
            c.weak,
            c.text,
            c.quantity,
        )
        for c in cells
    ]
    if meta.kind != "direct_frf" and any(c.name == "" for c in cols if c.role not in ("f", "skip")):
        raise InputError(
            "columns",
            f"the header does not name the FRF of every column; kind {meta.kind!r} needs "
            "names such as 'Re(H11)' or 'h11.re'; declare them, e.g. "
            "columns='f,h11.re,h11.im,h21.re,h21.im,h22.re,h22.im'",
        )
    _check_structure([(c.name, c.role) for c in cols], "the header")
    return cols


def _with_declared(declared: list[tuple[str, str]], table: TextTable, spec: str, meta: MeasurementMeta) -> list[_Col]:  # fmt: skip
    if len(declared) != table.ncols:
        raise InputError(
            "columns",
            f"line {table.lines[0]} has {table.ncols} values but {len(declared)} columns are "
            f"declared ({spec!r})",
        )
    cells: list[HeaderCell | str | None] = [None] * len(declared)
    if table.header is not None:
        cells = [
            parse_header_cell(c, meta.kind, first=(j == 0)) for j, c in enumerate(table.header)
        ]
        try:
            rename = _header_names([c for c in cells if isinstance(c, HeaderCell)], meta)
        except InputError as e:
            if e.field == "direction":
                raise
            rename = {}
    out = []
    for j, (name, role) in enumerate(declared):
        c = cells[j]
        if not isinstance(c, HeaderCell) or not c.text.strip() or role == "skip":
            out.append(_Col(name, role))
            continue
        h_name = rename.get(c.name, c.name) if c.role not in ("f", "skip") else ""
        if meta.kind == "direct_frf" and h_name:
            h_name = "h"  # a direct FRF has one FRF, whatever the header calls it
        if c.role != role or (c.name and h_name != name):
            said = f"{h_name}.{c.role}" if h_name and c.role not in ("f", "skip") else c.role
            raise InputError(
                "columns",
                f"column {j + 1} is declared {(name + '.' if name and role not in ('f', 'skip') else '') + role!r} "
                f"but the header (line {table.header_line}) says {c.text!r} ({said}); fix the "
                "declaration or leave it out to use the header",
            )
        out.append(_Col(name, role, c.unit, c.weak, c.text, c.quantity))
    return out


def _same(a: FrfUnit, b: FrfUnit) -> bool:
    return a.quantity == b.quantity and bool(np.isclose(a.factor_to_si, b.factor_to_si, rtol=1e-12))


def _is_db(text: str | None) -> bool:
    return isinstance(text, str) and text.strip().lower().startswith("db")


def _frf_unit(cols: list[_Col], units: str | None, meta: MeasurementMeta) -> tuple[FrfUnit, float | None, str]:  # fmt: skip
    """(FRF unit, SI value of 0 dB or None, unit text for provenance) from the declaration
    and the header, which must agree; a weak (snake_case) header unit declares nothing."""
    has_db = any(c.role == "db" for c in cols)
    decl_ref: DbReference | None = None
    decl: FrfUnit | None = None
    if _is_db(units):
        decl_ref = parse_db_reference(str(units))
        if decl_ref is None:
            raise InputError(
                "units", f"{units!r} has no reference; write e.g. 'dB re 1 m/N' or 'dB re 1 um/N'"
            )
        if not has_db:
            raise InputError("units", f"{units!r} is a dB unit but no column is in dB")
        decl = decl_ref.unit
    elif units is not None:
        decl = parse_frf_unit(units)
    strong: list[tuple[_Col, FrfUnit]] = []
    weak: list[tuple[_Col, FrfUnit]] = []
    refs: list[tuple[_Col, DbReference]] = []
    for c in cols:
        if c.unit is None or c.role not in _FRF_ROLES:
            continue
        if c.role == "db":
            ref = parse_db_reference(c.unit)
            if ref is None:
                continue  # "dB" alone: the reference is not said
            if not c.weak:
                refs.append((c, ref))
            u = ref.unit
        else:
            u = parse_frf_unit(c.unit)
        (weak if c.weak else strong).append((c, u))
    keep = " or leave it out to use the header"
    for c, u in strong + weak:
        if decl is not None and not _same(u, decl):
            raise InputError(
                "units",
                f"{units!r} was declared but the header says {c.header!r} ({u.quantity} in "
                f"{u.text}); fix the declaration{keep if not c.weak else ''}",
            )
    for (c1, u1), (c2, u2) in zip(strong, strong[1:], strict=False):
        if not _same(u1, u2):
            raise InputError(
                "units", f"the header gives different units, {c1.header!r} and {c2.header!r}"
            )
    for c, ref in refs:
        first = decl_ref or refs[0][1]
        if not np.isclose(ref.factor_to_si, first.factor_to_si, rtol=1e-12):
            raise InputError(
                "units",
                f"{first.text!r} but the header says {c.header!r}; fix the declaration{keep}",
            )
    if has_db and decl_ref is None and not refs:
        raise InputError(
            "units",
            "a magnitude in dB needs its reference, which neither the header nor the "
            "declaration states; declare it, e.g. units='dB re 1 m/N' (or 'dB re 1 um/N')",
        )
    if decl is not None:
        unit, text = decl, str(units)
    elif strong:
        unit = strong[0][1]
        text = (strong[0][0].unit or "") if strong[0][0].role != "db" else refs[0][1].text
    elif weak:
        c, u = weak[0]
        raise InputError(
            "units",
            f"the header name {c.header!r} suggests {u.text} but a name is not a unit statement; "
            f"declare the FRF unit (units='{u.text}'; CLI --units; form field units) or write "
            "it in the header as e.g. 'Real (um/N)'",
        )
    else:
        parse_frf_unit(None)  # raises: the FRF unit must be declared
        raise AssertionError  # pragma: no cover
    for c in cols:
        if c.quantity is not None and c.role in _FRF_ROLES and c.quantity != unit.quantity:
            raise InputError(
                "units",
                f"the header says {c.header!r} ({c.quantity}) but the unit is {text} "
                f"({unit.quantity})",
            )
    db_si = None
    if has_db:
        db_si = (decl_ref or refs[0][1]).factor_to_si
    if meta.kind == "point_receptance" and (
        unit.quantity != "receptance" or unit.factor_to_si != 1.0 or has_db
    ):
        raise InputError("units", "a point_receptance table must be in SI: declare units='m/N'")
    return unit, db_si, str(text)


def _one_unit(
    cols: list[_Col],
    role: str,
    declared: str | None,
    field: str,
    parse: Callable[[str, str], float],
) -> float | None:
    """Factor of the frequency or phase columns: header and declaration must agree."""
    factors = []
    for c in cols:
        if c.role != role:
            continue
        if (
            c.unit is not None
            and declared is not None
            and parse(c.unit, field) != parse(declared, field)
        ):
            raise InputError(
                field,
                f"{declared!r} was declared but the header says {c.header!r}; fix the declaration "
                "or leave it out to use the header",
            )
        text = declared if declared is not None else c.unit
        if text is None:
            if role == "f":
                factors.append(1.0)  # Hz unless said otherwise
                continue
            raise InputError(field, "a phase column needs its unit declared: deg or rad")
        factors.append(parse(text, field))
    if len(set(factors)) > 1:
        raise InputError(field, f"the {role} columns are in different units; declare the columns")
    return factors[0] if factors else None


def read_csv(
    source: str | os.PathLike[str] | bytes,
    meta: MeasurementMeta,
    *,
    units: str | None = None,
    columns: str | None = None,
    frequency_unit: str | None = None,
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
    units : str, optional
        FRF unit (e.g. ``"um/N"``, ``"m/s^2/N"``, ``"g/N"``; ``"dB re 1 m/N"`` for dB
        magnitudes); see :mod:`rcsa.measured.importers.units`. Required unless the header
        writes it; must agree with the header when both do. A ``point_receptance`` table
        must be in SI (``m/N``; l, n, p then in 1/N, rad/N, rad/(N·m)).
    columns : str, optional
        Column declaration (module docstring); default: from the header.
    frequency_unit : {"Hz", "kHz", "rad/s"}, optional
        Default: the header's, else Hz.
    phase_unit : {"deg", "rad"}, optional
        Required for a phase column whose header does not say.
    delimiter : str, optional
        Forced delimiter; default detects semicolon, tab, comma or whitespace.
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

    Raises
    ------
    InputError
        Naming the field (``columns``, ``units``, ``frequency_unit``, ``phase_unit``,
        ``file``, ``direction`` or an FRF) and what was seen.
    """
    declared = parse_columns(columns, meta.kind) if columns is not None else None
    if units is not None and not _is_db(units):
        parse_frf_unit(units)  # a bad declaration is reported before the file is read
    for text, parse, field in ((frequency_unit, frequency_factor_to_hz, "frequency_unit"),
                               (phase_unit, phase_factor_to_rad, "phase_unit")):  # fmt: skip
        if text is not None:
            parse(text, field)
    data, name, sha = read_source(source, file_name)
    table = read_table(decode_text(data), delimiter=delimiter)
    if declared is not None:
        cols = _with_declared(declared, table, columns or "", meta)
        origin = ""  # the caller's declaration, already in the caller's hands
    else:
        cols = _from_header(table, meta)
        origin = f"columns from the header (line {table.header_line}): " + ", ".join(
            repr(c.header) for c in cols
        )
    unit, db_si, unit_text = _frf_unit(cols, units, meta)
    f_factor = _one_unit(cols, "f", frequency_unit, "frequency_unit", frequency_factor_to_hz)
    ph_factor = _one_unit(cols, "phase", phase_unit, "phase_unit", phase_factor_to_rad)
    table_arr = np.array(table.rows, dtype=float)
    for j in range(table_arr.shape[1]):
        bad = np.flatnonzero(~(np.abs(table_arr[:, j]) <= MAX_JSON_NUMBER))
        if bad.size and cols[j].role != "skip":
            label = cols[j].header or f"{cols[j].name}.{cols[j].role}".lstrip(".")
            x = float(table_arr[bad[0], j])
            raise InputError(
                cols[j].name or ("frequency_hz" if cols[j].role == "f" else "file"),
                f"{row_label(int(bad[0]), table.lines)}, column {j + 1} ({label}) is {x!r}: "
                + ("not a finite number" if not np.isfinite(x) else
                   f"out of range (its magnitude must be <= {MAX_JSON_NUMBER:g})"),
            )
    col = {(c.name, c.role): table_arr[:, j] for j, c in enumerate(cols) if c.role != "skip"}
    freq = col[("", "f")] * f_factor
    values, coherence = {}, {}
    steps = [origin] if origin else []
    if table.decimal_comma:
        steps.append("decimal commas read as decimal points")
    with np.errstate(over="ignore", invalid="ignore"):
        for nm in sorted({c.name for c in cols if c.name}):
            polar = None
            if (nm, "mag") in col:
                polar = col[(nm, "mag")] * unit.factor_to_si
            elif (nm, "db") in col:
                assert db_si is not None  # a dB column has its reference (_frf_unit)
                polar = db_si * 10.0 ** (col[(nm, "db")] / 20.0)
                steps.append(f"{nm}: magnitude in dB -> linear, |H| = {db_si:.17g} * 10^(dB/20)")
            if polar is not None:
                phase = col[(nm, "phase")] * ph_factor
                if ph_factor == 1.0 and np.nanmax(np.abs(phase)) > MAX_ABS_PHASE_RAD:
                    i = int(np.nanargmax(np.abs(phase)))
                    raise InputError(
                        "phase_unit",
                        f"{nm}: the phase, declared in rad, reaches {phase[i]:.6g} at "
                        f"{row_label(i, table.lines)}, more than {MAX_ABS_PHASE_RAD / np.pi:g} pi: "
                        "it looks like degrees",
                    )
                polar = polar * np.exp(1j * phase)
            if (nm, "re") in col:
                v = (col[(nm, "re")] + 1j * col[(nm, "im")]) * unit.factor_to_si
                if polar is not None:
                    _check_both_forms(nm, v, polar, freq, table.lines)
                    steps.append(f"{nm}: re/im read; its magnitude/phase columns agree")
            else:
                assert polar is not None  # each name has re/im or magnitude/phase (checked with the roles)
                v = polar
            values[nm] = v
            if (nm, "coh") in col:
                coherence[nm] = col[(nm, "coh")]
    if unit.factor_to_si != 1.0 and any(c.role in ("re", "im", "mag") for c in cols):
        steps.append(f"scaled {unit.text} -> SI by {unit.factor_to_si:.17g}")
    if f_factor != 1.0:
        steps.append(f"frequency x {f_factor:.17g} -> Hz")
    prov = Provenance(
        source_format="csv",
        source_file=name,
        source_sha256=sha,
        original_quantity=unit.quantity,
        original_units=unit_text,
        conversions=tuple(steps),
    )
    return finish(
        freq,
        values,
        quantity=unit.quantity,
        meta=meta,
        provenance=prov,
        coherence=coherence,
        lines=table.lines,
        drop_nonpositive=drop_nonpositive,
        sensor_mass_kg=sensor_mass_kg,
    )


def _check_both_forms(name: str, reim: np.ndarray, polar: np.ndarray, freq: np.ndarray, lines: list[int]) -> None:  # fmt: skip
    finite = np.isfinite(reim) & np.isfinite(polar)
    if not finite.any():
        return
    tol = _BOTH_FORMS_RTOL * np.abs(reim) + _BOTH_FORMS_ATOL * np.max(np.abs(reim[finite]))
    bad = np.flatnonzero(finite & (np.abs(reim - polar) > tol))
    if bad.size:
        i = int(bad[0])
        raise InputError(
            "columns",
            f"{name}: the re/im and magnitude/phase columns disagree at {row_label(i, lines)} "
            f"({freq[i]:g} Hz: {reim[i]:.4g} vs {polar[i]:.4g}); declare which to read, e.g. "
            "columns='f,re,im,_,_'",
        )
