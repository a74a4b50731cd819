"""A spindle–holder–tool assembly as a chain of beams, joints and grounded attachments.

The assembly is one line of nodes along the global axis (spindle rear → tool tip,
``domain.md`` §2.1). Between consecutive nodes sits a :class:`Beam` (uniform Timoshenko
segment) or a :class:`Spring` (an elastic joint of zero length); a :class:`Ground` adds a
spring/damper to rigid ground and/or a lumped mass at the current node (bearings,
sensors). A chain is a plain tuple of these immutable items, so sub-chains can be shared
and cached (the spindle and holder are reused across tools).

Every item owns what the solvers do with it (like ROSS elements owning their matrices), so
the solvers (:mod:`rcsa.physics.elimination`, :mod:`rcsa.physics.natural_frequencies`,
:mod:`rcsa.physics.stacking`) never ask an item for its type. The protocol
(:class:`ChainItem`):

* :meth:`~ChainItem.eliminate` — its dynamic elimination step on the carried symmetric
  stiffness ``K`` "seen from the right" (:data:`Sym`), and the negative eigenvalues of its
  pivot for the Wittrick–Williams count;
* :meth:`~ChainItem.eliminate_static` — the same step at ω = 0, undamped;
* :meth:`~ChainItem.absorb_compliance` — the step on a grounded base known only as a
  receptance (a measured spindle), which is never inverted;
* :meth:`~ChainItem.undamped`, :meth:`~ChainItem.subdivided`,
  :meth:`~ChainItem.map_sections` — transformed copies;
* :meth:`~ChainItem.signature`, :meth:`~ChainItem.stack`, :meth:`~ChainItem.take_rows`,
  :attr:`~ChainItem.is_stacked` — many tools stacked into one chain with per-row parameters.

The elimination steps, with ``D = [[D11, D12], [D21, D22]]`` a beam's dynamic stiffness::

    beam   P = K + D11;   K ← D22 − D21 P⁻¹ D12
    spring P = K + K_j;   K ← K_j − K_j P⁻¹ K_j      (rigid DOFs shared, not penalised)
    ground K ← K + Δ
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, fields, replace
from typing import Any, Protocol, Self, TypeAlias

import numpy as np

from rcsa.physics.algebra2x2 import inv2, negative_count_sym
from rcsa.physics.arrays import ComplexArray, FloatArray, IntArray, RealParam
from rcsa.physics.sections import Section
from rcsa.physics.segments import (
    SixTerms,
    Waves,
    segment_terms,
    static_stiffness,
)

__all__ = ["Beam", "Chain", "ChainItem", "Grid", "Ground", "Lumped", "Spring", "Sym", "beam_step", "joint_step",
           "undamped"]

#: A symmetric 2×2 stiffness carried as its three entries ``(k11, k12, k22)``, each shape (nfreq,),
#: complex; units N/m, N/rad, N·m/rad.
Sym: TypeAlias = tuple[ComplexArray, ComplexArray, ComplexArray]

_EYE = np.eye(2)


class Grid:
    """The frequency grid of one elimination and what its steps share on it.

    By default the wavenumbers of a section (:class:`rcsa.physics.segments.Waves`) are
    shared by the beams of equal sections; a solver that runs many eliminations on one grid
    may subclass it to cache more (the diagnosis caches the terms of each beam).

    Parameters
    ----------
    omega_rad_s : numpy.ndarray, shape (nfreq,)
        Angular frequencies, rad/s.
    """

    def __init__(self, omega_rad_s: FloatArray) -> None:
        self.omega_rad_s: FloatArray = np.asarray(omega_rad_s, dtype=float)
        self._waves: dict[Section, Waves] = {}

    def waves(self, section: Section) -> Waves:
        """Wavenumbers of ``section``, shared by equal sections; stacked (array) sections are not cached."""
        try:
            hit = self._waves.get(section)
        except TypeError:  # unhashable: a section stacked over several tools
            return Waves(self.omega_rad_s, section)
        if hit is None:
            hit = self._waves[section] = Waves(self.omega_rad_s, section)
        return hit

    def beam_terms(self, beam: Beam) -> SixTerms:
        """Six-term dynamic stiffness of ``beam`` on this grid (:func:`rcsa.physics.segments.segment_terms`)."""
        return segment_terms(self.omega_rad_s, beam.section, beam.length_m, self.waves(beam.section))


def beam_step(k: Sym, terms: SixTerms) -> tuple[Sym, Sym]:
    """Condense the node before a beam: ``P = K + D11``; ``K ← D22 − D21 P⁻¹ D12``.

    Parameters
    ----------
    k : Sym
        Stiffness carried onto the beam's first node.
    terms : SixTerms
        The beam's six-term dynamic stiffness (:func:`rcsa.physics.segments.stiffness_terms`).

    Returns
    -------
    k : Sym
        Stiffness at the beam's second node.
    pivot : Sym
        ``P`` (its negative eigenvalues enter the Wittrick–Williams count).
    """
    a, b, c, e, f, g = terms
    p11, p12, p22 = k[0] + a, k[1] + b, k[2] + c
    inv_det = 1.0 / (p11 * p22 - p12 * p12)
    x11 = (p22 * e + p12 * f) * inv_det
    x12 = (p22 * f - p12 * g) * inv_det
    x21 = -(p12 * e + p11 * f) * inv_det
    x22 = (p11 * g - p12 * f) * inv_det
    return (a - (e * x11 - f * x21), -b - (e * x12 - f * x22), c - (f * x12 + g * x22)), (p11, p12, p22)


def joint_step(k: Sym, kt: ComplexArray | None, kr: ComplexArray | None, count: bool = False
               ) -> tuple[Sym, IntArray | None]:
    """Condense across an elastic joint ``diag(k_t, k_r)``; a ``None`` DOF is rigid (shared, not penalised).

    ``K ← (K⁻¹ + K_j⁻¹)⁻¹``, written as ``K_j P⁻¹ K`` (``P = K + K_j``) so stiff joints cancel nothing.

    Parameters
    ----------
    k : Sym
        Stiffness carried onto the joint's first node.
    kt, kr : numpy.ndarray, shape (nfreq,), complex, or None
        Translational (N/m) and rotational (N·m/rad) joint stiffness; ``None`` = rigid.
    count : bool
        Also return the negative eigenvalues of the pivot (undamped chains).

    Returns
    -------
    k : Sym
    negatives : numpy.ndarray of int, shape (nfreq,), or None
        ``None`` unless ``count`` (or when the joint is rigid: no pivot).
    """
    k11, k12, k22 = k
    if kt is None and kr is None:
        return k, None
    if kt is not None and kr is not None:
        p11, p12, p22 = k11 + kt, k12, k22 + kr
        inv_det = 1.0 / (p11 * p22 - p12 * p12)
        det_k = k11 * k22 - k12 * k12
        out = (kt * (det_k + kr * k11) * inv_det, kt * kr * k12 * inv_det, kr * (det_k + kt * k22) * inv_det)
        return out, negative_count_sym(p11, p12, p22) if count else None
    if kt is not None:  # rotation rigid: eliminate the old node's w only
        p = k11 + kt
        out = (kt * k11 / p, kt * k12 / p, k22 - k12 * k12 / p)
    else:  # translation rigid: eliminate the old node's ψ only
        assert kr is not None
        p = k22 + kr
        out = (k11 - k12 * k12 / p, kr * k12 / p, kr * k22 / p)
    return out, (p.real < 0).astype(int) if count else None


def _row(value: Any, rows: IntArray) -> Any:
    """``value[rows]`` for a per-row array; scalars and ``None`` are kept as they are."""
    return value if value is None or np.ndim(value) == 0 else np.asarray(value)[rows]


class ChainItem(Protocol):
    """What every item of a chain provides to the solvers (see the module docstring)."""

    def eliminate(self, k: Sym, grid: Grid, count: bool = False) -> tuple[Sym, IntArray | None]:
        """Carry the stiffness ``k`` across this item on ``grid``.

        Returns the new stiffness and, with ``count``, the number of negative eigenvalues of
        the eliminated pivot per frequency (``None`` when the item eliminates no node).
        """
        ...

    def eliminate_static(self, k: Sym) -> Sym:
        """:meth:`eliminate` at ω = 0 without damping (arrays of shape (1,))."""
        ...

    def absorb_compliance(self, compliance: ComplexArray, grid: Grid) -> tuple[ComplexArray, bool]:
        """Attach this item to a grounded base given by its receptance ``S``, shape (nfreq, 2, 2).

        Returns the new base receptance (``False``), or — for an item that eliminates the
        base's node, a beam — the dynamic stiffness at its far end (``True``).
        """
        ...

    def undamped(self) -> Self:
        """The item with every damper removed and real moduli."""
        ...

    def subdivided(self, omega_max_rad_s: float) -> tuple[ChainItem, ...]:
        """Equal pieces with no clamped–clamped natural frequency below ω_max (rad/s)."""
        ...

    def map_sections(self, fn: Callable[[Section], Section]) -> Self:
        """The item with ``fn`` applied to its cross-sections (if it has any)."""
        ...

    def signature(self) -> tuple[object, ...]:
        """Structure of the item: items with equal signatures stack."""
        ...

    def stack(self, items: Sequence[Self]) -> Self:
        """One item whose parameters are arrays over ``items`` (equal signatures; ``self`` is ``items[0]``)."""
        ...

    def take_rows(self, rows: IntArray) -> Self:
        """A stacked item with its parameter arrays indexed by ``rows`` (scalars kept)."""
        ...

    @property
    def is_stacked(self) -> bool:
        """True when some parameter is an array (one value per row)."""
        ...


Chain: TypeAlias = tuple[ChainItem, ...]


@dataclass(frozen=True, slots=True)
class Beam:
    """A uniform segment between two nodes.

    Parameters
    ----------
    section : Section
    length_m : float
        Segment length, m (> 0).
    """

    section: Section
    length_m: RealParam

    def eliminate(self, k: Sym, grid: Grid, count: bool = False) -> tuple[Sym, IntArray | None]:
        """Condense the beam's first node (:func:`beam_step`); the pivot is ``K + D11``."""
        k, pivot = beam_step(k, grid.beam_terms(self))
        return k, negative_count_sym(*pivot) if count else None

    def eliminate_static(self, k: Sym) -> Sym:
        """With the exact static Timoshenko stiffness; ``P = K + D11`` is positive definite."""
        d = static_stiffness(self.section.undamped(), self.length_m)
        a, b, c, e, f, g = (np.array([d[i, j]]) for i, j in ((0, 0), (0, 1), (1, 1), (0, 2), (0, 3), (1, 3)))
        return beam_step(k, (a, b, c, e, f, g))[0]

    def absorb_compliance(self, compliance: ComplexArray, grid: Grid) -> tuple[ComplexArray, bool]:
        """``D22 − D21 S (I + D11 S)⁻¹ D12``: the stiffness at the beam's end, never inverting ``S``.

        ``D`` from the grid's six terms (:meth:`Grid.beam_terms`), so a grid that caches them
        (the diagnosis's) absorbs a measured base without recomputing the beam.
        """
        a, b, c, e, f, g = grid.beam_terms(self)
        d = np.stack([np.stack(r, axis=-1) for r in ([a, b, e, f], [b, c, -f, g], [e, -f, a, -b], [f, g, -b, c])],
                     axis=-2)
        d11, d12, d21, d22 = d[:, :2, :2], d[:, :2, 2:], d[:, 2:, :2], d[:, 2:, 2:]
        s = compliance
        return d22 - d21 @ s @ inv2(_EYE + d11 @ s) @ d12, True

    def undamped(self) -> Beam:
        """The beam with real moduli."""
        return Beam(self.section.undamped(), self.length_m)

    def max_piece_length_m(self, omega_rad_s: float) -> float:
        """Longest piece of this beam whose first clamped–clamped frequency certainly exceeds ω.

        Rayleigh quotient bound for w = ψ = 0 at both ends, with Wirtinger's inequality
        ‖u‖² ≤ (ℓ/π)² ‖u'‖² on ψ and on w' = γ + ψ (γ the shear strain)::

            ω₁² ≥ min( κGA / (2ρA u),  EI / (2ρA u² + ρI u) ),    u = (ℓ/π)²

        (for Euler–Bernoulli γ = 0 and the bound is EI / (ρA u² + ρI u)). Stacked (array)
        sections give the shortest piece over all entries.

        Parameters
        ----------
        omega_rad_s : float
            Angular frequency, rad/s.

        Returns
        -------
        float
            Length, m.
        """
        s = self.section
        ei = np.real(np.asarray(s.ei))
        ra, ri = np.asarray(s.rho_a, dtype=float), np.asarray(s.rho_i, dtype=float)
        w2 = omega_rad_s**2 * 1.0001
        shear_rigid = s.is_euler_bernoulli
        a = ra if shear_rigid else 2.0 * ra
        u = (-ri + np.sqrt(ri * ri + 4.0 * a * ei / w2)) / (2.0 * a)
        if not shear_rigid:
            u = np.minimum(u, np.real(1.0 / np.asarray(s.shear_flexibility)) / (2.0 * ra * w2))
        return float(np.min(math.pi * np.sqrt(u)))

    def subdivided(self, omega_max_rad_s: float) -> tuple[Beam, ...]:
        """``n`` equal pieces, each shorter than :meth:`max_piece_length_m` at ω_max."""
        n = max(1, math.ceil(float(np.max(self.length_m)) / self.max_piece_length_m(omega_max_rad_s)))
        return (Beam(self.section, self.length_m / n),) * n

    def map_sections(self, fn: Callable[[Section], Section]) -> Beam:
        """The beam with section ``fn(section)``."""
        return Beam(fn(self.section), self.length_m)

    def signature(self) -> tuple[object, ...]:
        """Beams stack with beams."""
        return ("Beam",)

    def stack(self, items: Sequence[Beam]) -> Beam:
        """Sections and lengths as arrays over ``items``."""
        return Beam(Section.stack([i.section for i in items]), np.array([i.length_m for i in items]))

    def take_rows(self, rows: IntArray) -> Beam:
        """Section properties and length indexed by ``rows``."""
        return Beam(self.section.take_rows(rows), _row(self.length_m, rows))

    @property
    def is_stacked(self) -> bool:
        """True when the length is an array (one per row)."""
        return bool(np.ndim(self.length_m) > 0)


