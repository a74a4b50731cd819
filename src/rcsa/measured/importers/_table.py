"""Text tables as analysers, spreadsheets and scripts write them: one delimiter per file,
decimal points or decimal commas, a header (or none) before the data, and a last line that
may have been cut off.

:func:`read_table` finds the numbers and the header line but does not interpret the header
(that is :mod:`rcsa.measured.importers.header`), and refuses what it cannot read for sure:

* the delimiter is the one of ``; \\t , whitespace`` (in that order of preference) under
  which most lines near the end split into numbers;
* decimal commas (``1,25E-07``) are read only with a ``;``, tab or whitespace delimiter and
  only when no number in the file has a decimal point; a file that mixes both is refused
  (thousands separators are not supported);
* every data row must have as many fields as the first; a file that does not end with a
  newline and whose last row is short, or whose last value is written shorter than the same
  column in every other row (fewer decimals or exponent digits than a fixed format prints,
  or fewer significant digits than any other row), is refused as truncated. A file cut
  exactly at a line end cannot be told from a shorter one (CSV carries no row count).
"""

from __future__ import annotations

import re
from dataclasses import dataclass

from rcsa.errors import InputError
from rcsa.model.bounds import MAX_FREQUENCY_LINES
from rcsa.model.input_policy import check_count

__all__ = ["COMMENTS", "TextTable", "cut_column", "read_table"]

#: Comment markers: lines starting with one of these are not data (a header may hide there).
COMMENTS = ("#", "%", "//", "!")
_CANDIDATES: tuple[str | None, ...] = (";", "\t", ",", None)
_DETECT_LINES = 25
_DECIMAL_COMMA = re.compile(r"^[+-]?(\d+,\d*|,\d+)([eE][+-]?\d+)?$")
_NUMBER_SHAPE = re.compile(r"^[+-]?(\d*)[.,]?(\d*)(?:[eEdD]([+-]?)(\d*))?$")
_NAMES = {";": "semicolon", "\t": "tab", ",": "comma", None: "whitespace"}


@dataclass(frozen=True, slots=True)
class TextTable:
    """A numeric table read from text.

    Attributes
    ----------
    rows : list of list of float
        The data rows, each with ``ncols`` values.
    lines : list of int
        1-based line number of each row.
    tokens_last : list of str
        The last row as written (for messages).
    header : list of str or None
        The header cells when a line before the data splits into ``ncols`` fields (a
        two-line header of names over units is merged, ``"Real [m/N]"``); None otherwise.
    header_line : int or None
        Its line number (the names line of a two-line header).
    header_text : str
        The line taken as the header candidate, as written ('' when there is none).
    delimiter : str or None
        ``;``, tab, ``,`` or None for whitespace.
    decimal_comma : bool
        Numbers were written with decimal commas.
    """

    rows: list[list[float]]
    lines: list[int]
    tokens_last: list[str]
    header: list[str] | None
    header_line: int | None
    header_text: str
    delimiter: str | None
    decimal_comma: bool

    @property
    def ncols(self) -> int:
        """Number of columns of the data."""
        return len(self.rows[0])

    @property
    def delimiter_name(self) -> str:
        """``"comma"``, ``"semicolon"``, ``"tab"`` or ``"whitespace"``."""
        return _NAMES[self.delimiter]


def _split(line: str, delimiter: str | None) -> list[str]:
    if delimiter is None:
        return line.split()
    toks = [
        t.strip().strip('"').strip() for t in line.split(delimiter)
    ]  # "1.5" quoted by some writers
    while len(toks) > 1 and toks[-1] == "":  # "1,2,3," : a trailing delimiter, not a field
        toks.pop()
    return toks


def _numbers(toks: list[str], decimal_comma: bool) -> list[float] | None:
    """The tokens as numbers (decimal commas read as points, and then no point allowed)."""
    if decimal_comma:
        if any("." in t for t in toks):
            return None
        toks = [t.replace(",", ".") for t in toks]
    try:
        return [float(t) for t in toks]
    except ValueError:
        return None


