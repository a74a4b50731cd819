"""Exact dynamic-stiffness solution of a chain by block elimination along the axis.

The global dynamic stiffness of a chain is block tridiagonal (2 DOFs per node). Eliminating
the nodes one after the other from the spindle rear keeps only a 2×2 "stiffness seen from
the right" ``K`` and costs a few 2×2 operations per item and frequency::

    beam   (D = [[D11, D12], [D21, D22]]):   P = K + D11;   K ← D22 − D21 P⁻¹ D12
    spring (K_j):                            P = K + K_j;   K ← K_j − K_j P⁻¹ K_j
    ground (Δ):                              K ← K + Δ

Each step is the item's own (:meth:`rcsa.physics.chain.ChainItem.eliminate`); this module
only runs them. At the tool tip the point receptance is ``K⁻¹``. This is the ``docs/physics.md`` §3.5 global
dynamic-stiffness assembly (mathematically identical to receptance coupling, accurate down
to very low frequency), done without forming the global matrix.

The same elimination counts eigenvalues: by Sylvester's law of inertia the number of
negative eigenvalues of the real symmetric global matrix is the sum over the pivots ``P``
and the final ``K``. With every beam short enough to have no clamped–clamped natural
frequency below ω (:func:`subdivide`), that sum is the Wittrick–Williams count ``J(ω)`` of
natural frequencies below ω (Wittrick & Williams, Q. J. Mech. Appl. Math. 24 (1971) 263).
"""

from __future__ import annotations

import numpy as np

from rcsa.physics.algebra2x2 import Pivots, inv2
from rcsa.physics.arrays import ComplexArray, FloatArray, IntArray
from rcsa.physics.chain import Chain, ChainItem, Grid, Sym, Tiling
from rcsa.physics.elementwise import Scratch, local_scratch

__all__ = ["close", "march", "march_tools", "march_undamped", "static_condense", "static_condense_rows",
           "static_tip_receptance", "static_tip_receptance_rows", "subdivide", "tip_receptance",
           "wittrick_williams_count"]


#: Most frequency lines per block: a block's work arrays stay (mostly) in cache, and each
#: block costs the fixed overhead of one pass over the chain.
_BLOCK = 4096


