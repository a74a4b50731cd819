"""Write presets into a Fusion tool library and change nothing else, byte for byte.

A Fusion tool keeps its cutting data in ``start-values.presets``: a list of objects (``name``,
``guid``, ``n`` rpm, ``v_c``, ``f_z``, ``v_f``, ``stepdown``, …). :func:`write_presets` puts one
preset per tool into that list, replacing the presets it wrote before (same ``guid`` or same
``name``), and leaves every other byte of the file as it was: the text of the document is
*spliced*, not re-serialised. Only the ``presets`` array of an edited tool is rewritten, and
in it the other presets keep their original text; a tool without ``start-values`` (or without
``presets``) gets the member appended to its object. Key order, unknown fields, numbers as
written (``6000``, ``188.50``, ``1e3``), whitespace, line endings (``\\r\\n`` kept) and a UTF-8
byte-order mark are all preserved; the new text follows the file's indentation (compact files
stay compact).

A ``.tools`` file is a zip holding ``tools.json``: the other members are written back with
the same names, order, dates, attributes and content, ``tools.json`` with its new content.

Every result is checked before it is returned: parsed again, it must equal the original
document with exactly those presets changed (else :class:`~rcsa.errors.RcsaError`; nothing
is written).
"""

from __future__ import annotations

import copy
import io
import json
import re
import zipfile
import zlib
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any, Literal

from rcsa.errors import InputError, RcsaError
from rcsa.libraries.fusion import MAX_LIBRARY_BYTES, tools_json_member
from rcsa.model.input_policy import load_json

__all__ = ["FusionFile", "is_replaced", "read_fusion_file", "with_presets", "write_presets"]

_BOM = "\ufeff"
_WS = re.compile(r"[ \t\r\n]*")
_DECODER = json.JSONDecoder()


@dataclass(frozen=True, slots=True)
class FusionFile:
    """A Fusion library file as bytes, with its JSON text.

    Attributes
    ----------
    raw : bytes
        The file as given.
    kind : {"json", "tools"}
        A JSON file or a ``.tools`` zip.
    text : str
        The JSON text (without a byte-order mark).
    bom : bool
        Whether the JSON started with a UTF-8 byte-order mark.
    member : str or None
        The zip member holding the JSON (``.tools`` only).
    """

    raw: bytes
    kind: Literal["json", "tools"]
    text: str
    bom: bool
    member: str | None

    @property
    def document(self) -> Any:
        """The parsed document."""
        return json.loads(self.text)


def read_fusion_file(raw: bytes) -> FusionFile:
    """Split a Fusion ``.json`` / ``.tools`` file into what :func:`write_presets` needs.

    Raises
    ------
    InputError
        Not a zip holding one ``tools.json``, not UTF-8, not JSON.
    """
    if len(raw) > MAX_LIBRARY_BYTES:
        raise InputError("library", f"larger than {MAX_LIBRARY_BYTES} bytes")
    member = None
    data = raw
    kind: Literal["json", "tools"] = "json"
    if raw.startswith(b"PK"):
        kind = "tools"
        try:
            with zipfile.ZipFile(io.BytesIO(raw)) as zf:
                info = tools_json_member(zf)
                member = info.filename
                data = zf.read(info)
        except (zipfile.BadZipFile, RuntimeError, NotImplementedError, OSError, EOFError, zlib.error) as exc:
            raise InputError("library", f"not a readable .tools zip archive ({exc})") from exc
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise InputError("library", "not UTF-8 text: expected a Fusion tool-library JSON") from exc
    bom = text.startswith(_BOM)
    if bom:
        text = text[1:]
    load_json(text, path="library", what="the tool library")
    return FusionFile(raw, kind, text, bom, member)


def is_replaced(preset: object, guid: str, name: str) -> bool:
    """Whether an existing preset is the one rcsa wrote before (same ``guid`` or ``name``)."""
    return isinstance(preset, dict) and (preset.get("guid") == guid or preset.get("name") == name)


def with_presets(document: Mapping[str, Any], edits: Mapping[int, Mapping[str, Any]]) -> dict[str, Any]:
    """The parsed document with the presets of :func:`write_presets` (what its result must parse to).

    Parameters
    ----------
    document : mapping
        A parsed Fusion library.
    edits : mapping of int to dict
        ``data`` index → the preset to write (with its ``guid`` and ``name``).

    Returns
    -------
    dict
        A deep copy with, in each edited tool, the replaced presets removed and the new one
        at the place of the first of them (else at the end).
    """
    doc = copy.deepcopy(dict(document))
    for index, preset in edits.items():
        item = doc["data"][index]
        start = item.get("start-values")
        if not isinstance(start, dict):
            item["start-values"] = start = {}
        old = start.get("presets")
        old = old if isinstance(old, list) else []
        kept, at = _merge(old, preset)
        kept.insert(at, copy.deepcopy(dict(preset)))
        start["presets"] = kept
    return doc


