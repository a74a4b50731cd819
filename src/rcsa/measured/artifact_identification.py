"""Identification of the spindle-side 2×2 receptance from translational FRFs on an artifact.

A cylindrical blank (or a standard test holder) of known geometry is clamped in the spindle
and tapped at two points; from the direct and cross FRFs the full 2×2 receptance ``S`` at
the blank's base (including the clamping joint) is recovered exactly (``docs/physics.md`` §4.4):

    R_ae − G_ae = H_ab H_be x11 + (H_ab N_be + L_ab H_be) x12 + L_ab N_be x22,
    X = (R_bb + S)⁻¹,   S = X⁻¹ − R_bb,

linear in the three unknowns of the symmetric ``X`` for the pairs (1,1), (2,1), (2,2)
(three FRFs from one excitation point are rank-deficient, §4.4). A redundant FRF (e.g.
h31) is not used in the fit but predicted from the identified ``S`` as an independent
check. The finite-difference route (Duarte & Ewins 2000; ``P = N²/H``, §4.2) is kept only
as a labelled fallback: it carries a bias of ~12 % of the peak even without noise.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from rcsa.errors import InputError
from rcsa.model.receptance_coupling import free_free_nodes
from rcsa.physics.algebra2x2 import inv2
from rcsa.physics.chain import Beam
from rcsa.physics.materials import BUILTIN_MATERIALS, Material
from rcsa.physics.sections import tube

__all__ = [
    "ArtifactGeometry",
    "artifact_from_meta",
    "finite_difference_slope_weights",
    "identify_exact",
    "identify_exact_many",
    "identify_finite_difference",
]


@dataclass(frozen=True, slots=True)
class ArtifactGeometry:
    """A uniform cylindrical artifact sticking out of its clamp.

    Parameters
    ----------
    diameter_m : float
        Outer diameter, m.
    stickout_m : float
        Free length from the clamp face (the base, where ``S`` is identified) to the tip, m.
    material : Material
    inner_diameter_m : float
        Bore, m (0 for a solid blank).
    """

    diameter_m: float
    stickout_m: float
    material: Material
    inner_diameter_m: float = 0.0

    def receptance(self, omega_rad_s: np.ndarray, points_m: tuple[float, ...]) -> tuple[np.ndarray, list[int]]:
        """Free-free receptance over the base and the measurement points.

        Parameters
        ----------
        omega_rad_s : numpy.ndarray, shape (nfreq,)
            Angular frequencies, rad/s.
        points_m : tuple of float
            Distances from the tip toward the base, m.

        Returns
        -------
        r : numpy.ndarray, shape (nfreq, 2k, 2k)
            Nodes ordered from the base (node 0) to the tip.
        point_nodes : list of int
            Node index of each point.
        """
        xs = sorted({0.0, self.stickout_m, *(self.stickout_m - p for p in points_m)})
        section = tube(self.diameter_m, self.inner_diameter_m, self.material)
        beams = [Beam(section, b - a) for a, b in zip(xs[:-1], xs[1:], strict=True)]
        nodes = [xs.index(self.stickout_m - p) for p in points_m]
        return free_free_nodes(beams, omega_rad_s), nodes


def artifact_from_meta(artifact: Mapping[str, Any]) -> ArtifactGeometry:
    """The artifact geometry from a stored measurement's ``artifact`` description."""
    mat = artifact.get("material", "carbide")
    if isinstance(mat, str):
        if mat not in BUILTIN_MATERIALS:
            raise InputError("artifact.material", f"unknown material {mat!r}; give its properties as an object")
        material = BUILTIN_MATERIALS[mat]
    elif isinstance(mat, Mapping):
        try:
            material = Material(float(mat["youngs_modulus_pa"]), float(mat["poisson_ratio"]),
                                float(mat["density_kg_m3"]), float(mat.get("loss_factor", 0.0)))
        except (KeyError, TypeError, ValueError):
            raise InputError("artifact.material", "needs youngs_modulus_pa, poisson_ratio, density_kg_m3") from None
    else:
        raise InputError("artifact.material", "must be a material name or an object")
    return ArtifactGeometry(float(artifact["diameter_m"]), float(artifact["stickout_m"]), material,
                            float(artifact.get("inner_diameter_m", 0.0)))


