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

from rcsa.physics.algebra2x2 import inv2, negative_count_sym, negative_count_sym2
from rcsa.physics.chain import Beam, Chain, Ground, Spring
from rcsa.physics.sections import Section
from rcsa.physics.segments import _Waves, dynamic_stiffness, segment_terms, static_stiffness

__all__ = ["Sym", "beam_step", "march", "spring_step", "static_condense", "static_tip_receptance", "subdivide", "tip_receptance", "wittrick_williams_count"]


_BLOCK = 4096

# A symmetric 2×2 stiffness is carried as its three entries (k11, k12, k22), each (nfreq,).
Sym = tuple[np.ndarray, np.ndarray, np.ndarray]


def _to_sym(k: np.ndarray) -> Sym:
    return (k[:, 0, 0].copy(), 0.5 * (k[:, 0, 1] + k[:, 1, 0]), k[:, 1, 1].copy())


def _from_sym(k: Sym) -> np.ndarray:
    out = np.empty((k[0].size, 2, 2), dtype=complex)
    out[:, 0, 0], out[:, 0, 1], out[:, 1, 0], out[:, 1, 1] = k[0], k[1], k[1], k[2]
    return out


def beam_step(k: Sym, terms: tuple[np.ndarray, ...]) -> tuple[Sym, Sym]:
    """``P = K + D11``; ``K ← D22 − D21 P⁻¹ D12`` with the six-term segment stiffness.

    Parameters
    ----------
    k : Sym
        Dynamic stiffness condensed onto the beam's first node, entries ``(k11, k12, k22)``.
    terms : tuple of numpy.ndarray
        The beam's six stiffness entries ``(A, B, C, E, F, G)``
        (:func:`rcsa.physics.segments.segment_terms`), each shape (nfreq,).
    """
    a, b, c, e, f, g = terms
    p11, p12, p22 = k[0] + a, k[1] + b, k[2] + c
    inv_det = 1.0 / (p11 * p22 - p12 * p12)
    x11 = (p22 * e + p12 * f) * inv_det
    x12 = (p22 * f - p12 * g) * inv_det
    x21 = -(p12 * e + p11 * f) * inv_det
    x22 = (p11 * g - p12 * f) * inv_det
    return (a - (e * x11 - f * x21), -b - (e * x12 - f * x22), c - (f * x12 + g * x22)), (p11, p12, p22)


def spring_step(k: Sym, spring: Spring, omega_rad_s: np.ndarray) -> tuple[Sym, Sym | np.ndarray | None]:
    """Condense across an elastic joint; rigid DOFs are shared by both nodes, not penalised.

    Returns the new ``K`` and the pivot (a symmetric 2×2, a scalar array when one DOF is
    rigid, or None when the joint is rigid).

    Parameters
    ----------
    k : Sym
        Dynamic stiffness condensed onto the joint's first node, entries ``(k11, k12, k22)``.
    spring : Spring
    omega_rad_s : numpy.ndarray, shape (nfreq,)
        Angular frequencies, rad/s.
    """
    kt, kr = spring.translational(omega_rad_s), spring.rotational(omega_rad_s)
    k11, k12, k22 = k
    if kt is None and kr is None:
        return k, None
    # K_new = (K⁻¹ + K_j⁻¹)⁻¹ written as K_j P⁻¹ K (P = K + K_j): no cancellation for stiff joints
    if kt is not None and kr is not None:
        p11, p12, p22 = k11 + kt, k12, k22 + kr
        inv_det = 1.0 / (p11 * p22 - p12 * p12)
        det_k = k11 * k22 - k12 * k12
        return (kt * (det_k + kr * k11) * inv_det, kt * kr * k12 * inv_det,
                kr * (det_k + kt * k22) * inv_det), (p11, p12, p22)
    if kt is not None:  # rotation rigid: eliminate the old node's w only
        p = k11 + kt
        return (kt * k11 / p, kt * k12 / p, k22 - k12 * k12 / p), p
    p = k22 + kr  # translation rigid: eliminate the old node's ψ only
    return (k11 - k12 * k12 / p, kr * k12 / p, kr * k22 / p), p


def _negatives(pivot: Sym | np.ndarray) -> np.ndarray:
    if isinstance(pivot, np.ndarray):
        return (pivot.real < 0).astype(int)
    return negative_count_sym(*pivot)


