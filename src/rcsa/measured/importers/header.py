"""What a table's header says about its columns: role, FRF name and unit of each cell.

A header cell is a name and, optionally, a unit, in the styles seen in exports:
``Frequency (Hz)``, ``Real [m/N]``, ``|H| um/N``, ``Magnitude (dB re 1 m/N)``,
``Phase (deg)``, ``Re(H11) [(m/s²)/N]``, ``h21.im``, ``frequency_hz``, ``coherence``.
A names line over a units line (``Frequency;Real`` / ``Hz;m/N``) is merged before this.

Vocabulary (case-insensitive; words split at spaces, ``_ . - ( ) :``):

* frequency: ``f``, ``freq``, ``frequency``, ``frequenz``, or a cell that is only a
  frequency unit (``Hz``); units ``Hz``, ``kHz``, ``rad/s``;
* real and imaginary parts: ``re``, ``real``; ``im``, ``imag``, ``imaginary``;
* magnitude: ``mag``, ``magnitude``, ``abs``, ``amplitude``, ``amp``, ``modulus``, ``|H|``;
  in dB when the word ``dB`` or a dB unit appears (``dB re 1 m/N``, ``dB ref 1 µm/N``,
  ``dB re 1e-6 m/N``): |H| = ref · 10^(dB/20) (FRF amplitudes, never 10·log10);
* phase: ``phase``, ``phi``, ``arg``, ``angle``, ``∠``; units ``deg``, ``°``, ``rad``;
* coherence: ``coh``, ``coherence``, ``γ²``, ``gamma2``; unit none, ``-`` or ``1``;
* skipped: ``index``, ``idx``, ``row``, ``line``, ``no``, ``#``, and an unnamed first
  column (pandas' index);
* FRF names: ``h``, ``h11`` … ``h99`` (artifact points), ``hxx``/``hyy`` (checked against
  the measurement's direction), and ``l``, ``n``, ``p`` for a ``point_receptance``;
  ``H(f)`` reads as ``H``; filler words (``part``, ``of``, ``value``, ``frf``) are ignored
  and quantity words (``receptance``, ``mobility``, ``accelerance``, ``inertance``,
  ``compliance``) must agree with the unit;
* FRF units: anything :func:`~rcsa.measured.importers.units.parse_frf_unit` reads
  (``m/N``, ``µm/N``, ``(m/s²)/N``, ``g/N``, ``in/lbf`` …), in brackets or as the trailing
  words of the cell. A unit spelled only through a snake_case name (``real_um_n``) is
  *weak*: it must agree with a declared unit but does not declare one.

Anything else makes the cell unknown; the importer then refuses (or, with declared columns,
ignores the cell) — it never guesses.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass

from rcsa.errors import InputError
from rcsa.measured.importers.units import (
    FrfUnit,
    frequency_factor_to_hz,
    parse_frf_unit,
    phase_factor_to_rad,
)

__all__ = [
    "DbReference",
    "HeaderCell",
    "frf_unit_of",
    "is_unit_text",
    "parse_db_reference",
    "parse_header_cell",
]

_ROLE_WORDS = {
    "f": "f", "freq": "f", "frequency": "f", "frequencies": "f", "frequenz": "f", "frq": "f",
    "re": "re", "real": "re", "realpart": "re",
    "im": "im", "imag": "im", "imaginary": "im", "imagpart": "im",
    "mag": "mag", "magnitude": "mag", "abs": "mag", "amplitude": "mag", "amp": "mag",
    "modulus": "mag",
    "phase": "phase", "phi": "phase", "arg": "phase", "angle": "phase",
    "coh": "coh", "coherence": "coh", "gamma2": "coh",
    "index": "skip", "idx": "skip", "row": "skip", "line": "skip", "no": "skip", "#": "skip",
}  # fmt: skip
_FILLER = frozenset({"part", "of", "value", "values", "frf", "data", "the"})
_QUANTITY_WORDS = {
    "receptance": "receptance", "compliance": "receptance", "displacement": "receptance",
    "mobility": "mobility", "velocity": "mobility",
    "accelerance": "accelerance", "inertance": "accelerance", "acceleration": "accelerance",
}  # fmt: skip
_FRF_NAME = re.compile(r"^h([1-9][1-9]|xx|yy|zz|xy|yx|xz|zx|yz|zy)?$")
_ROTATIONAL_NAMES = frozenset({"l", "n", "p"})
_DB = re.compile(
    r"^db\s*(?:\(\s*)?(?:(?:re|ref|rel|reference)\b\.?\s*:?\s*)?"
    r"(?P<ref>.*?)(?:\s*\))?$",
    re.IGNORECASE,
)
_REF_VALUE = re.compile(
    r"^(?P<val>[0-9]+(?:\.[0-9]*)?(?:e[+-]?[0-9]+)?)\s*(?P<unit>.*)$", re.IGNORECASE
)
_DIMENSIONLESS = frozenset({"-", "1", "", "--", "–", "none"})
_WORD_SPLIT = re.compile(r"[\s_.\-():,;*=]+")


@dataclass(frozen=True, slots=True)
class DbReference:
    """A dB reference: |H| = ``value`` · ``unit`` · 10^(dB/20)."""

    text: str
    value: float
    unit: FrfUnit

    @property
    def factor_to_si(self) -> float:
        """SI value of 0 dB."""
        return self.value * self.unit.factor_to_si


def parse_db_reference(text: str) -> DbReference | None:
    """``"dB re 1 m/N"`` → its reference; ``"dB"`` → None (no reference said).

    Raises
    ------
    InputError
        Field ``units``: the text is not a dB unit, or its reference is not an FRF unit.
    """
    m = _DB.match(text.strip())
    if m is None:
        raise InputError("units", f"{text!r} is not a dB unit (write e.g. 'dB re 1 m/N')")
    ref = m["ref"].strip()
    if not ref:
        return None
    v = _REF_VALUE.match(ref)
    value, unit_text = (float(v["val"]), v["unit"]) if v and v["unit"] else (1.0, ref)
    if not math.isfinite(value) or value <= 0:
        raise InputError("units", f"{text!r}: the dB reference must be a positive value")
    unit = parse_frf_unit(unit_text.strip(), "units")
    return DbReference(text.strip(), value, unit)


def _unit_kind(text: str) -> str | None:
    """``frequency``, ``phase``, ``frf``, ``db``, ``none`` or None for a unit text."""
    t = text.strip()
    if t.lower() in _DIMENSIONLESS:
        return "none"
    if t.lower().startswith("db"):
        try:
            parse_db_reference(t)
        except InputError:
            return None
        return "db"
    for kind, parse in (
        ("frequency", frequency_factor_to_hz),
        ("phase", phase_factor_to_rad),
        ("frf", parse_frf_unit),
    ):
        try:
            parse(t)
        except InputError:
            continue
        return kind
    return None


def is_unit_text(text: str) -> bool:
    """Whether a cell is only a unit (a units line under a names line)."""
    return _unit_kind(text) is not None


@dataclass(frozen=True, slots=True)
class HeaderCell:
    """One understood header cell.

    Attributes
    ----------
    text : str
        The cell as written.
    role : {"f", "re", "im", "mag", "db", "phase", "coh", "skip"}
    name : str
        FRF name as written, lower case ('' when the cell names none; '' for f and skip).
    unit : str or None
        The unit as written (frequency, FRF, phase or dB unit), None when the cell has none.
    weak : bool
        The unit comes only from a snake_case name (``real_um_n``): it must agree with a
        declared unit but does not declare one.
    quantity : str or None
        ``receptance``, ``mobility`` or ``accelerance`` when a quantity word says so.
    """

    text: str
    role: str
    name: str = ""
    unit: str | None = None
    weak: bool = False
    quantity: str | None = None


def _split_unit(text: str) -> tuple[str, str | None]:
    """(name part, unit) from ``Name [unit]``, ``Name (unit)`` or ``Name unit words``."""
    if "[" in text and text.rstrip().endswith("]"):
        i, j = text.index("["), text.rindex("]")
        return (text[:i] + " " + text[j + 1 :]).strip(), text[i + 1 : j].strip()
    t = text.rstrip()
    if t.endswith(")"):
        depth, k = 0, len(t) - 1
        while k >= 0:
            depth += {")": 1, "(": -1}.get(t[k], 0)
            if depth == 0:
                break
            k -= 1
        inner = t[k + 1 : -1].strip() if k >= 0 else ""
        if k >= 0 and _unit_kind(inner) is not None:
            return t[:k].strip(), inner
    words = t.split()
    for k in range(len(words)):  # longest trailing run of words that is a unit
        tail = " ".join(words[k:])
        if _unit_kind(tail) not in (None, "none"):
            return " ".join(words[:k]), tail
    return t, None


def _words_unit(words: list[str]) -> tuple[str | None, bool]:
    """A unit from snake_case leftovers: ``["hz"]`` (strong), ``["um", "n"]`` (weak)."""
    if len(words) == 1 and _unit_kind(words[0]) in ("frequency", "phase"):
        return words[0], False
    ws = [w for w in words if w != "per"]
    if ws and ws[0] == "db":
        ref = ws[1:]
        if ref and ref[0] in ("re", "ref", "rel"):
            ref = ref[1:]
        value = (
            ref.pop(0) + " " if ref and _REF_VALUE.match(ref[0]) and not ref[0].isalpha() else ""
        )
        text = f"dB re {value}{'/'.join(ref)}" if ref else "dB"
        return (text, True) if _unit_kind(text) == "db" else (None, False)
    text = "/".join(ws)
    return (text, True) if _unit_kind(text) == "frf" else (None, False)


def parse_header_cell(cell: str, kind: str, *, first: bool = False) -> HeaderCell | str:
    """Understand one header cell, or say why not.

    Parameters
    ----------
    cell : str
        The cell as written.
    kind : {"direct_frf", "artifact_frfs", "point_receptance"}
        Which FRF names are possible.
    first : bool
        The cell is the first column (an unnamed first column is pandas' index: skipped).

    Returns
    -------
    HeaderCell or str
        The cell's meaning, or the reason it is not understood.
    """
    text = cell.strip().strip("\"'").strip()
    if not text:
        return HeaderCell(cell, "skip") if first else "the cell is empty"
    name_part, unit = _split_unit(text)
    s = name_part.lower().replace("µ", "u").replace("μ", "u")
    s = re.sub(r"γ\s*(\^?2|²)|gamma\s*(\^2|²)", " gamma2 ", s)
    roles: set[str] = set()
    if re.search(r"\|[^|]*\|", s):
        roles.add("mag")
        s = s.replace("|", " ")
    if "∠" in s:
        roles.add("phase")
        s = s.replace("∠", " ")
    s = re.sub(r"\b(h\w{0,2})\s*\(\s*(?:f|w|ω|jw|jω|iw|iω)\s*\)", r"\1", s)
    words = [w for w in _WORD_SPLIT.split(s) if w]
    db = False
    names: list[str] = []
    quantities: set[str] = set()
    leftovers: list[str] = []
    for k, w in enumerate(words):
        if db:
            leftovers.append(w)  # after "db": the reference
        elif w == "db":
            db = True
            leftovers.append(w)
        elif w in _ROLE_WORDS:
            roles.add(_ROLE_WORDS[w])
        elif _FRF_NAME.match(w) or (
            kind == "point_receptance" and w in _ROTATIONAL_NAMES and k == 0 and len(words) > 1
        ):
            names.append(w)
        elif w in _QUANTITY_WORDS:
            quantities.add(_QUANTITY_WORDS[w])
        elif w in _FILLER:
            continue
        else:
            leftovers.append(w)
    weak = False
    if leftovers:
        tail, weak = _words_unit(leftovers)
        if tail is None:
            unknown = ", ".join(repr(w) for w in leftovers)
            return f"{unknown} is not a word the importer knows"
        if unit is not None:
            return f"gives two units, {tail!r} and {unit!r}"
        unit = tail
    ukind = _unit_kind(unit) if unit is not None else None
    if ukind == "db" or db:
        if roles - {"mag"}:
            return f"says dB but also {sorted(roles - {'mag'})}"
        roles = {"db"}
    if not roles:
        if ukind == "frequency" and not names:
            roles = {"f"}
        else:
            return "does not say what the column holds (frequency, real, imag, magnitude, phase, coherence)"
    if len(roles) > 1:
        return f"names several things at once ({', '.join(sorted(roles))})"
    (role,) = roles
    expected = {"f": ("frequency",), "re": ("frf",), "im": ("frf",), "mag": ("frf",),
                "db": ("db",), "phase": ("phase",), "coh": ("none",)}.get(role)  # fmt: skip
    if unit is not None and ukind == "none":
        unit = None
    elif unit is not None and expected is not None and ukind not in expected:
        return f"a {role} column cannot be in {unit!r}"
    if len(set(names)) > 1:
        return f"names several FRFs ({', '.join(names)})"
    if names and role in ("f", "skip"):
        return f"a {role} column with an FRF name ({names[0]})"
    if len(quantities) > 1:
        return f"names several quantities ({', '.join(sorted(quantities))})"
    quantity = next(iter(quantities), None)
    q = frf_unit_of(role, unit)
    if quantity is not None and q is not None and q.quantity != quantity:
        return f"says {quantity} but its unit {unit!r} is {q.quantity}"
    return HeaderCell(
        cell, role, names[0] if names else "", unit, weak and unit is not None, quantity
    )


def frf_unit_of(role: str, unit: str | None) -> FrfUnit | None:
    """The FRF unit a column's unit text stands for: its own, or its dB reference's unit
    (None for non-FRF columns, no unit, or a dB unit without reference)."""
    if unit is None or role not in ("re", "im", "mag", "db"):
        return None
    if role == "db":
        ref = parse_db_reference(unit)
        return ref.unit if ref is not None else None
    return parse_frf_unit(unit)
