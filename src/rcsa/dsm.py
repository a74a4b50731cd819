"""Exact dynamic-stiffness solution of a chain by block elimination along the axis.

The global dynamic stiffness of a chain is block tridiagonal (2 DOFs per node). Eliminating
the nodes one after the other from the spindle rear keeps only a 2×2 "stiffness seen from
the right" ``K`` and costs a few 2×2 operations per item and frequency::

    beam   (D = [[D11, D12], [D21, D22]]):   P = K + D11;   K ← D22 − D21 P⁻¹ D12
    spring (K_j):                            P = K + K_j;   K ← K_j − K_j P⁻¹ K_j
    ground (Δ):                              K ← K + Δ

At the tool tip the point receptance is ``K⁻¹``. This is the ``domain.md`` §3.5 global
dynamic-stiffness assembly (mathematically identical to receptance coupling, accurate down
to very low frequency), done without forming the global matrix.

The same elimination counts eigenvalues: by Sylvester's law of inertia the number of
negative eigenvalues of the real symmetric global matrix is the sum over the pivots ``P``
and the final ``K``. With every beam short enough to have no clamped–clamped natural
frequency below ω (:func:`subdivide`), that sum is the Wittrick–Williams count ``J(ω)`` of
natural frequencies below ω (Wittrick & Williams, Q. J. Mech. Appl. Math. 24 (1971) 263).
"""

from __future__ import annotations

import math

import numpy as np

from .beams import dynamic_stiffness, static_stiffness
from .chain import Beam, Chain, Ground, Spring
from .linalg2 import inv2, negative_count_sym2

__all__ = ["march", "static_tip_receptance", "subdivide", "tip_receptance", "wittrick_williams_count"]


