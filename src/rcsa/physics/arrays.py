"""Array type aliases of the physics core (for annotations; numpy only).

Arrays are frequency-first (``docs/physics.md`` §2.1): ``(nfreq,)`` per line, ``(nfreq, 2, 2)`` for
a point receptance or stiffness. Parameters of chain items and sections are one number, or
— in a chain stacked over many tools (:mod:`rcsa.physics.stacking`) — one per row.
"""

from __future__ import annotations

from typing import Any, TypeAlias

import numpy as np
from numpy.typing import NDArray

__all__ = ["BoolArray", "ComplexArray", "ComplexParam", "FloatArray", "IntArray", "RealParam"]

# Typed by kind, not precision: the arrays are float64 / complex128, but numpy types the
# results of arithmetic by kind (``1j * w`` is ``complexfloating[Any, Any]``), and a
# precision-typed alias would need a cast after every operation.

#: Real array (float64).
FloatArray: TypeAlias = NDArray[np.floating[Any]]
#: Complex array (complex128).
ComplexArray: TypeAlias = NDArray[np.complexfloating[Any, Any]]
#: Integer array (counts, indices).
IntArray: TypeAlias = NDArray[np.integer[Any]]
#: Boolean array (masks).
BoolArray: TypeAlias = NDArray[np.bool_]
#: A real parameter: one value, or one per row of a stacked chain.
RealParam: TypeAlias = float | FloatArray
#: A complex parameter (hysteretic moduli): one value, or one per row of a stacked chain.
ComplexParam: TypeAlias = complex | ComplexArray
