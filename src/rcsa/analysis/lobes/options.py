"""The stability-lobes method of a request and its options (contract v1.1 "Stability-lobes method").

``"method": "zoa"`` (default: the Altintas–Budak zero-order solution, :mod:`.zoa`),
``"semi_discretization"`` (:mod:`.semi_discretization`) or ``"auto"`` (one of the two, by
the teeth in the cut: :func:`auto_method`); semi-discretization also takes
``"steps_per_period"`` and ``"modes_per_direction"``. Those two are refused with ``"zoa"``,
which has no use for them (a silent no-op would hide a mistake). The bounds below are the
single source: the service's schema imports them.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any, Literal

from rcsa.analysis.lobes.modal_model import DEFAULT_MODES_PER_DIRECTION, MAX_MODES_PER_DIRECTION
from rcsa.analysis.lobes.semi_discretization import (
    DEFAULT_STEPS_PER_PERIOD,
    MAX_STEPS_PER_PERIOD,
    MIN_STEPS_PER_PERIOD,
)
from rcsa.errors import InputError
from rcsa.model import fields

__all__ = [
    "AUTO",
    "AUTO_MIN_TEETH_IN_CUT",
    "DEFAULT_MODES_PER_DIRECTION",
    "DEFAULT_STEPS_PER_PERIOD",
    "MAX_MODES_PER_DIRECTION",
    "MAX_SDM_SPEED_COUNT",
    "MAX_STEPS_PER_PERIOD",
    "METHODS",
    "MIN_MODES_PER_DIRECTION",
    "MIN_STEPS_PER_PERIOD",
    "OPTION_KEYS",
    "LobesMethod",
    "Method",
    "auto_method",
    "parse_method",
    "teeth_in_cut",
]

Method = Literal["zoa", "semi_discretization"]
METHODS: tuple[Method, ...] = ("zoa", "semi_discretization")
#: ``"auto"`` in a request: :func:`auto_method` picks one of :data:`METHODS` for the cut.
AUTO = "auto"
#: ``"auto"`` uses zero-order averaging only when at least this many teeth are in the cut on
#: average (``N (φex − φst) / 2π``): then the cutting force never drops to zero and its time
#: variation is mild. Below it the force is a train of pulses and the zero-order limit is unsafe
#: or far too cautious; measured in ``benchmarks/bench_zoa_vs_sdm.py`` (``docs/presets.md`` "Which method").
AUTO_MIN_TEETH_IN_CUT = 1.0
MIN_MODES_PER_DIRECTION = 1
#: Largest speed grid with ``"semi_discretization"`` (about 6 ms a speed: 30 s).
MAX_SDM_SPEED_COUNT = 5000
#: Request fields read here.
OPTION_KEYS = ("method", "steps_per_period", "modes_per_direction")
_SDM_ONLY = ("steps_per_period", "modes_per_direction")


def teeth_in_cut(teeth: int, radial_immersion: float) -> float:
    """Average number of teeth cutting at once, ``N (φex − φst) / 2π`` (the same for up and down milling).

    Examples
    --------
    >>> teeth_in_cut(4, 0.5), round(teeth_in_cut(1, 0.05), 4)
    (1.0, 0.0718)
    """
    sweep = math.acos(1.0 - 2.0 * radial_immersion)  # φex − φst
    return teeth * sweep / (2.0 * math.pi)


def auto_method(teeth: int, radial_immersion: float) -> tuple[Method, str]:
    """The method ``"auto"`` picks for a cut, and why.

    Examples
    --------
    >>> auto_method(4, 0.5)[0], auto_method(2, 0.5)[0], auto_method(1, 0.05)[0]
    ('zoa', 'semi_discretization', 'semi_discretization')
    """
    inside = teeth_in_cut(teeth, radial_immersion)
    if inside >= AUTO_MIN_TEETH_IN_CUT - 1e-9:
        return "zoa", (f"auto: {inside:.2f} teeth in the cut on average (>= {AUTO_MIN_TEETH_IN_CUT:g}): the "
                       "cutting force never vanishes and zero-order averaging holds")
    return "semi_discretization", (f"auto: {inside:.2f} teeth in the cut on average (< {AUTO_MIN_TEETH_IN_CUT:g}): "
                                   "the force is a train of pulses, zero-order averaging is not trustworthy")


@dataclass(frozen=True, slots=True)
class LobesMethod:
    """How to compute the lobes.

    Attributes
    ----------
    name : {"zoa", "semi_discretization"}
    steps_per_period : int
        SDM steps per tooth period (``MIN_STEPS_PER_PERIOD … MAX_STEPS_PER_PERIOD``).
    modes_per_direction : int
        SDM: at most this many modes in x and in y (``1 … MAX_MODES_PER_DIRECTION``).
    reason : str
        Why ``"auto"`` chose ``name`` (empty when the request named the method).
    """

    name: Method = "zoa"
    steps_per_period: int = DEFAULT_STEPS_PER_PERIOD
    modes_per_direction: int = DEFAULT_MODES_PER_DIRECTION
    reason: str = ""


def parse_method(body: Mapping[str, Any], *, teeth: int | None = None,
                 radial_immersion: float | None = None) -> LobesMethod:
    """The method fields of a stability-lobes request body (absent or null: defaults).

    ``"method": "auto"`` is resolved by :func:`auto_method` from ``teeth`` and
    ``radial_immersion`` (the request's checked cut); the result says why (``reason``).

    Raises
    ------
    InputError
        An unknown method, an option out of bounds or not an integer, an SDM option with
        ``"zoa"``, or ``"auto"`` without the cut to resolve it.

    Examples
    --------
    >>> parse_method({})
    LobesMethod(name='zoa', steps_per_period=40, modes_per_direction=3, reason='')
    >>> parse_method({"method": "semi_discretization", "steps_per_period": 60}).steps_per_period
    60
    >>> parse_method({"method": "auto"}, teeth=1, radial_immersion=0.05).name
    'semi_discretization'
    """
    name = body.get("method")
    name = "zoa" if name is None else name
    reason = ""
    if name == AUTO:
        if teeth is None or radial_immersion is None:
            raise InputError("method", "'auto' needs the cut (teeth, radial_immersion) to choose a method")
        name, reason = auto_method(teeth, radial_immersion)
    if name not in METHODS:
        raise InputError("method", f"must be one of {', '.join(repr(m) for m in (*METHODS, AUTO))}, got {name!r}")
    given = {key: body[key] for key in _SDM_ONLY if body.get(key) is not None}
    if given and name != "semi_discretization":
        raise InputError(next(iter(given)), "is an option of method 'semi_discretization' only"
                         + (f" ({reason})" if reason else ""))
    steps = given.get("steps_per_period", DEFAULT_STEPS_PER_PERIOD)
    modes = given.get("modes_per_direction", DEFAULT_MODES_PER_DIRECTION)
    return LobesMethod(
        name,
        fields.integer(steps, "steps_per_period", ge=MIN_STEPS_PER_PERIOD, le=MAX_STEPS_PER_PERIOD),
        fields.integer(modes, "modes_per_direction", ge=MIN_MODES_PER_DIRECTION, le=MAX_MODES_PER_DIRECTION),
        reason,
    )