def _comma_ok(toks: list[str]) -> bool:
    """Every token a number once decimal commas are read as points (and none has a point)."""
    return all(_DECIMAL_COMMA.match(t) or (_numbers([t], False) is not None) for t in toks)


def _detect(lines: list[str], delimiter: str | None) -> tuple[str | None, bool]:
    """Delimiter and decimal-comma use, from the last lines (the last one may be cut)."""
    sample = lines[-_DETECT_LINES - 1 : -1] if len(lines) > 1 else lines
    cands = _CANDIDATES if delimiter is None else (delimiter,)
    best: tuple[int, str | None, bool] = (0, cands[0], False)
    for cand in cands:
        plain = comma = 0
        for line in sample:
            toks = _split(line, cand)
            if len(toks) < 2 and cand is not None and delimiter is None:
                continue
            if _numbers(toks, False) is not None:
                plain += 1
            elif cand != "," and any("," in t for t in toks) and _comma_ok(toks):
                comma += 1
        count, dc = (plain, False) if plain >= comma else (comma, True)
        if count > best[0]:
            best = (count, cand, dc)
    if best[0] == 0:
        raise InputError("file", "no rows of numbers found")
    _, cand, dc = best
    if dc:
        mixed = next(
            (t for line in sample for t in _split(line, cand) if "." in t and "," not in t),
            None,
        )
        if mixed is not None:
            raise InputError(
                "file",
                f"numbers are written with decimal commas and with decimal points ({mixed!r}); "
                "thousands separators are not supported: export with one decimal separator",
            )
    return cand, dc


def _shape(tok: str) -> tuple[int, int] | None:
    """(decimals, exponent digits or -1) of a number as written; None if it is no number."""
    m = _NUMBER_SHAPE.match(tok)
    if m is None:
        return None
    return len(m[2]), (len(m[4]) if m[4] is not None else -1)


def _significant(tok: str) -> int:
    """Significant digits as written: ``-0.0350486`` → 6, ``2.040000e+03`` → 7."""
    mant = re.split(r"[eEdD]", tok.lstrip("+-"), maxsplit=1)[0].replace(".", "").replace(",", "")
    return len(mant.lstrip("0"))


def cut_column(last: list[str], rows_toks: list[list[str]]) -> int | None:
    """Index of a value of ``last`` written shorter than the same column in every other row:
    fewer decimals or exponent digits than a fixed format (``%.6e``) prints, a lost exponent,
    or fewer significant digits than any other row (``%.17g``, ``repr``)."""
    for j, tok in enumerate(last):
        others = [r[j] for r in rows_toks if len(r) > j]
        shapes = {_shape(t) for t in others}
        got = _shape(tok)
        if not others or got is None or None in shapes:
            continue
        known = {s for s in shapes if s is not None}
        if len(shapes) == 1:
            ((decimals, exp_digits),) = known
            if got[1] < exp_digits or got[0] < decimals:
                return j
        if min(e for _, e in known) >= 0 and got[1] < min(e for _, e in known):
            return j
        if _significant(tok) < min(_significant(t) for t in others):
            return j
    return None


