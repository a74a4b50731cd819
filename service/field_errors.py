"""Pydantic's validation errors as the service reports them: ``[{"field", "detail"}]``.

A field is a dotted path from the body's root (``combinations[3].tool.stickout_m``), without
the names pydantic gives the members of a union.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

__all__ = ["UNION_TAGS", "field_path", "pydantic_errors"]

#: Names the schemas give the members of their unions (pydantic puts them in error locations).
UNION_TAGS = frozenset({"frequency-range", "frequency-values", "spindle-analytical", "spindle-measured",
                        "frf-inline", "frf-stored", "effects-assembly", "effects-request"})

#: What pydantic puts in error locations for the members of a union (not field names).
_PYDANTIC_TAGS = ("literal[", "function-", "json-or-python[", "lax-or-strict[", "constrained-", "list[", "dict[",
                  "tagged-union[", "nullable[", "union[", "model-fields[")
_PYDANTIC_TYPES = frozenset({"float", "int", "str", "bool", "none", "bytes", "list", "dict"})


def field_path(loc: Sequence[Any]) -> str:
    """Dotted path of a pydantic error location, without the ``body``/``query`` prefix and
    without the names pydantic gives union members."""
    parts: list[str] = []
    for i, item in enumerate(loc):
        if i == 0 and item in ("body", "query", "path", "header", "cookie", "form"):
            continue
        if isinstance(item, int):
            if parts:
                parts[-1] += f"[{item}]"
            else:
                parts.append(f"[{item}]")
            continue
        text = str(item)
        if text in UNION_TAGS or text.startswith(_PYDANTIC_TAGS) or text in _PYDANTIC_TYPES:
            continue
        parts.append(text)
    return ".".join(parts)



def pydantic_errors(errors: Sequence[Mapping[str, Any]], prefix: str = "") -> list[dict[str, str]]:
    """``[{"field", "detail"}]`` of pydantic errors (fields prefixed with ``prefix``)."""
    out: list[dict[str, str]] = []
    seen: set[tuple[str, str]] = set()
    for err in errors:
        loc = tuple(err.get("loc", ()))
        kind = err.get("type", "")
        if kind == "json_invalid":
            pos = loc[1] if len(loc) > 1 else "?"
            item = ("", f"the body is not valid JSON: {err.get('ctx', {}).get('error', 'decode error')} "
                        f"at character {pos}")
        else:
            field = field_path(loc)
            if kind == "unknown_field":
                field = ".".join(p for p in (field, str(err.get("ctx", {}).get("field", ""))) if p)
            if prefix:
                field = prefix + ("." + field if field and not field.startswith("[") else field)
            msg = str(err.get("msg", "invalid"))
            if kind == "extra_forbidden":
                msg = "unknown field; check its spelling against the schema at /docs"
            elif kind == "missing":
                msg = "is required"
            item = (field, msg)
        if item not in seen:
            seen.add(item)
            out.append({"field": item[0], "detail": item[1]})
    return out
