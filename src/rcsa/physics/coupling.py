"""Receptance coupling as small pure functions over a leading frequency axis.

One general formula covers every case (``docs/physics.md`` §3.1, Lagrange-multiplier
frequency-based substructuring; de Klerk, Rixen & Voormeeren 2008)::

    G = Y − Y Bᵀ (B Y Bᵀ + K⁻¹)⁻¹ B Y        (K⁻¹ = 0 for a rigid joint)

with ``Y`` the block diagonal of the free substructures' receptances and ``B`` the signed
Boolean matrix of the interface pairs. The paper's forms are special cases and are written
out below for readability and speed:

* :func:`couple` — two two-end components, elastic or rigid joint (§3.1 special cases);
* :func:`couple_to_base` — a two-end component on a grounded receptance (Budak/Ertürk
  ``SH22 = H22 − H21 (H11 + K⁻¹ + S)⁻¹ H12``, §3.3);
* :func:`modify` — Özgüven's structural modification (bearings, masks, masses; §3.4);
* :func:`decouple_base` — inverse RCSA, the base receptance from a coupled one (§4.3).

All arrays are frequency-first: ``(nfreq, k, k)`` complex.
"""

from __future__ import annotations

import numpy as np

from rcsa.physics.algebra2x2 import inv2
from rcsa.physics.arrays import ComplexArray, FloatArray, IntArray

__all__ = ["couple", "couple_general", "couple_to_base", "decouple_base", "modify"]


def couple_general(y: ComplexArray, b: FloatArray, k_inv: ComplexArray | None = None) -> ComplexArray:
    """Coupled receptance ``G = Y − Y Bᵀ (B Y Bᵀ + K⁻¹)⁻¹ B Y``.

    Parameters
    ----------
    y : numpy.ndarray, shape (nfreq, ndof, ndof)
        Block diagonal receptance of the uncoupled substructures.
    b : numpy.ndarray, shape (nint, ndof)
        Signed Boolean interface matrix: each row ``+1`` at DOF a, ``−1`` at DOF b.
    k_inv : numpy.ndarray, shape (nfreq, nint, nint), optional
        Joint compliance; ``None`` (or zeros) for rigid joints.

    Returns
    -------
    numpy.ndarray, shape (nfreq, ndof, ndof)
    """
    yb = y @ b.T
    z = b @ yb
    if k_inv is not None:
        z = z + k_inv
    out: ComplexArray = y - yb @ np.linalg.solve(z, b @ y)
    return out


def couple(a: ComplexArray, b: ComplexArray, joint_compliance: ComplexArray | None = None) -> ComplexArray:
    """Couple end 2 of ``a`` to end 1 of ``b``; keep ``a``'s end 1 and ``b``'s end 2.

    ``Z = A22 + B11 + K⁻¹``; ``G11 = A11 − A12 Z⁻¹ A21``, ``G12 = A12 Z⁻¹ B12``,
    ``G21 = B21 Z⁻¹ A21``, ``G22 = B22 − B21 Z⁻¹ B12`` (``docs/physics.md`` §3.1).

    Parameters
    ----------
    a, b : numpy.ndarray, shape (nfreq, 4, 4)
        Two-end receptances ordered ``(w1, ψ1, w2, ψ2)``.
    joint_compliance : numpy.ndarray, shape (nfreq, 2, 2), optional
        ``K⁻¹`` of the joint; ``None`` for a rigid joint.

    Returns
    -------
    numpy.ndarray, shape (nfreq, 4, 4)
    """
    a11, a12, a21, a22 = a[:, :2, :2], a[:, :2, 2:], a[:, 2:, :2], a[:, 2:, 2:]
    b11, b12, b21, b22 = b[:, :2, :2], b[:, :2, 2:], b[:, 2:, :2], b[:, 2:, 2:]
    z = a22 + b11
    if joint_compliance is not None:
        z = z + joint_compliance
    zi = inv2(z)
    out = np.empty_like(a)
    out[:, :2, :2] = a11 - a12 @ zi @ a21
    out[:, :2, 2:] = a12 @ zi @ b12
    out[:, 2:, :2] = b21 @ zi @ a21
    out[:, 2:, 2:] = b22 - b21 @ zi @ b12
    return out


