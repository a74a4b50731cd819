"""Request bodies decoded under the input policy, fast.

Every JSON request body of the REST service, every JSON text inside a form field and every
JSON file the CLI reads goes through :func:`decode_json`. The rules — and every message a
refused document gets — are :mod:`rcsa.model.input_policy`'s, the same the file importers
of the library apply to uploaded files; this function only parses faster (orjson, RFC 8259
strict) and, when orjson refuses a text, lets the policy's own parser say why.

>>> decode_json(b'{"tool": {"stickout_m": 0.05}}')
{'tool': {'stickout_m': 0.05}}
>>> decode_json(b'{"h": {"real": [1.0, 1e300]}}')
Traceback (most recent call last):
...
rcsa.errors.InputError: h.real[1]: number out of range: its magnitude must be <= 1e+30, got 1e+300
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import orjson

from rcsa.errors import MalformedInput
from rcsa.model.input_policy import JsonCounter, check_json, check_json_size, load_json

__all__ = ["decode_json", "json_counter"]


def json_counter(*, path: str = "", what: str = "the body") -> Callable[[bytes], None]:
    """A ``feed(piece)`` that counts JSON text piece by piece as it arrives and raises
    :class:`~rcsa.errors.InputError` once it holds too many objects, arrays or elements
    (:class:`rcsa.model.input_policy.JsonCounter`); what the service calls while a body arrives,
    before :func:`decode_json` (``counted=True``) parses it."""
    return JsonCounter(path=path, what=what).feed


def decode_json(data: bytes | bytearray | memoryview | str, *, path: str = "",
                what: str = "the body", counted: bool = False) -> Any:
    """Parse JSON text under :mod:`rcsa.model.input_policy`.

    Parameters
    ----------
    data : bytes or str
        The JSON text (UTF-8).
    path : str
        Where the document sits in the request (e.g. a form field's name), for messages.
    what : str
        What the text is, for the syntax message (``the body``, ``form field options``).
    counted : bool
        The text's objects, arrays and elements were counted already, as it arrived
        (:class:`rcsa.model.input_policy.JsonCounter`); else they are counted first.

    Returns
    -------
    Any
        The document (dicts, lists, str, int, float, bool, None).

    Raises
    ------
    InputError
        See :mod:`rcsa.model.input_policy` (:class:`~rcsa.errors.MalformedInput` when the
        text is not JSON at all).
    """
    if not counted:
        check_json_size(data, path=path, what=what)
    try:
        doc = orjson.loads(data)
    except orjson.JSONDecodeError as exc:
        load_json(data, path=path, what=what)  # raises with the policy's message
        raise MalformedInput(path, f"{what} is not valid JSON: {exc}") from None  # orjson alone refuses it
    return check_json(doc, path=path)
