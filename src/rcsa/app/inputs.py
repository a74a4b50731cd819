"""The one JSON-decoding policy of every request: what a JSON document may contain.

Every JSON request body of the REST service, every JSON text inside a form field and every
JSON file the CLI reads goes through :func:`decode_json`, so both doors refuse hostile
documents the same way, before anything else looks at them, with an
:class:`~rcsa.errors.InputError` naming where (the bounds are
:mod:`rcsa.model.bounds`'s, the one source):

* not JSON (syntax, not UTF-8): field ``""``, ``the body is not valid JSON: ...``;
* ``NaN``, ``Infinity``, ``-Infinity`` tokens: not JSON (RFC 8259), refused by the parser;
* a number whose magnitude exceeds :data:`~rcsa.model.bounds.MAX_JSON_NUMBER` (including
  ``1e400`` and integers such as ``10**400``): the path of the number;
* nesting deeper than :data:`~rcsa.model.bounds.MAX_JSON_DEPTH`: the path where it gets
  too deep.

The parser is orjson (RFC 8259 strict; integers beyond 64 bits become floats, and numbers
that overflow a double are refused). Numeric lists are checked by numpy in one pass.

>>> decode_json(b'{"tool": {"stickout_m": 0.05}}')
{'tool': {'stickout_m': 0.05}}
>>> decode_json(b'{"h": {"real": [1.0, 1e300]}}')
Traceback (most recent call last):
...
rcsa.errors.InputError: h.real[1]: number out of range: its magnitude must be <= 1e+30, got 1e+300
"""

from __future__ import annotations

import json
from typing import Any

import numpy as np
import orjson

from rcsa.errors import InputError
from rcsa.model.bounds import MAX_JSON_DEPTH, MAX_JSON_NUMBER

__all__ = ["check_json", "decode_json"]


def decode_json(data: bytes | bytearray | memoryview | str, *, path: str = "",
                what: str = "the body") -> Any:
    """Parse JSON text under the policy of the module docstring.

    Parameters
    ----------
    data : bytes or str
        The JSON text (UTF-8).
    path : str
        Where the document sits in the request (e.g. a form field's name), for messages.
    what : str
        What the text is, for the syntax message (``the body``, ``form field options``).

    Returns
    -------
    Any
        The document (dicts, lists, str, int, float, bool, None).

    Raises
    ------
    InputError
        See the module docstring.
    """
    try:
        doc = orjson.loads(data)
    except orjson.JSONDecodeError as exc:
        msg = str(exc.msg if hasattr(exc, "msg") else exc)
        if "depth limit" in msg or "recursion" in msg:
            raise InputError(path, f"nested deeper than {MAX_JSON_DEPTH} levels of objects and lists") from None
        if "infinity" in msg:
            _locate_overflow(data, path)
            raise InputError(path, f"{what} holds a number out of range (its magnitude must be <= "
                                   f"{MAX_JSON_NUMBER:g}) at character {exc.pos}") from None
        hint = " (NaN and Infinity are not JSON: send finite numbers)" if "unexpected character" in msg else ""
        raise InputError(path, f"{what} is not valid JSON: {msg} at character {exc.pos}{hint}") from None
    return check_json(doc, path=path)


def _locate_overflow(data: bytes | bytearray | memoryview | str, path: str) -> None:
    """Raise naming the field of a number too large for a double (orjson only gives the
    character): the standard parser keeps big integers exact and reads 1e400 as inf."""
    try:
        doc = json.loads(bytes(data) if isinstance(data, memoryview | bytearray) else data,
                         parse_constant=_no_constant)
    except (ValueError, RecursionError, TypeError):
        return
    check_json(doc, path=path)


def _no_constant(name: str) -> Any:
    raise ValueError(name)


def check_json(value: Any, *, path: str = "") -> Any:
    """Check an already parsed document against the policy (depth, number range); return it.

    Raises
    ------
    InputError
        See the module docstring.
    """
    _walk(value, path, 0)
    return value


def _join(path: str, key: str | int) -> str:
    if isinstance(key, int):
        return f"{path}[{key}]"
    return f"{path}.{key}" if path else str(key)


def _number(x: float | int, path: str) -> None:
    try:
        big = not abs(x) <= MAX_JSON_NUMBER  # NaN is "big" too
    except OverflowError:  # an int beyond a double (from the standard parser)
        big = True
    if big:
        shown = f"{x:g}" if isinstance(x, float) else f"an integer of {len(str(abs(x)))} digits"
        raise InputError(path, f"number out of range: its magnitude must be <= {MAX_JSON_NUMBER:g}, got {shown}")


def _walk(value: Any, path: str, depth: int) -> None:
    kind = type(value)
    if kind is float or kind is int:
        _number(value, path)
        return
    if kind is dict:
        if depth >= MAX_JSON_DEPTH:
            raise InputError(path, f"nested deeper than {MAX_JSON_DEPTH} levels of objects and lists")
        for key, item in value.items():
            if type(item) in (str, bool) or item is None:
                continue
            _walk(item, _join(path, key), depth + 1)
        return
    if kind is list:
        if depth >= MAX_JSON_DEPTH:
            raise InputError(path, f"nested deeper than {MAX_JSON_DEPTH} levels of objects and lists")
        if value and _numeric_list_ok(value, path):
            return
        for i, item in enumerate(value):
            if type(item) in (str, bool) or item is None:
                continue
            _walk(item, _join(path, i), depth + 1)
        return
    if isinstance(value, str | bool) or value is None:
        return
    if isinstance(value, float | int):
        _number(value, path)
        return
    if isinstance(value, dict | list | tuple):  # not from a parser: a Python caller's document
        _walk(dict(value) if isinstance(value, dict) else list(value), path, depth)
        return
    raise InputError(path, f"must be JSON data (object, list, string, number), got {type(value).__name__}")


def _numeric_list_ok(values: list[Any], path: str) -> bool:
    """True when ``values`` is a flat list of numbers within range (checked by numpy);
    raises for the first number out of range; False when it holds anything else."""
    first = type(values[0])
    if first is not float and first is not int:
        return False
    try:
        arr = np.array(values)
    except (ValueError, TypeError, OverflowError):  # ragged, or ints numpy cannot hold
        return False
    if arr.ndim != 1 or arr.dtype.kind not in "fiu":
        return False  # nested, or mixed with strings/objects: walk item by item
    if arr.dtype.kind == "f":
        bad = ~(np.abs(arr) <= MAX_JSON_NUMBER)
    else:
        bad = np.abs(arr.astype(np.float64)) > MAX_JSON_NUMBER
    if bad.any():
        i = int(np.argmax(bad))
        _number(values[i], _join(path, i))
    return True
