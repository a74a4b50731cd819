"""The one policy for what any input may contain: JSON documents, files, their numbers and sizes.

Every JSON request body, every JSON form field, every JSON file the CLI reads and every
uploaded file — Fusion ``.json``/``.tools``, FreeCAD ``.fctb``/``.fcholder``, measurement
JSON, UFF 58, CSV/TSV, CutPro ``.frf``, raw tap tests — meets the same rules before anything
computes with it, so that both doors (CLI and REST) and a library caller refuse hostile input
the same way, with an :class:`~rcsa.errors.InputError` naming where (the numbers are
:mod:`rcsa.model.bounds`'s, the one source):

* not JSON (syntax, not UTF-8): ``... is not valid JSON: ...`` at the character, line and column
  (:class:`~rcsa.errors.MalformedInput`: the REST service answers 400, the rest is 422);
* more objects and arrays than :data:`~rcsa.model.bounds.MAX_JSON_CONTAINERS`, more of
  their elements than :data:`~rcsa.model.bounds.MAX_JSON_ITEMS`, or a string of more than
  :data:`MAX_STRING_BYTES` bytes (certainly too long: a character takes at most 12): counted
  on the raw text before it is parsed (:class:`JsonCounter`, which the service also feeds
  while a body arrives), so a document of millions of tiny items, or one huge string, is
  refused before anything is made of it;
* ``NaN``, ``Infinity``, ``-Infinity`` (JSON tokens, or ``nan``/``inf`` in a text table): not
  finite numbers, refused;
* a number whose magnitude exceeds :data:`~rcsa.model.bounds.MAX_JSON_NUMBER` (``1e308``,
  ``1e400``, an integer of 400 digits): the path of the number, or the file's line and column;
* nesting deeper than :data:`~rcsa.model.bounds.MAX_JSON_DEPTH`: the path where it gets too deep;
* a string longer than :data:`~rcsa.model.bounds.MAX_STRING_CHARS`: its path;
* more rows than a file of its kind may have (:func:`check_count`): the file's field;
* a zip archive of more than :data:`~rcsa.model.bounds.MAX_LIBRARY_ITEMS` files
  (:func:`check_zip_members`, before the archive is opened: the members' directory alone of a
  million tiny files would cost hundreds of MB to read).

JSON text is parsed here by the standard library (strict: the tokens above are refused by
the parser); the service decodes its bodies with a faster parser and calls :func:`check_json`
on the result, and this module's :func:`load_json` for the message when that parser refuses.

>>> load_json('{"tool": {"stickout_m": 0.05}}')
{'tool': {'stickout_m': 0.05}}
>>> load_json('{"h": {"real": [1.0, 1e300]}}')
Traceback (most recent call last):
...
rcsa.errors.InputError: h.real[1]: number out of range: its magnitude must be <= 1e+30, got 1e+300
>>> check_numbers(np.array([[1.0, 2.0], [np.inf, 0.0]]), "file", lines=[3, 4], columns=["f", "re"])
Traceback (most recent call last):
...
rcsa.errors.InputError: file: line 4, column 1 (f) is inf: not a finite number
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from typing import Any

import numpy as np
import numpy.typing as npt

from rcsa.errors import InputError, MalformedInput
from rcsa.model.bounds import (
    MAX_JSON_CONTAINERS,
    MAX_JSON_DEPTH,
    MAX_JSON_ITEMS,
    MAX_JSON_NUMBER,
    MAX_LIBRARY_ITEMS,
    MAX_STRING_CHARS,
)

__all__ = ["MAX_STRING_BYTES", "JsonCounter", "check_count", "check_zip_members", "check_json", "check_json_size", "check_number", "check_numbers",
           "load_json"]

#: Raw bytes of a JSON string beyond which it certainly holds more than
#: :data:`~rcsa.model.bounds.MAX_STRING_CHARS` characters (a character is at most 12 bytes of
#: JSON text: a surrogate pair of ``\\uXXXX`` escapes).
MAX_STRING_BYTES = 12 * MAX_STRING_CHARS
#: Bytes a :class:`JsonCounter` looks at in one numpy pass (bounds its scratch memory).
_SCAN_BYTES = 1 << 20
_QUOTE, _BACKSLASH, _COMMA, _BRACE, _BRACKET = 34, 92, 44, 123, 91


class JsonCounter:
    """Count the objects, arrays and their elements of JSON text as it arrives, without parsing it.

    Feed the text piece by piece (:meth:`feed`, any split); it refuses as soon as the document
    holds more than ``max_containers`` objects and arrays or more than ``max_items`` of their
    elements. The count is made on the raw bytes by numpy, a pass per MiB: the structural
    bytes ``{`` ``[`` ``,`` are counted where they lie outside strings (a ``"`` ends a string
    unless an odd run of backslashes precedes it). Elements are counted as the commas between
    them plus one per object or array (an empty one counts one too). On text that is not JSON
    the counts mean nothing, but the parser refuses that text anyway.

    Parameters
    ----------
    path : str
        Where the document sits (a form field's name), for messages.
    what : str
        What the text is, for messages (``the body``, ``the tool library``).
    max_containers, max_items : int
        The bounds (default :data:`~rcsa.model.bounds.MAX_JSON_CONTAINERS` and
        :data:`~rcsa.model.bounds.MAX_JSON_ITEMS`).

    Examples
    --------
    >>> counter = JsonCounter(max_containers=3)
    >>> counter.feed(b'{"a": [1, 2], "b": "{[,"')
    >>> counter.containers, counter.items
    (2, 4)
    >>> counter.feed(b', "c": [[]]}')
    Traceback (most recent call last):
    ...
    rcsa.errors.InputError: the body holds more than 3 objects and arrays (at most 3 in one JSON document): send less, e.g. split a batch into several requests
    """

    def __init__(self, *, path: str = "", what: str = "the body", max_containers: int = MAX_JSON_CONTAINERS,
                 max_items: int = MAX_JSON_ITEMS) -> None:
        self.path = path
        self.what = what
        self.max_containers = int(max_containers)
        self.max_items = int(max_items)
        self.containers = 0
        self.items = 0
        self.bytes = 0
        self._in_string = False
        self._string_start = 0  # offset of the opening quote of the string the text ends in
        self.longest_string_bytes = 0  # from an opening quote to its closing one
        self._backslashes = 0  # backslashes ending the text fed so far

    def feed(self, data: bytes | bytearray | memoryview) -> None:
        """Count one more piece of the text.

        Parameters
        ----------
        data : bytes
            The next piece (any split of the text).

        Raises
        ------
        InputError
            The text so far exceeds a bound.
        """
        view = memoryview(data).cast("B")
        for start in range(0, len(view), _SCAN_BYTES):
            self._scan(np.frombuffer(view[start:start + _SCAN_BYTES], dtype=np.uint8))
            if self.containers > self.max_containers:
                raise InputError(self.path, f"{self.what} holds more than {self.max_containers} objects and arrays "
                                            f"(at most {self.max_containers} in one JSON document): send less, e.g. "
                                            "split a batch into several requests")
            if self.items > self.max_items:
                raise InputError(self.path, f"{self.what} holds more than {self.max_items} elements of objects and "
                                            f"arrays (at most {self.max_items} in one JSON document): send less, "
                                            "e.g. split a batch into several requests")
            if self.longest_string_bytes > MAX_STRING_BYTES:
                raise InputError(self.path, f"{self.what} holds a text of more than {MAX_STRING_CHARS} characters "
                                            f"(over {MAX_STRING_BYTES} bytes); at most {MAX_STRING_CHARS}")

    def _scan(self, a: npt.NDArray[np.uint8]) -> None:
        offset = self.bytes
        self.bytes += a.size
        quotes = np.flatnonzero(a == _QUOTE)
        backslash = a == _BACKSLASH
        carried = self._backslashes
        not_backslash = np.flatnonzero(~backslash)
        if not_backslash.size == 0:  # nothing but backslashes
            self._backslashes = carried + a.size
        else:
            self._backslashes = a.size - 1 - int(not_backslash[-1])
        if quotes.size and (carried or backslash.any()):
            # a quote is escaped when an odd run of backslashes precedes it
            k = np.searchsorted(not_backslash, quotes)  # quotes are not backslashes: exact positions
            before = np.where(k > 0, not_backslash[np.maximum(k - 1, 0)], -1)
            run = quotes - before - 1 + np.where(before < 0, carried, 0)
            quotes = quotes[run % 2 == 0]
        start_inside = self._in_string
        self._in_string = bool((quotes.size + start_inside) % 2)
        # string lengths: quote pairs (a string open since an earlier piece closes at the first)
        bounds = np.concatenate(([self._string_start - offset], quotes)) if start_inside else quotes
        if self._in_string:
            bounds = np.concatenate((bounds, [a.size]))
        if bounds.size >= 2:
            longest = int(np.max(bounds[1::2] - bounds[0::2]))
            self.longest_string_bytes = max(self.longest_string_bytes, longest)
        if self._in_string:
            self._string_start = offset + int(bounds[-2])
        for mask_value, is_container in ((_BRACE, True), (_BRACKET, True), (_COMMA, False)):
            found = np.flatnonzero(a == mask_value)
            if found.size == 0:
                continue
            if quotes.size:
                outside = (np.searchsorted(quotes, found) + start_inside) % 2 == 0
                n = int(np.count_nonzero(outside))
            else:
                n = 0 if start_inside else int(found.size)
            self.items += n
            if is_container:
                self.containers += n


def check_json_size(data: bytes | bytearray | memoryview | str, *, path: str = "", what: str = "the body") -> None:
    """Refuse JSON text with too many objects, arrays or elements before it is parsed (:class:`JsonCounter`).

    Text shorter than the bounds cannot exceed them and is not scanned.

    Parameters
    ----------
    data : bytes or str
        The JSON text.
    path : str
        Where the document sits, for messages.
    what : str
        What the text is, for messages.

    Raises
    ------
    InputError
        Naming ``path``, the count and the bound.
    """
    if len(data) <= min(MAX_JSON_CONTAINERS, MAX_JSON_ITEMS):
        return
    raw = data.encode("utf-8") if isinstance(data, str) else data
    JsonCounter(path=path, what=what).feed(raw)


def load_json(data: bytes | bytearray | memoryview | str, *, path: str = "", what: str = "the body") -> Any:
    """Parse JSON text under the policy of the module docstring.

    Parameters
    ----------
    data : bytes or str
        The JSON text (UTF-8, a byte-order mark allowed).
    path : str
        Where the document sits (a form field's name, a file's field), for messages.
    what : str
        What the text is, for the syntax message (``the body``, ``the file lib.json``).

    Returns
    -------
    Any
        The document (dicts, lists, str, int, float, bool, None).

    Raises
    ------
    InputError
        See the module docstring.
    """
    if isinstance(data, bytes | bytearray | memoryview):
        try:
            text = bytes(data).decode("utf-8-sig")
        except UnicodeDecodeError as exc:
            raise MalformedInput(path, f"{what} is not valid JSON: not UTF-8 text (byte {exc.start})") from None
    else:
        text = data
    check_json_size(text, path=path, what=what)
    try:
        doc = json.loads(text, parse_constant=_no_constant)
    except _Constant as exc:
        raise MalformedInput(path, f"{what} is not valid JSON: {exc.args[0]} is not a number "
                                   "(NaN and Infinity are not JSON: send finite numbers)") from None
    except RecursionError:
        raise InputError(path, f"nested deeper than {MAX_JSON_DEPTH} levels of objects and lists") from None
    except json.JSONDecodeError as exc:
        raise MalformedInput(path, f"{what} is not valid JSON: {exc.msg} at character {exc.pos} (line {exc.lineno}, "
                                   f"column {exc.colno})") from None
    except ValueError as exc:  # an integer of more digits than Python converts (sys.int_info)
        raise InputError(path, f"{what} holds a number out of range (its magnitude must be <= "
                               f"{MAX_JSON_NUMBER:g}): {exc}") from None
    return check_json(doc, path=path)


class _Constant(ValueError):
    pass


def _no_constant(name: str) -> Any:
    raise _Constant(name)


def check_json(value: Any, *, path: str = "") -> Any:
    """Check an already parsed document against the policy (depth, numbers, strings); return it.

    Parameters
    ----------
    value : Any
        A parsed JSON document (or a Python caller's equivalent of dicts, lists and tuples).
    path : str
        Where the document sits, for messages.

    Returns
    -------
    Any
        ``value`` itself.

    Raises
    ------
    InputError
        See the module docstring.
    """
    _walk(value, path, 0)
    return value


def check_number(x: float | int, field: str) -> float | int:
    """One number under the policy: finite and of magnitude at most ``MAX_JSON_NUMBER``.

    Parameters
    ----------
    x : float or int
        The number.
    field : str
        Its field, for the message.

    Returns
    -------
    float or int
        ``x`` itself.

    Raises
    ------
    InputError
        Naming ``field``.

    Examples
    --------
    >>> check_number(2.5, "mass_kg")
    2.5
    """
    try:
        big = not abs(x) <= MAX_JSON_NUMBER  # NaN is "big" too
    except OverflowError:  # an int beyond a double
        big = True
    if big:
        shown = f"{x:g}" if isinstance(x, float) else f"an integer of {len(str(abs(x)))} digits"
        raise InputError(field, f"number out of range: its magnitude must be <= {MAX_JSON_NUMBER:g}, got {shown}")
    return x


def check_numbers(values: npt.ArrayLike, field: str, *, lines: Sequence[int] | None = None,
                  columns: Sequence[str] | None = None) -> None:
    """A table read from a text file under the number policy, in one numpy pass.

    Parameters
    ----------
    values : array_like, shape (nrows,) or (nrows, ncols)
        The numbers as read (``float('1e400')`` is ``inf``, so every overflow shows).
    field : str
        The field the file stands for (``file``).
    lines : sequence of int, optional
        The file's line of each row, for the message (else the row's index).
    columns : sequence of str, optional
        Names of the columns, for the message.

    Raises
    ------
    InputError
        Naming the field, the first offending line and column, and the value.
    """
    arr = np.asarray(values, dtype=float)
    bad = ~(np.abs(arr) <= MAX_JSON_NUMBER)
    if not bad.any():
        return
    first = np.argwhere(bad)[0]
    i = int(first[0])
    where = f"line {lines[i]}" if lines is not None else f"row {i + 1}"
    if arr.ndim > 1:
        j = int(first[1])
        name = f" ({columns[j]})" if columns is not None and j < len(columns) else ""
        where += f", column {j + 1}{name}"
    x = float(arr[tuple(first)])
    if not np.isfinite(x):
        raise InputError(field, f"{where} is {x!r}: not a finite number")
    raise InputError(field, f"{where}: number out of range: its magnitude must be <= {MAX_JSON_NUMBER:g}, "
                            f"got {x:g}")


def check_count(count: int, field: str, limit: int, what: str = "rows") -> None:
    """Refuse more than ``limit`` items (rows, lines, samples, entries) of ``field``.

    Parameters
    ----------
    count : int
        How many there are.
    field : str
        Their field, for the message.
    limit : int
        The most allowed.
    what : str
        What they are, for the message.

    Raises
    ------
    InputError
        Naming ``field``, the count and the limit.

    Examples
    --------
    >>> check_count(3, "file", 2)
    Traceback (most recent call last):
    ...
    rcsa.errors.InputError: file: at most 2 rows, got 3
    """
    if count > limit:
        raise InputError(field, f"at most {limit} {what}, got {count}")


def check_zip_members(raw: bytes | bytearray | memoryview, field: str, limit: int = MAX_LIBRARY_ITEMS) -> None:
    """Refuse a zip archive of more than ``limit`` files, before it is opened.

    Counts the signature every entry of a zip's central directory starts with (``PK\\1\\2``;
    :mod:`zipfile` refuses an entry without it) in the raw bytes, whatever count the archive
    states: an upper bound of its members, made without building one object per member.

    Parameters
    ----------
    raw : bytes
        The archive.
    field : str
        The field it stands for, for the message.
    limit : int
        Most files allowed.

    Raises
    ------
    InputError
        Naming ``field`` and the bound.

    Examples
    --------
    >>> check_zip_members(b"PK\\x01\\x02" * 3, "library", limit=2)
    Traceback (most recent call last):
    ...
    rcsa.errors.InputError: library: the zip archive holds more than 2 files (3 entries)
    """
    n = bytes(raw).count(b"PK\x01\x02") if not isinstance(raw, bytes) else raw.count(b"PK\x01\x02")
    if n > limit:
        raise InputError(field, f"the zip archive holds more than {limit} files ({n} entries)")


def _join(path: str, key: str | int) -> str:
    if isinstance(key, int):
        return f"{path}[{key}]"
    return f"{path}.{key}" if path else str(key)


def _string(value: str, path: str) -> None:
    if len(value) > MAX_STRING_CHARS:
        raise InputError(path, f"a text of {len(value)} characters; at most {MAX_STRING_CHARS}")


def _too_deep(path: str) -> InputError:
    return InputError(path, f"nested deeper than {MAX_JSON_DEPTH} levels of objects and lists")


def _walk(value: Any, path: str, depth: int) -> None:
    kind = type(value)
    if kind is float or kind is int:
        check_number(value, path)
        return
    if kind is str:
        _string(value, path)
        return
    if kind is dict:
        if depth >= MAX_JSON_DEPTH:
            raise _too_deep(path)
        for key, item in value.items():
            if type(key) is str:
                _string(key, path)
            if type(item) is bool or item is None:
                continue
            _walk(item, _join(path, key), depth + 1)
        return
    if kind is list:
        if depth >= MAX_JSON_DEPTH:
            raise _too_deep(path)
        if value and _numeric_list_ok(value, path):
            return
        for i, item in enumerate(value):
            if type(item) is bool or item is None:
                continue
            _walk(item, _join(path, i), depth + 1)
        return
    if isinstance(value, bool) or value is None:
        return
    if isinstance(value, str):
        _string(value, path)
        return
    if isinstance(value, float | int | np.floating | np.integer):
        check_number(value.item() if isinstance(value, np.generic) else value, path)
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
        check_number(values[i], _join(path, i))
    return True
