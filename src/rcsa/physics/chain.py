"""A spindle–holder–tool assembly as a chain of beams, joints and grounded attachments.

The assembly is one line of nodes along the global axis (spindle rear → tool tip,
``docs/physics.md`` §2.1). Between consecutive nodes sits a :class:`Beam` (uniform Timoshenko
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

from rcsa.physics.algebra2x2 import Pivots, inv2, negative_count_sym
from rcsa.physics.arrays import ComplexArray, FloatArray, IntArray, RealParam
from rcsa.physics.elementwise import WORK, Scratch, local_scratch
from rcsa.physics.sections import Section
from rcsa.physics.segments import (
    MAX_DECAY_PER_PIECE,
    RealTerms,
    RealWaves,
    SixTerms,
    Waves,
    double,
    segment_terms,
    six_terms,
    static_terms,
    undamped_segment_terms,
)

__all__ = ["Beam", "Chain", "ChainItem", "Grid", "Ground", "Lumped", "Spring", "Sym", "Tiling", "beam_step",
           "joint_step", "undamped"]

#: A symmetric 2×2 stiffness carried as its three entries ``(k11, k12, k22)``, each shape (nfreq,),
#: complex; units N/m, N/rad, N·m/rad.
Sym: TypeAlias = tuple[ComplexArray, ComplexArray, ComplexArray]

_EYE = np.eye(2)


class Grid:
    """The frequency grid of one elimination and what its steps share on it.

    The wavenumbers of a section (:class:`rcsa.physics.segments.Waves`) are shared by the
    beams of equal sections, the terms of a beam by consecutive repeats of it (the equal
    pieces of a subdivided beam), and the work arrays (:class:`Scratch`) by every step and
    frequency block of one solve. A solver that runs many eliminations on one grid may
    subclass it to cache more (the diagnosis caches the terms of each beam).

    Parameters
    ----------
    omega_rad_s : numpy.ndarray, shape (nfreq,)
        Angular frequencies, rad/s.
    scratch : Scratch, optional
        Work arrays to use (shared by the blocks of one solve); fresh ones by default.
    pivots : Pivots, optional
        Given, the undamped steps (:meth:`ChainItem.eliminate_undamped`) report the pivots
        they eliminate to it (Wittrick–Williams count and determinant).
    tiling : Tiling, optional
        When the lines are one grid repeated (tools × lines of a stacked solve), the waves
        of a section shared by all rows are computed on the grid once and repeated.

    Attributes
    ----------
    omega_rad_s : numpy.ndarray, shape (nfreq,)
    scratch : Scratch
    pivots : Pivots or None
    """

    def __init__(self, omega_rad_s: FloatArray, scratch: Scratch | None = None, pivots: Pivots | None = None,
                 tiling: Tiling | None = None) -> None:
        self.omega_rad_s: FloatArray = np.asarray(omega_rad_s, dtype=float)
        self._tiling = tiling
        self.scratch = Scratch() if scratch is None else scratch
        self.pivots = pivots
        self._waves: dict[Section, Waves] = {}
        self._real_waves: dict[Section, RealWaves] = {}
        self._last: tuple[object, SixTerms | RealTerms | None] = (None, None)
        self._carry = 0
        self._expected: dict[int, Beam] = {}
        self._table: tuple[bool, dict[int, int], SixTerms | RealTerms] | None = None

    def expect(self, beam: Beam) -> None:
        """Announce that ``beam`` will ask for its terms (:meth:`ChainItem.announce`).

        When the announced beams are few lines each, the first request computes the terms
        of all of them in one vectorised pass (a table with one row per beam): one set of
        array operations instead of one per beam.

        Parameters
        ----------
        beam : Beam
            A beam whose terms will be asked for.
        """
        self._expected[id(beam)] = beam

    def _from_table(self, beam: Beam, real: bool) -> SixTerms | RealTerms | None:
        """The row of ``beam`` in the table of announced beams (computing it on first use), or None."""
        if self._table is None or self._table[0] != real:
            n_beams, n = len(self._expected), self.omega_rad_s.size
            if n_beams < 2 or n > _TABLE_LINES or n_beams * n > _TABLE_MAX:
                return None
            self._table = (real, *_terms_table(list(self._expected.values()), self.omega_rad_s, self.scratch,
                                                real, self.pivots))
        row = self._table[1].get(id(beam))
        if row is None:
            return None
        terms = self._table[2]
        return terms[0][row], terms[1][row], terms[2][row], terms[3][row], terms[4][row], terms[5][row]

    def waves(self, section: Section) -> Waves:
        """Wavenumbers of ``section``, shared by the beams of equal sections that follow each other.

        The last two sections are kept (a chain lists the pieces of one section together:
        spindle segments split at bearings, the pieces of a subdivided beam), so the work
        arrays stay few and in cache; stacked (array) sections are not cached.

        Parameters
        ----------
        section : Section
            Cross-section (scalar, or stacked over tools).

        Returns
        -------
        Waves
            Its wavenumbers at every frequency of the grid.
        """
        hit: Waves | None = self._find(self._waves, section)
        if hit is None:
            slot = self._slot(self._waves, section)
            t = self._tiling
            hit = Waves(self.omega_rad_s, section, self.scratch, slot) if t is None or slot == "wv.x." \
                else Waves.tiled(t.waves(section), t.reps, self.scratch, slot)
            if slot != "wv.x.":
                self._waves[section] = hit
        return hit

    def real_waves(self, section: Section) -> RealWaves:
        """:meth:`waves` of an undamped section in real arithmetic (:class:`RealWaves`).

        Parameters
        ----------
        section : Section
            Undamped section.
        """
        hit: RealWaves | None = self._find(self._real_waves, section)
        if hit is None:
            slot = self._slot(self._real_waves, section)
            t = self._tiling
            hit = RealWaves(self.omega_rad_s, section, self.scratch, slot) if t is None or slot == "wv.x." \
                else RealWaves.tiled(t.real_waves(section), t.reps, self.scratch, slot)
            if slot != "wv.x.":
                self._real_waves[section] = hit
        return hit

    @staticmethod
    def _find(cache: dict[Section, Any], section: Section) -> Any:
        try:
            return cache.get(section)
        except TypeError:  # unhashable: a section stacked over several tools
            return None

    @staticmethod
    def _slot(cache: dict[Section, Any], section: Section) -> str:
        """Work-array prefix for a new section's waves: one of two, evicting the older cached one."""
        try:
            hash(section)
        except TypeError:
            return "wv.x."
        if len(cache) >= 2:
            del cache[next(iter(cache))]
        used = {w.slot for w in cache.values()}
        return "wv.a." if "wv.a." not in used else "wv.b."

    def beam_terms(self, beam: Beam) -> SixTerms:
        """Six-term dynamic stiffness of ``beam`` on this grid (:func:`rcsa.physics.segments.segment_terms`).

        The arrays are this grid's work arrays: valid until the next call.

        Parameters
        ----------
        beam : Beam
            The segment.

        Returns
        -------
        SixTerms
            ``(a, b, c, e, f, g)``, each shape (nfreq,) (or (ntools·nfreq,) stacked), complex.
        """
        last, terms = self._last
        if last is beam and terms is not None and not np.isrealobj(terms[0]):
            return terms  # type: ignore[return-value]
        hit = self._from_table(beam, real=False)
        if hit is not None:
            return hit  # type: ignore[return-value]
        sc = self.scratch
        n = self.omega_rad_s.size
        out = (sc.complex("bt.a", n), sc.complex("bt.b", n), sc.complex("bt.c", n), sc.complex("bt.e", n),
               sc.complex("bt.f", n), sc.complex("bt.g", n))
        terms = segment_terms(self.omega_rad_s, beam.section, beam.length_m, self.waves(beam.section),
                              scratch=sc, out=out)
        self._last = (beam, terms)
        return terms

    def undamped_beam_terms(self, beam: Beam) -> RealTerms:
        """Real six-term dynamic stiffness of an undamped ``beam``; reports internal pivots to :attr:`pivots`.

        The arrays are this grid's work arrays: valid until the next call.

        Parameters
        ----------
        beam : Beam
            Undamped beam.
        """
        hit = self._from_table(beam, real=True)
        if hit is not None:
            return hit  # type: ignore[return-value]
        wv = self.real_waves(beam.section)
        last, terms = self._last
        if last is beam and terms is not None and np.isrealobj(terms[0]) and \
                (self.pivots is None or wv.pieces(beam.length_m) == 1):
            return terms  # type: ignore[return-value]
        sc = self.scratch
        n = self.omega_rad_s.size
        out = (sc.real("bt.a", n), sc.real("bt.b", n), sc.real("bt.c", n), sc.real("bt.e", n),
               sc.real("bt.f", n), sc.real("bt.g", n))
        terms = undamped_segment_terms(self.omega_rad_s, beam.section, beam.length_m, wv, scratch=sc, out=out,
                                       pivots=self.pivots)
        self._last = (beam, terms)
        return terms

    def carried(self, real: bool) -> Sym:
        """Work arrays for the stiffness a step carries on; two sets used in turn.

        A step reads the stiffness its predecessor wrote (one set, or fresh arrays from a
        lumped item) and writes the other set, so input and output never overlap.

        Parameters
        ----------
        real : bool
            Real (undamped) arrays, else complex.
        """
        self._carry ^= 1
        k = self.scratch.many(_CARRIED[self._carry], self.omega_rad_s.size, real)
        return k[0], k[1], k[2]


