"""Presets spliced into Fusion libraries: nothing else changes, byte for byte."""

from __future__ import annotations

import io
import json
import zipfile

import pytest

from rcsa.errors import InputError
from rcsa.libraries.fusion import library_combinations
from rcsa.libraries.fusion_presets import read_fusion_file, with_presets, write_presets
from tests.helpers import REPO

SAMPLES = REPO / "tests" / "data" / "tool-libraries" / "fusion-synthetic"
JSON_SAMPLE = (SAMPLES / "synthetic_library.json").read_bytes()
TOOLS_SAMPLE = (SAMPLES / "synthetic_library.tools").read_bytes()
OURS = {"name": "rcsa chatter-safe: aluminium 7075", "guid": "6f1c0a57-0000-5000-8000-000000000001",
        "n": 12000, "stepdown": 1.25, "use-stepdown": True}


def without_presets(doc: dict) -> dict:
    """The document with every ``start-values`` removed (what must not change)."""
    doc = json.loads(json.dumps(doc))
    for item in doc["data"]:
        item.pop("start-values", None)
    return doc


def is_two_insertions(a: bytes, b: bytes) -> bool:
    """Whether ``b`` is ``a`` with (at most) two runs of bytes inserted and nothing else changed."""
    p = next((i for i, (x, y) in enumerate(zip(a, b, strict=False)) if x != y), min(len(a), len(b)))
    s = next((i for i, (x, y) in enumerate(zip(a[::-1], b[::-1], strict=False)) if x != y), min(len(a), len(b)))
    s = min(s, len(a) - p)
    middle = a[p:len(a) - s]
    return b[:p] == a[:p] and b[len(b) - s:] == a[len(a) - s:] and middle in b[p:len(b) - s]


def test_round_trip_changes_only_the_presets():
    out = write_presets(read_fusion_file(JSON_SAMPLE), {0: OURS, 1: OURS})
    before, after = json.loads(JSON_SAMPLE), json.loads(out)
    assert after == with_presets(before, {0: OURS, 1: OURS})
    assert without_presets(after) == without_presets(before)
    # our own reader sees the same combinations
    assert library_combinations(out).to_dict()["combinations"] == library_combinations(JSON_SAMPLE).to_dict()[
        "combinations"]
    # the existing "Steel" preset keeps its text, ours follows it
    presets = after["data"][0]["start-values"]["presets"]
    assert [p["name"] for p in presets] == ["Steel", OURS["name"]] and presets[0] == before["data"][0][
        "start-values"]["presets"][0]
    assert after["data"][1]["start-values"] == {"presets": [OURS]}
    # byte level: the output is the input with text inserted, nothing removed or rewritten
    assert is_two_insertions(JSON_SAMPLE, out)


def test_rerun_replaces_our_preset_and_leaves_the_others():
    first = write_presets(read_fusion_file(JSON_SAMPLE), {0: OURS})
    changed = {**OURS, "n": 13000}
    second = write_presets(read_fusion_file(first), {0: changed})
    presets = json.loads(second)["data"][0]["start-values"]["presets"]
    assert [p["name"] for p in presets] == ["Steel", OURS["name"]] and presets[1]["n"] == 13000
    assert second.decode() == first.decode().replace('"n": 12000', '"n": 13000')
    assert write_presets(read_fusion_file(second), {0: changed}) == second  # idempotent
    # matched by guid even when renamed, and by name even with another guid
    renamed = write_presets(read_fusion_file(first), {0: {**OURS, "name": "rcsa chatter-safe: renamed"}})
    assert len(json.loads(renamed)["data"][0]["start-values"]["presets"]) == 2


def test_nothing_to_write_returns_the_file_itself():
    assert write_presets(read_fusion_file(JSON_SAMPLE), {}) is JSON_SAMPLE


