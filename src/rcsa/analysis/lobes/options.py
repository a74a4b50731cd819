"""The stability-lobes method of a request and its options (contract v1.1 "Stability-lobes method").

``"method": "zoa"`` (default: the Altintas–Budak zero-order solution, :mod:`.zoa`) or
``"semi_discretization"`` (:mod:`.semi_discretization`), which also takes
``"steps_per_period"`` and ``"modes_per_direction"``. Those two are refused with ``"zoa"``,
which has no use for them (a silent no-op would hide a mistake). The bounds below are the
single source: the service's schema imports them.
"""

from __future__ import annotations

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
    "parse_method",
]

Method = Literal["zoa", "semi_discretization"]
METHODS: tuple[Method, ...] = ("zoa", "semi_discretization")
MIN_MODES_PER_DIRECTION = 1
#: Largest speed grid with ``"semi_discretization"`` (about 6 ms a speed: 30 s).
MAX_SDM_SPEED_COUNT = 5000
#: Request fields read here.
OPTION_KEYS = ("method", "steps_per_period", "modes_per_direction")
_SDM_ONLY = ("steps_per_period", "modes_per_direction")


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
    """

    name: Method = "zoa"
    steps_per_period: int = DEFAULT_STEPS_PER_PERIOD
    modes_per_direction: int = DEFAULT_MODES_PER_DIRECTION


def parse_method(body: Mapping[str, Any]) -> LobesMethod:
    """The method fields of a stability-lobes request body (absent or null: defaults).

    Raises
    ------
    InputError
        An unknown method, an option out of bounds or not an integer, or an SDM option
        with ``"zoa"``.

    Examples
    --------
    >>> parse_method({})
    LobesMethod(name='zoa', steps_per_period=40, modes_per_direction=3)
    >>> parse_method({"method": "semi_discretization", "steps_per_period": 60}).steps_per_period
    60
    """
    name = body.get("method")
    name = "zoa" if name is None else name
    if name not in METHODS:
        raise InputError("method", f"must be one of {', '.join(repr(m) for m in METHODS)}, got {name!r}")
    given = {key: body[key] for key in _SDM_ONLY if body.get(key) is not None}
    if given and name != "semi_discretization":
        raise InputError(next(iter(given)), "is an option of method 'semi_discretization' only")
    steps = given.get("steps_per_period", DEFAULT_STEPS_PER_PERIOD)
    modes = given.get("modes_per_direction", DEFAULT_MODES_PER_DIRECTION)
    return LobesMethod(
        name,
        fields.integer(steps, "steps_per_period", ge=MIN_STEPS_PER_PERIOD, le=MAX_STEPS_PER_PERIOD),
        fields.integer(modes, "modes_per_direction", ge=MIN_MODES_PER_DIRECTION, le=MAX_MODES_PER_DIRECTION),
    )