_CARRIED = (("k0.11", "k0.12", "k0.22"), ("k1.11", "k1.12", "k1.22"))

class Tiling:
    """Waves on one grid, for grids that repeat it (:class:`Grid` ``tiling``).

    Parameters
    ----------
    omega_rad_s : numpy.ndarray, shape (nfreq,)
        The repeated grid, rad/s.
    reps : int
        How many times a grid using this repeats it.
    """

    def __init__(self, omega_rad_s: FloatArray, reps: int = 1) -> None:
        self.omega_rad_s, self.reps = omega_rad_s, reps
        self._scratch = Scratch()
        self._waves: dict[Section, Waves] = {}
        self._real: dict[Section, RealWaves] = {}

    def repeated(self, reps: int) -> Tiling:
        """The same waves for a grid repeating this one ``reps`` times.

        Parameters
        ----------
        reps : int
            How many times the new grid repeats this one.
        """
        out = Tiling.__new__(Tiling)
        out.omega_rad_s, out.reps, out._scratch, out._waves, out._real = \
            self.omega_rad_s, reps, self._scratch, self._waves, self._real
        return out

    def waves(self, section: Section) -> Waves:
        """:class:`Waves` of ``section`` on the grid (computed once).

        Parameters
        ----------
        section : Section
        """
        hit = self._waves.get(section)
        if hit is None:
            hit = self._waves[section] = Waves(self.omega_rad_s, section, self._scratch, f"t{len(self._waves)}.")
        return hit

    def real_waves(self, section: Section) -> RealWaves:
        """:class:`RealWaves` of ``section`` on the grid (computed once).

        Parameters
        ----------
        section : Section
            Undamped section.
        """
        hit = self._real.get(section)
        if hit is None:
            hit = self._real[section] = RealWaves(self.omega_rad_s, section, self._scratch, f"r{len(self._real)}.")
        return hit


