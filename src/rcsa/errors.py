"""Exceptions raised by :mod:`rcsa`.

Every error a user can cause is an :class:`InputError` (a ``ValueError``) that names the
offending field with a JSON-pointer-like dotted path and the rule it broke, so the CLI can
print one line and the service can answer ``422`` with ``application/problem+json``.
"""

from __future__ import annotations

from typing import Any

__all__ = [
    "ConflictError",
    "DamagedError",
    "FrequencyMismatch",
    "InputError",
    "MalformedInput",
    "NotFoundError",
    "RcsaError",
    "StoreError",
    "TimeLimitExceeded",
]


def _rebuilt(cls: type[RcsaError], args: tuple[Any, ...], state: dict[str, Any]) -> RcsaError:
    """An :class:`RcsaError` as it was pickled: made without its ``__init__`` (whose parameters
    differ from class to class), with its message and attributes as they were."""
    error = cls.__new__(cls)
    error.args = args
    error.__dict__.update(state)
    return error


class RcsaError(Exception):
    """Base class of every error raised on purpose by :mod:`rcsa`.

    Every one survives pickling with its class, message and attributes (``field``, ``rule``,
    ``seconds``, …), so an error raised in a worker process or on a Dask worker reaches the
    caller as itself, not as a failure to unpickle it (the standard exception pickling calls
    ``cls(message)``, which the errors with several parameters refuse).

    Examples
    --------
    >>> import pickle
    >>> e = pickle.loads(pickle.dumps(InputError("teeth", "must be >= 1")))
    >>> type(e).__name__, e.field, e.rule, str(e)
    ('InputError', 'teeth', 'must be >= 1', 'teeth: must be >= 1')
    """

    def __reduce__(self) -> tuple[Any, ...]:
        return (_rebuilt, (type(self), self.args, dict(self.__dict__)))


class InputError(RcsaError, ValueError):
    """Invalid user input.

    Parameters
    ----------
    field : str
        Dotted path of the offending field, e.g. ``"holder.segments[2].length_m"``;
        empty for an error about the whole document.
    rule : str
        What the field must satisfy, phrased so a person can act on it.
    """

    def __init__(self, field: str, rule: str) -> None:
        self.field = field
        self.rule = rule
        super().__init__(f"{field}: {rule}" if field else rule)


class MalformedInput(InputError):
    """Input that is not well-formed at all: not JSON (RFC 8259: syntax, ``NaN``/``Infinity``
    tokens), not UTF-8 text. The REST service answers ``400``; an :class:`InputError` about a
    well-formed document (a value out of range, a missing field) is a ``422``.

    Parameters
    ----------
    field, rule : str
        As for :class:`InputError`.
    """


class FrequencyMismatch(InputError):
    """Two receptances that must share a frequency axis do not (never interpolated silently).

    Parameters
    ----------
    field, rule : str
        As for :class:`InputError`.
    """


class NotFoundError(RcsaError, KeyError):
    """A stored object (measurement, job, library) does not exist.

    Parameters
    ----------
    what : str
        What was looked for, e.g. ``"measurement"``.
    ident : str
        The id that was not found.
    """

    def __init__(self, what: str, ident: str) -> None:
        self.what = what
        self.ident = ident
        super().__init__(f"{what} {ident!r} not found")

    def __str__(self) -> str:  # KeyError would quote the message
        return f"{self.what} {self.ident!r} not found"


class ConflictError(RcsaError):
    """The request conflicts with the stored state (e.g. the object a retried request created
    was deleted since), so it cannot be answered as asked."""

    def __init__(self, what: str, ident: str, reason: str) -> None:
        self.what = what
        self.ident = ident
        self.reason = reason
        super().__init__(f"{what} {ident}: {reason}")


class StoreError(RcsaError):
    """The store is unreadable, has a foreign schema, or a write could not be committed."""


class DamagedError(StoreError):
    """A stored object exists but cannot be read (corrupt file, foreign schema, bad checksum).

    A :class:`StoreError` about one object, not the store as a whole: retrying does not help
    (the service answers 409, not 503).
    """

    def __init__(self, what: str, ident: str, reason: str) -> None:
        self.what = what
        self.ident = ident
        self.reason = reason
        super().__init__(f"{what} {ident} is damaged: {reason}")


class TimeLimitExceeded(RcsaError):
    """A computation ran past the time limit set for it (:func:`rcsa.analysis.progress.time_limit`).

    Parameters
    ----------
    seconds : float
        The limit, s.
    """

    def __init__(self, seconds: float) -> None:
        self.seconds = float(seconds)
        super().__init__(f"the computation ran past its time limit of {self.seconds:g} s")
