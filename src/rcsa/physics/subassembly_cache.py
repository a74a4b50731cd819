"""Condense the spindle once, march the rest: the one cache of condensed subassemblies.

Every solver of rcsa that evaluates many assemblies sharing a front part works the same
way. The chain is condensed from the spindle rear (or a measured spindle's receptance at its
plane) onto the end of the shared part — spindle, or spindle + holder — once per frequency
grid, and only the rest (joints, holder, tool) is marched for each assembly:

* a prediction of many tools condenses spindle + holder once per holder and marches each
  tool (:mod:`rcsa.model.prediction`);
* the joint identification and the effect analysis on measured spindles condense the
  spindle once and march holder and tool for every set of joint values
  (:class:`rcsa.analysis.tool_point_model.ToolPointModel`);
* the diagnosis condenses spindle and holder under each set of tolerances it draws and
  marches each measurement's tool (:class:`rcsa.analysis.diagnosis.perturbed_model.Solver`).

A :class:`SubassemblyCache` is that shared part on one grid: the condensed state after a
sequence of sub-chains (:meth:`~SubassemblyCache.condensed`), the six stiffness terms of
each beam (its :attr:`~SubassemblyCache.grid`), and the static stiffness of a sub-chain
(:meth:`~SubassemblyCache.static`). **What it hands out is read-only** (numpy
``writeable=False``): the elimination steps write into the grid's work arrays, so whatever
is kept is copied once when it is stored (beam terms) or is a fresh array to begin with
(condensed states), and no caller needs a defensive copy. **One eviction policy**
(:class:`LruStore`: least recently used first, bounded by a count) governs the states, the
beam terms and the caches per grid that :class:`~rcsa.analysis.tool_point_model.ToolPointModel`
keeps.

Keys: a measured base by identity (each Monte-Carlo draw of a spindle is its own array),
sub-chains by identity first — builders that share sub-chain objects (the diagnosis's
``PartsBuilder``) never pay for hashing a chain — and then by value, so that two tools whose
spindle + holder chains are equal but built apart share one condensation.

>>> import numpy as np
>>> from rcsa.physics.chain import Beam, Ground, Spring
>>> from rcsa.physics.sections import Section
>>> beam = Beam(Section(ei=2.0e5, shear_flexibility=0.0, rho_a=20.0, rho_i=0.0), 0.1)
>>> cache = SubassemblyCache(2 * np.pi * np.array([100.0, 200.0]))
>>> front = (Ground(stiffness_n_m=1e8), beam)
>>> k = cache.condensed((front,))
>>> k.stiffness.flags.writeable, cache.condensed((tuple(front),)) is k
(False, True)
"""

from __future__ import annotations

import threading
from collections import OrderedDict
from collections.abc import Callable, Hashable
from dataclasses import dataclass
from typing import Generic, TypeVar

import numpy as np

from rcsa.physics.algebra2x2 import inv2
from rcsa.physics.arrays import ComplexArray, FloatArray
from rcsa.physics.chain import Beam, Chain, Grid, Sym
from rcsa.physics.elimination import march, static_condense
from rcsa.physics.sections import Section
from rcsa.physics.segments import SixTerms, Waves, segment_terms

__all__ = ["Condensed", "LruStore", "SubassemblyCache"]

K = TypeVar("K", bound=Hashable)
V = TypeVar("V")

#: Condensed states kept per grid by default.
DEFAULT_STATES = 128
#: Beam terms kept per grid by default when the grid caches them.
DEFAULT_BEAMS = 512


