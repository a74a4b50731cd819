"""Pages of a listing: one cursor form for every list the service and the CLI hand out.

Measurements, stored libraries and jobs are listed a page at a time as ``{"items": [...],
"next_cursor": str | None}``: ``next_cursor`` is opaque to the client (URL-safe base64 of the
sort key of the page's last item) and names where the next page starts, so that pages stay
consistent while items are added or removed in between.

>>> items = [("2025-01-01", "a"), ("2025-01-02", "b"), ("2025-01-03", "c")]
>>> page, cursor = paginate(items, key=lambda x: x, limit=2)
>>> page, paginate(items, key=lambda x: x, limit=2, cursor=cursor)
([('2025-01-01', 'a'), ('2025-01-02', 'b')], ([('2025-01-03', 'c')], None))
"""

from __future__ import annotations

import base64
import binascii
import json
from collections.abc import Callable, Sequence
from typing import TypeVar

from rcsa.errors import InputError

__all__ = ["decode_cursor", "encode_cursor", "paginate"]

T = TypeVar("T")


def encode_cursor(key: Sequence[str]) -> str:
    """The cursor of a sort key (strings), e.g. ``(created_utc, id)``."""
    raw = json.dumps([str(k) for k in key]).encode()
    return base64.urlsafe_b64encode(raw).decode().rstrip("=")


def decode_cursor(cursor: str, parts: int | None = 2) -> tuple[str, ...]:
    """The sort key a cursor stands for (of ``parts`` strings; None: any number).

    Raises
    ------
    InputError
        ``cursor`` is not one that :func:`encode_cursor` made (field ``cursor``).
    """
    try:
        raw = base64.urlsafe_b64decode(cursor + "=" * (-len(cursor) % 4))
        key = json.loads(raw)
        if not isinstance(key, list) or (parts is not None and len(key) != parts) or \
                not all(isinstance(k, str) for k in key):
            raise ValueError
        return tuple(key)
    except (ValueError, TypeError, binascii.Error, UnicodeDecodeError):
        raise InputError("cursor", "is not a cursor this service handed out; start again without it") from None


def paginate(items: Sequence[T], *, key: Callable[[T], Sequence[str]], limit: int, cursor: str | None = None,
             newest_first: bool = False) -> tuple[list[T], str | None]:
    """One page of ``items`` (sorted by ``key``: ascending, or descending with ``newest_first``)
    after ``cursor``, and the cursor of the next page (None on the last).

    Raises
    ------
    InputError
        A cursor this function did not hand out, or ``limit`` below 1.
    """
    if limit < 1:
        raise InputError("limit", f"must be >= 1, got {limit}")
    ordered = sorted(items, key=lambda x: tuple(key(x)), reverse=newest_first)
    if cursor:
        after = decode_cursor(cursor, len(key(ordered[0])) if ordered else None)
        ordered = [x for x in ordered if (tuple(key(x)) < after if newest_first else tuple(key(x)) > after)]
    page = ordered[:limit]
    return page, (encode_cursor(key(page[-1])) if len(ordered) > limit else None)