def _rows(r: np.ndarray, a: int, e: int) -> tuple[np.ndarray, np.ndarray]:
    """Coefficient row (x11, x12, x22) and left side ``R_ae`` for the pair (a, e); base node 0."""
    wa, we = 2 * a, 2 * e
    h_ab, l_ab = r[:, wa, 0], r[:, wa, 1]
    h_be, n_be = r[:, 0, we], r[:, 1, we]
    coef = np.stack([h_ab * h_be, h_ab * n_be + l_ab * h_be, l_ab * n_be], axis=-1)
    return coef, r[:, wa, we]


def _exact_system(geometry: ArtifactGeometry, points_m: tuple[float, ...], frequency_hz: np.ndarray
                  ) -> tuple[np.ndarray, list[int], np.ndarray, np.ndarray]:
    """Artifact receptance, point nodes, column-scaled 3×3 coefficient matrices and their column norms."""
    omega = 2 * np.pi * np.asarray(frequency_hz, dtype=float)
    r, nodes = geometry.receptance(omega, points_m)
    coef_rows = [_rows(r, nodes[a], nodes[e])[0] for a, e in _PAIRS]
    a_mat = np.stack(coef_rows, axis=1)  # (nfreq, 3, 3)
    scale = np.linalg.norm(a_mat, axis=1, keepdims=True)
    return r, nodes, a_mat / scale, scale


