"""Many chains of one structure stacked into one chain with per-row parameters.

Tools of a batch on one spindle differ only in their numbers: stacking them into one chain
whose parameters are arrays (one row per tool, or per tool and frequency) lets the
elimination run over all of them in one vectorised pass.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import fields
from typing import Any

import numpy as np

from rcsa.physics.chain import Beam, Chain, Ground, Spring
from rcsa.physics.sections import Section

__all__ = ["chain_signature", "stack_chains", "take_rows"]


def chain_signature(chain: Chain) -> tuple:
    """Structure of a chain (item kinds, rigid joint DOFs): chains with equal signatures stack.

    Parameters
    ----------
    chain : Chain
    """
    sig = []
    for item in chain:
        if isinstance(item, Spring):
            sig.append(("spring", item.stiffness_n_m is None, item.rotational_stiffness_nm_rad is None))
        else:
            sig.append((type(item).__name__,))
    return tuple(sig)


def stack_chains(chains: Sequence[Chain]) -> Chain:
    """One chain whose parameters are arrays over ``chains`` (which share one signature).

    Parameters
    ----------
    chains : sequence of Chain
        Chains with one :func:`chain_signature` (none, or empty ones, give an empty chain).
    """
    if not chains or not chains[0]:
        return ()
    out: list[Beam | Spring | Ground] = []
    for items in zip(*chains, strict=True):
        first = items[0]
        if isinstance(first, Beam):
            sec = Section(*(np.array([getattr(i.section, f) for i in items]) for f in ("ei", "shear_flexibility",
                                                                                      "rho_a", "rho_i")))
            out.append(Beam(sec, np.array([i.length_m for i in items])))
        else:
            names = [f.name for f in fields(first)]
            values = {n: None if getattr(first, n) is None else np.array([getattr(i, n) for i in items])
                      for n in names}
            out.append(type(first)(**values))
    return tuple(out)


def take_rows(chain: Chain, rows: np.ndarray) -> Chain:
    """The stacked chain with its parameter arrays indexed by ``rows`` (one row per frequency).

    Scalar parameters (shared by all rows, e.g. a damping set to zero) are kept as they are.

    Parameters
    ----------
    chain : Chain
        A chain made by :func:`stack_chains`.
    rows : numpy.ndarray of int, shape (nfreq,)
        Which stacked chain each frequency line uses.
    """

    def pick(value: Any) -> Any:
        return value if value is None or np.ndim(value) == 0 else np.asarray(value)[rows]

    out: list[Beam | Spring | Ground] = []
    for item in chain:
        if isinstance(item, Beam):
            s = item.section
            out.append(Beam(Section(pick(s.ei), pick(s.shear_flexibility), pick(s.rho_a), pick(s.rho_i)),
                            pick(item.length_m)))
        else:
            out.append(type(item)(**{f.name: pick(getattr(item, f.name)) for f in fields(item)}))
    return tuple(out)