#: A terms table for at most this many lines (few lines: the per-item overhead dominates) ...
_TABLE_LINES = 512
#: ... and beams × lines (beyond it each beam is computed on its own, its work arrays
#: staying in cache).
_TABLE_MAX = 16384


def _stacked(values: Sequence[Any], n: int) -> np.ndarray:
    """Parameters of several beams as a column (one value each) or a matrix (one per line each)."""
    if all(np.ndim(v) == 0 for v in values):
        return np.array(values)[:, None]
    return np.stack([np.broadcast_to(v, (n,)) for v in values])


def _terms_table(beams: list[Beam], omega_rad_s: FloatArray, scratch: Scratch, real: bool,
                 pivots: Pivots | None) -> tuple[dict[int, int], SixTerms | RealTerms]:
    """Six terms of several beams at once, shape (nbeams, nfreq) each, and each beam's row.

    A beam that needs splitting into pieces (strongly evanescent waves) is left out when its
    internal pivots would have to be counted (it is then computed on its own).
    """
    n = omega_rad_s.size
    section = Section(_stacked([b.section.ei for b in beams], n), _stacked([b.section.shear_flexibility for b in beams], n),
                      _stacked([b.section.rho_a for b in beams], n), _stacked([b.section.rho_i for b in beams], n))
    length = _stacked([b.length_m for b in beams], n)
    wv: Waves | RealWaves = (RealWaves if real else Waves)(omega_rad_s, section, scratch, "tab.")
    decay = wv.decay_rows if wv.decay_rows is not None else np.full(len(beams), wv.decay_per_m)
    pieces = np.maximum(1, np.ceil(decay * np.max(length, axis=1) / MAX_DECAY_PER_PIECE))
    m = np.ceil(np.log2(pieces)).astype(int)
    get = scratch.real if real else scratch.complex
    out = tuple(get(f"tab.{x}", wv.n) for x in "abcefg")
    six_terms(wv, wv.functions(length / 2.0 ** m[:, None], scratch), out, scratch)  # type: ignore[arg-type]
    for level in range(1, int(m.max(initial=0)) + 1):
        rows = np.flatnonzero(m >= level)
        sub = tuple(t[rows] for t in out)
        double(sub, scratch)  # type: ignore[arg-type]
        for t, x in zip(out, sub, strict=True):
            t[rows] = x
    keep = range(len(beams)) if pivots is None else np.flatnonzero(m == 0).tolist()
    return {id(beams[i]): i for i in keep}, out  # type: ignore[return-value]


def beam_step(k: Sym, terms: SixTerms, *, scratch: Scratch | None = None, out: Sym | None = None
              ) -> tuple[Sym, Sym]:
    """Condense the node before a beam: ``P = K + D11``; ``K ← D22 − D21 P⁻¹ D12``.

    Parameters
    ----------
    k : Sym
        Stiffness carried onto the beam's first node (complex or, undamped, real).
    terms : SixTerms
        The beam's six-term dynamic stiffness (:func:`rcsa.physics.segments.stiffness_terms`).
    scratch : Scratch, optional
        Work arrays (this thread's by default); the pivot is returned in them.
    out : Sym, optional
        Where to write the new stiffness (not ``k`` or ``terms``; fresh arrays by default).

    Returns
    -------
    k : Sym
        Stiffness at the beam's second node.
    pivot : Sym
        ``P`` (its negative eigenvalues enter the Wittrick–Williams count).
    """
    new, pivot, _ = _beam_step(k, terms, local_scratch("step") if scratch is None else scratch, out)
    return new, pivot


