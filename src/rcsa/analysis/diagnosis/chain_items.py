"""Chain items the diagnosis adds to the model: corrections of a spindle's receptance at its plane.

Both are :class:`rcsa.physics.chain.ChainItem` s without length (frequency-independent,
undamped, eliminating no node), so they sit in a chain like a joint and stack like one:

* :class:`AddedCompliance` — ``R → R + [[0, c_wψ], [c_wψ, c_ψψ]]``: a residual rotational
  compliance, the correction form used to compensate truncated or estimated rotational
  receptances (Duarte & Ewins 2000);
* :class:`RotationRescale` — the rotational entries of the receptance scaled (``l, n × s``,
  ``p × s²·c``): with ``c = 1`` as a change of the effective cantilever length of an
  equivalent-cantilever estimate does (``N = 3H/2L``, ``P = 3H/L²``: ``L → L/s``), and ``c``
  its shape ``PH/N²``.

And one wrapper, :class:`CachedInsertion`: a clamping along the insertion whose two-port is
computed once per frequency grid and kept by value, so the many candidates that change only
what lies before the holder (bearings, the spindle–holder joint, a nose correction) do not
re-evaluate it (they were half of a diagnosis on a ``bonded`` base).

Their parameters may be numbers or per-row arrays (a chain stacked over many variants,
:mod:`rcsa.physics.stacking`).
"""

from __future__ import annotations

from collections.abc import Hashable
from dataclasses import dataclass
from typing import Any

import numpy as np

from rcsa.physics.algebra2x2 import inv2
from rcsa.physics.arrays import ComplexArray, IntArray, RealParam
from rcsa.physics.chain import Grid, Lumped, Sym
from rcsa.physics.insertion import Insertion
from rcsa.physics.subassembly_cache import LruStore

__all__ = ["AddedCompliance", "CachedInsertion", "RotationRescale"]

#: Two-ports kept (each nfreq × 4 × 4 complex: ~0.3 MB at 1 200 lines).
TWO_PORTS_KEPT = 64
_TWO_PORTS: LruStore[Hashable, ComplexArray] = LruStore(TWO_PORTS_KEPT)


def _two_port(insertion: Insertion, omega_rad_s: np.ndarray) -> ComplexArray:
    """The insertion's two-port on ``omega_rad_s``, kept by (insertion, grid) value; read-only."""
    omega = np.asarray(omega_rad_s, dtype=float)
    key = (insertion, omega.size, hash(omega.tobytes()))

    def make() -> ComplexArray:
        d = np.array(insertion.two_port(omega))
        d.flags.writeable = False
        return d
    return _TWO_PORTS.get(key, make)


@dataclass(frozen=True, slots=True)
class CachedInsertion:
    """An :class:`~rcsa.physics.insertion.Insertion` whose two-port is computed once per grid.

    Carries a stiffness across the insertion exactly as the insertion does (``K ← D22 − D21
    (K + D11)⁻¹ D12``, or from a grounded base's compliance ``S``: ``D22 − D21 S (I + D11 S)⁻¹
    D12``), with ``D`` from a cache shared by value; everything else (counts, statics,
    undamped copies, stacking) is the insertion's own.

    Parameters
    ----------
    insertion : Insertion
    """

    insertion: Insertion

    def __getattr__(self, name: str) -> Any:
        return getattr(self.insertion, name)

    def eliminate(self, k: Sym, grid: Grid, count: bool = False) -> tuple[Sym, IntArray | None]:
        """See :meth:`rcsa.physics.insertion.Insertion.eliminate` (with ``count``: the insertion's own).

        Parameters
        ----------
        k : Sym
            Stiffness at the entry node, each (nfreq,).
        grid : Grid
        count : bool
        """
        if count:
            return self.insertion.eliminate(k, grid, count)
        d = _two_port(self.insertion, grid.omega_rad_s)
        p = np.array(d[:, :2, :2], dtype=np.result_type(d, *k))
        p[:, 0, 0] += k[0]
        p[:, 0, 1] += k[1]
        p[:, 1, 0] += k[1]
        p[:, 1, 1] += k[2]
        out = d[:, 2:, 2:] - d[:, 2:, :2] @ inv2(p) @ d[:, :2, 2:]
        return (out[:, 0, 0], 0.5 * (out[:, 0, 1] + out[:, 1, 0]), out[:, 1, 1]), None

    def absorb_compliance(self, compliance: ComplexArray, grid: Grid) -> tuple[ComplexArray, bool]:
        """See :meth:`rcsa.physics.insertion.Insertion.absorb_compliance`.

        Parameters
        ----------
        compliance : numpy.ndarray, shape (nfreq, 2, 2)
        grid : Grid
        """
        d = _two_port(self.insertion, grid.omega_rad_s)
        s = compliance
        return d[:, 2:, 2:] - d[:, 2:, :2] @ s @ inv2(np.eye(2) + d[:, :2, :2] @ s) @ d[:, :2, 2:], True


