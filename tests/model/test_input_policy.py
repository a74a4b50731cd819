"""The input policy's raw count of JSON documents (``JsonCounter``) and its malformed/invalid split.

The counter is judged against an independent count: the parsed document walked recursively
(objects and arrays, and their members), on random documents whose strings hold the
structural bytes, escaped quotes and runs of backslashes, fed in random pieces.
"""

from __future__ import annotations

import json

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from rcsa.errors import InputError, MalformedInput
from rcsa.model.bounds import MAX_JSON_CONTAINERS, MAX_JSON_ITEMS
from rcsa.model.input_policy import JsonCounter, check_json_size, load_json

#: text rich in what the counter must see through: structural bytes, quotes, backslashes
tricky_text = st.text(alphabet=st.sampled_from(list('{}[],:"\\ab \n') + ["é", "\u2028"]), max_size=12)
scalars = st.one_of(st.none(), st.booleans(), st.integers(-10**6, 10**6), st.floats(-1e6, 1e6), tricky_text)
documents = st.recursive(scalars, lambda inner: st.one_of(
    st.lists(inner, max_size=6), st.dictionaries(tricky_text, inner, max_size=6)), max_leaves=60)


def strings(doc: object) -> list[str]:
    """Every string of a parsed document, keys too."""
    if isinstance(doc, dict):
        return [s for k, v in doc.items() for s in [k, *strings(v)]]
    if isinstance(doc, list):
        return [s for v in doc for s in strings(v)]
    return [doc] if isinstance(doc, str) else []


def reference_counts(doc: object) -> tuple[int, int]:
    """(objects and arrays, their members + one per empty one), by walking the parsed document."""
    if isinstance(doc, dict | list):
        values = list(doc.values()) if isinstance(doc, dict) else doc
        containers, items = 1, max(len(values), 1)
        for v in values:
            c, i = reference_counts(v)
            containers, items = containers + c, items + i
        return containers, items
    return 0, 0


@settings(max_examples=300, deadline=None)
@given(doc=documents, cuts=st.lists(st.integers(0, 10_000), max_size=8), indent=st.sampled_from([None, 1]))
def test_counts_match_the_parsed_document_whatever_the_split(doc, cuts, indent):
    text = json.dumps(doc, ensure_ascii=False, indent=indent).encode()
    counter = JsonCounter()
    points = sorted({c % (len(text) + 1) for c in cuts} | {0, len(text)})
    for a, b in zip(points, points[1:], strict=False):
        counter.feed(text[a:b])
    assert (counter.containers, counter.items) == reference_counts(doc)
    assert counter.bytes == len(text)
    assert counter.longest_string_bytes == max(
        [len(json.dumps(s, ensure_ascii=False).encode()) - 1 for s in strings(doc)], default=0)


def test_a_piece_ending_inside_a_run_of_backslashes():
    # '"a\\\\\\"b"' : the quote after three backslashes is escaped; split inside the run
    text = b'["x\\\\\\"{,[", {"k": []}]'
    for cut in range(len(text) + 1):
        counter = JsonCounter()
        counter.feed(text[:cut])
        counter.feed(text[cut:])
        assert (counter.containers, counter.items) == reference_counts(json.loads(text)), cut


def test_tiny_items_are_refused_while_they_arrive():
    counter = JsonCounter()
    piece = b'{"a":1},' * 8192  # 64 KiB
    counter.feed(b'{"combinations": [')
    with pytest.raises(InputError, match=f"more than {MAX_JSON_CONTAINERS} objects and arrays"):
        for _ in range(64):  # 4 MiB: refused after ~2 MiB
            counter.feed(piece)
    assert counter.bytes < 3 * 2**20
    numbers = JsonCounter()
    with pytest.raises(InputError, match=f"more than {MAX_JSON_ITEMS} elements"):
        numbers.feed(b"[" + b"0," * (MAX_JSON_ITEMS + 1) + b"0]")


def test_check_json_size_and_load_json_apply_the_bounds():
    check_json_size(b"[" + b"{}," * 1000 + b"{}]")  # small: not even scanned
    big = b"[" + b"[]," * MAX_JSON_CONTAINERS + b"[]]"
    with pytest.raises(InputError, match="objects and arrays"):
        check_json_size(big)
    with pytest.raises(InputError, match="objects and arrays") as caught:
        load_json(big, path="library", what="the tool library")
    assert caught.value.field == "library" and not isinstance(caught.value, MalformedInput)


@pytest.mark.parametrize("text", [b'{"a": ', b'{"a": NaN}', b'{"a": Infinity}', b"\xff\xfe", b"[1,]"])
def test_text_that_is_not_json_is_malformed(text):
    with pytest.raises(MalformedInput, match="not valid JSON"):
        load_json(text)


@pytest.mark.parametrize("text", [b'{"a": 1e300}', b"[" * 40 + b"]" * 40, b'{"a": "' + b"x" * 20000 + b'"}'])
def test_well_formed_but_invalid_is_not_malformed(text):
    with pytest.raises(InputError) as caught:
        load_json(text)
    assert not isinstance(caught.value, MalformedInput)


def test_a_huge_string_is_refused_long_before_its_end():
    counter = JsonCounter()
    counter.feed(b'{"notes": "')
    with pytest.raises(InputError, match="more than 16384 characters"):
        for _ in range(1000):  # 64 MiB, if it were all read
            counter.feed(b"x" * 65536)
    assert counter.bytes < 2**20
