"""Frequency-first receptance types.

Conventions (``docs/physics.md`` §2.1, fixed for the whole package)
-------------------------------------------------------------
* One global axis x from the spindle rear to the tool tip.
* Per node two DOFs: lateral displacement ``w`` (m, +y) and section rotation ``psi``
  (rad, counter-clockwise positive, ``psi = dw/dx`` for Euler–Bernoulli); loads ``F`` (N, +y)
  and ``M`` (N·m, counter-clockwise).
* A point receptance is the 2×2 block ``[[h, l], [n, p]]`` with ``h = w/F`` (m/N),
  ``l = w/M`` (m/(N·m) = 1/N), ``n = psi/F`` (rad/N), ``p = psi/M`` (rad/(N·m)).
  Reciprocity gives ``l == n``.
* Time dependence ``exp(i ω t)``: a damped driving-point receptance has ``Im h <= 0``.

Arrays always carry frequency on the first axis: ``(nfreq,)`` for the grid,
``(nfreq, 2, 2)`` for a point receptance.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rcsa.errors import InputError
from rcsa.physics.arrays import ComplexArray, FloatArray

__all__ = ["Receptance", "check_frequency_hz"]


def check_frequency_hz(frequency_hz: object, field: str = "frequency_hz") -> FloatArray:
    """Validate a frequency axis and return it as a read-only float64 array.

    Parameters
    ----------
    frequency_hz : array_like, shape (nfreq,)
        Frequencies in Hz; finite, strictly positive and strictly increasing.
    field : str
        Name used in the error message.

    Returns
    -------
    numpy.ndarray, shape (nfreq,)
    """
    f = np.array(frequency_hz, dtype=float)
    if f.ndim != 1 or f.size == 0:
        raise InputError(field, f"must be a non-empty 1-D list of frequencies, got shape {f.shape}")
    if not np.all(np.isfinite(f)):
        raise InputError(field, "must contain only finite numbers")
    if np.any(f <= 0):
        raise InputError(
            field, "all frequencies must be > 0 Hz (free-free receptances are singular at 0 Hz)"
        )
    if f.size > 1 and np.any(np.diff(f) <= 0):
        raise InputError(field, "frequencies must be strictly increasing")
    f.flags.writeable = False
    return f


def _readonly_complex(values: object, shape_tail: tuple[int, ...], nfreq: int, what: str) -> ComplexArray:
    v = np.array(values, dtype=complex)
    if v.shape != (nfreq, *shape_tail):
        raise InputError(what, f"expected shape {(nfreq, *shape_tail)}, got {v.shape}")
    if not np.all(np.isfinite(v)):
        raise InputError(what, "contains NaN or infinite values")
    v.flags.writeable = False
    return v


@dataclass(frozen=True, slots=True)
class Receptance:
    """Point receptance ``[[h, l], [n, p]]`` at one node over a frequency grid.

    Parameters
    ----------
    frequency_hz : array_like, shape (nfreq,)
        Strictly increasing frequencies > 0, Hz.
    values : array_like, shape (nfreq, 2, 2)
        Complex receptance; units m/N, 1/N, rad/N, rad/(N·m) (see module docstring).
    """

    frequency_hz: FloatArray
    values: ComplexArray

    def __post_init__(self) -> None:
        f = check_frequency_hz(self.frequency_hz)
        object.__setattr__(self, "frequency_hz", f)
        object.__setattr__(self, "values", _readonly_complex(self.values, (2, 2), f.size, "values"))

    @property
    def omega_rad_s(self) -> FloatArray:
        """Angular frequency, rad/s, shape (nfreq,)."""
        return 2.0 * np.pi * self.frequency_hz

    @property
    def h(self) -> ComplexArray:
        """Displacement per force, m/N, shape (nfreq,)."""
        return self.values[:, 0, 0]

    @property
    def l(self) -> ComplexArray:  # noqa: E743 - the literature's name
        """Displacement per moment, 1/N, shape (nfreq,)."""
        return self.values[:, 0, 1]

    @property
    def n(self) -> ComplexArray:
        """Rotation per force, rad/N, shape (nfreq,)."""
        return self.values[:, 1, 0]

    @property
    def p(self) -> ComplexArray:
        """Rotation per moment, rad/(N·m), shape (nfreq,)."""
        return self.values[:, 1, 1]

    @classmethod
    def from_hlnp(cls, frequency_hz: object, h: object, l: object, n: object, p: object) -> Receptance:  # noqa: E741
        """Build from the four entries, each shape (nfreq,).

        Parameters
        ----------
        frequency_hz : array_like, shape (nfreq,)
            Strictly increasing, > 0, Hz.
        h, l, n, p : array_like, shape (nfreq,), complex
            The entries ``[[h, l], [n, p]]``, in m/N, 1/N, rad/N and rad/(N·m).
        """
        f = np.asarray(frequency_hz, dtype=float)
        v = np.empty((f.size, 2, 2), dtype=complex)
        for (i, j), x in zip(((0, 0), (0, 1), (1, 0), (1, 1)), (h, l, n, p), strict=True):
            v[:, i, j] = np.asarray(x, dtype=complex)
        return cls(f, v)