def _solve_exact(r: np.ndarray, nodes: list[int], scaled: np.ndarray, scale: np.ndarray,
                 frfs: Mapping[str, np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    """``S`` and ``x = (x11, x12, x22)`` from FRFs of shape (..., nfreq) (leading axes broadcast)."""
    rhs = [r[:, 2 * nodes[a], 2 * nodes[e]] - np.asarray(frfs[name]) for name, (a, e) in zip(_NAMES, _PAIRS, strict=True)]
    b_vec = np.stack(np.broadcast_arrays(*rhs), axis=-1)  # (..., nfreq, 3)
    x = np.linalg.solve(scaled, b_vec[..., None])[..., 0] / scale[:, 0, :]
    xm = np.empty((*x.shape[:-1], 2, 2), dtype=complex)
    xm[..., 0, 0], xm[..., 0, 1], xm[..., 1, 0], xm[..., 1, 1] = x[..., 0], x[..., 1], x[..., 1], x[..., 2]
    return inv2(xm) - r[:, :2, :2], x


_NAMES = ("h11", "h21", "h22")
_PAIRS = ((0, 0), (1, 0), (1, 1))  # (1,1), (2,1), (2,2) as zero-based point indices


def identify_exact(geometry: ArtifactGeometry, points_m: tuple[float, ...], frequency_hz: np.ndarray,
                   frfs: Mapping[str, np.ndarray]) -> tuple[np.ndarray, dict[str, Any]]:
    """Spindle-side receptance at the artifact base by the exact three-FRF method.

    Parameters
    ----------
    geometry : ArtifactGeometry
    points_m : tuple of float
        Positions of points 1, 2, … from the tip, m.
    frequency_hz : numpy.ndarray, shape (nfreq,)
    frfs : mapping
        ``h11``, ``h21``, ``h22`` (m/N, shape (nfreq,)) and optionally more ``hij`` used as
        independent checks.

    Returns
    -------
    s : numpy.ndarray, shape (nfreq, 2, 2)
        Identified receptance at the base.
    report : dict
        Per-frequency condition numbers of the column-scaled 3×3 system
        (``condition_number``), their median and maximum, and the relative residual of each
        redundant FRF re-predicted from ``s``.
    """
    r, nodes, scaled, scale = _exact_system(geometry, points_m, frequency_hz)
    s, x = _solve_exact(r, nodes, scaled, scale, frfs)
    cond = np.linalg.cond(scaled)
    checks = {}
    for name, values in frfs.items():
        i, j = int(name[1]) - 1, int(name[2]) - 1
        if name in ("h11", "h21", "h22", "h12") or max(i, j) >= len(points_m):
            continue
        c, r_ae = _rows(r, nodes[i], nodes[j])
        predicted = r_ae - np.einsum("fk,fk->f", c, x)
        measured = np.asarray(values)
        checks[name] = float(np.max(np.abs(predicted - measured)) / np.max(np.abs(measured)))
    report = {
        "method": "exact_three_frf",
        "condition_number": cond.tolist(),
        "condition_number_median": float(np.median(cond)),
        "condition_number_max": float(np.max(cond)),
        "redundant_frf_error_of_peak": checks,
    }
    return s, report


def identify_exact_many(geometry: ArtifactGeometry, points_m: tuple[float, ...], frequency_hz: np.ndarray,
                        frfs: Mapping[str, np.ndarray]) -> np.ndarray:
    """:func:`identify_exact` of many sets of FRFs at once (e.g. noise draws), without the report.

    The artifact's receptance and the 3×3 systems are formed once; only the right-hand sides
    differ between the sets.

    Parameters
    ----------
    geometry : ArtifactGeometry
    points_m : tuple of float
    frequency_hz : numpy.ndarray, shape (nfreq,)
    frfs : mapping
        ``h11``, ``h21``, ``h22``, each shape (n, nfreq) (or broadcastable to it), m/N.

    Returns
    -------
    numpy.ndarray, shape (n, nfreq, 2, 2)
    """
    r, nodes, scaled, scale = _exact_system(geometry, points_m, frequency_hz)
    return _solve_exact(r, nodes, scaled, scale, frfs)[0]


def finite_difference_slope_weights(points_m: tuple[float, ...], order: int = 1) -> np.ndarray:
    """Weights ``c`` with ``w'(tip) ≈ Σ c_k w_k`` from points at distances ``points_m`` from the tip.

    The axis points toward the tip, so a point at distance p sits at x = x₁ − (p − p₁).
    ``order`` 1 uses two points (best at a free end, ``docs/physics.md`` §4.6), 2 uses three
    (Lagrange weights for unequal spacing, e.g. the 0/55/90 mm points of a tap test).
    """
    x = -(np.asarray(points_m[:order + 1], dtype=float) - points_m[0])
    if x.size != order + 1:
        raise InputError("points_m", f"finite differences of order {order} need {order + 1} points")
    weights = np.zeros(x.size)
    for k in range(x.size):  # derivative at x[0] of the Lagrange basis polynomial ℓ_k
        others = np.delete(x, k)
        denom = np.prod(x[k] - others)
        weights[k] = sum(np.prod([x[0] - o for o in others if o != m]) for m in others) / denom
    return weights


def identify_finite_difference(geometry: ArtifactGeometry, points_m: tuple[float, ...],
                               frequency_hz: np.ndarray, frfs: Mapping[str, np.ndarray],
                               order: int = 1) -> tuple[np.ndarray, dict[str, Any]]:
    """Labelled fallback: FD rotation at point 1, ``P = N²/H``, then inverse RCSA to the base.

    ``N11 ≈ Σ c_k H_k1`` (:func:`finite_difference_slope_weights`), ``L11 = N11``,
    ``P11 ≈ N11²/H11`` (exact only for a single mode), ``S = R_b1 (R_11 − G_11)⁻¹ R_1b − R_bb``.

    Returns
    -------
    s : numpy.ndarray, shape (nfreq, 2, 2)
    report : dict
    """
    omega = 2 * np.pi * np.asarray(frequency_hz, dtype=float)
    r, nodes = geometry.receptance(omega, points_m)
    c = finite_difference_slope_weights(points_m, order)
    names = ["h11", "h21", "h31"][:order + 1]
    missing = [n for n in names if n not in frfs]
    if missing:
        raise InputError("frfs", f"finite differences of order {order} need {', '.join(names)}")
    h11 = np.asarray(frfs["h11"])
    n11 = sum(ck * np.asarray(frfs[n]) for ck, n in zip(c, names, strict=True))
    g11 = np.empty((omega.size, 2, 2), dtype=complex)
    g11[:, 0, 0], g11[:, 0, 1], g11[:, 1, 0], g11[:, 1, 1] = h11, n11, n11, n11**2 / h11
    p = 2 * nodes[0]
    r11 = r[:, p:p + 2, p:p + 2]
    r1b, rb1 = r[:, p:p + 2, :2], r[:, :2, p:p + 2]
    s = rb1 @ inv2(r11 - g11) @ r1b - r[:, :2, :2]
    return s, {"method": "finite_difference_fallback", "order": order,
               "warning": "rotations by finite differences and P = N²/H: biased (≈12 % of peak in "
                          "docs/physics.md §4.6 even without noise); use the exact three-FRF method when h22 exists"}
