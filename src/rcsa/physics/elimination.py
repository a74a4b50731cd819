"""Exact dynamic-stiffness solution of a chain by block elimination along the axis.

The global dynamic stiffness of a chain is block tridiagonal (2 DOFs per node). Eliminating
the nodes one after the other from the spindle rear keeps only a 2×2 "stiffness seen from
the right" ``K`` and costs a few 2×2 operations per item and frequency::

    beam   (D = [[D11, D12], [D21, D22]]):   P = K + D11;   K ← D22 − D21 P⁻¹ D12
    spring (K_j):                            P = K + K_j;   K ← K_j − K_j P⁻¹ K_j
    ground (Δ):                              K ← K + Δ

Each step is the item's own (:meth:`rcsa.physics.chain.ChainItem.eliminate`); this module
only runs them. At the tool tip the point receptance is ``K⁻¹``. This is the ``domain.md`` §3.5 global
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

from rcsa.physics.algebra2x2 import inv2, negative_count_sym2
from rcsa.physics.arrays import ComplexArray, FloatArray, IntArray
from rcsa.physics.chain import Chain, ChainItem, Grid, Sym

__all__ = ["march", "static_condense", "static_tip_receptance", "subdivide", "tip_receptance",
           "wittrick_williams_count"]


_BLOCK = 4096


def _to_sym(k: ComplexArray) -> Sym:
    return (k[:, 0, 0].copy(), 0.5 * (k[:, 0, 1] + k[:, 1, 0]), k[:, 1, 1].copy())


def _from_sym(k: Sym) -> ComplexArray:
    out = np.empty((k[0].size, 2, 2), dtype=complex)
    out[:, 0, 0], out[:, 0, 1], out[:, 1, 0], out[:, 1, 1] = k[0], k[1], k[1], k[2]
    return out


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

    Each item carries the stiffness across itself (:meth:`rcsa.physics.chain.ChainItem.eliminate`).

    Parameters
    ----------
    chain : Chain
    omega_rad_s : numpy.ndarray, shape (nfreq,)
        Angular frequencies, rad/s.
    start : numpy.ndarray, shape (nfreq, 2, 2), optional
        Dynamic stiffness already attached at the first node (e.g. a condensed spindle, or
        the inverse of a measured base receptance; symmetrised); zero (free end) by default.
    count : bool
        Also return the number of negative pivot eigenvalues per frequency (undamped chains).
    start_compliance : numpy.ndarray, shape (nfreq, 2, 2), optional
        Instead of ``start``: the receptance of a grounded base at the first node (a
        measured spindle), used without inverting it.
    grid : Grid, optional
        The grid of ``omega_rad_s`` with what it caches across calls (e.g. the diagnosis's
        beam terms); by default a fresh one per call. Given a grid, the frequency axis is
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
    if grid is None and w.size > _BLOCK and not any(item.is_stacked for item in chain):
        # blocks of the frequency axis keep temporaries in cache
        parts = [march(chain, w[i:i + _BLOCK], None if start is None else start[i:i + _BLOCK], count)
                 for i in range(0, w.size, _BLOCK)]
        k_all = np.concatenate([p[0] for p in parts])
        return k_all, (np.concatenate([p[1] for p in parts if p[1] is not None]) if count else None)
    grid = Grid(w) if grid is None else grid
    if start is None:
        zero = np.zeros(w.size, dtype=complex)
        k: Sym = (zero, zero, zero)
    else:
        k = _to_sym(np.asarray(start, dtype=complex))
    neg = np.zeros(w.size, dtype=int) if count else None
    for item in chain:
        k, negatives = item.eliminate(k, grid, count)
        if neg is not None and negatives is not None:
            neg += negatives
    return _from_sym(k), neg


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


def wittrick_williams_count(chain: Chain, omega_rad_s: FloatArray, start: ComplexArray | None = None) -> IntArray:
    """Number of natural frequencies below each ω of an undamped, subdivided chain.

    The chain must be real (undamped) and subdivided with :func:`subdivide` for at least the
    largest ω, so that no beam has a clamped–clamped natural frequency below it (J₀ = 0).
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
    k, neg = march(chain, omega_rad_s, start, count=True)
    assert neg is not None  # count=True
    return neg + negative_count_sym2(k)


def subdivide(chain: Chain, omega_max_rad_s: float) -> Chain:
    """Split beams into equal pieces with no clamped–clamped natural frequency below ω_max (rad/s)."""
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
    if start is None:
        k: Sym = (np.array([0.0j]), np.array([0.0j]), np.array([0.0j]))
    else:
        k = (np.array([complex(start[0, 0])]), np.array([complex(start[0, 1])]), np.array([complex(start[1, 1])]))
    for item in chain:
        k = item.eliminate_static(k)
    k11, k12, k22 = (float(x[0].real) for x in k)
    return np.array([[k11, k12], [k12, k22]])


def static_tip_receptance(chain: Chain, start: FloatArray | None = None) -> FloatArray | None:
    """Static (ω = 0) undamped point receptance at the last node, shape (2, 2).

    ``None`` when the chain is not grounded (a free body has no static stiffness).

    Parameters
    ----------
    chain : Chain
    start : numpy.ndarray, shape (2, 2), optional
        Static stiffness already condensed onto the first node (as for :func:`static_condense`).
    """
    k = static_condense(chain, start)
    det = k[0, 0] * k[1, 1] - k[0, 1] ** 2
    if abs(det) <= 1e-12 * max(abs(k[0, 0] * k[1, 1]), 1e-300):
        return None
    out: FloatArray = np.array([[k[1, 1], -k[0, 1]], [-k[0, 1], k[0, 0]]]) / det
    return out