class Lumped:
    """Base of the chain items without length (joints, grounds, added compliances).

    Provides the parts of :class:`ChainItem` that follow from having no length and only
    number fields: no subdivision, no sections, and stacking that turns each number field
    into an array (``None`` stays ``None``). A subclass is a frozen dataclass and adds the
    elimination steps, :meth:`~ChainItem.undamped` and, if needed, a finer
    :meth:`~ChainItem.signature`.
    """

    __slots__ = ()

    def subdivided(self, omega_max_rad_s: float) -> tuple[Self, ...]:
        """A lumped item has no natural frequency of its own: itself."""
        return (self,)

    def map_sections(self, fn: Callable[[Section], Section]) -> Self:
        """A lumped item has no section: itself."""
        return self

    def signature(self) -> tuple[object, ...]:
        """Its type name: lumped items of one type stack."""
        return (type(self).__name__,)

    def _values(self) -> dict[str, Any]:
        """The dataclass fields of the subclass, by name."""
        item: Any = self  # a dataclass: every subclass is one
        return {f.name: getattr(self, f.name) for f in fields(item)}

    def stack(self, items: Sequence[Self]) -> Self:
        """Every field as an array over ``items`` (``None`` stays ``None``: equal signatures agree on it)."""
        values = [i._values() for i in items]
        return type(self)(**{name: None if value is None else np.array([v[name] for v in values])
                             for name, value in self._values().items()})

    def take_rows(self, rows: IntArray) -> Self:
        """Every array field indexed by ``rows`` (scalars kept)."""
        return type(self)(**{name: _row(value, rows) for name, value in self._values().items()})

    @property
    def is_stacked(self) -> bool:
        """True when some field is an array (one value per row)."""
        return any(value is not None and np.ndim(value) > 0 for value in self._values().values())


