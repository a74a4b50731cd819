"""Elementwise kernels on preallocated arrays: work buffers, versine and sine, square roots.

The solvers run a few hundred elementwise operations per chain item on arrays of a few
thousand frequency lines. Fresh temporaries for each of them cost more than the arithmetic
(each new array is new memory the kernel must map), so the hot paths write into named work
arrays of a :class:`Scratch` with ``out=``, reused across items and frequency blocks.

Two elementary functions are cheaper here than numpy's own:

* :func:`vers_sin` gives ``1 − cos x`` and ``sin x`` of real ``x`` from one vectorised
  tangent of the half angle (numpy's float64 ``cos``/``sin`` are scalar libm calls, its
  ``tan`` is SIMD), and the versine keeps full relative precision where ``cos x ≈ 1`` —
  which the segment formulas need at low frequency (:mod:`rcsa.physics.segments`).
* :func:`sqrt_any` gives *a* square root of complex ``z`` (the segment formulas are even in
  the root) from real operations, and ``|z|`` with it.
"""

from __future__ import annotations

import math
import threading

import numpy as np

from rcsa.physics.arrays import ComplexArray, FloatArray

__all__ = ["WORK", "Scratch", "Shape", "local_scratch", "sqrt_any", "vers_sin"]

#: Names of the work arrays of one stage of a step, free when the stage ends (the wave
#: functions' temporaries, then the six terms', then the elimination step's): reusing them
#: keeps the working set of a frequency block small.
WORK = ("f.x", "f.y", "f.vx", "f.sx", "f.w", "f.t", "vsn", "vsh", "vst", "w.9", "w.10", "w.11")

# π/2 split for Cody–Waite reduction (fdlibm's pio2_1, pio2_1t): the high part has 33
# significant bits, so n·_PIO2_HI is exact for |n| < 2^20.
_PIO2_HI = 1.57079632673412561417e00
_PIO2_LO = 6.07710050650619224932e-11
_INV_PI = 1.0 / np.pi
#: Largest |x| reduced by the two-part π/2 (beyond it numpy's cos/sin are used).
_MAX_REDUCED = 1.0e5


Shape = int | tuple[int, ...]


class Scratch:
    """Named work arrays of a solve, reused across the items and frequency blocks.

    ``real(name, shape)`` / ``complex(name, shape)`` return a contiguous array of that
    shape called ``name`` (``real2``/``complex2``: with a leading axis of 2, one row per
    wavenumber), allocating or enlarging the storage on first use. A name is one piece of
    memory whatever the dtype and shape asked for (so the temporaries of consecutive stages
    can share it, keeping the working set in cache) and holds one value at a time: a caller
    owns the names it writes until it hands the result on.
    """

    __slots__ = ("_arrays", "_sets", "_views")

    def __init__(self) -> None:
        self._arrays: dict[str, np.ndarray] = {}
        self._views: dict[tuple[str, Shape, type], np.ndarray] = {}
        self._sets: dict[tuple[tuple[str, ...], Shape, bool], tuple[np.ndarray, ...]] = {}

    def _get(self, name: str, shape: Shape, dtype: type) -> np.ndarray:
        key = (name, shape, dtype)
        view = self._views.get(key)
        if view is not None:
            return view
        size = shape if isinstance(shape, int) else math.prod(shape)
        floats = 2 * size if dtype is complex else size
        a = self._arrays.get(name)
        if a is None or a.size < floats:  # (views of the old storage stay valid for their shapes)
            a = self._arrays[name] = np.empty(max(floats, 2 * (0 if a is None else a.size)))
        view = self._views[key] = a[:floats].view(dtype).reshape(shape)
        return view

    def many(self, names: tuple[str, ...], shape: Shape, real: bool) -> tuple[np.ndarray, ...]:
        """The work arrays ``names`` at once (one lookup when used again).

        Parameters
        ----------
        names : tuple of str
            Names of the arrays.
        shape : int or tuple of int
            Their common shape.
        real : bool
            Real (float64) arrays, else complex.
        """
        key = (names, shape, real)
        hit = self._sets.get(key)
        if hit is None:
            get = self.real if real else self.complex
            hit = self._sets[key] = tuple(get(name, shape) for name in names)
        return hit

    def real(self, name: str, shape: Shape) -> FloatArray:
        """Real work array of the given shape.

        Parameters
        ----------
        name : str
            Name of the array in this scratch (one storage per name).
        shape : int or tuple of int
            Its shape.
        """
        return self._get(name, shape, float)

    def complex(self, name: str, shape: Shape) -> ComplexArray:
        """Complex work array of the given shape (the same storage as the real array of that name).

        Parameters
        ----------
        name : str
            Name of the array in this scratch (one storage per name).
        shape : int or tuple of int
            Its shape.
        """
        return self._get(name, shape, complex)

    def real2(self, name: str, shape: Shape) -> FloatArray:
        """Real work array of shape ``(2, *shape)`` (one row per wavenumber).

        Parameters
        ----------
        name : str
            Name of the array in this scratch (one storage per name).
        shape : int or tuple of int
            Its shape. (without the leading 2).
        """
        return self._get(name, (2, shape) if isinstance(shape, int) else (2, *shape), float)

    def complex2(self, name: str, shape: Shape) -> ComplexArray:
        """Complex work array of shape ``(2, *shape)`` (one row per wavenumber).

        Parameters
        ----------
        name : str
            Name of the array in this scratch (one storage per name).
        shape : int or tuple of int
            Its shape. (without the leading 2).
        """
        return self._get(name, (2, shape) if isinstance(shape, int) else (2, *shape), complex)