@dataclass(frozen=True, slots=True)
class AddedCompliance(Lumped):
    """A residual compliance added to the receptance at this node: R → R + [[0, c_wψ], [c_wψ, c_ψψ]].

    ``c_wψ`` in rad/N (= m/(N·m)), ``c_ψψ`` in rad/(N·m). A correction term of the kind used to
    compensate truncated or estimated rotational receptances (Duarte & Ewins 2000), not a spring.

    Parameters
    ----------
    cross_rad_n : float or numpy.ndarray
        ``c_wψ``, rad/N (one value, or one per row).
    rotational_rad_nm : float or numpy.ndarray
        ``c_ψψ``, rad/(N·m).
    """

    cross_rad_n: RealParam
    rotational_rad_nm: RealParam

    def eliminate(self, k: Sym, grid: Grid, count: bool = False) -> tuple[Sym, IntArray | None]:
        """``K ← (K⁻¹ + C)⁻¹`` with ``C = [[0, c_wψ], [c_wψ, c_ψψ]]``; no pivot."""
        k11, k12, k22 = k
        det = k11 * k22 - k12 * k12
        r11, r12, r22 = k22 / det, -k12 / det + self.cross_rad_n, k11 / det + self.rotational_rad_nm
        det_r = r11 * r22 - r12 * r12
        return (r22 / det_r, -r12 / det_r, r11 / det_r), None

    def eliminate_static(self, k: Sym) -> Sym:
        """The same as :meth:`eliminate`: the compliance does not depend on frequency."""
        return self.eliminate(k, Grid(np.zeros(1)))[0]

    def absorb_compliance(self, compliance: ComplexArray, grid: Grid) -> tuple[ComplexArray, bool]:
        """``S ← S + C`` (``S`` shape (nrows, 2, 2))."""
        out = np.array(compliance, dtype=complex)
        out[:, 0, 1] += self.cross_rad_n
        out[:, 1, 0] += self.cross_rad_n
        out[:, 1, 1] += self.rotational_rad_nm
        return out, False

    def undamped(self) -> AddedCompliance:
        """Real already: itself."""
        return self


@dataclass(frozen=True, slots=True)
class RotationRescale(Lumped):
    """The rotational entries of the receptance at this node scaled: l, n × s and p × s²·c.

    With ``c = 1`` this is ``R → D R D``, ``D = diag(1, s)``: for an equivalent-cantilever
    estimate of a measured spindle's rotations (``N = 3H/2L``, ``P = 3H/L²``,
    :func:`rcsa.measured.hybrid.cantilever_rotations`), ``s = L/L'`` turns the estimate with
    length ``L`` into the one with ``L'``; ``c`` changes the estimate's shape ``PH/N²`` (4/3
    for a cantilever). Meant as the first item after a measured base (a rescaling of the
    base's rotations, not a physical part).

    Parameters
    ----------
    scale : float or numpy.ndarray
        ``s`` (> 0), one value or one per row.
    shape : float or numpy.ndarray
        ``c`` (> 0).
    """

    scale: RealParam
    shape: RealParam = 1.0

    def eliminate(self, k: Sym, grid: Grid, count: bool = False) -> tuple[Sym, IntArray | None]:
        """``K ← S'⁻¹`` with ``S = K⁻¹`` rescaled; no pivot."""
        k11, k12, k22 = k
        s, c = self.scale, self.shape
        det = k11 * k22 - k12 * k12
        r11, r12, r22 = k22 / det, -k12 * s / det, k11 * s * s * c / det
        det_r = r11 * r22 - r12 * r12
        return (r22 / det_r, -r12 / det_r, r11 / det_r), None

    def eliminate_static(self, k: Sym) -> Sym:
        """The same as :meth:`eliminate`."""
        return self.eliminate(k, Grid(np.zeros(1)))[0]

    def absorb_compliance(self, compliance: ComplexArray, grid: Grid) -> tuple[ComplexArray, bool]:
        """``l, n × s``, ``p × s² c`` (``S`` shape (nrows, 2, 2))."""
        s = self.scale
        out = np.array(compliance, dtype=complex)
        out[:, 0, 1] *= s
        out[:, 1, 0] *= s
        out[:, 1, 1] *= s * s * self.shape
        return out, False

    def undamped(self) -> RotationRescale:
        """Real already: itself."""
        return self
