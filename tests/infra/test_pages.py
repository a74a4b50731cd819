"""Pages of a listing (``rcsa.infra.pages``): every item once, in order, whatever the page size."""

from __future__ import annotations

import pytest

from rcsa.errors import InputError
from rcsa.infra.pages import decode_cursor, encode_cursor, paginate

ITEMS = [(f"2025-01-{d:02d}", f"id-{k}") for d in range(1, 6) for k in range(3)]


@pytest.mark.parametrize("limit", [1, 2, 4, 15, 100])
@pytest.mark.parametrize("newest_first", [False, True])
def test_pages_cover_every_item_once_in_order(limit, newest_first):
    seen, cursor = [], None
    for _ in range(len(ITEMS) + 1):
        page, cursor = paginate(ITEMS[::-1], key=lambda x: x, limit=limit, cursor=cursor, newest_first=newest_first)
        assert len(page) <= limit
        seen += page
        if cursor is None:
            break
    assert seen == sorted(ITEMS, reverse=newest_first)


def test_a_cursor_stands_for_its_key_and_a_foreign_one_is_refused():
    assert decode_cursor(encode_cursor(("a", "b"))) == ("a", "b")
    for bad in ("x", encode_cursor(("a",)), "W10", "!!!"):
        with pytest.raises(InputError, match="cursor"):
            decode_cursor(bad)