_LOCAL = threading.local()


def local_scratch(purpose: str = "solve") -> Scratch:
    """This thread's reusable :class:`Scratch` for ``purpose`` (its arrays are mapped once, not per solve).

    For solvers that are done with it when they return (:func:`rcsa.physics.elimination.march`
    uses ``"solve"``; a solver that may run while another is under way picks its own
    ``purpose``); threads (the service's workers) each have their own.

    Parameters
    ----------
    purpose : str
        Which of this thread's scratches (one per purpose).
    """
    pool: dict[str, Scratch] | None = getattr(_LOCAL, "pool", None)
    if pool is None:
        pool = _LOCAL.pool = {}
    sc = pool.get(purpose)
    if sc is None:
        sc = pool[purpose] = Scratch()
    return sc


def vers_sin(x: FloatArray, vers: FloatArray, sin: FloatArray, scratch: Scratch, tag: str = "vs") -> None:
    """``vers = 1 − cos x`` and ``sin = sin x`` of real ``x``, written into the given arrays.

    With ``n`` the integer nearest ``x/π`` and ``h = x/2 − nπ/2`` (|h| ≤ π/4, Cody–Waite
    two-part reduction), ``τ = tan h`` and ``σ = (−1)^n``::

        sin x = 2στ / (1 + τ²)
        1 − cos x = 2τ² / (1 + τ²)       (n even: no cancellation near x = 2πm)
                  = 2 / (1 + τ²)         (n odd)

    Absolute error a few 1e-16, relative error of ``sin`` and ``vers`` a few ulps (``cos``
    itself, ``1 − vers``, has the absolute precision its argument allows). Beyond
    ``|x| = 1e5`` numpy's ``cos``/``sin`` are used.

    Parameters
    ----------
    x : numpy.ndarray
        Angles, rad; any shape.
    vers, sin : numpy.ndarray
        Outputs, the shape of ``x`` (not ``x`` itself).
    scratch : Scratch
    tag : str
        Prefix of the work arrays used (callers nesting this function pick distinct tags).
    """
    shape = x.shape
    n = scratch.real(tag + "n", shape)
    h = scratch.real(tag + "h", shape)
    t = scratch.real(tag + "t", shape)
    if x.size and max(float(x.max()), -float(x.min())) > _MAX_REDUCED:
        np.cos(x, out=vers)
        np.subtract(1.0, vers, out=vers)
        np.sin(x, out=sin)
        return
    np.multiply(x, _INV_PI, out=n)
    np.rint(n, out=n)
    np.multiply(x, 0.5, out=h)
    np.multiply(n, _PIO2_HI, out=sin)
    np.subtract(h, sin, out=h)
    np.multiply(n, _PIO2_LO, out=sin)
    np.subtract(h, sin, out=h)
    np.tan(h, out=h)                               # τ
    np.multiply(n, 0.5, out=t)
    np.rint(t, out=t)
    np.multiply(t, 2.0, out=t)
    np.subtract(n, t, out=n)
    np.abs(n, out=n)                               # 1 for odd n, else 0
    np.multiply(h, h, out=vers)                    # τ²
    np.add(vers, 1.0, out=sin)                     # 1 + τ²
    np.subtract(1.0, vers, out=t)
    np.multiply(t, n, out=t)
    np.add(vers, t, out=vers)                      # τ² (n even) or 1 (n odd)
    np.divide(vers, sin, out=vers)
    np.multiply(vers, 2.0, out=vers)
    np.multiply(n, -2.0, out=n)
    np.add(n, 1.0, out=n)                          # σ
    np.divide(n, sin, out=sin)
    np.multiply(sin, h, out=sin)
    np.multiply(sin, 2.0, out=sin)


def sqrt_any(z: ComplexArray, out: ComplexArray, modulus: FloatArray, scratch: Scratch, tag: str = "sq") -> None:
    """A square root of each complex ``z`` (not always the principal one), and ``|z|``.

    With ``u = √((|z| + |Re z|)/2)`` and ``v = Im z / (2u)``, ``(u + iv)² = |Re z| + i Im z``:
    the root is ``u + iv`` for Re z ≥ 0 and ``i(u − iv) = v + iu`` for Re z < 0, both free of
    cancellation. For functions even in the root (``cos(kL)``, ``sin(kL)/k``) the branch does
    not matter. ``u`` is kept ≥ 1e-150, so ``z = 0`` gives the root 1e-150 (whose use in
    ``sin(kL)/k`` etc. gives the exact limits) instead of 0/0.

    Parameters
    ----------
    z : numpy.ndarray, complex
    out : numpy.ndarray, complex
        The root, shape of ``z``.
    modulus : numpy.ndarray, real
        ``|z|``, shape of ``z``.
    scratch : Scratch
    tag : str
        Prefix of the work arrays used.
    """
    shape = z.shape
    u = scratch.real(tag + "u", shape)
    v = scratch.real(tag + "v", shape)
    left = scratch.real(tag + "l", shape)
    np.abs(z, out=modulus)
    np.abs(z.real, out=u)
    np.add(u, modulus, out=u)
    np.multiply(u, 0.5, out=u)
    np.sqrt(u, out=u)
    np.maximum(u, 1e-150, out=u)
    np.divide(z.imag, u, out=v)
    np.multiply(v, 0.5, out=v)
    np.less(z.real, 0.0, out=left)                     # 1 where Re z < 0
    np.subtract(v, u, out=out.imag)
    np.multiply(out.imag, left, out=left)              # (v − u) where Re z < 0, else 0
    np.add(u, left, out=out.real)
    np.subtract(v, left, out=out.imag)
