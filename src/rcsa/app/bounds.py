"""The validation bounds of every request, as the library checks them (:mod:`rcsa.model.bounds`).

The REST schemas publish these numbers in the OpenAPI document, so that the schema accepts
exactly what the library accepts. The semi-discretization lobes' options keep their bounds
beside their solver (:mod:`rcsa.analysis.lobes.options`); they are published here under
``SDM_`` names.
"""

from __future__ import annotations

from rcsa.analysis.lobes.options import (
    DEFAULT_MODES_PER_DIRECTION as SDM_DEFAULT_MODES_PER_DIRECTION,
)
from rcsa.analysis.lobes.options import DEFAULT_STEPS_PER_PERIOD as SDM_DEFAULT_STEPS_PER_PERIOD
from rcsa.analysis.lobes.options import MAX_MODES_PER_DIRECTION as SDM_MAX_MODES_PER_DIRECTION
from rcsa.analysis.lobes.options import MAX_STEPS_PER_PERIOD as SDM_MAX_STEPS_PER_PERIOD
from rcsa.analysis.lobes.options import MIN_MODES_PER_DIRECTION as SDM_MIN_MODES_PER_DIRECTION
from rcsa.analysis.lobes.options import MIN_STEPS_PER_PERIOD as SDM_MIN_STEPS_PER_PERIOD
from rcsa.model import bounds as _model_bounds
from rcsa.model.bounds import *  # noqa: F403 (the whole table, by design)

__all__ = [
    *_model_bounds.__all__,
    "SDM_DEFAULT_MODES_PER_DIRECTION",
    "SDM_DEFAULT_STEPS_PER_PERIOD",
    "SDM_MAX_MODES_PER_DIRECTION",
    "SDM_MAX_STEPS_PER_PERIOD",
    "SDM_MIN_MODES_PER_DIRECTION",
    "SDM_MIN_STEPS_PER_PERIOD",
]
