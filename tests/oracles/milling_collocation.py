"""Stability of milling by spectral-element collocation (an oracle written apart from ``rcsa``).

Nothing here imports ``rcsa``. The cut is the textbook delay equation of regenerative milling
(Altintas, *Manufacturing Automation*, 2nd ed. 2012, §4.4; the conventions of
``tests/oracles/milling_time_domain.py``): tool-point modes in x (feed) and y (normal to the feed),
``q̈ + 2ζω q̇ + ω² q = φ F_dir``, teeth at ``φ_j = Ω t + 2πj/N`` clockwise from +y, cutting while
``φ_st <= φ_j <= φ_ex``; a tooth's dynamic chip is the outward displacement now minus one tooth
period ago, ``v(φ)·(r(t) − r(t − T))`` with ``v = (sin φ, cos φ)``, and it pushes the tool by
``F = K_t b u(φ) v(φ)ᵀ (r(t) − r(t − T))`` with ``u = (−cos φ − K_r sin φ, sin φ − K_r cos φ)``.

The method is not the semi-discretization the product uses: one tooth period is split at every
tooth entry and exit; while no tooth cuts the tool vibrates freely (one exact matrix exponential);
on every stretch where the same teeth cut, the state is a polynomial of degree ``M`` collocated at
``M + 1`` Chebyshev points with the time-varying coefficients evaluated exactly at those points
(spectral elements: Butcher, Bobrenkov, Bueler & Nindujarla, "Analysis of milling stability by the
Chebyshev collocation method", J. Comput. Nonlinear Dynam. 4, 2009; Khasawneh & Mann 2011); a long
stretch is split into elements of degree at most ``MAX_DEGREE``, continuous at their joints. The
delay is one period, so the delayed displacement at a point is the previous period's at the same
point: the period map ``L X = R X_prev`` is square, and its eigenvalues (Floquet multipliers)
converge exponentially in ``M`` where first-order semi-discretization converges as ``1/k²``.

:func:`depth_limit` finds the smallest depth at which the largest multiplier reaches 1: a
geometric scan (so that an unstable island is not stepped over) and a bisection; each answer
comes with the same limit at about 1.4 times the points, and the two must agree
(:class:`Limit`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.linalg import expm

# the same description of a mode (no shared numerics)
from tests.oracles.milling_time_domain import Mode

__all__ = ["Limit", "Mode", "depth_limit", "spectral_radius"]


@dataclass(frozen=True)
class Limit:
    """A depth limit (m): the stable end of a bracket ``[depth_m, unstable_m]`` at ``points_per_cycle``,
    and whether 1.4 times the points put the crossing inside the same bracket widened by ``rtol``.

    Attributes
    ----------
    depth_m, unstable_m : float
    points_per_cycle : float
    finer_agrees : bool
    """

    depth_m: float
    unstable_m: float
    points_per_cycle: float
    finer_agrees: bool


def _angles(immersion: float, milling: str) -> tuple[float, float]:
    if milling == "down":
        return math.acos(2.0 * immersion - 1.0), math.pi
    return 0.0, math.acos(1.0 - 2.0 * immersion)


#: Polynomial degree of one element, at most and at least: Chebyshev differentiation matrices lose
#: accuracy as ``M²`` (a single 230-point element moved the limit by 0.2 %), so a long cut is split.
MAX_DEGREE, MIN_DEGREE = 32, 12


def _cheb(m: int) -> tuple[np.ndarray, np.ndarray]:
    """Chebyshev points ``x_j = cos(πj/m)`` and the differentiation matrix (Trefethen, *Spectral
    Methods in MATLAB*, 2000, ``cheb.m``)."""
    x = np.cos(np.pi * np.arange(m + 1) / m)
    c = np.ones(m + 1)
    c[0] = c[-1] = 2.0
    c *= (-1.0) ** np.arange(m + 1)
    dx = x[:, None] - x[None, :]
    d = np.outer(c, 1.0 / c) / (dx + np.eye(m + 1))
    d -= np.diag(d.sum(axis=1))
    return x, d


def _elements(teeth: int, omega: float, st: float, ex: float) -> list[tuple[float, float, tuple[int, ...]]]:
    """``(start, end, cutting teeth)`` over one tooth period, split at every entry and exit."""
    period = 2.0 * math.pi / (teeth * omega)
    cuts = {0.0, period}
    for j in range(teeth):
        for angle in (st, ex):
            for k in range(-2, teeth + 2):
                t = (angle - 2.0 * math.pi * j / teeth + 2.0 * math.pi * k) / omega
                if 1e-12 * period < t < period * (1 - 1e-12):
                    cuts.add(t)
    edges = sorted(cuts)
    out = []
    for a, b in zip(edges[:-1], edges[1:], strict=True):
        mid = 0.5 * (a + b)
        inside = tuple(j for j in range(teeth)
                       if st <= (omega * mid + 2.0 * math.pi * j / teeth) % (2.0 * math.pi) <= ex)
        out.append((a, b, inside))
    return out


def _model(modes: list[Mode]) -> tuple[np.ndarray, np.ndarray]:
    """The free system matrix (state ``[q; q̇]``) and ``Φ`` (2 × d): displacement per modal coordinate."""
    d = len(modes)
    w = np.array([2.0 * math.pi * m.frequency_hz for m in modes])
    z = np.array([m.damping_ratio for m in modes])
    a0 = np.zeros((2 * d, 2 * d))
    a0[:d, d:] = np.eye(d)
    a0[d:, :d] = -np.diag(w**2)
    a0[d:, d:] = -np.diag(2.0 * z * w)
    phi = np.zeros((2, d))
    for r, m in enumerate(modes):
        phi[m.direction, r] = 1.0 / math.sqrt(m.mass_kg)
    return a0, phi


def _force_matrix(angles: np.ndarray, kr: float) -> np.ndarray:
    """``Σ u vᵀ`` over the cutting teeth at each point, shape (npoints, 2, 2)."""
    s, c = np.sin(angles), np.cos(angles)
    u = np.stack([-c - kr * s, s - kr * c], axis=-1)
    v = np.stack([s, c], axis=-1)
    return np.einsum("pti,ptj->pij", u, v)


def _period_map(modes: list[Mode], teeth: int, kt: float, kr: float, immersion: float, milling: str, rpm: float,
                depth_m: float, points_per_cycle: float) -> tuple[np.ndarray, np.ndarray]:
    """``(L, R)`` of the period map ``L X = R X_prev`` (X: the states at every collocation point)."""
    omega = rpm * 2.0 * math.pi / 60.0
    st, ex = _angles(immersion, milling)
    a0, phi = _model(modes)
    n, d = a0.shape[0], phi.shape[1]
    f_top = max(m.frequency_hz for m in modes)
    elements = _elements(teeth, omega, st, ex)
    cut = []
    for a, b, teeth_in in elements:  # long stretches in elements of at most MAX_DEGREE (conditioning)
        if not teeth_in:
            continue
        pieces = max(1, math.ceil(points_per_cycle * f_top * (b - a) / MAX_DEGREE))
        edges = np.linspace(a, b, pieces + 1)
        cut.extend((float(lo), float(hi), teeth_in) for lo, hi in zip(edges[:-1], edges[1:], strict=True))
    if not cut:
        raise ValueError("no tooth ever cuts")
    sizes = [max(MIN_DEGREE, math.ceil(points_per_cycle * f_top * (b - a))) for a, b, _ in cut]
    offsets = np.concatenate([[0], np.cumsum([(m + 1) * n for m in sizes])]).astype(int)
    total = int(offsets[-1])
    big_l = np.zeros((total, total))
    big_r = np.zeros((total, total))
    # the free flight before each cut stretch (possibly across the period's end)
    for e, ((a, b, teeth_in), m) in enumerate(zip(cut, sizes, strict=True)):
        x, dmat = _cheb(m)
        h = b - a
        t = a + h * (1.0 - x) / 2.0  # 0 → h, in point order
        dt = -(2.0 / h) * dmat
        angles = omega * t[:, None] + 2.0 * math.pi * np.array(teeth_in)[None, :] / teeth
        w = _force_matrix(angles, kr)  # (m+1, 2, 2)
        gain = kt * depth_m * np.einsum("di,pij,je->pde", phi.T, w, phi)  # (m+1, d, d): modal force per q
        base = offsets[e]
        rows = slice(base, base + (m + 1) * n)
        block = np.kron(dt, np.eye(n))
        for p in range(m + 1):  # a loop over collocation points (an oracle)
            a_p = a0.copy()
            a_p[d:, :d] += gain[p]
            block[p * n : (p + 1) * n, p * n : (p + 1) * n] -= a_p
            big_r[base + p * n + d : base + (p + 1) * n, base + p * n : base + p * n + d] = -gain[p]
        big_l[rows, rows] = block
        # the first point: the state where the previous cut stretch ended, carried over the free flight
        r0 = slice(base, base + n)
        big_l[r0, :] = 0.0
        big_r[r0, :] = 0.0
        big_l[r0, base : base + n] = np.eye(n)
        prev = e - 1 if e > 0 else len(cut) - 1
        gap = a - cut[prev][1] if e > 0 else a + (2.0 * math.pi / (teeth * omega) - cut[prev][1])
        carry = expm(a0 * gap) if gap > 0 else np.eye(n)
        end = offsets[prev] + sizes[prev] * n
        target = big_l if e > 0 else big_r
        target[r0, end : end + n] += -carry if e > 0 else carry
    return big_l, big_r


def spectral_radius(modes: list[Mode], teeth: int, kt: float, kr: float, immersion: float, milling: str,
                    rpm: float, depth_m: float, points_per_cycle: float = 10.0) -> float:
    """Largest modulus of the period map's eigenvalues.

    ``R`` acts only through its nonzero columns ``S`` (the delayed displacements and the state the
    previous period ends with): ``L⁻¹R = (L⁻¹R_S) E_Sᵀ`` has the nonzero eigenvalues of the smaller
    ``E_Sᵀ L⁻¹ R_S``.
    """
    big_l, big_r = _period_map(modes, teeth, kt, kr, immersion, milling, rpm, depth_m, points_per_cycle)
    cols = np.flatnonzero(np.any(big_r != 0.0, axis=0))
    small = np.linalg.solve(big_l, big_r[:, cols])[cols]
    return float(np.max(np.abs(np.linalg.eigvals(small))))


def _limit(modes: list[Mode], teeth: int, kt: float, kr: float, immersion: float, milling: str, rpm: float,
           points_per_cycle: float, low_m: float, high_m: float, scan: int, rtol: float) -> tuple[float, float]:
    depths = np.geomspace(low_m, high_m, scan)
    first = None
    for i, b in enumerate(depths):  # upwards until the first unstable depth of the scan
        if spectral_radius(modes, teeth, kt, kr, immersion, milling, rpm, b, points_per_cycle) >= 1.0:
            first = i
            break
    if first is None:
        return math.nan, math.nan
    lo, hi = (depths[first - 1] if first else 0.0), depths[first]
    while hi - lo > rtol * hi:
        mid = 0.5 * (lo + hi) if lo == 0.0 else math.sqrt(lo * hi)
        if spectral_radius(modes, teeth, kt, kr, immersion, milling, rpm, mid, points_per_cycle) >= 1.0:
            hi = mid
        else:
            lo = mid
    return lo, hi


def depth_limit(modes: list[Mode], teeth: int, kt: float, kr: float, immersion: float, milling: str, rpm: float,
                *, low_m: float, high_m: float, points_per_cycle: float = 10.0, scan: int = 40,
                rtol: float = 1e-4, agreement: float = 1e-3) -> Limit:
    """The smallest unstable depth (m, a bracket's stable end, relative width ``rtol``) at one speed,
    searched upwards from ``low_m`` over a geometric scan to ``high_m`` (NaN: stable there), and
    whether 1.4 times the points agree: stable at ``(1 − agreement)·lo``, unstable at
    ``(1 + agreement)·hi``."""
    lo, hi = _limit(modes, teeth, kt, kr, immersion, milling, rpm, points_per_cycle, low_m, high_m, scan, rtol)
    if not math.isfinite(hi):
        return Limit(lo, hi, points_per_cycle, True)
    finer = 1.4 * points_per_cycle
    below = spectral_radius(modes, teeth, kt, kr, immersion, milling, rpm, lo * (1 - agreement), finer) < 1.0
    above = spectral_radius(modes, teeth, kt, kr, immersion, milling, rpm, hi * (1 + agreement), finer) >= 1.0
    return Limit(lo, hi, points_per_cycle, below and above)