def test_tools_zip_keeps_every_other_member():
    buf = io.BytesIO()
    with zipfile.ZipFile(io.BytesIO(TOOLS_SAMPLE)) as zin, zipfile.ZipFile(buf, "w") as zout:
        zout.comment = b"shop export"
        zout.writestr(zipfile.ZipInfo("README.txt", (2025, 1, 2, 3, 4, 6)), b"keep me")
        for info in zin.infolist():
            zout.writestr(info, zin.read(info))
        zout.writestr(zipfile.ZipInfo("images/tool.png", (2025, 1, 2, 3, 4, 8)), b"\x89PNG...",
                      compress_type=zipfile.ZIP_DEFLATED)
    raw = buf.getvalue()
    out = write_presets(read_fusion_file(raw), {0: OURS})
    with zipfile.ZipFile(io.BytesIO(raw)) as zin, zipfile.ZipFile(io.BytesIO(out)) as zout:
        assert zout.comment == zin.comment
        assert [(i.filename, i.date_time, i.compress_type, i.external_attr) for i in zout.infolist()] == \
            [(i.filename, i.date_time, i.compress_type, i.external_attr) for i in zin.infolist()]
        for info in zin.infolist():
            if info.filename != "tools.json":
                assert zout.read(info.filename) == zin.read(info)
        assert json.loads(zout.read("tools.json")) == with_presets(json.loads(zin.read("tools.json")), {0: OURS})
    assert library_combinations(out).to_dict()["combinations"] == library_combinations(raw).to_dict()["combinations"]


@pytest.mark.parametrize("variant", ["compact", "crlf_bom", "tabs", "numbers"])
def test_formatting_of_the_file_is_kept(variant):
    doc = {"data": [{"type": "flat end mill", "guid": "g1", "zzz-unknown": {"b": 1, "a": [1.50, 2e3]},
                     "geometry": {"DC": 10}}, {"type": "holder"}], "version": 36}
    if variant == "compact":
        text = json.dumps(doc, separators=(",", ":"))
    elif variant == "crlf_bom":
        text = "\ufeff" + json.dumps(doc, indent=4).replace("\n", "\r\n")
    elif variant == "tabs":
        text = json.dumps(doc, indent="\t")
    else:  # numbers as a hand-edited file writes them
        text = json.dumps(doc, indent=2).replace("1.5", "1.50").replace("2000.0", "2e3")
    raw = text.encode("utf-8")
    out = write_presets(read_fusion_file(raw), {0: OURS}).decode("utf-8")
    assert json.loads(out.lstrip("\ufeff")) == with_presets(json.loads(text.lstrip("\ufeff")), {0: OURS})
    added = out[out.index('"DC"'):]
    assert out.startswith(text[:text.index('"DC"')])  # everything before the tool's last member untouched
    assert out.endswith(text[text.index("}", text.index('"DC"')) + 1:])  # and everything after the tool
    if variant == "compact":
        assert "\n" not in out and " " not in added.split('"name"')[0]
    if variant == "crlf_bom":
        assert out.startswith("\ufeff") and "\n" not in out.replace("\r\n", "")
    if variant == "tabs":
        assert '\n\t\t\t"start-values": {\n\t\t\t\t"presets": [\n\t\t\t\t\t{\n\t\t\t\t\t\t"name"' in out
    if variant == "numbers":
        assert "1.50" in out and "2e3" in out


def test_start_values_without_presets_and_empty_presets():
    for start in ({"other": 1}, {"presets": []}, {}, None):
        doc = {"data": [{"type": "flat end mill", "start-values": start}]}
        for text in (json.dumps(doc, indent=2), json.dumps(doc)):
            out = write_presets(read_fusion_file(text.encode()), {0: OURS})
            assert json.loads(out) == with_presets(doc, {0: OURS}), (start, text)


def test_not_an_object_and_not_a_library():
    with pytest.raises(InputError):
        write_presets(read_fusion_file(b'{"data": [1]}'), {0: OURS})
    with pytest.raises(InputError):
        read_fusion_file(b"PK\x03\x04 broken")
    with pytest.raises(InputError):
        read_fusion_file(b"{not json")
