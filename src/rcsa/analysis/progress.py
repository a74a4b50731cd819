"""Progress reports of long analyses: an optional ``progress(done, total)`` callback.

The diagnosis, the joint identification and the effect analysis take seconds to minutes;
their entry points accept ``progress`` and call it at natural step boundaries with the
number of steps done and the total (``done`` reaches ``total`` when the analysis ends,
also when it ends early). The CLI draws a progress bar from it; the callback must be cheap
and must not raise.
"""

from __future__ import annotations

from collections.abc import Callable

__all__ = ["Progress", "report"]

#: ``progress(done, total)``: steps done so far, of ``total``.
Progress = Callable[[int, int], None]


def report(progress: Progress | None, done: int, total: int) -> None:
    """Call ``progress(done, total)`` when a callback was given."""
    if progress is not None:
        progress(done, total)
