"""Declared units of foreign FRF files, and conversion to receptance in m/N.

Units are never guessed: every importer takes them from the file (UFF dataset 164) or
from the caller, and :func:`parse_frf_unit` refuses what it does not recognise.

Recognised spellings (case-insensitive, spaces and parentheses ignored, ``µ``/``μ``/``u``
alike, ``s^2``/``s2``/``s²`` alike):

* receptance ``L/F``: ``m/N``, ``mm/N``, ``um/N``, ``nm/N``, ``in/lbf``, ``mm/mN`` …
* mobility ``L/s/F``: ``m/s/N``, ``(mm/s)/N``, ``in/s/lbf`` …
* accelerance ``L/s^2/F`` or ``g/F``: ``m/s^2/N``, ``(m/s²)/N``, ``g/N``, ``g/lbf`` …

with lengths L in m, mm, um, nm, in, ft and forces F in N, mN, kN, lbf, kgf.
``g`` is standard gravity, 9.80665 m/s² (CGPM 1901, exact).
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass

import numpy as np

from rcsa.errors import InputError

__all__ = [
    "FORCE_N",
    "LENGTH_M",
    "STANDARD_GRAVITY_M_S2",
    "FrfUnit",
    "SignalUnit",
    "frequency_factor_to_hz",
    "parse_frf_unit",
    "parse_signal_unit",
    "phase_factor_to_rad",
    "to_receptance",
]

STANDARD_GRAVITY_M_S2 = 9.80665
#: Metres per unit of length (inch and foot exact by the 1959 agreement).
LENGTH_M = {"m": 1.0, "mm": 1e-3, "um": 1e-6, "nm": 1e-9, "in": 0.0254, "ft": 0.3048}
#: Newtons per unit of force (lbf = 0.45359237 kg × g, exact; kgf = g, exact).
FORCE_N = {
    "n": 1.0,
    "mn": 1e-3,
    "kn": 1e3,
    "lbf": 0.45359237 * STANDARD_GRAVITY_M_S2,
    "kgf": STANDARD_GRAVITY_M_S2,
}
_QUANTITY = {"": "receptance", "/s": "mobility", "/s2": "accelerance"}
_FRF = re.compile(r"^(?P<num>m|mm|um|nm|in|ft|g)(?P<per>/s2|/s)?/(?P<force>n|mn|kn|lbf|kgf)$")
_SIGNAL = re.compile(r"^(?P<num>m|mm|um|nm|in|ft|g)(?P<per>/s2|/s)?$")
_EXAMPLES = "m/N, um/N, mm/N, in/lbf, m/s/N, m/s^2/N, g/N"


def _normalise(text: str) -> str:
    t = text.strip().lower().replace(" ", "").replace("(", "").replace(")", "")
    t = (
        t.replace("µ", "u")
        .replace("μ", "u")
        .replace("²", "2")
        .replace("^2", "2")
        .replace("**2", "2")
    )
    return t.replace("sec", "s")


@dataclass(frozen=True, slots=True)
class FrfUnit:
    """A parsed FRF unit.

    Attributes
    ----------
    text : str
        The unit as declared.
    quantity : {"receptance", "mobility", "accelerance"}
    factor_to_si : float
        Multiply values by this to get m/N, (m/s)/N or (m/s²)/N.
    """

    text: str
    quantity: str
    factor_to_si: float


@dataclass(frozen=True, slots=True)
class SignalUnit:
    """A parsed time-signal unit: ``kind`` is displacement, velocity, acceleration or force."""

    text: str
    kind: str
    factor_to_si: float


def parse_frf_unit(text: object, field: str = "units") -> FrfUnit:
    """Parse a declared FRF unit such as ``"um/N"`` or ``"g/N"``.

    Raises
    ------
    InputError
        ``text`` is missing or not a recognised unit.
    """
    if not isinstance(text, str) or not text.strip():
        raise InputError(field, f"the FRF unit must be declared, e.g. {_EXAMPLES}")
    m = _FRF.match(_normalise(text))
    if m is None:
        raise InputError(field, f"unknown FRF unit {text!r}; use e.g. {_EXAMPLES}")
    num, per, force = m["num"], m["per"] or "", m["force"]
    if num == "g":
        if per:
            raise InputError(field, f"{text!r}: g is already an acceleration")
        return FrfUnit(text, "accelerance", STANDARD_GRAVITY_M_S2 / FORCE_N[force])
    return FrfUnit(text, _QUANTITY[per], LENGTH_M[num] / FORCE_N[force])


def parse_signal_unit(text: object, field: str) -> SignalUnit:
    """Parse a time-signal unit: a force (``N``, ``lbf`` …) or a response (``m/s^2``, ``g`` …)."""
    if not isinstance(text, str) or not text.strip():
        raise InputError(field, "the signal unit must be declared, e.g. N, lbf, m/s^2, g, m/s, um")
    t = _normalise(text)
    if t in FORCE_N:
        return SignalUnit(text, "force", FORCE_N[t])
    m = _SIGNAL.match(t)
    if m is None:
        raise InputError(field, f"unknown signal unit {text!r}; use e.g. N, lbf, m/s^2, g, m/s, um")
    if m["num"] == "g":
        if m["per"]:
            raise InputError(field, f"{text!r}: g is already an acceleration")
        return SignalUnit(text, "acceleration", STANDARD_GRAVITY_M_S2)
    kind = {"": "displacement", "/s": "velocity", "/s2": "acceleration"}[m["per"] or ""]
    return SignalUnit(text, kind, LENGTH_M[m["num"]])


def frequency_factor_to_hz(text: str, field: str = "frequency_unit") -> float:
    """Hz per unit of a declared frequency unit: ``Hz``, ``kHz`` or ``rad/s``."""
    t = _normalise(text)
    table = {"hz": 1.0, "khz": 1e3, "rad/s": 1.0 / (2.0 * math.pi)}
    if t not in table:
        raise InputError(field, f"unknown frequency unit {text!r}; use Hz, kHz or rad/s")
    return table[t]


def phase_factor_to_rad(text: object, field: str = "phase_unit") -> float:
    """Radians per unit of a declared phase unit: ``deg`` (``°``) or ``rad``."""
    if not isinstance(text, str) or not text.strip():
        raise InputError(field, "a phase column needs its unit declared: deg or rad")
    t = _normalise(text)
    if t in ("deg", "degree", "degrees", "°"):
        return math.pi / 180.0
    if t in ("rad", "radian", "radians"):
        return 1.0
    raise InputError(field, f"unknown phase unit {text!r}; use deg or rad")


def to_receptance(frequency_hz: np.ndarray, values: np.ndarray, quantity: str) -> np.ndarray:
    """Convert an FRF in SI to receptance (m/N), ``docs/physics.md`` §2.1.

    Parameters
    ----------
    frequency_hz : numpy.ndarray, shape (nfreq,)
        Frequencies > 0, Hz.
    values : numpy.ndarray, shape (nfreq,)
        Receptance m/N, mobility (m/s)/N or accelerance (m/s²)/N, complex.
    quantity : {"receptance", "mobility", "accelerance"}

    Returns
    -------
    numpy.ndarray, shape (nfreq,), complex128
        ``H = values``, ``H = Y/(iω)`` or ``H = −A/ω²`` (time dependence e^{iωt}).
    """
    v = np.asarray(values, dtype=np.complex128)
    omega = 2.0 * np.pi * np.asarray(frequency_hz, dtype=float)
    if quantity == "receptance":
        return v.copy()
    if quantity == "mobility":
        return v / (1j * omega)
    if quantity == "accelerance":
        return -v / omega**2
    raise InputError("quantity", f"must be receptance, mobility or accelerance, got {quantity!r}")
