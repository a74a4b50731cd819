"""Closed-form operations on stacks of 2×2 matrices, shape (..., 2, 2).

``numpy.linalg`` dispatches one LAPACK call per matrix; for the 2×2 blocks of beam
coupling the explicit formulas below are an order of magnitude faster and exact.
"""

from __future__ import annotations

import numpy as np

from rcsa.physics.arrays import ComplexArray, FloatArray, IntArray

__all__ = ["Pivots", "det2", "inv2", "negative_count_sym"]


def det2(a: ComplexArray) -> ComplexArray:
    """Determinant of each 2×2 matrix, shape (...).

    Parameters
    ----------
    a : numpy.ndarray, shape (..., 2, 2)
        Stacked 2×2 matrices (e.g. receptances over frequency).
    """
    out: ComplexArray = a[..., 0, 0] * a[..., 1, 1] - a[..., 0, 1] * a[..., 1, 0]
    return out


def inv2(a: ComplexArray) -> ComplexArray:
    """Inverse of each 2×2 matrix, shape (..., 2, 2).

    Parameters
    ----------
    a : numpy.ndarray, shape (..., 2, 2)
        Stacked non-singular 2×2 matrices (a singular one gives inf/NaN, not an error).
    """
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


class Pivots:
    """Running Wittrick–Williams count and ``log|det|`` of the pivots eliminated so far.

    By Sylvester's law of inertia the number of negative eigenvalues of a real symmetric
    matrix is the sum of those of the pivots of any block elimination, and its determinant
    is their product; an undamped elimination reports each pivot here.

    Parameters
    ----------
    n : int
        Frequency lines (rows).
    negatives, log_abs_det : numpy.ndarray, optional
        Arrays to accumulate into (e.g. one block's part of a longer count); zeros by default.

    Attributes
    ----------
    negatives : numpy.ndarray of int, shape (n,)
        Negative eigenvalues of the pivots so far.
    log_abs_det : numpy.ndarray, shape (n,)
        Sum of ``log|det P|`` over the pivots so far.
    det_known : bool
        False once an item reported a count without its determinant.
    """

    __slots__ = ("_work", "det_known", "log_abs_det", "negatives")

    def __init__(self, n: int, negatives: IntArray | None = None, log_abs_det: FloatArray | None = None) -> None:
        self.negatives: IntArray = np.zeros(n, dtype=np.int64) if negatives is None else negatives
        self.log_abs_det: FloatArray = np.zeros(n) if log_abs_det is None else log_abs_det
        self.det_known = True
        self._work = np.empty(n), np.empty(n, dtype=bool), np.empty(n, dtype=bool)

    def block(self, start: int, stop: int) -> Pivots:
        """The accumulator of rows ``start:stop``, adding into this one's arrays.

        Parameters
        ----------
        start, stop : int
            The rows, ``start:stop``.
        """
        return Pivots(stop - start, self.negatives[start:stop], self.log_abs_det[start:stop])

    def add_sym(self, p11: FloatArray, p22: FloatArray, det: FloatArray) -> None:
        """A symmetric 2×2 pivot given by its diagonal and determinant ``p11 p22 − p12²``.

        Its inertia is that of ``p11`` and of the Schur complement ``det/p11``: negatives
        ``[p11 < 0] + [det < 0 ≠ p11 < 0]``. (``p11 = 0``: one negative if det < 0; the
        measure-zero case ``p11 = det = 0`` counts none.) A zero ``det`` enters the log as
        1e-300.

        Parameters
        ----------
        p11, p22 : numpy.ndarray, shape (nrows,)
            Diagonal of the pivot.
        det : numpy.ndarray, shape (nrows,)
            Its determinant ``p11 p22 − p12²``.
        """
        t, f1, f2 = self._work
        np.less(p11, 0.0, out=f1)
        np.less(det, 0.0, out=f2)
        np.not_equal(f1, f2, out=f2)
        np.add(self.negatives, f1, out=self.negatives)
        np.add(self.negatives, f2, out=self.negatives)
        np.abs(det, out=t)
        np.maximum(t, 1e-300, out=t)
        np.log(t, out=t)
        np.add(self.log_abs_det, t, out=self.log_abs_det)

    def add_scalar(self, p: FloatArray, multiplicity: int = 1) -> None:
        """A 1×1 pivot ``p`` (``multiplicity`` equal ones).

        Parameters
        ----------
        p : numpy.ndarray, shape (nrows,)
            The pivot.
        multiplicity : int
            How many equal pivots it stands for.
        """
        t, flag, _ = self._work
        np.less(p, 0.0, out=flag)
        if multiplicity == 1:
            np.add(self.negatives, flag, out=self.negatives)
        else:
            np.add(self.negatives, flag.astype(np.int64) * multiplicity, out=self.negatives)
        np.abs(p, out=t)
        np.maximum(t, 1e-300, out=t)
        np.log(t, out=t)
        if multiplicity != 1:
            np.multiply(t, multiplicity, out=t)
        np.add(self.log_abs_det, t, out=self.log_abs_det)

    def add_negatives(self, negatives: IntArray) -> None:
        """A count from an item that does not report its pivot's determinant.

        Parameters
        ----------
        negatives : numpy.ndarray of int, shape (nrows,)
            Negative pivots the item eliminated, per row.
        """
        np.add(self.negatives, negatives, out=self.negatives)
        self.det_known = False