def _beam_step(k: Sym, terms: SixTerms | RealTerms, sc: Scratch, out: Sym | None
               ) -> tuple[Sym, Sym, ComplexArray | FloatArray]:
    """:func:`beam_step`, also returning ``det P``.

    With ``D12 = [[E, F], [−F, G]]``, ``D21 = D12ᵀ`` and ``M = adj(P) D12``::

        K ← D22 − D21 M / det P,   D22 = [[A, −B], [−B, C]]
    """
    a, b, c, e, f, g = terms
    real = np.isrealobj(a) and np.isrealobj(k[0])
    p11, p12, p22, det, inv, m11, m12, m21, m22, u = sc.many(WORK[:10], a.shape, real)
    if out is None:
        out = (np.empty_like(p11), np.empty_like(p11), np.empty_like(p11))
    o11, o12, o22 = out
    add, sub, mul = np.add, np.subtract, np.multiply
    add(k[0], a, out=p11)
    add(k[1], b, out=p12)
    add(k[2], c, out=p22)
    mul(p11, p22, out=det)
    mul(p12, p12, out=u)
    sub(det, u, out=det)
    np.divide(1.0, det, out=inv)
    mul(p22, e, out=m11)                                  # M = adj(P) D12
    mul(p12, f, out=u)
    add(m11, u, out=m11)
    mul(p22, f, out=m12)
    mul(p12, g, out=u)
    sub(m12, u, out=m12)
    mul(p12, e, out=m21)
    mul(p11, f, out=u)
    add(m21, u, out=m21)                                  # −M21
    mul(p11, g, out=m22)
    mul(p12, f, out=u)
    sub(m22, u, out=m22)
    mul(e, m11, out=o11)                                  # (D21 M)11 = E M11 − F M21
    mul(f, m21, out=u)
    add(o11, u, out=o11)
    mul(o11, inv, out=o11)
    sub(a, o11, out=o11)
    mul(e, m12, out=o12)                                  # (D21 M)12 = E M12 − F M22
    mul(f, m22, out=u)
    sub(o12, u, out=o12)
    mul(o12, inv, out=o12)
    add(b, o12, out=o12)
    np.negative(o12, out=o12)
    mul(f, m12, out=o22)                                  # (D21 M)22 = F M12 + G M22
    mul(g, m22, out=u)
    add(o22, u, out=o22)
    mul(o22, inv, out=o22)
    sub(c, o22, out=o22)
    return (o11, o12, o22), (p11, p12, p22), det


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


def _joint_step(k: Sym, kt: Any, kr: Any, sc: Scratch, out: Sym, pivots: Pivots | None = None) -> Sym:
    """:func:`joint_step` into ``out`` with work arrays (complex, or real when everything is);
    reports the pivot ``K + K_j`` to ``pivots``."""
    k11, k12, k22 = k
    if kt is None and kr is None:
        return k
    o11, o12, o22 = out
    mul, add, sub = np.multiply, np.add, np.subtract
    p11, p22, det, inv, u, v = sc.many(WORK[:6], k11.shape, np.isrealobj(o11))
    if kt is not None and kr is not None:
        add(k11, kt, out=p11)
        add(k22, kr, out=p22)
        mul(p11, p22, out=det)
        mul(k12, k12, out=u)
        sub(det, u, out=det)                              # det P
        np.divide(1.0, det, out=inv)
        mul(k11, k22, out=v)
        sub(v, u, out=v)                                  # det K
        mul(k11, kr, out=o11)
        add(o11, v, out=o11)
        mul(o11, kt, out=o11)
        mul(o11, inv, out=o11)                            # k_t (det K + k_r k11) / det P
        mul(k22, kt, out=o22)
        add(o22, v, out=o22)
        mul(o22, kr, out=o22)
        mul(o22, inv, out=o22)                            # k_r (det K + k_t k22) / det P
        mul(k12, kt, out=o12)
        mul(o12, kr, out=o12)
        mul(o12, inv, out=o12)                            # k_t k_r k12 / det P
        if pivots is not None:
            pivots.add_sym(p11, p22, det)
        return out
    if kt is not None:  # rotation rigid: eliminate the old node's w only
        add(k11, kt, out=p11)
        np.divide(1.0, p11, out=inv)
        mul(k11, kt, out=o11)
        mul(o11, inv, out=o11)
        mul(k12, kt, out=o12)
        mul(o12, inv, out=o12)
        mul(k12, k12, out=o22)
        mul(o22, inv, out=o22)
        sub(k22, o22, out=o22)
    else:  # translation rigid: eliminate the old node's ψ only
        add(k22, kr, out=p11)
        np.divide(1.0, p11, out=inv)
        mul(k12, k12, out=o11)
        mul(o11, inv, out=o11)
        sub(k11, o11, out=o11)
        mul(k12, kr, out=o12)
        mul(o12, inv, out=o12)
        mul(k22, kr, out=o22)
        mul(o22, inv, out=o22)
    if pivots is not None:
        pivots.add_scalar(p11)
    return out


def _row(value: Any, rows: IntArray) -> Any:
    """``value[rows]`` for a per-row array; scalars and ``None`` are kept as they are."""
    return value if value is None or np.ndim(value) == 0 else np.asarray(value)[rows]


