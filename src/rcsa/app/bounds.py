"""The validation bounds of every request, as the library checks them (:mod:`rcsa.model.bounds`).

The REST schemas publish these numbers in the OpenAPI document, so that the schema accepts
exactly what the library accepts.
"""

from __future__ import annotations

from rcsa.model.bounds import *  # noqa: F403 (the whole table, by design)
from rcsa.model.bounds import __all__  # noqa: F401
