"""Closed-form operations on stacks of 2×2 matrices, shape (..., 2, 2).

``numpy.linalg`` dispatches one LAPACK call per matrix; for the 2×2 blocks of beam
coupling the explicit formulas below are an order of magnitude faster and exact.
"""

from __future__ import annotations

import numpy as np

from rcsa.physics.arrays import ComplexArray, FloatArray, IntArray

__all__ = ["det2", "inv2", "negative_count_sym", "negative_count_sym2"]


def det2(a: ComplexArray) -> ComplexArray:
    """Determinant of each 2×2 matrix, shape (...)."""
    out: ComplexArray = a[..., 0, 0] * a[..., 1, 1] - a[..., 0, 1] * a[..., 1, 0]
    return out


def inv2(a: ComplexArray) -> ComplexArray:
    """Inverse of each 2×2 matrix, shape (..., 2, 2)."""
    d = det2(a)
    out = np.empty_like(a)
    out[..., 0, 0] = a[..., 1, 1] / d
    out[..., 1, 1] = a[..., 0, 0] / d
    out[..., 0, 1] = -a[..., 0, 1] / d
    out[..., 1, 0] = -a[..., 1, 0] / d
    return out


def negative_count_sym(a11: ComplexArray | FloatArray, a12: ComplexArray | FloatArray,
                       a22: ComplexArray | FloatArray) -> IntArray:
    """Negative eigenvalues of real symmetric 2×2 matrices given by their entries, int.

    Sylvester's criterion: det < 0 → one negative; det > 0 and trace < 0 → two; det = 0 and
    trace < 0 → one (the other eigenvalue is zero). Imaginary parts are ignored.

    Parameters
    ----------
    a11, a12, a22 : numpy.ndarray, shape (...)
        Entries ``[[a11, a12], [a12, a22]]``, broadcast together.
    """
    a11, a12, a22 = np.real(a11), np.real(a12), np.real(a22)
    d = a11 * a22 - a12 * a12
    tr = a11 + a22
    return np.where(d < 0, 1, np.where(tr < 0, np.where(d > 0, 2, 1), 0))


def negative_count_sym2(a: ComplexArray | FloatArray) -> IntArray:
    """Number of negative eigenvalues of each real symmetric 2×2 matrix, shape (...), int."""
    return negative_count_sym(a[..., 0, 0], a[..., 0, 1], a[..., 1, 1])