def couple_to_base(a: ComplexArray, base: ComplexArray,
                   joint_compliance: ComplexArray | None = None) -> ComplexArray:
    """Receptance at end 2 of ``a`` once its end 1 sits on a grounded ``base``.

    ``G22 = A22 − A21 (A11 + K⁻¹ + S)⁻¹ A12`` — the Budak/Ertürk form (``docs/physics.md`` §3.3).

    Parameters
    ----------
    a : numpy.ndarray, shape (nfreq, 4, 4)
        Free-free two-end receptance of the added component.
    base : numpy.ndarray, shape (nfreq, 2, 2)
        Receptance ``S`` of the grounded structure at the coupling point.
    joint_compliance : numpy.ndarray, shape (nfreq, 2, 2), optional

    Returns
    -------
    numpy.ndarray, shape (nfreq, 2, 2)
    """
    z = a[:, :2, :2] + base
    if joint_compliance is not None:
        z = z + joint_compliance
    out: ComplexArray = a[:, 2:, 2:] - a[:, 2:, :2] @ inv2(z) @ a[:, :2, 2:]
    return out


def modify(y: ComplexArray, dofs: list[int] | IntArray, delta: ComplexArray) -> ComplexArray:
    """Özgüven's FRF-based structural modification.

    ``G = Y − Y[:, m] Δ (I + Y[m, m] Δ)⁻¹ Y[m, :]`` for a modification of dynamic stiffness
    ``Δ`` on the DOF set ``m`` (springs to ground: ``Δ = k + iωc``; lumped mass: ``−ω²m``).
    No inverse of ``Δ`` is needed, so rigid-body and zero entries are fine.

    Parameters
    ----------
    y : numpy.ndarray, shape (nfreq, ndof, ndof)
    dofs : sequence of int
        The modified DOFs ``m``.
    delta : numpy.ndarray, shape (nfreq, len(m), len(m))

    Returns
    -------
    numpy.ndarray, shape (nfreq, ndof, ndof)

    References
    ----------
    H.N. Özgüven, Mech. Syst. Signal Process. 4 (1990) 53–63.
    """
    m = np.asarray(dofs, dtype=int)
    y_cm = y[:, :, m]
    y_mm = y[:, m[:, None], m[None, :]]
    eye = np.eye(m.size)
    out: ComplexArray = y - y_cm @ delta @ np.linalg.solve(eye + y_mm @ delta, y[:, m, :])
    return out


def decouple_base(a: ComplexArray, coupled_tip: ComplexArray,
                  joint_compliance: ComplexArray | None = None) -> ComplexArray:
    """Inverse RCSA: the base receptance ``S`` from a measured/computed tip receptance ``G22``.

    Inverts :func:`couple_to_base`: ``S = A12 (A22 − G22)⁻¹ A21 − A11 − K⁻¹``
    (``docs/physics.md`` §4.3; rearranged from ``G22 = A22 − A21 (A11 + K⁻¹ + S)⁻¹ A12``).

    Parameters
    ----------
    a : numpy.ndarray, shape (nfreq, 4, 4)
        Free-free receptance of the known component (end 1 on the base, end 2 = tip).
    coupled_tip : numpy.ndarray, shape (nfreq, 2, 2)
    joint_compliance : numpy.ndarray, shape (nfreq, 2, 2), optional

    Returns
    -------
    numpy.ndarray, shape (nfreq, 2, 2)
    """
    s: ComplexArray = a[:, :2, 2:] @ inv2(a[:, 2:, 2:] - coupled_tip) @ a[:, 2:, :2] - a[:, :2, :2]
    if joint_compliance is not None:
        s = s - joint_compliance
    return s
