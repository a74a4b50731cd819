"""Validation bounds of every request: the one source the library and the REST schemas share.

Sanity bounds lie far outside any machine tool, so that no accepted value can overflow the
arithmetic (2πf, d⁴, k/ω …); size limits bound the work a request may ask for.
"""

from __future__ import annotations

__all__ = [
    "MAX_BATCH_COMBINATIONS",
    "MAX_DAMPING",
    "MAX_DENSITY_KG_M3",
    "MAX_FREQUENCY_HZ",
    "MAX_FREQUENCY_LINES",
    "MAX_LENGTH_M",
    "MAX_MODULUS_PA",
    "MAX_STIFFNESS",
    "MIN_LENGTH_M",
]

#: Frequency lines of one request.
MAX_FREQUENCY_LINES = 200_000
#: Tool–holder combinations of one batch.
MAX_BATCH_COMBINATIONS = 10_000
#: Highest frequency, Hz.
MAX_FREQUENCY_HZ = 1.0e7
#: Shortest and longest length or diameter, m.
MIN_LENGTH_M, MAX_LENGTH_M = 1.0e-6, 100.0
#: Largest Young's modulus, Pa.
MAX_MODULUS_PA = 1.0e13
#: Largest density, kg/m³.
MAX_DENSITY_KG_M3 = 1.0e5
#: Largest stiffness, N/m or N·m/rad.
MAX_STIFFNESS = 1.0e15
#: Largest viscous damping, N·s/m or N·m·s/rad.
MAX_DAMPING = 1.0e12