@dataclass(frozen=True, slots=True)
class Spring(Lumped):
    """An elastic joint between two coincident nodes: ``K = diag(k_t + iωc_t, k_r + iωc_r)``.

    ``None`` for a stiffness means that DOF is rigid (the two nodes share it).

    Parameters
    ----------
    stiffness_n_m : float or None
        Translational stiffness k_t, N/m.
    damping_ns_m : float
        Translational viscous damping c_t, N·s/m.
    rotational_stiffness_nm_rad : float or None
        Rotational stiffness k_r, N·m/rad.
    rotational_damping_nms_rad : float
        Rotational viscous damping c_r, N·m·s/rad.
    """

    stiffness_n_m: RealParam | None
    damping_ns_m: RealParam = 0.0
    rotational_stiffness_nm_rad: RealParam | None = None
    rotational_damping_nms_rad: RealParam = 0.0

    def translational(self, omega_rad_s: FloatArray) -> ComplexArray | None:
        """``k_t + iωc_t`` (N/m), shape (nfreq,), or ``None`` if rigid."""
        if self.stiffness_n_m is None:
            return None
        return self.stiffness_n_m + 1j * omega_rad_s * self.damping_ns_m

    def rotational(self, omega_rad_s: FloatArray) -> ComplexArray | None:
        """``k_r + iωc_r`` (N·m/rad), shape (nfreq,), or ``None`` if rigid."""
        if self.rotational_stiffness_nm_rad is None:
            return None
        return self.rotational_stiffness_nm_rad + 1j * omega_rad_s * self.rotational_damping_nms_rad

    def compliance(self, omega_rad_s: FloatArray) -> ComplexArray:
        """Joint compliance ``K⁻¹``, shape (nfreq, 2, 2); zero for rigid DOFs."""
        out = np.zeros((omega_rad_s.size, 2, 2), dtype=complex)
        kt, kr = self.translational(omega_rad_s), self.rotational(omega_rad_s)
        if kt is not None:
            out[:, 0, 0] = 1.0 / kt
        if kr is not None:
            out[:, 1, 1] = 1.0 / kr
        return out

    def eliminate(self, k: Sym, grid: Grid, count: bool = False) -> tuple[Sym, IntArray | None]:
        """Condense across the joint (:func:`joint_step`)."""
        w = grid.omega_rad_s
        return joint_step(k, self.translational(w), self.rotational(w), count)

    def eliminate_static(self, k: Sym) -> Sym:
        """Across the joint's static stiffness."""
        w0 = np.zeros(1)
        stiff = self.undamped()
        return joint_step(k, stiff.translational(w0), stiff.rotational(w0))[0]

    def absorb_compliance(self, compliance: ComplexArray, grid: Grid) -> tuple[ComplexArray, bool]:
        """A joint adds its compliance to the base's."""
        return compliance + self.compliance(grid.omega_rad_s), False

    def undamped(self) -> Spring:
        """The joint without dampers."""
        return replace(self, damping_ns_m=0.0, rotational_damping_nms_rad=0.0)

    def signature(self) -> tuple[object, ...]:
        """Joints stack when the same DOFs are rigid."""
        return ("spring", self.stiffness_n_m is None, self.rotational_stiffness_nm_rad is None)


