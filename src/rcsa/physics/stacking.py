"""Many chains of one structure stacked into one chain with per-row parameters.

Tools of a batch on one spindle differ only in their numbers: stacking them into one chain
whose parameters are arrays (one row per tool, or per tool and frequency) lets the
elimination run over all of them in one vectorised pass. Each item knows its own structure
and how to stack (:class:`rcsa.physics.chain.ChainItem`).
"""

from __future__ import annotations

from collections.abc import Sequence

from rcsa.physics.arrays import IntArray
from rcsa.physics.chain import Chain, ChainItem

__all__ = ["chain_signature", "stack_chains", "take_rows"]


def chain_signature(chain: Chain) -> tuple[tuple[object, ...], ...]:
    """Structure of a chain (item kinds, rigid joint DOFs): chains with equal signatures stack.

    Parameters
    ----------
    chain : Chain
        The items, spindle rear to tool tip.

    Returns
    -------
    tuple of tuple
        Each item's :meth:`~rcsa.physics.chain.ChainItem.signature`.
    """
    return tuple(item.signature() for item in chain)


def stack_chains(chains: Sequence[Chain]) -> Chain:
    """One chain whose parameters are arrays over ``chains`` (which share one signature).

    Parameters
    ----------
    chains : sequence of Chain
        Chains with one :func:`chain_signature` (none, or empty ones, give an empty chain).
    """
    if not chains or not chains[0]:
        return ()
    return tuple(items[0].stack(items) for items in zip(*chains, strict=True))


def take_rows(chain: Chain, rows: IntArray) -> Chain:
    """The stacked chain with its parameter arrays indexed by ``rows`` (one row per frequency).

    Scalar parameters (shared by all rows, e.g. a damping set to zero) are kept as they are.
    An item repeated in the chain (the equal pieces of a subdivided beam) stays one object
    repeated, so the solvers compute its terms once.

    Parameters
    ----------
    chain : Chain
        A chain made by :func:`stack_chains`.
    rows : numpy.ndarray of int, shape (nfreq,)
        Which stacked chain each frequency line uses.
    """
    done: dict[int, ChainItem] = {}
    out = []
    for item in chain:
        hit = done.get(id(item))
        if hit is None:
            hit = done[id(item)] = item.take_rows(rows)
        out.append(hit)
    return tuple(out)
