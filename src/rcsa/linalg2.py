"""Closed-form operations on stacks of 2×2 matrices, shape (..., 2, 2).

``numpy.linalg`` dispatches one LAPACK call per matrix; for the 2×2 blocks of beam
coupling the explicit formulas below are an order of magnitude faster and exact.
"""

from __future__ import annotations

import numpy as np

__all__ = ["det2", "inv2", "negative_count_sym2", "solve2"]


def det2(a: np.ndarray) -> np.ndarray:
    """Determinant of each 2×2 matrix, shape (...)."""
    return a[..., 0, 0] * a[..., 1, 1] - a[..., 0, 1] * a[..., 1, 0]


def inv2(a: np.ndarray) -> np.ndarray:
    """Inverse of each 2×2 matrix, shape (..., 2, 2)."""
    d = det2(a)
    out = np.empty_like(a)
    out[..., 0, 0] = a[..., 1, 1] / d
    out[..., 1, 1] = a[..., 0, 0] / d
    out[..., 0, 1] = -a[..., 0, 1] / d
    out[..., 1, 0] = -a[..., 1, 0] / d
    return out


def solve2(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``inv(a) @ b`` for stacks of 2×2 ``a`` and (..., 2, k) ``b``."""
    return inv2(a) @ b


def negative_count_sym2(a: np.ndarray) -> np.ndarray:
    """Number of negative eigenvalues of each real symmetric 2×2 matrix, shape (...), int.

    Uses Sylvester's criterion: det < 0 → one negative; det > 0 and trace < 0 → two.
    """
    a = a.real
    d = det2(a)
    tr = a[..., 0, 0] + a[..., 1, 1]
    return np.where(d < 0, 1, np.where((d > 0) & (tr < 0), 2, np.where((d == 0) & (tr < 0), 1, 0)))