def _merge(old: list[Any], preset: Mapping[str, Any]) -> tuple[list[Any], int]:
    """The presets kept, and where the new one goes."""
    guid, name = str(preset["guid"]), str(preset["name"])
    kept: list[Any] = []
    at: int | None = None
    for p in old:
        if is_replaced(p, guid, name):
            at = len(kept) if at is None else at
        else:
            kept.append(p)
    return kept, len(kept) if at is None else at


def write_presets(file: FusionFile, edits: Mapping[int, Mapping[str, Any]]) -> bytes:
    """The library file with one preset written into each edited tool (module docstring).

    Parameters
    ----------
    file : FusionFile
        From :func:`read_fusion_file`.
    edits : mapping of int to dict
        ``data`` index → the preset (JSON-ready, with ``guid`` and ``name``).

    Returns
    -------
    bytes
        The new ``.json`` or ``.tools`` file (the input unchanged when ``edits`` is empty).

    Raises
    ------
    InputError
        An edited ``data`` item is not a JSON object.
    RcsaError
        The spliced text does not parse to the expected document (a bug; nothing returned).
    """
    if not edits:
        return file.raw
    text = _splice(file.text, edits)
    if json.loads(text) != with_presets(file.document, edits):
        raise RcsaError("internal error: writing the presets would change more than the presets; nothing written")
    data = ((_BOM if file.bom else "") + text).encode("utf-8")
    if file.kind == "json":
        return data
    return _rewrite_zip(file.raw, str(file.member), data)


# --------------------------------------------------------------------------- the splice


@dataclass(frozen=True, slots=True)
class _Node:
    """A JSON value's place in the text: ``[start, end)``."""

    start: int
    end: int


@dataclass(frozen=True, slots=True)
class _Member:
    key: str
    key_start: int
    value: _Node


def _ws(s: str, i: int) -> int:
    m = _WS.match(s, i)
    return m.end() if m else i


def _value_end(s: str, i: int) -> int:
    return int(_DECODER.raw_decode(s, i)[1])


def _members(s: str, node: _Node) -> list[_Member]:
    """The members of the object at ``node`` (in text order)."""
    i = _ws(s, node.start + 1)
    out: list[_Member] = []
    if s[i] == "}":
        return out
    while True:
        key, j = json.decoder.scanstring(s, i + 1)  # type: ignore[attr-defined]
        j = _ws(s, j)
        vs = _ws(s, j + 1)  # past ':'
        ve = _value_end(s, vs)
        out.append(_Member(key, i, _Node(vs, ve)))
        i = _ws(s, ve)
        if s[i] == "}":
            return out
        i = _ws(s, i + 1)  # past ','


def _elements(s: str, node: _Node) -> list[_Node]:
    """The elements of the array at ``node``."""
    i = _ws(s, node.start + 1)
    out: list[_Node] = []
    if s[i] == "]":
        return out
    while True:
        end = _value_end(s, i)
        out.append(_Node(i, end))
        i = _ws(s, end)
        if s[i] == "]":
            return out
        i = _ws(s, i + 1)


def _last(members: list[_Member], key: str) -> _Member | None:
    """The member ``key`` as a JSON parser sees it (the last one when repeated)."""
    found = [m for m in members if m.key == key]
    return found[-1] if found else None


@dataclass(frozen=True, slots=True)
class _Style:
    newline: str
    unit: str | None  # indentation step; None: compact
    colon: str
    comma: str

    def dumps(self, value: Any, indent: str | None) -> str:
        """``value`` as JSON whose continuation lines start at ``indent`` (None: on one line)."""
        if self.unit is None or indent is None:
            comma = self.comma if self.unit is None else ", "
            return json.dumps(value, ensure_ascii=False, separators=(comma, self.colon))
        text = json.dumps(value, ensure_ascii=False, indent=self.unit, separators=(",", self.colon))
        return text.replace("\n", self.newline + indent)


def _style(s: str) -> _Style:
    newline = "\r\n" if "\r\n" in s else "\n"
    m = re.search(r"\n([ \t]+)\S", s)
    unit = m.group(1) if m else None
    colon = ": " if re.search(r'"\s*:\s', s[:4096]) else ":"
    comma = ", " if unit is None and re.search(r",\s", s[:4096]) else ","
    return _Style(newline, unit, colon, comma)


def _indent_at(s: str, pos: int) -> str | None:
    """The whitespace between the line start and ``pos`` when only whitespace precedes it."""
    line_start = s.rfind("\n", 0, pos) + 1
    head = s[line_start:pos]
    return head if head.strip() == "" and line_start > 0 else None


def _line_indent(s: str, pos: int) -> str | None:
    """The indentation of the line holding ``pos`` (None on the first line: a compact file)."""
    line_start = s.rfind("\n", 0, pos) + 1
    if line_start == 0:
        return None
    return re.match(r"[ \t]*", s[line_start:pos]).group(0)  # type: ignore[union-attr]