def _absorb_compliance(chain: Chain, w: np.ndarray, compliance: np.ndarray) -> tuple[np.ndarray, int]:
    """Attach the leading items of ``chain`` to a grounded base given by its compliance ``S``.

    A measured spindle is known as a receptance, possibly rank-deficient (estimated rotations),
    so it is never inverted: joints add compliance, grounds give ``S (I + Δ S)⁻¹``, and the
    first beam turns it into a stiffness ``D22 − D21 S (I + D11 S)⁻¹ D12``.

    Returns the stiffness at the end of the first beam and the number of items consumed.
    """
    s = np.array(compliance, dtype=complex)
    eye = np.eye(2)
    for i, item in enumerate(chain):
        if isinstance(item, Spring):
            s = s + item.compliance(w)
        elif isinstance(item, Ground):
            s = s @ inv2(eye + item.stiffness(w) @ s)
        else:
            d = dynamic_stiffness(w, item.section, item.length_m)
            d11, d12, d21, d22 = d[:, :2, :2], d[:, :2, 2:], d[:, 2:, :2], d[:, 2:, 2:]
            return d22 - d21 @ s @ inv2(eye + d11 @ s) @ d12, i + 1
    raise ValueError("a chain on a measured base must contain at least one beam")


def _per_row(chain: Chain) -> bool:
    """True when some item carries per-frequency-row parameters (a stacked chain)."""
    names = ("length_m", "stiffness_n_m", "damping_ns_m", "rotational_stiffness_nm_rad", "mass_kg")
    return any(np.ndim(getattr(item, n, None)) > 0 for item in chain for n in names)


def _waves(cache: dict[Section, _Waves], w: np.ndarray, section: Section) -> _Waves:
    """Wavenumbers of a section, shared by equal sections; stacked (array) sections are not cached."""
    try:
        hit = cache.get(section)
    except TypeError:  # unhashable: a section stacked over several tools
        return _Waves(w, section)
    if hit is None:
        hit = cache[section] = _Waves(w, section)
    return hit


def march(chain: Chain, omega_rad_s: np.ndarray, start: np.ndarray | None = None,
          count: bool = False, start_compliance: np.ndarray | None = None
          ) -> tuple[np.ndarray, np.ndarray | None]:
    """Condense a chain onto its last node.

    Parameters
    ----------
    chain : Chain
    omega_rad_s : numpy.ndarray, shape (nfreq,)
    start : numpy.ndarray, shape (nfreq, 2, 2), optional
        Dynamic stiffness already attached at the first node (e.g. a condensed spindle, or
        the inverse of a measured base receptance; symmetrised); zero (free end) by default.
    count : bool
        Also return the number of negative pivot eigenvalues per frequency (undamped chains).
    start_compliance : numpy.ndarray, shape (nfreq, 2, 2), optional
        Instead of ``start``: the receptance of a grounded base at the first node (a
        measured spindle), used without inverting it.

    Returns
    -------
    k : numpy.ndarray, shape (nfreq, 2, 2)
        Dynamic stiffness at the last node of everything in the chain (and ``start``).
    negatives : numpy.ndarray of int, shape (nfreq,), or None
        Negative eigenvalues of the eliminated pivots (excluding the returned ``k``).
    """
    w = np.asarray(omega_rad_s, dtype=float)
    if start_compliance is not None:
        start, used = _absorb_compliance(chain, w, start_compliance)
        chain = chain[used:]
    if w.size > _BLOCK and not _per_row(chain):  # blocks of the frequency axis keep temporaries in cache
        parts = [march(chain, w[i:i + _BLOCK], None if start is None else start[i:i + _BLOCK], count)
                 for i in range(0, w.size, _BLOCK)]
        k_all = np.concatenate([p[0] for p in parts])
        return k_all, (np.concatenate([p[1] for p in parts]) if count else None)  # type: ignore[misc]
    if start is None:
        zero = np.zeros(w.size, dtype=complex)
        k: Sym = (zero, zero, zero)
    else:
        k = _to_sym(np.asarray(start, dtype=complex))
    neg = np.zeros(w.size, dtype=int) if count else None
    waves: dict[Section, _Waves] = {}
    for item in chain:
        pivot: Sym | np.ndarray | None = None
        if isinstance(item, Beam):
            k, pivot = beam_step(k, segment_terms(w, item.section, item.length_m, _waves(waves, w, item.section)))
        elif isinstance(item, Spring):
            k, pivot = spring_step(k, item, w)
        elif isinstance(item, Ground):
            g = item.stiffness(w)
            k = (k[0] + g[:, 0, 0], k[1], k[2] + g[:, 1, 1])
        else:  # pragma: no cover - Chain is a closed union
            raise TypeError(f"unknown chain item {item!r}")
        if neg is not None and pivot is not None:
            neg += _negatives(pivot)
    return _from_sym(k), neg