def read_table(text: str, *, delimiter: str | None = None, max_rows: int = MAX_FREQUENCY_LINES) -> TextTable:
    """Read a numeric table; see the module docstring for the rules.

    Parameters
    ----------
    text : str
        The whole file, decoded.
    delimiter : str, optional
        Forced delimiter (``","``, ``";"``, ``"\\t"``); default: detected.
    max_rows : int
        Most data rows (the input policy's row count): a longer file is refused.

    Raises
    ------
    InputError
        Field ``file`` (no numbers, a non-numeric line among the data, mixed decimal
        separators, truncation) or ``columns`` (rows of different lengths).
    """
    content: list[tuple[int, str, bool]] = []  # (line number, stripped text, is comment)
    for ln, raw in enumerate(text.splitlines(), 1):
        s = raw.strip()
        if s:
            content.append((ln, s, s.startswith(COMMENTS)))
    data_like = [s for _, s, c in content if not c]
    if not data_like:
        raise InputError("file", "no rows of numbers found")
    delim, dc = _detect(data_like, delimiter)
    ends_with_newline = text.endswith(("\n", "\r"))
    last_ln = next((ln for ln, _, c in reversed(content) if not c), 0)

    rows: list[list[float]] = []
    lines: list[int] = []
    toks_kept: list[list[str]] = []
    preamble: list[tuple[int, str, bool]] = []
    for ln, s, is_comment in content:
        if is_comment:
            if not rows:
                preamble.append((ln, s, True))
            continue
        toks = _split(s, delim)
        vals = _numbers(toks, dc)
        if vals is None:
            if not rows:
                preamble.append((ln, s, False))
                continue
            cut = ln == last_ln and not ends_with_newline
            raise InputError(
                "file",
                f"line {ln} is not a row of numbers: {s[:80]!r}"
                + ("; the file ends there without a newline: it looks truncated" if cut else ""),
            )
        if rows and len(vals) != len(rows[0]):
            cut = ln == last_ln and not ends_with_newline and len(vals) < len(rows[0])
            raise InputError(
                "columns",
                (
                    f"the last line {ln} has {len(vals)} of {len(rows[0])} values and no newline: "
                    "the file looks truncated (cut mid-row)"
                )
                if cut
                else f"line {ln} has {len(vals)} values but line {lines[0]} has {len(rows[0])} "
                f"({_NAMES[delim]}-delimited)",
            )
        rows.append(vals)
        lines.append(ln)
        toks_kept.append(toks)
        if len(rows) > max_rows:
            check_count(len(rows), "file", max_rows, f"rows of numbers (the file goes on past line {ln})")
    if not rows:
        raise InputError("file", "no rows of numbers found")
    if not ends_with_newline and len(rows) > 2:
        j = cut_column(toks_kept[-1], toks_kept[-50:-1])
        if j is not None:
            raise InputError(
                "file",
                f"the last line {lines[-1]} ends without a newline and its value {toks_kept[-1][j]!r} "
                f"(column {j + 1}) is written shorter than every other row's "
                f"({toks_kept[-2][j]!r}): the file looks truncated (cut mid-number)",
            )
    header, header_line, header_text = _header(preamble, delim, len(rows[0]))
    return TextTable(rows, lines, toks_kept[-1], header, header_line, header_text, delim, dc)


def _cells(line: str, delimiter: str | None, n: int) -> list[str] | None:
    cells = _split(line, delimiter)
    if len(cells) != n and delimiter is None:
        # whitespace-delimited data under a header whose names contain single spaces
        cells = [c for c in re.split(r"\t|\s{2,}", line.strip()) if c]
    return cells if len(cells) == n else None


def _uncomment(s: str) -> str:
    for mark in sorted(COMMENTS, key=len, reverse=True):
        if s.startswith(mark):
            return s[len(mark) :].strip()
    return s


def _header(
    preamble: list[tuple[int, str, bool]], delimiter: str | None, n: int
) -> tuple[list[str] | None, int | None, str]:
    """The header cells: the last non-comment line before the data, else the last comment
    line (``numpy.savetxt`` writes ``# f,re,im``); a names line over a units line is merged."""
    plain = [(ln, s) for ln, s, c in preamble if not c]
    cand = plain or [(ln, _uncomment(s)) for ln, s, c in preamble if c]
    if not cand:
        return None, None, ""
    ln, text = cand[-1]
    cells = _cells(text, delimiter, n)
    if cells is None:
        return None, None, text
    if len(cand) >= 2 and _all_units(cells):
        above = _cells(cand[-2][1], delimiter, n)
        if above is not None and not _all_units(above):
            merged = [
                f"{a} [{u}]" if u.strip() not in ("", "-") else a
                for a, u in zip(above, cells, strict=True)
            ]
            return merged, cand[-2][0], f"{cand[-2][1]} / {text}"
    return cells, ln, text


def _all_units(cells: list[str]) -> bool:
    from rcsa.measured.importers.header import is_unit_text

    return all(is_unit_text(c) for c in cells) and any(c.strip() for c in cells)
