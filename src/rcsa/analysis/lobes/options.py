"""The stability-lobes method of a request and its options (contract v1.1 "Stability-lobes method").

``"method": "auto"`` (the default) picks one of ``"zoa"`` (the Altintas–Budak zero-order
solution, :mod:`.zoa`) and ``"semi_discretization"`` (:mod:`.semi_discretization`) for the cut
(:func:`auto_method`: zero-order only where it is exact); either may be named. The
semi-discretization also takes ``"steps_per_period"`` (fixed steps over the whole tooth period,
instead of the steps that resolve the cut) and ``"modes_per_direction"`` (at most this many
modes per direction; by default every mode above the peak threshold, up to
``MAX_MODES_PER_DIRECTION``). Those two are refused with ``"zoa"``, which has no use for them (a
silent no-op would hide a mistake). The bounds below are the single source: the service's schema
imports them.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any, Literal

from rcsa.analysis.lobes.modal_model import MAX_MODES_PER_DIRECTION
from rcsa.analysis.lobes.semi_discretization import (
    DEFAULT_STEPS_PER_PERIOD,
    MAX_STEPS_PER_PERIOD,
    MIN_STEPS_PER_PERIOD,
)
from rcsa.errors import InputError
from rcsa.model import fields

__all__ = [
    "AUTO",
    "DEFAULT_METHOD",
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
    "zoa_is_exact",
]

Method = Literal["zoa", "semi_discretization"]
METHODS: tuple[Method, ...] = ("zoa", "semi_discretization")
#: ``"auto"`` in a request: :func:`auto_method` picks one of :data:`METHODS` for the cut.
AUTO = "auto"
#: The method of a request that names none.
DEFAULT_METHOD = AUTO
MIN_MODES_PER_DIRECTION = 1
#: Largest speed grid with ``"semi_discretization"``.
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


def zoa_is_exact(teeth: int, radial_immersion: float) -> bool:
    """Whether zero-order averaging is exact for the cut: slotting with an even number of teeth, at least four.

    Then exactly ``N/2`` teeth cut at every instant, ``2π/N`` apart over ``[0, π]``, and the sums of
    ``cos 2φ_j`` and ``sin 2φ_j`` over them vanish (the angles ``2φ_j`` are ``N/2 ≥ 2`` equally
    spaced points of the circle): the directional matrix of the cut is constant in time, so its
    average *is* the cut and the zero-order limit is the exact one
    (``tests/analysis/lobes/test_auto_method.py`` checks the constant matrix and the agreement with a
    converged semi-discretization).

    Examples
    --------
    >>> zoa_is_exact(4, 1.0), zoa_is_exact(6, 1.0), zoa_is_exact(2, 1.0), zoa_is_exact(4, 0.5)
    (True, True, False, False)
    """
    return radial_immersion >= 1.0 - 1e-12 and teeth >= 4 and teeth % 2 == 0


def auto_method(teeth: int, radial_immersion: float) -> tuple[Method, str]:
    """The method ``"auto"`` picks for a cut, and why.

    Zero-order averaging only where it is exact (:func:`zoa_is_exact`); everywhere else the
    semi-discretization with the steps that resolve the cut. Measured against converged
    semi-discretization (``benchmarks/bench_zoa_vs_sdm.py``, docs/presets.md "Which method"), zero-order
    limits lie 0.44–2.2× the truth at low immersion and still up to +11 % above it with one or more
    teeth always cutting (two-flute slotting, four flutes at half immersion): outside the −10 %…+5 %
    a default answer must keep, so it is not the default there.

    Examples
    --------
    >>> auto_method(4, 1.0)[0], auto_method(4, 0.5)[0], auto_method(1, 0.05)[0]
    ('zoa', 'semi_discretization', 'semi_discretization')
    """
    inside = teeth_in_cut(teeth, radial_immersion)
    if zoa_is_exact(teeth, radial_immersion):
        return "zoa", (f"auto: slotting with {teeth} teeth: {teeth // 2} teeth always cut, the cutting force's "
                       "direction never changes, and zero-order averaging is exact")
    return "semi_discretization", (f"auto: {inside:.2f} teeth in the cut on average: the cutting force varies "
                                   "over a tooth period, so the time-periodic semi-discretization (zero-order "
                                   "averaging is exact only for even-toothed slotting)")


@dataclass(frozen=True, slots=True)
class LobesMethod:
    """How to compute the lobes.

    Attributes
    ----------
    name : {"zoa", "semi_discretization"}
    steps_per_period : int or None
        SDM: fixed steps per tooth period over the whole period (``MIN_STEPS_PER_PERIOD …
        MAX_STEPS_PER_PERIOD``); None: the steps that resolve the cut, checked per speed.
    modes_per_direction : int
        SDM: at most this many modes in x and in y (``1 … MAX_MODES_PER_DIRECTION``; default the
        maximum: every mode above the peak threshold).
    reason : str
        Why ``"auto"`` chose ``name`` (empty when the request named the method).
    """

    name: Method = "semi_discretization"
    steps_per_period: int | None = None
    modes_per_direction: int = MAX_MODES_PER_DIRECTION
    reason: str = ""


def parse_method(body: Mapping[str, Any], *, teeth: int | None = None,
                 radial_immersion: float | None = None) -> LobesMethod:
    """The method fields of a stability-lobes request body (absent or null: defaults).

    ``method`` absent or ``"auto"`` is resolved by :func:`auto_method` from ``teeth`` and
    ``radial_immersion`` (the request's checked cut); the result says why (``reason``).

    Raises
    ------
    InputError
        An unknown method, an option out of bounds or not an integer, an SDM option with
        ``"zoa"``, or ``"auto"`` without the cut to resolve it.

    Examples
    --------
    >>> parse_method({}, teeth=1, radial_immersion=0.05).name
    'semi_discretization'
    >>> parse_method({"method": "semi_discretization", "steps_per_period": 60}).steps_per_period
    60
    >>> parse_method({"method": "zoa"})
    LobesMethod(name='zoa', steps_per_period=None, modes_per_direction=8, reason='')
    """
    name = body.get("method")
    name = DEFAULT_METHOD if name is None else name
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
    steps = given.get("steps_per_period")
    modes = given.get("modes_per_direction", MAX_MODES_PER_DIRECTION)
    return LobesMethod(
        name,
        None if steps is None else fields.integer(steps, "steps_per_period", ge=MIN_STEPS_PER_PERIOD,
                                                  le=MAX_STEPS_PER_PERIOD),
        fields.integer(modes, "modes_per_direction", ge=MIN_MODES_PER_DIRECTION, le=MAX_MODES_PER_DIRECTION),
        reason,
    )