class LruStore(Generic[K, V]):
    """A bounded mapping that drops the least recently used entry first: rcsa's one eviction policy.

    Each operation is atomic (one re-entrant lock per store), so threads may share a store;
    :meth:`get` does not hold the lock while ``make()`` runs (two threads missing the same key
    may both make it; the later one is kept).

    Parameters
    ----------
    size : int
        Entries kept (>= 0; 0 keeps nothing).
    on_evict : callable, optional
        Called with each dropped key and value (under the store's lock).

    Examples
    --------
    >>> lru = LruStore(2)
    >>> [lru.get(k, lambda: k.upper()) for k in "aba"] + [lru.get("c", lambda: "C")]
    ['A', 'B', 'A', 'C']
    >>> "b" in lru, "a" in lru
    (False, True)
    """

    def __init__(self, size: int, on_evict: Callable[[K, V], None] | None = None) -> None:
        self.size = int(size)
        self._items: OrderedDict[K, V] = OrderedDict()
        self._on_evict = on_evict
        self._lock = threading.RLock()

    def __contains__(self, key: object) -> bool:
        return key in self._items

    def __len__(self) -> int:
        return len(self._items)

    def values(self) -> list[V]:
        """The entries kept, least recently used first."""
        with self._lock:
            return list(self._items.values())

    def peek(self, key: K) -> V | None:
        """The entry of ``key`` (marked as just used), or None.

        Parameters
        ----------
        key : hashable
        """
        with self._lock:
            hit = self._items.get(key)
            if hit is not None:
                self._items.move_to_end(key)
            return hit

    def pop(self, key: K) -> V | None:
        """Drop the entry of ``key`` (None when there is none); ``on_evict`` is not called.

        Parameters
        ----------
        key : hashable
        """
        with self._lock:
            return self._items.pop(key, None)

    def clear(self) -> None:
        """Drop every entry (``on_evict`` is not called)."""
        with self._lock:
            self._items.clear()

    def put(self, key: K, value: V) -> V:
        """Keep ``value`` under ``key`` (dropping the least recently used beyond :attr:`size`).

        Parameters
        ----------
        key : hashable
        value : object
            Returned.
        """
        if self.size <= 0:
            return value
        with self._lock:
            self._items[key] = value
            self._items.move_to_end(key)
            while len(self._items) > self.size:
                old, dropped = self._items.popitem(last=False)
                if self._on_evict is not None:
                    self._on_evict(old, dropped)
        return value

    def get(self, key: K, make: Callable[[], V]) -> V:
        """The entry of ``key``, made by ``make()`` and kept on a miss.

        Parameters
        ----------
        key : hashable
        make : callable
            ``make()`` gives the value of a missing key.
        """
        hit = self.peek(key)
        return hit if hit is not None else self.put(key, make())


def _frozen(a: np.ndarray) -> np.ndarray:
    a.flags.writeable = False
    return a


@dataclass(frozen=True, eq=False)
class Condensed:
    """The state of a chain condensed onto its last node, read-only.

    Exactly one of the two is set: ``stiffness`` once a beam has been condensed (an
    analytical spindle, or a measured base followed by a beam), ``compliance`` while a
    measured base has only been joined by joints and lumped items (it is never inverted).

    Attributes
    ----------
    stiffness : numpy.ndarray, shape (nfreq, 2, 2), complex, or None
        Dynamic stiffness seen from the right, N/m, N/rad, N·m/rad (symmetric).
    compliance : numpy.ndarray, shape (nfreq, 2, 2), complex, or None
        Receptance of the grounded base, m/N, 1/N, rad/N, rad/(N·m).
    """

    stiffness: ComplexArray | None = None
    compliance: ComplexArray | None = None

    @property
    def sym(self) -> Sym:
        """``(k11, k12, k22)`` views of :attr:`stiffness` (read-only), each shape (nfreq,)."""
        k = self.stiffness
        assert k is not None
        return k[:, 0, 0], k[:, 0, 1], k[:, 1, 1]


@dataclass(frozen=True, eq=False)
class _Entry:
    """A kept state, the objects it was condensed from (kept alive: their ids are its key) and
    its key by value."""

    objs: tuple[object, ...]
    state: Condensed
    value_key: tuple[object, ...]