def _splice(s: str, edits: Mapping[int, Mapping[str, Any]]) -> str:
    style = _style(s)
    root = _Node(_ws(s, 0), _value_end(s, _ws(s, 0)))
    data = _last(_members(s, root), "data")
    if data is None or s[data.value.start] != "[":
        raise InputError("data", "a Fusion tool library needs a data list")
    items = _elements(s, data.value)
    replacements: list[tuple[int, int, str]] = []
    for index in sorted(edits):
        item = items[index]
        if s[item.start] != "{":
            raise InputError(f"data[{index}]", "not a JSON object")
        replacements.append(_item_replacement(s, item, edits[index], style))
    out, pos = [], 0
    for start, end, new in replacements:  # in text order: edits are sorted by data index
        out.append(s[pos:start])
        out.append(new)
        pos = end
    out.append(s[pos:])
    return "".join(out)


def _item_replacement(s: str, item: _Node, preset: Mapping[str, Any], style: _Style) -> tuple[int, int, str]:
    members = _members(s, item)
    start_values = _last(members, "start-values")
    if start_values is None:
        return _append_member(s, item, members, "start-values", {"presets": [dict(preset)]}, style)
    if s[start_values.value.start] != "{":  # null or something else: the whole value is replaced
        indent = _line_indent(s, start_values.key_start)
        return (start_values.value.start, start_values.value.end,
                style.dumps({"presets": [dict(preset)]}, indent))
    sv_members = _members(s, start_values.value)
    presets = _last(sv_members, "presets")
    if presets is None:
        return _append_member(s, start_values.value, sv_members, "presets", [dict(preset)], style)
    if s[presets.value.start] != "[":
        indent = _line_indent(s, presets.key_start)
        return presets.value.start, presets.value.end, style.dumps([dict(preset)], indent)
    return _array_replacement(s, presets, preset, style)


def _array_replacement(s: str, presets: _Member, preset: Mapping[str, Any], style: _Style) -> tuple[int, int, str]:
    node = presets.value
    elements = _elements(s, node)
    texts = [s[e.start:e.end] for e in elements]
    kept, at = _merge([json.loads(t) for t in texts], preset)
    guid, name = str(preset["guid"]), str(preset["name"])
    kept_texts = [t for t in texts if not is_replaced(json.loads(t), guid, name)]
    assert len(kept_texts) == len(kept)
    if elements:
        lead = s[node.start + 1:elements[0].start]
        trail = s[elements[-1].end:node.end - 1]
        sep = s[elements[0].end:elements[1].start] if len(elements) > 1 else "," + lead
        indent = _indent_at(s, elements[0].start)
    else:
        outer = _line_indent(s, presets.key_start)
        if outer is None or style.unit is None:
            lead = trail = ""
            sep = style.comma
            indent = None
        else:
            indent = outer + style.unit
            lead, trail = style.newline + indent, style.newline + outer
            sep = "," + lead
    new_text = style.dumps(dict(preset), indent)
    kept_texts.insert(at, new_text)
    return node.start, node.end, "[" + lead + sep.join(kept_texts) + trail + "]"


def _append_member(s: str, obj: _Node, members: list[_Member], key: str, value: Any,
                   style: _Style) -> tuple[int, int, str]:
    """Insert ``"key": value`` as the last member of the object ``obj`` (a pure insertion)."""
    if members:
        last = members[-1]
        indent = _indent_at(s, last.key_start)
        if len(members) > 1:
            sep = s[members[-2].value.end:members[-1].key_start]
        else:
            sep = "," + s[obj.start + 1:last.key_start]
        sep = sep if sep.lstrip().startswith(",") else "," + sep
        text = sep + json.dumps(key) + style.colon + style.dumps(value, indent)
        return last.value.end, last.value.end, text
    outer = _line_indent(s, obj.start)
    if style.unit is None or outer is None:
        body = "{" + json.dumps(key) + style.colon + style.dumps(value, None) + "}"
    else:
        inner = outer + style.unit
        body = ("{" + style.newline + inner + json.dumps(key) + style.colon + style.dumps(value, inner)
                + style.newline + outer + "}")
    return obj.start, obj.end, body


# --------------------------------------------------------------------------- .tools


def _rewrite_zip(raw: bytes, member: str, data: bytes) -> bytes:
    """The zip with ``member``'s content replaced; every other member as it was."""
    out = io.BytesIO()
    with zipfile.ZipFile(io.BytesIO(raw)) as zin, zipfile.ZipFile(out, "w") as zout:
        zout.comment = zin.comment
        for info in zin.infolist():
            content = data if info.filename == member else zin.read(info)
            clone = copy.copy(info)
            zout.writestr(clone, content, compress_type=info.compress_type)
    return out.getvalue()
