"""The elimination step written plainly: assemble, constrain, condense — a reference for the fast one.

:func:`rcsa.physics.elimination.march` carries a 2×2 stiffness ``K`` along the chain with
hand-unrolled 2×2 algebra in reused work arrays (each item's ``eliminate``). This module does
the same mathematics the way a textbook writes it, with whole ``(nfreq, 2, 2)`` and
``(nfreq, 4, 4)`` numpy matrices and ``numpy.linalg.solve``, no work arrays and no special
cases beyond the items' own definitions. It is slow and only there to be read and to test the
fast solver against (``tests/physics/test_elimination_reference.py``: equal to 1e-12 on random
chains).

One step, for an item between the current node ``a`` and a new node ``b``:

1. **assemble** the 4×4 stiffness of the DOFs ``(w_a, ψ_a, w_b, ψ_b)``: the carried ``K`` on
   node ``a`` plus the item's element stiffness ``E`` — a beam's exact dynamic stiffness
   (:func:`rcsa.physics.segments.dynamic_stiffness`), or a joint's ``[[K_j, −K_j], [−K_j,
   K_j]]`` with ``K_j = diag(k_t + iωc_t, k_r + iωc_r)``;
2. **constrain** a rigid joint DOF (``None`` stiffness): ``a`` and ``b`` share it, which is
   ``Tᵀ A T`` with the matrix ``T`` that maps the remaining DOFs onto the four;
3. **condense** the DOFs of node ``a`` that remain: ``K ← A_bb − A_ba A_aa⁻¹ A_ab``.

A grounded item (bearing, lumped mass) has no second node: ``K ← K + Δ``. At the tool tip the
point receptance is ``K⁻¹`` (docs/physics.md conventions: ``[[h, l], [n, p]]``, e^{iωt}).
"""

from __future__ import annotations

import numpy as np

from rcsa.physics.arrays import ComplexArray, FloatArray
from rcsa.physics.chain import Beam, Chain, ChainItem, Ground, Spring
from rcsa.physics.segments import dynamic_stiffness

__all__ = ["reference_march", "reference_step", "reference_tip_receptance"]


def _joint_element(item: Spring, omega_rad_s: FloatArray) -> tuple[ComplexArray, tuple[int, ...]]:
    """``[[K_j, −K_j], [−K_j, K_j]]`` (rigid DOFs left at zero) and the rigid DOFs (0: w, 1: ψ)."""
    n = omega_rad_s.size
    kj = np.zeros((n, 2, 2), dtype=complex)
    rigid = []
    for dof, value in enumerate((item.translational(omega_rad_s), item.rotational(omega_rad_s))):
        if value is None:
            rigid.append(dof)
        else:
            kj[:, dof, dof] = value
    e = np.block([[kj, -kj], [-kj, kj]]) if n else np.zeros((0, 4, 4), dtype=complex)
    return e, tuple(rigid)


def reference_step(k: ComplexArray, item: ChainItem, omega_rad_s: FloatArray) -> ComplexArray:
    """The stiffness at the far node of ``item``, given ``k`` at its near node.

    Parameters
    ----------
    k : numpy.ndarray, shape (nfreq, 2, 2), complex
        Stiffness carried onto the item's first node (N/m, N/rad, N·m/rad).
    item : Beam, Spring or Ground
    omega_rad_s : numpy.ndarray, shape (nfreq,)
        Angular frequencies, rad/s.

    Returns
    -------
    numpy.ndarray, shape (nfreq, 2, 2), complex
        A new array.
    """
    w = np.asarray(omega_rad_s, dtype=float)
    if isinstance(item, Ground):
        return k + item.stiffness(w)
    rigid: tuple[int, ...] = ()
    if isinstance(item, Beam):
        element = dynamic_stiffness(w, item.section, item.length_m)
    elif isinstance(item, Spring):
        element, rigid = _joint_element(item, w)
    else:
        raise TypeError(f"no reference step for {type(item).__name__}")
    assembled = element.astype(complex)                       # 1. assemble (w_a, ψ_a, w_b, ψ_b)
    assembled[:, :2, :2] += k
    kept = [dof for dof in (0, 1) if dof not in rigid] + [2, 3]
    t = np.zeros((4, len(kept)))                              # 2. constrain: a rigid DOF of a is b's
    for col, dof in enumerate(kept):
        t[dof, col] = 1.0
    for dof in rigid:
        t[dof, kept.index(dof + 2)] = 1.0
    a = t.T @ assembled @ t
    m = len(kept) - 2                                         # 3. condense what remains of node a
    if m == 0:
        out: ComplexArray = a[:, m:, m:]
        return out
    a_aa, a_ab, a_ba, a_bb = a[:, :m, :m], a[:, :m, m:], a[:, m:, :m], a[:, m:, m:]
    out = a_bb - a_ba @ np.linalg.solve(a_aa, a_ab)
    return out


def reference_march(chain: Chain, omega_rad_s: FloatArray, start: ComplexArray | None = None) -> ComplexArray:
    """Condense a whole chain onto its last node, one :func:`reference_step` after the other.

    Parameters
    ----------
    chain : Chain
        Beams, springs and grounds.
    omega_rad_s : numpy.ndarray, shape (nfreq,)
        Angular frequencies, rad/s.
    start : numpy.ndarray, shape (nfreq, 2, 2), optional
        Stiffness attached at the first node; zero (a free end) by default.

    Returns
    -------
    numpy.ndarray, shape (nfreq, 2, 2), complex
    """
    w = np.asarray(omega_rad_s, dtype=float)
    k = np.zeros((w.size, 2, 2), dtype=complex) if start is None else np.array(start, dtype=complex)
    for item in chain:
        k = reference_step(k, item, w)
    return k


def reference_tip_receptance(chain: Chain, omega_rad_s: FloatArray, start: ComplexArray | None = None
                             ) -> ComplexArray:
    """Point receptance ``[[h, l], [n, p]]`` at the last node: ``K⁻¹`` of :func:`reference_march`.

    Parameters
    ----------
    chain : Chain
    omega_rad_s : numpy.ndarray, shape (nfreq,)
        Angular frequencies, rad/s.
    start : numpy.ndarray, shape (nfreq, 2, 2), optional
        Stiffness attached at the first node.

    Returns
    -------
    numpy.ndarray, shape (nfreq, 2, 2), complex
        m/N, 1/N, rad/N, rad/(N·m).
    """
    return np.linalg.inv(reference_march(chain, omega_rad_s, start))