def tip_receptance(chain: Chain, omega_rad_s: np.ndarray, start: np.ndarray | None = None) -> np.ndarray:
    """Point receptance ``[[h, l], [n, p]]`` at the last node, shape (nfreq, 2, 2).

    Parameters
    ----------
    chain : Chain
    omega_rad_s : numpy.ndarray, shape (nfreq,)
        Angular frequencies, rad/s.
    start : numpy.ndarray, shape (nfreq, 2, 2), optional
        Dynamic stiffness already attached at the first node (see :func:`march`).
    """
    return inv2(march(chain, omega_rad_s, start)[0])


def wittrick_williams_count(chain: Chain, omega_rad_s: np.ndarray, start: np.ndarray | None = None) -> np.ndarray:
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
    return neg + negative_count_sym2(k)


def _max_piece_length_m(beam: Beam, omega_rad_s: float) -> float:
    """Longest piece of ``beam`` whose first clamped–clamped frequency certainly exceeds ω.

    Rayleigh quotient bound for w = ψ = 0 at both ends, with Wirtinger's inequality
    ‖u‖² ≤ (ℓ/π)² ‖u'‖² on ψ and on w' = γ + ψ (γ the shear strain)::

        ω₁² ≥ min( κGA / (2ρA u),  EI / (2ρA u² + ρI u) ),    u = (ℓ/π)²

    (for Euler–Bernoulli γ = 0 and the bound is EI / (ρA u² + ρI u)). Stacked (array)
    sections give the shortest piece over all entries.
    """
    s = beam.section
    ei, ra, ri = np.real(s.ei), np.asarray(s.rho_a, dtype=float), np.asarray(s.rho_i, dtype=float)
    w2 = omega_rad_s**2 * 1.0001
    shear_rigid = s.is_euler_bernoulli
    a = ra if shear_rigid else 2.0 * ra
    u = (-ri + np.sqrt(ri * ri + 4.0 * a * ei / w2)) / (2.0 * a)
    if not shear_rigid:
        u = np.minimum(u, np.real(1.0 / np.asarray(s.shear_flexibility)) / (2.0 * ra * w2))
    return float(np.min(math.pi * np.sqrt(u)))


def subdivide(chain: Chain, omega_max_rad_s: float) -> Chain:
    """Split beams into equal pieces with no clamped–clamped natural frequency below ω_max.

    Parameters
    ----------
    chain : Chain
    omega_max_rad_s : float
        Largest angular frequency the subdivided chain will be counted at, rad/s.
    """
    out: list[Beam | Spring | Ground] = []
    for item in chain:
        if isinstance(item, Beam):
            n = max(1, math.ceil(float(np.max(item.length_m)) / _max_piece_length_m(item, omega_max_rad_s)))
            out.extend([Beam(item.section, item.length_m / n)] * n)
        else:
            out.append(item)
    return tuple(out)


def static_condense(chain: Chain, start: np.ndarray | None = None) -> np.ndarray:
    """Static (ω = 0) undamped stiffness condensed onto the last node, shape (2, 2).

    Uses the exact static Timoshenko stiffness of each beam; ``start`` continues a
    condensation (e.g. a cached spindle + holder).

    Parameters
    ----------
    chain : Chain
    start : numpy.ndarray, shape (2, 2), optional
        Static stiffness already condensed onto the first node; zero (free end) by default.
    """
    k: Sym = tuple(np.array([x]) for x in (0.0j, 0.0j, 0.0j)) if start is None else \
        tuple(np.array([complex(start[i, j])]) for i, j in ((0, 0), (0, 1), (1, 1)))  # type: ignore[assignment]
    for item in chain:
        if isinstance(item, Beam):
            d = static_stiffness(item.section.undamped(), item.length_m)
            terms = tuple(np.array([d[i, j]]) for i, j in ((0, 0), (0, 1), (1, 1), (0, 2), (0, 3), (1, 3)))
            k = beam_step(k, terms)[0]  # P = K + D11 is positive definite: K >= 0, D11 > 0
        elif isinstance(item, Spring):
            stiff = Spring(item.stiffness_n_m, 0.0, item.rotational_stiffness_nm_rad, 0.0)
            k = spring_step(k, stiff, np.zeros(1))[0]
        else:
            k = (k[0] + item.stiffness_n_m, k[1], k[2] + item.rotational_stiffness_nm_rad)
    k11, k12, k22 = (float(x[0].real) for x in k)
    return np.array([[k11, k12], [k12, k22]])


def static_tip_receptance(chain: Chain, start: np.ndarray | None = None) -> np.ndarray | None:
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
    return np.array([[k[1, 1], -k[0, 1]], [-k[0, 1], k[0, 0]]]) / det