class ChainItem(Protocol):
    """What every item of a chain provides to the solvers (see the module docstring)."""

    def eliminate(self, k: Sym, grid: Grid, count: bool = False) -> tuple[Sym, IntArray | None]:
        """Carry the stiffness ``k`` across this item on ``grid``.

        Returns the new stiffness and, with ``count``, the number of negative eigenvalues of
        the eliminated pivot per frequency (``None`` when the item eliminates no node).

        Parameters
        ----------
        k : Sym
            Carried stiffness at the current node ``(k11, k12, k22)``, each shape (nfreq,),
            N/m, N/rad, N·m/rad.
        grid : Grid
            Frequencies, work arrays (the result may live in them) and caches.
        count : bool
            Also return the number of negative eigenvalues of the eliminated pivot per
            frequency (the Wittrick–Williams count).
        """
        ...

    def eliminate_static(self, k: Sym) -> Sym:
        """:meth:`eliminate` at ω = 0 without damping (arrays of shape (1,)).

        Parameters
        ----------
        k : Sym
            Static stiffness at the current node, arrays of shape (1,) (or (ntools,) stacked),
            N/m, N/rad, N·m/rad.
        """
        ...

    def announce(self, grid: Grid) -> None:
        """Tell ``grid``, before any elimination on it, what this item will ask of it.

        A beam announces its terms (:meth:`Grid.expect`), so the grid can compute those of
        all beams at once; lumped items ask for nothing.

        Parameters
        ----------
        grid : Grid
            The grid the item will be eliminated on.
        """
        ...

    def eliminate_undamped(self, k: Sym, grid: Grid) -> Sym:
        """:meth:`eliminate` of the undamped item in real arithmetic (``k`` real).

        Every pivot the step eliminates is reported to ``grid.pivots`` when it is set
        (:class:`rcsa.physics.algebra2x2.Pivots`: negatives and ``log|det|``).
        :class:`Lumped` items inherit a version built on :meth:`eliminate`.

        Parameters
        ----------
        k : Sym
            Stiffness at the current node, real arrays.
        grid : Grid
            Frequencies, work arrays and the pivot accumulator.
        """
        ...

    def absorb_compliance(self, compliance: ComplexArray, grid: Grid) -> tuple[ComplexArray, bool]:
        """Attach this item to a grounded base given by its receptance ``S``, shape (nfreq, 2, 2).

        Returns the new base receptance (``False``), or — for an item that eliminates the
        base's node, a beam — the dynamic stiffness at its far end (``True``).

        Parameters
        ----------
        compliance : numpy.ndarray, shape (nfreq, 2, 2), complex
            Receptance ``S`` of the grounded base at the current node, m/N, 1/N, rad/N, rad/(N·m).
        grid : Grid
            Frequencies, work arrays and caches.
        """
        ...

    def undamped(self) -> Self:
        """The item with every damper removed and real moduli."""
        ...

    def subdivided(self, omega_max_rad_s: float) -> tuple[ChainItem, ...]:
        """Equal pieces with no clamped–clamped natural frequency below ω_max (rad/s).

        Parameters
        ----------
        omega_max_rad_s : float
            Highest angular frequency the pieces must be free of clamped–clamped modes below, rad/s.
        """
        ...

    def map_sections(self, fn: Callable[[Section], Section]) -> Self:
        """The item with ``fn`` applied to its cross-sections (if it has any).

        Parameters
        ----------
        fn : callable
            ``fn(section) -> Section``.
        """
        ...

    def signature(self) -> tuple[object, ...]:
        """Structure of the item: items with equal signatures stack."""
        ...

    def stack(self, items: Sequence[Self]) -> Self:
        """One item whose parameters are arrays over ``items`` (equal signatures; ``self`` is ``items[0]``).

        Parameters
        ----------
        items : sequence of items of this type
            Items with equal :meth:`signature` (``self`` is ``items[0]``), one per stacked row (tool).
        """
        ...

    def take_rows(self, rows: IntArray) -> Self:
        """A stacked item with its parameter arrays indexed by ``rows`` (scalars kept).

        Parameters
        ----------
        rows : numpy.ndarray of int
            Rows (tools) to keep, in the order given.
        """
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
        """Condense the beam's first node (:func:`beam_step`); the pivot is ``K + D11``.

        Parameters
        ----------
        k : Sym
            Carried stiffness at the current node ``(k11, k12, k22)``, each shape (nfreq,),
            N/m, N/rad, N·m/rad.
        grid : Grid
            Frequencies, work arrays (the result may live in them) and caches.
        count : bool
            Also return the number of negative eigenvalues of the eliminated pivot per
            frequency (the Wittrick–Williams count).

        Returns
        -------
        k : Sym
            The carried stiffness at the next node.
        negatives : numpy.ndarray of int, shape (nfreq,), or None
            With ``count``, negative eigenvalues of the pivot; ``None`` otherwise or when
            no node is eliminated.
        """
        k, pivot, _ = _beam_step(k, grid.beam_terms(self), grid.scratch, grid.carried(real=False))
        return k, negative_count_sym(*pivot) if count else None

    def eliminate_undamped(self, k: Sym, grid: Grid) -> Sym:
        """:meth:`eliminate` in real arithmetic; reports the pivot ``K + D11`` (and the beam's own
        internal pivots when it is computed from pieces, :func:`rcsa.physics.segments.undamped_segment_terms`).

        Parameters
        ----------
        k : Sym
            Stiffness at the current node, real arrays.
        grid : Grid
            Frequencies, work arrays and the pivot accumulator.
        """
        k, pivot, det = _beam_step(k, grid.undamped_beam_terms(self), grid.scratch, grid.carried(real=True))
        if grid.pivots is not None:
            grid.pivots.add_sym(pivot[0].real, pivot[2].real, det.real)  # real already: no copies
        return k

    def announce(self, grid: Grid) -> None:
        """The beam will ask for its terms.

        Parameters
        ----------
        grid : Grid
            The grid the beam will be eliminated on.
        """
        grid.expect(self)

    def eliminate_static(self, k: Sym) -> Sym:
        """With the exact static Timoshenko stiffness; ``P = K + D11`` is positive definite.

        The six terms of :func:`rcsa.physics.segments.static_terms`, per row for a stacked beam.

        Parameters
        ----------
        k : Sym
            Static stiffness at the current node, arrays of shape (1,) (or (ntools,) stacked),
            N/m, N/rad, N·m/rad.
        """
        shape = k[0].shape
        terms = tuple(np.broadcast_to(x, shape) for x in static_terms(self.section.undamped(), self.length_m))
        return _beam_step(k, terms, local_scratch("static"), None)[0]  # type: ignore[arg-type]

    def absorb_compliance(self, compliance: ComplexArray, grid: Grid) -> tuple[ComplexArray, bool]:
        """``D22 − D21 S (I + D11 S)⁻¹ D12``: the stiffness at the beam's end, never inverting ``S``.

        ``D`` from the grid's six terms (:meth:`Grid.beam_terms`), so a grid that caches them
        (the diagnosis's) absorbs a measured base without recomputing the beam.

        Parameters
        ----------
        compliance : numpy.ndarray, shape (nfreq, 2, 2), complex
            Receptance ``S`` of the grounded base at the current node, m/N, 1/N, rad/N, rad/(N·m).
        grid : Grid
            Frequencies, work arrays and caches.

        Returns
        -------
        numpy.ndarray, shape (nfreq, 2, 2), complex
            The new base receptance, or (a beam) the dynamic stiffness at its far end.
        bool
            True when the result is a stiffness (the base's node was eliminated).
        """
        a, b, c, e, f, g = grid.beam_terms(self)
        d = np.stack([np.stack(r, axis=-1) for r in ([a, b, e, f], [b, c, -f, g], [e, -f, a, -b], [f, g, -b, c])],
                     axis=-2)
        d11, d12, d21, d22 = d[:, :2, :2], d[:, :2, 2:], d[:, 2:, :2], d[:, 2:, 2:]
        s = compliance
        return d22 - d21 @ s @ inv2(_EYE + d11 @ s) @ d12, True

    def undamped(self) -> Beam:
        """The beam with real moduli (itself when they are real already)."""
        section = self.section.undamped()
        return self if section is self.section else Beam(section, self.length_m)

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
        """``n`` equal pieces, each shorter than :meth:`max_piece_length_m` at ω_max and short
        enough to need no further splitting below ω_max (decay exponent ≤ ``MAX_DECAY_PER_PIECE``).

        Below the shear cut-off the evanescent wavenumber obeys ``|s₂|² ≤ s₁|s₂| = c/EI ≤
        ρAω²/EI`` (``s₁ + s₂ ≥ 0``), so its decay rate is at most ``(ρAω²/EI)^¼`` up to ω_max;
        above it there is none. The pieces are one object repeated (their terms are computed once).

        Parameters
        ----------
        omega_max_rad_s : float
            Highest angular frequency the pieces must be free of clamped–clamped modes below, rad/s.
        """
        length = float(np.max(self.length_m))
        s = self.section
        decay = float(np.max((np.asarray(s.rho_a, dtype=float) * omega_max_rad_s**2
                              / np.real(np.asarray(s.ei))) ** 0.25))
        n = max(1, math.ceil(length / self.max_piece_length_m(omega_max_rad_s)),
                math.ceil(decay * length / MAX_DECAY_PER_PIECE))
        return (Beam(self.section, self.length_m / n),) * n

    def map_sections(self, fn: Callable[[Section], Section]) -> Beam:
        """The beam with section ``fn(section)``.

        Parameters
        ----------
        fn : callable
            ``fn(section) -> Section``.
        """
        return Beam(fn(self.section), self.length_m)

    def signature(self) -> tuple[object, ...]:
        """Beams stack with beams."""
        return ("Beam",)

    def stack(self, items: Sequence[Beam]) -> Beam:
        """Sections and lengths as arrays over ``items``.

        Parameters
        ----------
        items : sequence of items of this type
            Items with equal :meth:`signature` (``self`` is ``items[0]``), one per stacked row (tool).
        """
        return Beam(Section.stack([i.section for i in items]), np.array([i.length_m for i in items]))

    def take_rows(self, rows: IntArray) -> Beam:
        """Section properties and length indexed by ``rows``.

        Parameters
        ----------
        rows : numpy.ndarray of int
            Rows (tools) to keep, in the order given.
        """
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
        """A lumped item has no natural frequency of its own: itself.

        Parameters
        ----------
        omega_max_rad_s : float
            Highest angular frequency the pieces must be free of clamped–clamped modes below, rad/s.
        """
        return (self,)

    def announce(self, grid: Grid) -> None:
        """A lumped item asks the grid for nothing in advance.

        Parameters
        ----------
        grid : Grid
            The grid (unused).
        """

    def eliminate_undamped(self, k: Sym, grid: Grid) -> Sym:
        """:meth:`~ChainItem.eliminate` (with its count, but no determinant) in real arrays.

        For items that define only the complex step; the built-in ones override it.

        Parameters
        ----------
        k : Sym
            Stiffness at the current node, real arrays.
        grid : Grid
            Frequencies, work arrays and the pivot accumulator.
        """
        item: Any = self  # a ChainItem: every subclass defines eliminate
        new, negatives = item.eliminate(k, grid, grid.pivots is not None)
        if negatives is not None and grid.pivots is not None:
            grid.pivots.add_negatives(negatives)
        return tuple(np.ascontiguousarray(np.real(x)) for x in new)  # type: ignore[return-value]

    def map_sections(self, fn: Callable[[Section], Section]) -> Self:
        """A lumped item has no section: itself.

        Parameters
        ----------
        fn : callable
            ``fn(section) -> Section``.
        """
        return self

    def signature(self) -> tuple[object, ...]:
        """Its type name: lumped items of one type stack."""
        return (type(self).__name__,)

    def _values(self) -> dict[str, Any]:
        """The dataclass fields of the subclass, by name."""
        item: Any = self  # a dataclass: every subclass is one
        return {f.name: getattr(self, f.name) for f in fields(item)}

    def stack(self, items: Sequence[Self]) -> Self:
        """Every field as an array over ``items`` (``None`` stays ``None``: equal signatures agree on it).

        Parameters
        ----------
        items : sequence of items of this type
            Items with equal :meth:`signature` (``self`` is ``items[0]``), one per stacked row (tool).
        """
        values = [i._values() for i in items]
        return type(self)(**{name: None if value is None else np.array([v[name] for v in values])
                             for name, value in self._values().items()})

    def take_rows(self, rows: IntArray) -> Self:
        """Every array field indexed by ``rows`` (scalars kept).

        Parameters
        ----------
        rows : numpy.ndarray of int
            Rows (tools) to keep, in the order given.
        """
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
        """``k_t + iωc_t`` (N/m), shape (nfreq,), or ``None`` if rigid.

        Parameters
        ----------
        omega_rad_s : numpy.ndarray, shape (nfreq,)
            Angular frequencies, rad/s.
        """
        if self.stiffness_n_m is None:
            return None
        return self.stiffness_n_m + 1j * omega_rad_s * self.damping_ns_m

    def rotational(self, omega_rad_s: FloatArray) -> ComplexArray | None:
        """``k_r + iωc_r`` (N·m/rad), shape (nfreq,), or ``None`` if rigid.

        Parameters
        ----------
        omega_rad_s : numpy.ndarray, shape (nfreq,)
            Angular frequencies, rad/s.
        """
        if self.rotational_stiffness_nm_rad is None:
            return None
        return self.rotational_stiffness_nm_rad + 1j * omega_rad_s * self.rotational_damping_nms_rad

    def compliance(self, omega_rad_s: FloatArray) -> ComplexArray:
        """Joint compliance ``K⁻¹``, shape (nfreq, 2, 2); zero for rigid DOFs.

        Parameters
        ----------
        omega_rad_s : numpy.ndarray, shape (nfreq,)
            Angular frequencies, rad/s.
        """
        out = np.zeros((omega_rad_s.size, 2, 2), dtype=complex)
        kt, kr = self.translational(omega_rad_s), self.rotational(omega_rad_s)
        if kt is not None:
            out[:, 0, 0] = 1.0 / kt
        if kr is not None:
            out[:, 1, 1] = 1.0 / kr
        return out

    def eliminate(self, k: Sym, grid: Grid, count: bool = False) -> tuple[Sym, IntArray | None]:
        """Condense across the joint (:func:`joint_step`).

        Parameters
        ----------
        k : Sym
            Carried stiffness at the current node ``(k11, k12, k22)``, each shape (nfreq,),
            N/m, N/rad, N·m/rad.
        grid : Grid
            Frequencies, work arrays (the result may live in them) and caches.
        count : bool
            Also return the number of negative eigenvalues of the eliminated pivot per
            frequency (the Wittrick–Williams count).

        Returns
        -------
        k : Sym
            The carried stiffness at the next node.
        negatives : numpy.ndarray of int, shape (nfreq,), or None
            With ``count``, negative eigenvalues of the pivot; ``None`` otherwise or when
            no node is eliminated.
        """
        w = grid.omega_rad_s
        if count:
            return joint_step(k, self.translational(w), self.rotational(w), count)
        sc, n = grid.scratch, w.size
        kt = kr = None
        if self.stiffness_n_m is not None:
            kt = sc.complex("sp.kt", n)
            kt.real = self.stiffness_n_m
            np.multiply(w, self.damping_ns_m, out=kt.imag)
        if self.rotational_stiffness_nm_rad is not None:
            kr = sc.complex("sp.kr", n)
            kr.real = self.rotational_stiffness_nm_rad
            np.multiply(w, self.rotational_damping_nms_rad, out=kr.imag)
        return _joint_step(k, kt, kr, sc, grid.carried(real=False)), None

    def eliminate_static(self, k: Sym) -> Sym:
        """Across the joint's static stiffness.

        Parameters
        ----------
        k : Sym
            Static stiffness at the current node, arrays of shape (1,) (or (ntools,) stacked),
            N/m, N/rad, N·m/rad.
        """
        w0 = np.zeros(1)
        stiff = self.undamped()
        return joint_step(k, stiff.translational(w0), stiff.rotational(w0))[0]

    def eliminate_undamped(self, k: Sym, grid: Grid) -> Sym:
        """Across the joint's stiffness, real; reports the pivot ``K + K_j`` (one DOF if the other is rigid).

        Parameters
        ----------
        k : Sym
            Stiffness at the current node, real arrays.
        grid : Grid
            Frequencies, work arrays and the pivot accumulator.
        """
        return _joint_step(k, self.stiffness_n_m, self.rotational_stiffness_nm_rad, grid.scratch,
                           grid.carried(real=True), grid.pivots)

    def absorb_compliance(self, compliance: ComplexArray, grid: Grid) -> tuple[ComplexArray, bool]:
        """A joint adds its compliance to the base's.

        Parameters
        ----------
        compliance : numpy.ndarray, shape (nfreq, 2, 2), complex
            Receptance ``S`` of the grounded base at the current node, m/N, 1/N, rad/N, rad/(N·m).
        grid : Grid
            Frequencies, work arrays and caches.

        Returns
        -------
        numpy.ndarray, shape (nfreq, 2, 2), complex
            The new base receptance, or (a beam) the dynamic stiffness at its far end.
        bool
            True when the result is a stiffness (the base's node was eliminated).
        """
        return compliance + self.compliance(grid.omega_rad_s), False

    def undamped(self) -> Spring:
        """The joint without dampers (itself when it has none)."""
        if not np.any(self.damping_ns_m) and not np.any(self.rotational_damping_nms_rad):
            return self
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
        """Dynamic stiffness, shape (nfreq, 2, 2).

        Parameters
        ----------
        omega_rad_s : numpy.ndarray, shape (nfreq,)
            Angular frequencies, rad/s.
        """
        w = omega_rad_s
        out = np.zeros((w.size, 2, 2), dtype=complex)
        out[:, 0, 0] = self.stiffness_n_m + 1j * w * self.damping_ns_m - w**2 * self.mass_kg
        out[:, 1, 1] = (self.rotational_stiffness_nm_rad + 1j * w * self.rotational_damping_nms_rad
                        - w**2 * self.rotary_inertia_kg_m2)
        return out

    def eliminate(self, k: Sym, grid: Grid, count: bool = False) -> tuple[Sym, IntArray | None]:
        """``K ← K + Δ``: no node is eliminated, so no pivot.

        Parameters
        ----------
        k : Sym
            Carried stiffness at the current node ``(k11, k12, k22)``, each shape (nfreq,),
            N/m, N/rad, N·m/rad.
        grid : Grid
            Frequencies, work arrays (the result may live in them) and caches.
        count : bool
            Also return the number of negative eigenvalues of the eliminated pivot per
            frequency (the Wittrick–Williams count).

        Returns
        -------
        k : Sym
            The carried stiffness at the next node.
        negatives : numpy.ndarray of int, shape (nfreq,), or None
            With ``count``, negative eigenvalues of the pivot; ``None`` otherwise or when
            no node is eliminated.
        """
        return self._add(k, grid, real=False), None

    def eliminate_undamped(self, k: Sym, grid: Grid) -> Sym:
        """``K ← K + diag(k_t − ω²m, k_r − ω²J)``, real.

        Parameters
        ----------
        k : Sym
            Stiffness at the current node, real arrays.
        grid : Grid
            Frequencies, work arrays and the pivot accumulator.
        """
        return self._add(k, grid, real=True)

    def _add(self, k: Sym, grid: Grid, real: bool) -> Sym:
        """``K + Δ`` into the grid's carried arrays (``Δ`` without its dampers when ``real``)."""
        w = grid.omega_rad_s
        w2 = grid.scratch.real("gr.w2", w.size)
        np.multiply(w, w, out=w2)
        o11, o12, o22 = grid.carried(real)
        for o, ki, kk, c, m in ((o11, k[0], self.stiffness_n_m, self.damping_ns_m, self.mass_kg),
                                (o22, k[2], self.rotational_stiffness_nm_rad, self.rotational_damping_nms_rad,
                                 self.rotary_inertia_kg_m2)):
            re = o if real else o.real
            np.multiply(w2, -m, out=re)
            np.add(re, kk, out=re)                        # k − ω²m
            if real:
                np.add(o, ki, out=o)
            else:
                o.imag = 0.0
                if np.any(c):
                    np.multiply(w, c, out=o.imag)         # + iωc
                np.add(o, ki, out=o)
        np.copyto(o12, k[1])
        return o11, o12, o22

    def eliminate_static(self, k: Sym) -> Sym:
        """``K ← K + diag(k_t, k_r)``.

        Parameters
        ----------
        k : Sym
            Static stiffness at the current node, arrays of shape (1,) (or (ntools,) stacked),
            N/m, N/rad, N·m/rad.
        """
        return k[0] + self.stiffness_n_m, k[1], k[2] + self.rotational_stiffness_nm_rad

    def absorb_compliance(self, compliance: ComplexArray, grid: Grid) -> tuple[ComplexArray, bool]:
        """``S (I + Δ S)⁻¹``.

        Parameters
        ----------
        compliance : numpy.ndarray, shape (nfreq, 2, 2), complex
            Receptance ``S`` of the grounded base at the current node, m/N, 1/N, rad/N, rad/(N·m).
        grid : Grid
            Frequencies, work arrays and caches.

        Returns
        -------
        numpy.ndarray, shape (nfreq, 2, 2), complex
            The new base receptance, or (a beam) the dynamic stiffness at its far end.
        bool
            True when the result is a stiffness (the base's node was eliminated).
        """
        s = compliance
        return s @ inv2(_EYE + self.stiffness(grid.omega_rad_s) @ s), False

    def undamped(self) -> Ground:
        """The attachment without dampers (itself when it has none)."""
        if not np.any(self.damping_ns_m) and not np.any(self.rotational_damping_nms_rad):
            return self
        return replace(self, damping_ns_m=0.0, rotational_damping_nms_rad=0.0)


def undamped(chain: Chain) -> Chain:
    """The chain with every damper removed and real moduli (for natural frequencies).

    Parameters
    ----------
    chain : Chain
        The items, spindle rear to tool tip.

    Returns
    -------
    Chain
    """
    return tuple(item.undamped() for item in chain)
