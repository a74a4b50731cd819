"""Array type aliases of the physics core (for annotations; numpy only).

Arrays are frequency-first (``style.md`` §9.1): ``(nfreq,)`` per line, ``(nfreq, 2, 2)`` for
a point receptance or stiffness. Parameters of chain items and sections are one number, or
— in a chain stacked over many tools (:mod:`rcsa.physics.stacking`) — one per row.
"""

from __future__ import annotations

from typing import TypeAlias

import numpy as np
from numpy.typing import NDArray

__all__ = ["BoolArray", "ComplexArray", "ComplexParam", "FloatArray", "IntArray", "RealParam"]

#: Real float64 array.
FloatArray: TypeAlias = NDArray[np.float64]
#: Complex128 array.
ComplexArray: TypeAlias = NDArray[np.complex128]
#: Integer array (counts, indices).
IntArray: TypeAlias = NDArray[np.int_]
#: Boolean array (masks).
BoolArray: TypeAlias = NDArray[np.bool_]
#: A real parameter: one value, or one per row of a stacked chain.
RealParam: TypeAlias = float | FloatArray
#: A complex parameter (hysteretic moduli): one value, or one per row of a stacked chain.
ComplexParam: TypeAlias = complex | ComplexArray
