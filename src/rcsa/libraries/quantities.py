"""Lengths and counts as CAM libraries write them: units, and numbers stored as strings.

Real exports store numbers as JSON numbers, and sometimes as strings (``"44"``, ``"44 mm"``,
spreadsheet round trips, hand-edited files). The rule here is strict, so that nothing is
read wrong silently:

* a JSON number is a number in the object's declared unit;
* a string holding one decimal number (``"44"``, ``" 4.5e1 "``) is that number, in the
  object's unit;
* a string with a number and a length unit (``"44 mm"``, ``"0.5in"``) is accepted only when
  the unit is a known spelling *and* the same unit the object declares — a tool in
  millimetres with ``"DC": "0.5 in"`` contradicts itself and is refused, not converted;
* anything else (``"44,5"``, ``"ten"``, ``"44 cm"``, ``true``, ``NaN``) is refused with the
  field named.

Counts (flutes ``NOF``, T numbers) are integers or strings holding one integer.
"""

from __future__ import annotations

import math
import re

from rcsa.errors import InputError
from rcsa.model import fields
from rcsa.model.bounds import MAX_LENGTH_M

__all__ = ["MAX_COUNT", "UNIT_SPELLINGS", "Unit", "count_value", "length_value", "unit_fraction", "unit_to_metres"]

#: A length unit as an exact ratio to the metre: (numerator, denominator).
Unit = tuple[int, int]

#: Accepted length-unit spellings (lower case) and their ratio to the metre.
UNIT_SPELLINGS: dict[str, Unit] = {}
for _names, _frac in (
    (("millimeters", "millimeter", "millimetres", "millimetre", "mm"), (1, 1000)),
    (("inches", "inch", "in"), (254, 10000)),
    (("meters", "meter", "metres", "metre", "m"), (1, 1)),
):
    for _name in _names:
        UNIT_SPELLINGS[_name] = _frac

_UNIT_NAMES = {(1, 1000): "millimeters", (254, 10000): "inches", (1, 1): "meters"}
_NUMBER = r"[+-]?(?:\d+(?:\.\d*)?|\.\d+)(?:[eE][+-]?\d+)?"
_NUMERIC = re.compile(rf"\s*({_NUMBER})\s*")
_WITH_UNIT = re.compile(rf"\s*({_NUMBER})\s*([A-Za-z]+)\s*")
_INTEGER = re.compile(r"\s*([+-]?\d+)\s*")


def unit_fraction(unit: object, field: str) -> Unit:
    """The exact ratio to the metre of a unit spelling; the field named when it is not one.

    Raises
    ------
    InputError
        Missing, not a string, or not a known spelling (a unit is never guessed).
    """
    if not isinstance(unit, str) or not unit.strip():
        raise InputError(field, "missing; the length unit must be stated (millimeters or inches)")
    key = unit.strip().strip("'\"").strip().lower()
    if key not in UNIT_SPELLINGS:
        raise InputError(field, f"unknown length unit {unit!r} (use millimeters or inches)")
    return UNIT_SPELLINGS[key]


def unit_to_metres(value: float, unit: str) -> float:
    """Convert a length in a unit spelling to metres.

    Parameters
    ----------
    value : float
        Length in ``unit``.
    unit : str
        A spelling of :data:`UNIT_SPELLINGS` (e.g. ``"inches"``, ``"millimeters"``, ``"mm"``).

    Returns
    -------
    float
        Length, m (one rounding: ``value * num / den`` with an exact integer ratio).

    Examples
    --------
    >>> unit_to_metres(0.5, "inches")
    0.0127
    >>> unit_to_metres(72, "millimeters")
    0.072
    """
    num, den = unit_fraction(unit, "unit")
    return value * num / den


def length_value(value: object, field: str, unit: Unit, *, gt: float | None = 0.0) -> float:
    """A length in the object's own unit, from a JSON number or a string (module docstring).

    Parameters
    ----------
    value : object
        As read from the JSON.
    field : str
        Its path, for messages (``geometry.DC``).
    unit : Unit
        The unit the object declares; a unit written in the string must be this one.
    gt : float or None
        The value must exceed this (None: any finite value).

    Returns
    -------
    float
        The number in ``unit`` (not converted to metres).

    Raises
    ------
    InputError
        Not a number, a string that is not one number (with at most the object's unit), a
        unit other than the object's, not finite, or not above ``gt``.

    Examples
    --------
    >>> length_value("44", "geometry.DC", (1, 1000))
    44.0
    >>> length_value("0.5 in", "geometry.DC", (254, 10000))
    0.5
    """
    if isinstance(value, str):
        value = _number_from_text(value, field, unit)
    number = fields.number(value, field, gt=gt)
    metres = abs(number) * unit[0] / unit[1]
    if metres > MAX_LENGTH_M:
        raise InputError(field, f"{value!r} is {metres:g} m, longer than any machine-tool part ({MAX_LENGTH_M:g} m)")
    return number


def _number_from_text(text: str, field: str, unit: Unit) -> float:
    if (m := _NUMERIC.fullmatch(text)) is not None:
        return float(m.group(1))
    if (m := _WITH_UNIT.fullmatch(text)) is None:
        raise InputError(field, f"must be a number, got the text {text!r}")
    stated = UNIT_SPELLINGS.get(m.group(2).lower())
    if stated is None:
        raise InputError(field, f"{text!r}: unknown length unit {m.group(2)!r} (use the object's own unit, "
                                f"{_UNIT_NAMES.get(unit, unit)})")
    if stated != unit:
        raise InputError(field, f"{text!r} states {_UNIT_NAMES[stated]} but the object's unit is "
                                f"{_UNIT_NAMES.get(unit, unit)}; the export contradicts itself and is not converted")
    return float(m.group(1))


def count_value(value: object) -> int | None:
    """An integer count (flutes, T number) from a JSON number or a string; None when not one.

    Integers, integer-valued floats and strings holding one integer (``"4"``) count; ``"4.5"``,
    ``"four"``, ``true``, ``NaN`` and counts beyond :data:`MAX_COUNT` do not (the caller decides
    whether that is a warning).

    Examples
    --------
    >>> count_value("4"), count_value(4.0), count_value("4.5")
    (4, 4, None)
    """
    count = _count(value)
    return count if count is not None and abs(count) <= MAX_COUNT else None


#: Largest count (flutes, T number) read from a library: beyond a 32-bit integer it is no count.
MAX_COUNT = 2**31 - 1


def _count(value: object) -> int | None:
    if isinstance(value, str):
        m = _INTEGER.fullmatch(value)
        return int(m.group(1)) if m else None
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        return None
    if isinstance(value, float) and not (math.isfinite(value) and value.is_integer()):
        return None
    return int(value)
