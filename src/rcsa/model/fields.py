"""Reading request fields: typed getters that name the field's path in every error.

Every request parser (the assembly, batches, lobes, diagnosis, identification, effects,
measurement uploads) reads parsed JSON through these functions, so a field that is missing,
of the wrong type or out of bounds is reported the same way everywhere: an
:class:`~rcsa.errors.InputError` with the dotted path of the field and the rule it broke.

Values: :func:`number` (finite, with ``gt``/``ge``/``le``/``lt`` bounds), :func:`integer`,
:func:`boolean`, :func:`string` (with ``choices``), :func:`json_object` (with the allowed
keys). :class:`Fields` reads the members of one object and builds their paths.

>>> o = Fields({"stickout_m": 0.05, "material": "carbide"}, "tool")
>>> o.number("stickout_m", gt=0.0, le=0.2), o.string("material", choices=("steel", "carbide"))
(0.05, 'carbide')
>>> o.number("diameter_m")
Traceback (most recent call last):
...
rcsa.errors.InputError: tool.diameter_m: is required
>>> number(-1.0, "teeth_angle", gt=0.0)
Traceback (most recent call last):
...
rcsa.errors.InputError: teeth_angle: must be > 0, got -1
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Collection, Mapping
from typing import Any, TypeVar

from rcsa.errors import InputError

_L = TypeVar("_L", bound=str)
_T = TypeVar("_T")

__all__ = ["Fields", "boolean", "integer", "join", "json_object", "number", "only", "string"]

def join(path: str, key: str | int) -> str:
    """The path of ``key`` inside ``path``: ``tool.stickout_m``, ``segments[2]``.

    Parameters
    ----------
    path : str
        The dotted path of the containing value (``""`` for the request itself).
    key : str or int
        A member name, or a list index.

    Returns
    -------
    str
    """
    if isinstance(key, int):
        return f"{path}[{key}]"
    return f"{path}.{key}" if path else key


def _is_number(value: object) -> bool:
    return isinstance(value, numbers.Real) and not isinstance(value, bool)


def number(value: object, field: str, *, gt: float | None = None, ge: float | None = None,
           le: float | None = None, lt: float | None = None, text: bool = False) -> float:
    """A finite number within the bounds given.

    The bounds are checked in the order ``gt``, ``ge``, ``le``, ``lt``, so that a value
    that is not positive hears "must be > 0" before any sanity minimum. With ``text``, a
    string holding a number is read too (form fields, command-line options).

    Parameters
    ----------
    value : object
        The parsed JSON value.
    field : str
        Its path, named in the error.
    gt, ge, le, lt : float, optional
        Bounds: greater than, at least, at most, less than.
    text : bool
        Also read a string holding a number.

    Returns
    -------
    float

    Raises
    ------
    InputError
        ``must be a number, got <type or text>``, ``must be a finite number`` or
        ``must be <op> <bound>, got <value>``.
    """
    if text and isinstance(value, str):
        try:
            value = float(value)
        except ValueError:
            raise InputError(field, f"must be a number, got {value!r}") from None
    if not _is_number(value):
        raise InputError(field, f"must be a number, got {type(value).__name__}")
    x = float(value)  # type: ignore[arg-type]
    if not math.isfinite(x):
        raise InputError(field, "must be a finite number")
    for bound, ok, word in ((gt, x > (gt or 0.0), ">"), (ge, x >= (ge or 0.0), ">="),
                            (le, x <= (le or 0.0), "<="), (lt, x < (lt or 0.0), "<")):
        if bound is not None and not ok:
            raise InputError(field, f"must be {word} {bound:g}, got {x:g}")
    return x


def integer(value: object, field: str, *, ge: int | None = None, le: int | None = None) -> int:
    """An integer (not a bool, not a float) within ``[ge, le]``.

    Parameters
    ----------
    value : object
        The parsed JSON value.
    field : str
        Its path, named in the error.
    ge, le : int, optional
        Smallest and largest allowed value.

    Returns
    -------
    int

    Raises
    ------
    InputError
        ``must be an integer, got <value>``, or ``must be between <ge> and <le>, got <n>``
        (``must be >= <ge>`` / ``must be <= <le>`` with one bound).
    """
    if not isinstance(value, numbers.Integral) or isinstance(value, bool):
        raise InputError(field, f"must be an integer, got {value!r}")
    n = int(value)
    if (ge is not None and n < ge) or (le is not None and n > le):
        if ge is not None and le is not None:
            raise InputError(field, f"must be between {ge} and {le}, got {n}")
        raise InputError(field, f"must be >= {ge}, got {n}" if ge is not None else f"must be <= {le}, got {n}")
    return n


_TRUE, _FALSE = ("true", "1", "yes", "on"), ("false", "0", "no", "off", "")


def boolean(value: object, field: str, *, text: bool = False) -> bool:
    """``true`` or ``false``; with ``text`` also a string (``true``/``1``/``yes``/``on``,
    ``false``/``0``/``no``/``off``/empty, any case) from a form field.

    Parameters
    ----------
    value : object
        The parsed JSON value.
    field : str
        Its path, named in the error.
    text : bool
        Also read the strings above.

    Returns
    -------
    bool

    Raises
    ------
    InputError
        ``must be true or false, got <value>``.
    """
    if text and isinstance(value, str) and value.strip().lower() in (*_TRUE, *_FALSE):
        return value.strip().lower() in _TRUE
    if not isinstance(value, bool):
        raise InputError(field, f"must be true or false, got {value!r}")
    return value


def string(value: object, field: str, *, choices: Collection[str] | None = None) -> str:
    """A non-empty string, one of ``choices`` when given.

    Parameters
    ----------
    value : object
        The parsed JSON value.
    field : str
        Its path, named in the error.
    choices : collection of str, optional
        The allowed values.

    Returns
    -------
    str

    Raises
    ------
    InputError
        ``must be a non-empty string`` or ``must be one of <choices>, got <value>``.
    """
    if not isinstance(value, str) or not value:
        raise InputError(field, "must be a non-empty string")
    if choices is not None and value not in choices:
        raise InputError(field, f"must be one of {', '.join(choices)}, got {value!r}")
    return value


def only(value: Mapping[str, Any], field: str, allowed: Collection[str]) -> None:
    """Refuse keys of ``value`` that are not ``allowed`` (the first one, sorted, is named).

    Parameters
    ----------
    value : mapping
        A JSON object.
    field : str
        Its path.
    allowed : collection of str
        The keys it may have.

    Raises
    ------
    InputError
        ``<field>.<key>: unknown field (allowed: ...)``.
    """
    unknown = sorted(set(value) - set(allowed))
    if unknown:
        raise InputError(join(field, unknown[0]), f"unknown field (allowed: {', '.join(allowed)})")


def json_object(value: object, field: str, allowed: Collection[str] | None = None) -> Mapping[str, Any]:
    """A JSON object (a mapping), with only ``allowed`` keys when given.

    Parameters
    ----------
    value : object
        The parsed JSON value.
    field : str
        Its path, named in the error.
    allowed : collection of str, optional
        The keys it may have.

    Returns
    -------
    mapping

    Raises
    ------
    InputError
        ``must be an object, got <type>``, or an unknown key (:func:`only`).
    """
    if not isinstance(value, Mapping):
        raise InputError(field, f"must be an object, got {type(value).__name__}")
    if allowed is not None:
        only(value, field, allowed)
    return value


class Fields:
    """The members of one JSON object, read by typed getters that name their path.

    Parameters
    ----------
    value : object
        The parsed JSON value; must be an object.
    path : str
        Its dotted path in the request (``""`` for the whole request).
    allowed : collection of str, optional
        The keys it may have (others are refused at once).

    Getters take the member's key; ``number``, ``integer`` and ``boolean`` return
    ``default`` when the member is absent or null, and without a default (None) say "is
    required"; :meth:`optional_number` returns None for an absent member.
    """

    def __init__(self, value: object, path: str, allowed: Collection[str] | None = None) -> None:
        self.value = json_object(value, path, allowed)
        self.path = path

    def at(self, key: str | int) -> str:
        """The path of a member.

        Parameters
        ----------
        key : str or int
            The member's name (or index).
        """
        return join(self.path, key)

    def only(self, *allowed: str) -> None:
        """Refuse members not in ``allowed``.

        Parameters
        ----------
        *allowed : str
            The member names allowed.
        """
        only(self.value, self.path, allowed)

    def has(self, key: str) -> bool:
        """Whether the member is present and not null.

        Parameters
        ----------
        key : str
            The member's name.
        """
        return self.value.get(key) is not None

    def _absent(self, key: str, default: _T | None) -> _T:
        if default is not None:
            return default
        raise InputError(self.at(key), "is required")

    def number(self, key: str, *, default: float | None = None,
               gt: float | None = None, ge: float | None = None, le: float | None = None,
               lt: float | None = None) -> float:
        """A finite number member (:func:`number`).

        Parameters
        ----------
        key : str
            The member's name.
        default : float, optional
            Returned when the member is absent or null; without it the member is required.
        gt, ge, le, lt : float, optional
            Bounds (:func:`number`).
        """
        raw = self.value.get(key)
        if raw is None:
            return self._absent(key, default)
        return number(raw, self.at(key), gt=gt, ge=ge, le=le, lt=lt)

    def optional_number(self, key: str, *, gt: float | None = None, ge: float | None = None,
                        le: float | None = None, lt: float | None = None) -> float | None:
        """:meth:`number`, or None when the member is absent or null.

        Parameters
        ----------
        key : str
            The member's name.
        gt, ge, le, lt : float, optional
            Bounds (:func:`number`).
        """
        raw = self.value.get(key)
        return None if raw is None else number(raw, self.at(key), gt=gt, ge=ge, le=le, lt=lt)

    def choice(self, key: str, default: _L, choices: tuple[_L, ...]) -> _L:
        """:meth:`string` restricted to ``choices``, typed as their ``Literal``.

        Parameters
        ----------
        key : str
            The member's name.
        default : str
            Returned when the member is absent.
        choices : tuple of str
            The allowed values.
        """
        raw = self.string(key, default, choices)
        return next(c for c in choices if c == raw)

    def integer(self, key: str, *, default: int | None = None,
                ge: int | None = None, le: int | None = None) -> int:
        """An integer member (:func:`integer`).

        Parameters
        ----------
        key : str
            The member's name.
        default : int, optional
            Returned when the member is absent or null; without it the member is required.
        ge, le : int, optional
            Smallest and largest allowed value.
        """
        raw = self.value.get(key)
        if raw is None:
            return self._absent(key, default)
        return integer(raw, self.at(key), ge=ge, le=le)

    def boolean(self, key: str, *, default: bool | None = None) -> bool:
        """A boolean member (:func:`boolean`).

        Parameters
        ----------
        key : str
            The member's name.
        default : bool, optional
            Returned when the member is absent or null; without it the member is required.
        """
        raw = self.value.get(key)
        if raw is None:
            return self._absent(key, default)
        return boolean(raw, self.at(key))

    def string(self, key: str, default: str | None = None, choices: Collection[str] | None = None) -> str:
        """A non-empty string member (:func:`string`); ``default`` when absent (an explicit
        null is "is required").

        Parameters
        ----------
        key : str
            The member's name.
        default : str, optional
            Returned when the member is absent; without it the member is required.
        choices : collection of str, optional
            The allowed values.
        """
        raw = self.value.get(key, default)
        if raw is None:
            raise InputError(self.at(key), "is required")
        return string(raw, self.at(key), choices=choices)

    def array(self, key: str) -> list[Any]:
        """A list member (required).

        Parameters
        ----------
        key : str
            The member's name.
        """
        raw = self.value.get(key)
        if not isinstance(raw, list):
            raise InputError(self.at(key), "must be a list")
        return raw
