"""Progress reports of long analyses, and the time limit they stop at.

The diagnosis, the joint identification and the effect analysis take seconds to minutes;
their entry points accept ``progress`` and call it at natural step boundaries with the
number of steps done and the total (``done`` reaches ``total`` when the analysis ends,
also when it ends early). The CLI draws a progress bar from it; the callback must be cheap.

A caller that must answer within a time (the service's answers given at once) runs the
computation inside :func:`time_limit`; every step boundary — :func:`report`, and
:func:`check_time` in the loops of batches and semi-discretization lobes — raises
:class:`~rcsa.errors.TimeLimitExceeded` once the limit has passed, so the computation stops
there instead of running on after nobody waits for it. The limit is a context variable:
it follows the computation into the worker thread that runs it (``contextvars`` are
copied into threads started through asyncio and anyio).
"""

from __future__ import annotations

import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from contextvars import ContextVar

from rcsa.errors import TimeLimitExceeded

__all__ = ["Progress", "check_time", "report", "time_limit"]

#: ``progress(done, total)``: steps done so far, of ``total``.
Progress = Callable[[int, int], None]

#: (monotonic deadline, the limit in s) of the computation running in this context, if any.
_DEADLINE: ContextVar[tuple[float, float] | None] = ContextVar("rcsa_deadline", default=None)


@contextmanager
def time_limit(seconds: float | None) -> Iterator[None]:
    """Run the body under a time limit of ``seconds`` (None: none) from now.

    Examples
    --------
    >>> with time_limit(0.0):
    ...     check_time()
    Traceback (most recent call last):
    ...
    rcsa.errors.TimeLimitExceeded: the computation ran past its time limit of 0 s
    """
    token = _DEADLINE.set(None if seconds is None else (time.monotonic() + float(seconds), float(seconds)))
    try:
        yield
    finally:
        _DEADLINE.reset(token)


def check_time() -> None:
    """Raise :class:`~rcsa.errors.TimeLimitExceeded` when the time limit of this context has passed."""
    deadline = _DEADLINE.get()
    if deadline is not None and time.monotonic() > deadline[0]:
        raise TimeLimitExceeded(deadline[1])


def report(progress: Progress | None, done: int, total: int) -> None:
    """Stop at the time limit (:func:`check_time`), else call ``progress(done, total)`` when a
    callback was given."""
    check_time()
    if progress is not None:
        progress(done, total)
