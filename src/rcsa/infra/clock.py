"""Timestamps as the stores write them: ISO 8601 in UTC with a ``Z``.

Every store records times as text that sorts in time order (the job queue purges by string
comparison, the measurement catalogue lists by it), so all writers share these two
functions instead of each formatting ``datetime.now`` itself.

>>> utc_iso(0.0)
'1970-01-01T00:00:00.000000Z'
>>> utc_iso(0.0, timespec="seconds")
'1970-01-01T00:00:00Z'
"""

from __future__ import annotations

from datetime import UTC, datetime
from typing import Literal

__all__ = ["utc_iso", "utc_now_iso"]

Timespec = Literal["microseconds", "seconds"]
_FORMATS = {"microseconds": "%Y-%m-%dT%H:%M:%S.%fZ", "seconds": "%Y-%m-%dT%H:%M:%SZ"}


def utc_iso(unix_s: float, *, timespec: Timespec = "microseconds") -> str:
    """``unix_s`` (seconds since the epoch) as ``YYYY-MM-DDTHH:MM:SS[.ffffff]Z``.

    Parameters
    ----------
    unix_s : float
    timespec : {"microseconds", "seconds"}
        ``"microseconds"`` (the default: jobs, libraries, measurements, exports — fixed
        width, so the strings sort in time order) or ``"seconds"`` (API keys, read by people).
    """
    return datetime.fromtimestamp(unix_s, UTC).strftime(_FORMATS[timespec])


def utc_now_iso(*, timespec: Timespec = "microseconds") -> str:
    """The current time as :func:`utc_iso` writes it."""
    return datetime.now(UTC).strftime(_FORMATS[timespec])