class _CachingGrid(Grid):
    """A :class:`Grid` that keeps each beam's six terms and each section's waves (fresh arrays,
    not the work arrays; read-only), least recently used dropped first."""

    def __init__(self, omega_rad_s: FloatArray, max_beams: int) -> None:
        super().__init__(omega_rad_s)
        self._terms: LruStore[Beam, SixTerms] = LruStore(max_beams)
        self._kept_waves: LruStore[Section, Waves] = LruStore(max(max_beams // 4, 1))

    def waves(self, section: Section) -> Waves:
        """Wavenumbers of ``section`` (kept: a Monte Carlo makes new sections all the time)."""
        try:
            hit = self._kept_waves.peek(section)
        except TypeError:  # a section stacked over several tools (unhashable): not kept, as the plain grid does
            return super().waves(section)
        return hit if hit is not None else self._kept_waves.put(section, Waves(self.omega_rad_s, section))

    def beam_terms(self, beam: Beam) -> SixTerms:
        """The beam's terms on this grid, computed once, read-only."""
        if beam.is_stacked:
            return super().beam_terms(beam)

        def make() -> SixTerms:
            a, b, c, e, f, g = segment_terms(self.omega_rad_s, beam.section, beam.length_m, self.waves(beam.section))
            return _frozen(a), _frozen(b), _frozen(c), _frozen(e), _frozen(f), _frozen(g)

        return self._terms.get(beam, make)


class SubassemblyCache:
    """Condensed subassemblies on one frequency grid, handed out read-only.

    Parameters
    ----------
    omega_rad_s : numpy.ndarray, shape (nfreq,)
        Angular frequencies of the grid, rad/s.
    base : numpy.ndarray, shape (nfreq, 2, 2), optional
        A measured spindle-side receptance chains start from by default (hybrid).
    max_states : int
        Condensed states kept (least recently used dropped first).
    max_beams : int
        Beam terms kept by :attr:`grid` (0: none — the condensations are then marched in
        frequency blocks by :func:`rcsa.physics.elimination.march`, the fastest for one-off
        condensations; keep terms when the same beams are marched again and again).

    Attributes
    ----------
    omega_rad_s : numpy.ndarray, shape (nfreq,)
        Read-only.
    grid : Grid
        Where the caller marches the rest (:meth:`tip_h`), keeping beam terms when
        ``max_beams`` > 0.
    """

    def __init__(self, omega_rad_s: FloatArray, base: ComplexArray | None = None, *,
                 max_states: int = DEFAULT_STATES, max_beams: int = 0) -> None:
        self.omega_rad_s: FloatArray = _frozen(np.array(omega_rad_s, dtype=float))
        self.base = None if base is None else _frozen(np.array(base, dtype=complex))
        self._caching = max_beams > 0
        self.grid: Grid = _CachingGrid(self.omega_rad_s, max_beams) if self._caching else Grid(self.omega_rad_s)
        # states by the identity of (base, *chains) — cheap to hash —, the entry keeping those
        # objects alive; an index by value finds equal chains built apart (one deep hash)
        self._states: LruStore[tuple[object, ...], _Entry] = LruStore(max_states, on_evict=self._forget)
        self._by_value: dict[tuple[object, ...], tuple[object, ...]] = {}
        zero = _frozen(np.zeros((self.omega_rad_s.size, 2, 2), dtype=complex))
        self._free = Condensed(stiffness=zero)

    def __len__(self) -> int:
        """Condensed (and static) states kept."""
        return len(self._states)

    # ------------------------------------------------------------------ condensed states

    def condensed(self, chains: tuple[Chain, ...], base: ComplexArray | None = None) -> Condensed:
        """The state after ``chains`` (condensed one after the other) on ``base``, cached.

        Parameters
        ----------
        chains : tuple of Chain
            Sub-chains from the spindle rear (or from the measured base), e.g.
            ``(spindle, holder)``; the state after every prefix of them is cached too.
        base : numpy.ndarray, shape (nfreq, 2, 2), optional
            A measured receptance to start from (default: the cache's ``base``; none: a free
            end). Keyed by identity: pass the same array for the same base.

        Returns
        -------
        Condensed
            Read-only.
        """
        if not isinstance(chains, tuple) or not all(isinstance(c, tuple) for c in chains):
            raise TypeError("condensed() takes a tuple of chains, e.g. (spindle, holder); for one chain: (chain,)")
        start = self.base if base is None else base
        if not chains:
            return self._free if start is None else Condensed(compliance=start)
        objs = (start, *chains)
        ident = tuple(map(id, objs))
        entry = self._states.peek(ident)
        if entry is not None and all(a is b for a, b in zip(entry.objs, objs, strict=True)):
            return entry.state  # the very objects that were condensed (kept alive by the entry)
        value_key = (id(start), *chains)
        known = self._by_value.get(value_key)
        entry = None if known is None else self._states.peek(known)
        if entry is None:
            state = self._condense(self.condensed(chains[:-1], start), chains[-1])
            entry = self._states.put(ident, _Entry(objs, state, value_key))
            if ident in self._states:  # kept (size > 0)
                self._by_value[value_key] = ident
        return entry.state

    def stiffness(self, chain: Chain) -> ComplexArray:
        """Dynamic stiffness at the end of ``chain`` on the cache's base, shape (nfreq, 2, 2), read-only.

        Parameters
        ----------
        chain : Chain
            Must contain a beam when the cache has a measured base.
        """
        state = self.condensed((chain,))
        if state.stiffness is None:
            raise ValueError("a chain on a measured base must contain at least one beam")
        return state.stiffness

    def static(self, chain: Chain) -> FloatArray:
        """Static undamped stiffness at the end of ``chain`` (ω = 0), shape (2, 2), read-only.

        Parameters
        ----------
        chain : Chain
            A sub-chain from the spindle rear (e.g. spindle + holder), shared across tools.
        """
        key = ("static", id(chain))
        entry = self._states.peek(key)
        if entry is None or entry.objs[0] is not chain:
            known = self._by_value.get(("static", chain))
            entry = None if known is None else self._states.peek(known)
        if entry is None:
            static = Condensed(stiffness=_frozen(static_condense(chain)))
            entry = self._states.put(key, _Entry((chain,), static, ("static", chain)))
            if key in self._states:
                self._by_value[("static", chain)] = key
        out = entry.state.stiffness
        assert out is not None
        return out.real

    def _forget(self, key: tuple[object, ...], entry: _Entry) -> None:
        """An evicted state's index entry goes with it."""
        if self._by_value.get(entry.value_key) == key:
            del self._by_value[entry.value_key]

    def _condense(self, state: Condensed, chain: Chain) -> Condensed:
        """``state`` carried across ``chain``: fresh arrays, made read-only."""
        s = state.compliance
        if s is not None:  # a measured base: each item absorbs it until a beam turns it into a stiffness
            for i, item in enumerate(chain):
                out, is_stiffness = item.absorb_compliance(s, self.grid)
                if is_stiffness:
                    return self._march(chain[i + 1:], out)
                s = out
            return Condensed(compliance=_frozen(np.array(s)))
        return self._march(chain, None if state is self._free else state.stiffness)

    def _march(self, chain: Chain, start: ComplexArray | None) -> Condensed:
        k = march(chain, self.omega_rad_s, start, grid=self.grid if self._caching else None)[0]
        return Condensed(stiffness=_frozen(k))

    # ------------------------------------------------------------------ marching the rest

    def tip_h(self, state: Condensed, chain: Chain) -> ComplexArray:
        """Driving-point ``h`` at the end of ``chain`` attached to ``state``, shape (nfreq,), m/N.

        Not cached: the evaluation of one assembly, each item's own elimination step on
        :attr:`grid` (whose beam terms are kept). A fresh array.

        Parameters
        ----------
        state : Condensed
            From :meth:`condensed` on this cache.
        chain : Chain
        """
        grid = self.grid
        k: Sym | None = state.sym if state.stiffness is not None else None
        s = state.compliance
        for item in chain:
            if s is not None:
                out, is_stiffness = item.absorb_compliance(s, grid)
                if is_stiffness:
                    k, s = (out[:, 0, 0], 0.5 * (out[:, 0, 1] + out[:, 1, 0]), out[:, 1, 1]), None
                else:
                    s = out
            else:
                assert k is not None
                k, _ = item.eliminate(k, grid)
        if s is not None:
            return np.array(s[:, 0, 0])
        assert k is not None
        k11, k12, k22 = k
        return k22 / (k11 * k22 - k12 * k12)

    def tip_receptance(self, state: Condensed, chain: Chain) -> ComplexArray:
        """Point receptance ``[[h, l], [n, p]]`` at the end of ``chain`` attached to ``state``.

        Parameters
        ----------
        state : Condensed
        chain : Chain

        Returns
        -------
        numpy.ndarray, shape (nfreq, 2, 2), complex
            A fresh array, m/N, 1/N, rad/N, rad/(N·m).
        """
        if state.compliance is not None:
            inner = self._condense(state, chain)
            if inner.compliance is not None:
                return np.array(inner.compliance)
            assert inner.stiffness is not None
            return inv2(inner.stiffness)
        return inv2(march(chain, self.omega_rad_s, state.stiffness, grid=self.grid if self._caching else None)[0])
