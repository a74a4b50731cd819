"""Two vectorised numpy FRFs: the yardsticks of ``bench_engine.py`` (not library code).

* :func:`tip_receptance` — what one would write first with numpy, vectorised over frequency:
  every beam's exact Timoshenko dynamic stiffness as a (nfreq, 4, 4) array (closed form from
  the transfer matrix, ``docs/physics.md`` §2.3–2.4), joints and bearings added in, the global
  dynamic stiffness assembled as (nfreq, N, N) and ``np.linalg.solve`` for the tip's two DOFs.
* :func:`block_sweep_receptance` — the stronger one: the same beam stiffnesses, but the
  chain swept from the spindle's rear to the tip as 2×2 blocks (static condensation of each
  item's first node, Schur complement ``K' = D22 − D21 (K + D11)⁻¹ D12``; a joint in series,
  a bearing added at its node), with closed-form 2×2 inverses, vectorised over frequency: the
  banded structure used, no dense solve. Plain numpy, no rcsa code (only the chain's items
  are read).

No natural frequencies, peaks or static stiffness: the FRF alone.
"""

from __future__ import annotations

import numpy as np

from rcsa.physics.chain import Beam, Ground, Spring


def beam_dynamic_stiffness(omega: np.ndarray, section, length: float) -> np.ndarray:
    """Exact Timoshenko ``D`` (nfreq, 4, 4), DOFs ``(w0, psi0, wL, psiL)``."""
    w2 = omega**2
    ei, fs = section.ei, section.shear_flexibility
    ra, ri = section.rho_a * w2, section.rho_i * w2
    b = ri + ei * ra * fs
    c = ra * (1.0 - ri * fs)
    r = np.sqrt(b * b + 4.0 * ei * c + 0j)
    r = np.where((np.conj(b) * r).real < 0, -r, r)
    s1 = (b + r) / (2.0 * ei)
    s2 = -c / (ei * s1)
    q1, q2 = s1 - ra * fs, s2 - ra * fs
    k1, k2 = np.sqrt(s1), np.sqrt(s2)
    c1, c2 = np.cos(k1 * length), np.cos(k2 * length)
    sf1, sf2 = np.sin(k1 * length) / k1, np.sin(k2 * length) / k2
    ss1, ss2 = k1 * np.sin(k1 * length), k2 * np.sin(k2 * length)
    dc = c2 - c1
    t_ww, t_pw, t_wp, t_pp = q1 * c2 - q2 * c1, q1 * q2 * (sf1 - sf2), ss1 - ss2, q1 * c1 - q2 * c2
    t_wv, t_pv = (q1 * ss2 - q2 * ss1) / ra, q1 * q2 * dc / ra
    t_wm, t_pm = dc / ei, (q1 * sf1 - q2 * sf2) / ei
    inv_det = 1.0 / (t_wv * t_pm - t_wm * t_pv)
    a = (t_pm * t_ww - t_wm * t_pw) * inv_det
    bb = (t_pm * t_wp - t_wm * t_pp) * inv_det
    cc = (t_wv * t_pp - t_pv * t_wp) * inv_det
    scale = (s1 - s2) * inv_det
    e, f, g = -t_pm * scale, t_wm * scale, -t_wv * scale
    rows = [[a, bb, e, f], [bb, cc, -f, g], [e, -f, a, -bb], [f, g, -bb, cc]]
    return np.stack([np.stack(row, axis=-1) for row in rows], axis=-2)


def tip_receptance(chain, omega: np.ndarray) -> np.ndarray:
    """Point receptance (nfreq, 2, 2) at the chain's last node, by global assembly and solve."""
    n_nodes = 1 + sum(isinstance(item, Beam | Spring) for item in chain)
    n = 2 * n_nodes
    k = np.zeros((omega.size, n, n), dtype=complex)
    node = 0
    for item in chain:
        i = 2 * node
        if isinstance(item, Beam):
            k[:, i:i + 4, i:i + 4] += beam_dynamic_stiffness(omega, item.section, item.length_m)
            node += 1
        elif isinstance(item, Spring):
            for dof, stiff, damp in ((0, item.stiffness_n_m, item.damping_ns_m),
                                     (1, item.rotational_stiffness_nm_rad, item.rotational_damping_nms_rad)):
                kj = stiff + 1j * omega * damp
                k[:, i + dof, i + dof] += kj
                k[:, i + 2 + dof, i + 2 + dof] += kj
                k[:, i + dof, i + 2 + dof] -= kj
                k[:, i + 2 + dof, i + dof] -= kj
            node += 1
        elif isinstance(item, Ground):
            k[:, i, i] += item.stiffness_n_m + 1j * omega * item.damping_ns_m - omega**2 * item.mass_kg
            k[:, i + 1, i + 1] += (item.rotational_stiffness_nm_rad + 1j * omega * item.rotational_damping_nms_rad
                                   - omega**2 * item.rotary_inertia_kg_m2)
        else:
            raise TypeError(f"the baseline does not model {type(item).__name__}")
    rhs = np.zeros((omega.size, n, 2), dtype=complex)
    rhs[:, n - 2, 0] = rhs[:, n - 1, 1] = 1.0
    return np.linalg.solve(k, rhs)[:, n - 2:, :]


def _inv2(a: np.ndarray) -> np.ndarray:
    """Closed-form inverse of each 2×2 matrix, shape (..., 2, 2)."""
    det = a[..., 0, 0] * a[..., 1, 1] - a[..., 0, 1] * a[..., 1, 0]
    out = np.empty_like(a)
    out[..., 0, 0], out[..., 1, 1] = a[..., 1, 1] / det, a[..., 0, 0] / det
    out[..., 0, 1], out[..., 1, 0] = -a[..., 0, 1] / det, -a[..., 1, 0] / det
    return out


def block_sweep_receptance(chain, omega: np.ndarray) -> np.ndarray:
    """Point receptance (nfreq, 2, 2) at the chain's last node, by a 2×2 block sweep."""
    k = np.zeros((omega.size, 2, 2), dtype=complex)  # stiffness condensed onto the current node
    for item in chain:
        if isinstance(item, Beam):
            d = beam_dynamic_stiffness(omega, item.section, item.length_m)
            d11, d12, d21, d22 = d[:, :2, :2], d[:, :2, 2:], d[:, 2:, :2], d[:, 2:, 2:]
            k = d22 - d21 @ _inv2(k + d11) @ d12
        elif isinstance(item, Spring):
            j = np.zeros_like(k)
            j[:, 0, 0] = item.stiffness_n_m + 1j * omega * item.damping_ns_m
            j[:, 1, 1] = item.rotational_stiffness_nm_rad + 1j * omega * item.rotational_damping_nms_rad
            k = j - j @ _inv2(k + j) @ j  # the joint in series: condense the node before it
        elif isinstance(item, Ground):
            k = k.copy()
            k[:, 0, 0] += item.stiffness_n_m + 1j * omega * item.damping_ns_m - omega**2 * item.mass_kg
            k[:, 1, 1] += (item.rotational_stiffness_nm_rad + 1j * omega * item.rotational_damping_nms_rad
                           - omega**2 * item.rotary_inertia_kg_m2)
        else:
            raise TypeError(f"the baseline does not model {type(item).__name__}")
    return _inv2(k)
