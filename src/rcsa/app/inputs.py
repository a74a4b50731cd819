"""How every request document is read: the one JSON-decoding policy (:mod:`rcsa.model.json_input`).

The REST service decodes every JSON body and every JSON form field with
:func:`decode_json`, and the CLI every JSON file it reads, so both doors refuse the same
hostile documents (NaN/Infinity, numbers out of range, nesting too deep) with the same
:class:`~rcsa.errors.InputError` naming the field.
"""

from __future__ import annotations

from rcsa.model.json_input import check_json, decode_json

__all__ = ["check_json", "decode_json"]