def _blocks(n: int) -> list[tuple[int, int]]:
    """Equal blocks of at most ``_BLOCK`` lines."""
    count = max(1, -(-n // _BLOCK))
    edges = [round(i * n / count) for i in range(count + 1)]
    return list(zip(edges[:-1], edges[1:], strict=True))


def _rows(chain: Chain, start: int, stop: int, n: int) -> Chain:
    """The block ``start:stop`` of a chain stacked with one row per line (the chain itself otherwise)."""
    if (start, stop) == (0, n) or not any(item.is_stacked for item in chain):
        return chain
    rows = np.arange(start, stop)
    return tuple(item.take_rows(rows) if item.is_stacked else item for item in chain)


def _is_undamped(chain: Chain) -> bool:
    """Every item has real moduli and no dampers (its undamped copy is itself)."""
    return all(item.undamped() is item for item in chain)


def _absorb_compliance(chain: Chain, grid: Grid, compliance: ComplexArray) -> tuple[ComplexArray, int]:
    """Attach the leading items of ``chain`` to a grounded base given by its compliance ``S``.

    A measured spindle is known as a receptance, possibly rank-deficient (estimated rotations),
    so it is never inverted: each item absorbs it (:meth:`rcsa.physics.chain.ChainItem.absorb_compliance`)
    until the first beam turns it into a stiffness.

    Returns the stiffness at the end of the first beam and the number of items consumed.
    """
    s = np.array(compliance, dtype=complex)
    for i, item in enumerate(chain):
        s, is_stiffness = item.absorb_compliance(s, grid)
        if is_stiffness:
            return s, i + 1
    raise ValueError("a chain on a measured base must contain at least one beam")


def march(chain: Chain, omega_rad_s: FloatArray, start: ComplexArray | None = None,
          count: bool = False, start_compliance: ComplexArray | None = None, *, grid: Grid | None = None
          ) -> tuple[ComplexArray, IntArray | None]:
    """Condense a chain onto its last node.

    Each item carries the stiffness across itself (:meth:`rcsa.physics.chain.ChainItem.eliminate`),
    one block of frequency lines at a time; an undamped chain runs in real arithmetic
    (:meth:`~rcsa.physics.chain.ChainItem.eliminate_undamped`).

    Parameters
    ----------
    chain : Chain
    omega_rad_s : numpy.ndarray, shape (nfreq,)
        Angular frequencies, rad/s.
    start : numpy.ndarray, shape (nfreq, 2, 2), optional
        Dynamic stiffness already attached at the first node (e.g. a condensed spindle, or
        the inverse of a measured base receptance; symmetrised); zero (free end) by default.
    count : bool
        Also return the number of negative pivot eigenvalues per frequency (undamped chains;
        :func:`march_undamped` also gives their determinants).
    start_compliance : numpy.ndarray, shape (nfreq, 2, 2), optional
        Instead of ``start``: the receptance of a grounded base at the first node (a
        measured spindle), used without inverting it.
    grid : Grid, optional
        The grid of ``omega_rad_s`` with what it caches across calls (e.g. the diagnosis's
        beam terms); by default a fresh one per block. Given a grid, the frequency axis is
        not split into blocks.

    Returns
    -------
    k : numpy.ndarray, shape (nfreq, 2, 2)
        Dynamic stiffness at the last node of everything in the chain (and ``start``).
    negatives : numpy.ndarray of int, shape (nfreq,), or None
        Negative eigenvalues of the eliminated pivots (excluding the returned ``k``).
    """
    w = np.asarray(omega_rad_s, dtype=float)
    if start_compliance is not None:
        start, used = _absorb_compliance(chain, Grid(w) if grid is None else grid, start_compliance)
        chain = chain[used:]
    n = w.size
    s0 = None if start is None else np.asarray(start)
    real = grid is None and not count and _is_undamped(chain) and (s0 is None or not np.any(np.imag(s0)))
    out = np.empty((n, 2, 2), dtype=complex)
    neg = np.zeros(n, dtype=int) if count else None
    scratch = local_scratch()
    for i0, i1 in [(0, n)] if grid is not None else _blocks(n):
        g = grid if grid is not None else Grid(w[i0:i1], scratch)
        k, negatives = _carry(_rows(chain, i0, i1, n), g, _start_sym(s0, i0, i1, real), real, count)
        if neg is not None:
            neg[i0:i1] += negatives
        _put_sym(out[i0:i1], k)
    return out, neg


def march_undamped(chain: Chain, omega_rad_s: FloatArray, start: FloatArray | None = None, *,
                   count: bool = True, scratch: Scratch | None = None) -> tuple[FloatArray, Pivots | None]:
    """:func:`march` of an undamped chain in real arithmetic, with the pivots it eliminates.

    Parameters
    ----------
    chain : Chain
        Damping is ignored (each item's :meth:`~rcsa.physics.chain.ChainItem.eliminate_undamped`).
    omega_rad_s : numpy.ndarray, shape (nfreq,)
        Angular frequencies, rad/s.
    start : numpy.ndarray, shape (nfreq, 2, 2), optional
        Real stiffness at the first node; zero by default.
    count : bool
        Collect the pivots.
    scratch : Scratch, optional
        Work arrays to reuse (e.g. across the steps of a search); fresh ones by default.

    Returns
    -------
    k : numpy.ndarray, shape (nfreq, 2, 2), float
        Stiffness at the last node.
    pivots : Pivots or None
        Negatives and ``log|det|`` of the eliminated pivots (not of ``k``).
    """
    w = np.asarray(omega_rad_s, dtype=float)
    n = w.size
    out = np.empty((n, 2, 2))
    pivots = Pivots(n) if count else None
    scratch = local_scratch() if scratch is None else scratch
    s0 = None if start is None else np.ascontiguousarray(np.real(start), dtype=float)
    for i0, i1 in _blocks(n):
        block = None if pivots is None else pivots.block(i0, i1)
        g = Grid(w[i0:i1], scratch, block)
        k = _start_sym(s0, i0, i1, True)
        part = _rows(chain, i0, i1, n)
        for item in part:
            item.announce(g)
        for item in part:
            k = item.eliminate_undamped(k, g)
        _put_sym(out[i0:i1], k)
        if pivots is not None and block is not None and not block.det_known:
            pivots.det_known = False
    return out, pivots


def march_tools(stacked: Chain, omega_rad_s: FloatArray, n_tools: int, start: ComplexArray | None = None
                ) -> ComplexArray:
    """:func:`march` of a chain stacked over tools, every tool on the whole grid.

    Line ``t·nfreq + i`` is tool ``t`` (row ``t`` of the stacked parameters) at
    ``omega_rad_s[i]`` with ``start[i]``; the rows of each block are taken as it is solved,
    so memory stays that of one block.

    Parameters
    ----------
    stacked : Chain
        Stacked over ``n_tools`` tools (:func:`rcsa.physics.stacking.stack_chains`).
    omega_rad_s : numpy.ndarray, shape (nfreq,)
        Angular frequencies, rad/s.
    n_tools : int
    start : numpy.ndarray, shape (nfreq, 2, 2), optional
        Stiffness at the first node, the same for every tool (a condensed spindle + holder).

    Returns
    -------
    numpy.ndarray, shape (n_tools, nfreq, 2, 2), complex
    """
    w = np.asarray(omega_rad_s, dtype=float)
    nf = w.size
    n = n_tools * nf
    s0 = None if start is None else np.asarray(start)
    real = _is_undamped(stacked) and (s0 is None or not np.any(np.imag(s0)))
    out = np.empty((n, 2, 2), dtype=complex)
    scratch = local_scratch()
    per_block = _BLOCK // nf  # whole tools per block: the waves of shared sections are the grid's, repeated
    tiling = Tiling(w) if per_block >= 1 else None
    blocks = [(t * nf, min(t + per_block, n_tools) * nf) for t in range(0, n_tools, per_block)] \
        if per_block >= 1 else _blocks(n)
    for i0, i1 in blocks:
        tool, line = np.divmod(np.arange(i0, i1), nf)
        g = Grid(w[line], scratch, tiling=None if tiling is None else tiling.repeated((i1 - i0) // nf))
        part = tuple(item.take_rows(tool) if item.is_stacked else item for item in stacked)
        k, _ = _carry(part, g, _start_sym(None if s0 is None else s0[line], 0, i1 - i0, real), real)
        _put_sym(out[i0:i1], k)
    return out.reshape(n_tools, nf, 2, 2)


def _carry(part: Chain, grid: Grid, k: Sym, real: bool, count: bool = False) -> tuple[Sym, IntArray]:
    """``k`` carried across the items of ``part`` on ``grid`` (announced first), and with
    ``count`` the negative eigenvalues of the pivots eliminated on the way (zeros without)."""
    for item in part:
        item.announce(grid)
    negatives = np.zeros(grid.omega_rad_s.size, dtype=int)
    if real:
        for item in part:
            k = item.eliminate_undamped(k, grid)
        return k, negatives
    for item in part:
        k, more = item.eliminate(k, grid, count)
        if more is not None:
            negatives += more
    return k, negatives


def _start_sym(start: ComplexArray | FloatArray | None, i0: int, i1: int, real: bool) -> Sym:
    """Rows ``i0:i1`` of a start stiffness (symmetrised), or zeros (a free end)."""
    if start is None:
        zero = np.zeros(i1 - i0, dtype=float if real else complex)
        return zero, zero, zero
    s = start[i0:i1]
    if real:
        s = np.real(s)
    dtype = float if real else complex
    return (np.array(s[:, 0, 0], dtype=dtype), np.array(0.5 * (s[:, 0, 1] + s[:, 1, 0]), dtype=dtype),
            np.array(s[:, 1, 1], dtype=dtype))


def _put_sym(out: np.ndarray, k: Sym) -> None:
    out[:, 0, 0], out[:, 0, 1], out[:, 1, 0], out[:, 1, 1] = k[0], k[1], k[1], k[2]


def tip_receptance(chain: Chain, omega_rad_s: FloatArray, start: ComplexArray | None = None) -> ComplexArray:
    """Point receptance ``[[h, l], [n, p]]`` at the last node, shape (nfreq, 2, 2).

    Parameters
    ----------
    chain : Chain
    omega_rad_s : numpy.ndarray, shape (nfreq,)
        Angular frequencies, rad/s.
    start : numpy.ndarray, shape (nfreq, 2, 2), optional
        Dynamic stiffness attached at the first node (see :func:`march`).

    Returns
    -------
    numpy.ndarray, shape (nfreq, 2, 2), complex
        m/N, m/(N·m), rad/N, rad/(N·m).
    """
    return inv2(march(chain, omega_rad_s, start)[0])


def wittrick_williams_count(chain: Chain, omega_rad_s: FloatArray, start: FloatArray | None = None) -> IntArray:
    """Number of natural frequencies below each ω of an undamped, subdivided chain.

    The chain is taken undamped; it must be subdivided with :func:`subdivide` for at least
    the largest ω, so that no beam has a clamped–clamped natural frequency below it (J₀ = 0).
    ``start`` is the condensed stiffness of a prefix whose own negative pivots the caller adds.

    Parameters
    ----------
    chain : Chain
        Undamped and subdivided (see above).
    omega_rad_s : numpy.ndarray, shape (nfreq,)
        Angular frequencies, rad/s.
    start : numpy.ndarray, shape (nfreq, 2, 2), optional
        Condensed stiffness of a prefix (see above).

    Returns
    -------
    numpy.ndarray of int, shape (nfreq,)
    """
    k, pivots = march_undamped(chain, omega_rad_s, start)
    assert pivots is not None  # count=True
    close(k, pivots)
    return pivots.negatives


def close(k: FloatArray, pivots: Pivots) -> None:
    """Add the final condensed stiffness ``k`` (nfreq, 2, 2) to ``pivots`` as the last pivot.

    Then ``pivots.negatives`` is the Wittrick–Williams count of the chain and
    ``pivots.log_abs_det`` the ``log|det|`` of its whole dynamic stiffness matrix.

    Parameters
    ----------
    k : numpy.ndarray, shape (nfreq, 2, 2), float
        Condensed undamped stiffness at the last node.
    pivots : Pivots
        The pivots of the elimination that gave ``k`` (added to in place).
    """
    k11, k12, k22 = k[:, 0, 0], k[:, 0, 1], k[:, 1, 1]
    pivots.add_sym(k11, k22, k11 * k22 - k12 * k12)


def subdivide(chain: Chain, omega_max_rad_s: float) -> Chain:
    """Split beams into equal pieces with no clamped–clamped natural frequency below ω_max (rad/s).

    Parameters
    ----------
    chain : Chain
        The items, spindle rear to tool tip.
    omega_max_rad_s : float
        Highest angular frequency of interest, rad/s.

    Returns
    -------
    Chain
        The same structure with each beam replaced by its pieces
        (:meth:`rcsa.physics.chain.ChainItem.subdivided`); lumped items unchanged.
    """
    out: list[ChainItem] = []
    for item in chain:
        out.extend(item.subdivided(omega_max_rad_s))
    return tuple(out)


def static_condense(chain: Chain, start: FloatArray | None = None) -> FloatArray:
    """Static (ω = 0) undamped stiffness condensed onto the last node, shape (2, 2).

    Uses the exact static Timoshenko stiffness of each beam
    (:meth:`rcsa.physics.chain.ChainItem.eliminate_static`); ``start`` continues a
    condensation (e.g. a cached spindle + holder).

    Parameters
    ----------
    chain : Chain
    start : numpy.ndarray, shape (2, 2), optional
        Static stiffness already condensed onto the first node; zero (free end) by default.
    """
    out: FloatArray = static_condense_rows(chain, 1, start)[0]
    return out


def static_condense_rows(chain: Chain, rows: int, start: FloatArray | None = None) -> FloatArray:
    """:func:`static_condense` of a chain stacked over ``rows`` rows (or of one chain, repeated).

    Parameters
    ----------
    chain : Chain
        Stacked over ``rows`` rows, or one chain (then every row is the same).
    rows : int
        Number of rows.
    start : numpy.ndarray, shape (2, 2), optional
        Static stiffness at the first node, shared by all rows (e.g. a cached spindle + holder).

    Returns
    -------
    numpy.ndarray, shape (rows, 2, 2)
    """
    if start is None:
        k: Sym = (np.zeros(rows, dtype=complex), np.zeros(rows, dtype=complex), np.zeros(rows, dtype=complex))
    else:
        k = tuple(np.full(rows, complex(start[i, j])) for i, j in ((0, 0), (0, 1), (1, 1)))  # type: ignore[assignment]
    for item in chain:
        k = item.eliminate_static(k)
    out = np.empty((rows, 2, 2))
    k11, k12, k22 = (np.broadcast_to(np.real(x), (rows,)) for x in k)
    out[:, 0, 0], out[:, 0, 1], out[:, 1, 0], out[:, 1, 1] = k11, k12, k12, k22
    return out


def static_tip_receptance(chain: Chain, start: FloatArray | None = None) -> FloatArray | None:
    """Static (ω = 0) undamped point receptance at the last node, shape (2, 2).

    ``None`` when the chain is not grounded (a free body has no static stiffness).

    Parameters
    ----------
    chain : Chain
    start : numpy.ndarray, shape (2, 2), optional
        Static stiffness already condensed onto the first node (as for :func:`static_condense`).
    """
    return static_tip_receptance_rows(static_condense(chain, start)[None])[0]


def static_tip_receptance_rows(k: FloatArray) -> list[FloatArray | None]:
    """Static point receptances from condensed static stiffnesses ``k`` (rows, 2, 2); ``None`` if singular.

    Parameters
    ----------
    k : numpy.ndarray, shape (rows, 2, 2)
        Condensed static stiffnesses (:func:`static_condense_rows`).
    """
    det = k[:, 0, 0] * k[:, 1, 1] - k[:, 0, 1] ** 2
    out: list[FloatArray | None] = []
    for i in range(k.shape[0]):
        if abs(det[i]) <= 1e-12 * max(abs(k[i, 0, 0] * k[i, 1, 1]), 1e-300):
            out.append(None)
        else:
            out.append(np.array([[k[i, 1, 1], -k[i, 0, 1]], [-k[i, 0, 1], k[i, 0, 0]]]) / det[i])
    return out