@dataclass(frozen=True, slots=True)
class Ground(Lumped):
    """Grounded spring/damper and lumped mass at the current node.

    Its dynamic stiffness is ``diag(k_t + iωc_t − ω²m, k_r + iωc_r − ω²J)``.

    Parameters
    ----------
    stiffness_n_m, damping_ns_m : float
        Translational spring to ground (N/m) and damper (N·s/m).
    rotational_stiffness_nm_rad, rotational_damping_nms_rad : float
        Rotational spring (N·m/rad) and damper (N·m·s/rad).
    mass_kg : float
        Lumped mass, kg.
    rotary_inertia_kg_m2 : float
        Lumped rotary inertia about the bending axis, kg·m².
    """

    stiffness_n_m: RealParam = 0.0
    damping_ns_m: RealParam = 0.0
    rotational_stiffness_nm_rad: RealParam = 0.0
    rotational_damping_nms_rad: RealParam = 0.0
    mass_kg: RealParam = 0.0
    rotary_inertia_kg_m2: RealParam = 0.0

    def stiffness(self, omega_rad_s: FloatArray) -> ComplexArray:
        """Dynamic stiffness, shape (nfreq, 2, 2)."""
        w = omega_rad_s
        out = np.zeros((w.size, 2, 2), dtype=complex)
        out[:, 0, 0] = self.stiffness_n_m + 1j * w * self.damping_ns_m - w**2 * self.mass_kg
        out[:, 1, 1] = (self.rotational_stiffness_nm_rad + 1j * w * self.rotational_damping_nms_rad
                        - w**2 * self.rotary_inertia_kg_m2)
        return out

    def eliminate(self, k: Sym, grid: Grid, count: bool = False) -> tuple[Sym, IntArray | None]:
        """``K ← K + Δ``: no node is eliminated, so no pivot."""
        g = self.stiffness(grid.omega_rad_s)
        return (k[0] + g[:, 0, 0], k[1], k[2] + g[:, 1, 1]), None

    def eliminate_static(self, k: Sym) -> Sym:
        """``K ← K + diag(k_t, k_r)``."""
        return k[0] + self.stiffness_n_m, k[1], k[2] + self.rotational_stiffness_nm_rad

    def absorb_compliance(self, compliance: ComplexArray, grid: Grid) -> tuple[ComplexArray, bool]:
        """``S (I + Δ S)⁻¹``."""
        s = compliance
        return s @ inv2(_EYE + self.stiffness(grid.omega_rad_s) @ s), False

    def undamped(self) -> Ground:
        """The attachment without dampers."""
        return replace(self, damping_ns_m=0.0, rotational_damping_nms_rad=0.0)


def undamped(chain: Chain) -> Chain:
    """The chain with every damper removed and real moduli (for natural frequencies)."""
    return tuple(item.undamped() for item in chain)