def _beam_step(k: np.ndarray, d: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    p = k + d[:, :2, :2]
    pi = inv2(p)
    return d[:, 2:, 2:] - d[:, 2:, :2] @ pi @ d[:, :2, 2:], p


def _spring_step(k: np.ndarray, spring: Spring, omega_rad_s: np.ndarray
                 ) -> tuple[np.ndarray, np.ndarray | None]:
    """Condense across an elastic joint; rigid DOFs are shared, not penalised.

    Returns the new ``K`` and the pivot (2×2, 1×1 as (n,1,1), or None when fully rigid).
    """
    kt, kr = spring.translational(omega_rad_s), spring.rotational(omega_rad_s)
    if kt is None and kr is None:
        return k, None
    if kt is not None and kr is not None:
        kj = np.zeros_like(k)
        kj[:, 0, 0], kj[:, 1, 1] = kt, kr
        p = k + kj
        return kj - kj @ inv2(p) @ kj, p
    # One DOF elastic (index e), the other rigid (index r, shared by both nodes).
    e, kv = (0, kt) if kt is not None else (1, kr)
    r = 1 - e
    p = k[:, e, e] + kv
    out = np.empty_like(k)
    out[:, e, e] = kv - kv * kv / p
    out[:, e, r] = kv * k[:, e, r] / p
    out[:, r, e] = k[:, r, e] * kv / p
    out[:, r, r] = k[:, r, r] - k[:, r, e] * k[:, e, r] / p
    return out, p[:, None, None]


def march(chain: Chain, omega_rad_s: np.ndarray, start: np.ndarray | None = None,
          count: bool = False) -> tuple[np.ndarray, np.ndarray | None]:
    """Condense a chain onto its last node.

    Parameters
    ----------
    chain : Chain
    omega_rad_s : numpy.ndarray, shape (nfreq,)
    start : numpy.ndarray, shape (nfreq, 2, 2), optional
        Dynamic stiffness already attached at the first node (e.g. a condensed spindle, or
        the inverse of a measured base receptance); zero (free end) by default.
    count : bool
        Also return the number of negative pivot eigenvalues per frequency (undamped chains).

    Returns
    -------
    k : numpy.ndarray, shape (nfreq, 2, 2)
        Dynamic stiffness at the last node of everything in the chain (and ``start``).
    negatives : numpy.ndarray of int, shape (nfreq,), or None
        Negative eigenvalues of the eliminated pivots (excluding the returned ``k``).
    """
    w = np.asarray(omega_rad_s, dtype=float)
    k = np.zeros((w.size, 2, 2), dtype=complex) if start is None else np.array(start, dtype=complex)
    neg = np.zeros(w.size, dtype=int) if count else None
    for item in chain:
        pivot = None
        if isinstance(item, Beam):
            k, pivot = _beam_step(k, dynamic_stiffness(w, item.section, item.length_m))
        elif isinstance(item, Spring):
            k, pivot = _spring_step(k, item, w)
        elif isinstance(item, Ground):
            k = k + item.stiffness(w)
        else:  # pragma: no cover - Chain is a closed union
            raise TypeError(f"unknown chain item {item!r}")
        if count and pivot is not None:
            neg += _negatives(pivot)
    return k, neg


def _negatives(pivot: np.ndarray) -> np.ndarray:
    if pivot.shape[-1] == 1:
        return (pivot[:, 0, 0].real < 0).astype(int)
    return negative_count_sym2(pivot)


def tip_receptance(chain: Chain, omega_rad_s: np.ndarray, start: np.ndarray | None = None) -> np.ndarray:
    """Point receptance ``[[h, l], [n, p]]`` at the last node, shape (nfreq, 2, 2)."""
    return inv2(march(chain, omega_rad_s, start)[0])


def wittrick_williams_count(chain: Chain, omega_rad_s: np.ndarray) -> np.ndarray:
    """Number of natural frequencies below each ω of an undamped, subdivided chain.

    The chain must be real (undamped) and subdivided with :func:`subdivide` for at least the
    largest ω, so that no beam has a clamped–clamped natural frequency below it (J₀ = 0).

    Returns
    -------
    numpy.ndarray of int, shape (nfreq,)
    """
    k, neg = march(chain, omega_rad_s, count=True)
    return neg + negative_count_sym2(k)


def _max_piece_length_m(beam: Beam, omega_rad_s: float) -> float:
    """Longest piece of ``beam`` whose first clamped–clamped frequency certainly exceeds ω.

    Rayleigh quotient bound for w = ψ = 0 at both ends, with Wirtinger's inequality
    ‖u‖² ≤ (ℓ/π)² ‖u'‖² on ψ and on w' = γ + ψ (γ the shear strain)::

        ω₁² ≥ min( κGA / (2ρA u),  EI / (2ρA u² + ρI u) ),    u = (ℓ/π)²

    (for Euler–Bernoulli γ = 0 and the bound is EI / (ρA u² + ρI u)).
    """
    s = beam.section
    ei, ra, ri = s.ei.real, s.rho_a, s.rho_i
    w2 = omega_rad_s**2 * 1.0001
    shear_rigid = s.shear_flexibility == 0
    a = ra if shear_rigid else 2.0 * ra
    u = (-ri + math.sqrt(ri * ri + 4.0 * a * ei / w2)) / (2.0 * a)
    if not shear_rigid:
        u = min(u, (1.0 / s.shear_flexibility.real) / (2.0 * ra * w2))
    return math.pi * math.sqrt(u)


def subdivide(chain: Chain, omega_max_rad_s: float) -> Chain:
    """Split beams into equal pieces with no clamped–clamped natural frequency below ω_max."""
    out: list[Beam | Spring | Ground] = []
    for item in chain:
        if isinstance(item, Beam):
            n = max(1, math.ceil(item.length_m / _max_piece_length_m(item, omega_max_rad_s)))
            out.extend([Beam(item.section, item.length_m / n)] * n)
        else:
            out.append(item)
    return tuple(out)


def static_tip_receptance(chain: Chain) -> np.ndarray | None:
    """Static (ω = 0) undamped point receptance at the last node, shape (2, 2).

    Uses the exact static Timoshenko stiffness of each beam; ``None`` when the chain is not
    grounded (a free body has no static stiffness).
    """
    k = np.zeros((1, 2, 2))
    for item in chain:
        if isinstance(item, Beam):
            d = static_stiffness(item.section.undamped(), item.length_m).real[None]
            k = _beam_step(k, d)[0]  # P = K + D11 is positive definite: K ≥ 0, D11 > 0
        elif isinstance(item, Spring):
            stiff = Spring(item.stiffness_n_m, 0.0, item.rotational_stiffness_nm_rad, 0.0)
            k = _spring_step(k.astype(complex), stiff, np.zeros(1))[0].real
        else:
            k = k + np.diag([item.stiffness_n_m, item.rotational_stiffness_nm_rad])[None]
    det = np.linalg.det(k[0])
    scale = max(abs(k[0, 0, 0]) * abs(k[0, 1, 1]), 1e-300)
    if abs(det) <= 1e-12 * scale:
        return None
    return np.linalg.inv(k[0])
