"""The paper's receptance-coupling path (Budak, Ertürk & Özgüven 2006), step by step.

An independent route to the tool-point receptance, written the way the RCSA literature
states it (``docs/physics.md`` §3.1–3.4), used to cross-check the dynamic-stiffness solver
(:mod:`rcsa.physics.elimination`, the production path) and for measured substructures:

1. free-free segment receptances (:func:`rcsa.physics.segments.free_free_receptance`) coupled rigidly
   into the free-free spindle, keeping the nose and the bearing nodes (general LM-FBS);
2. bearings added by Özgüven's structural modification → spindle-nose receptance ``S``;
3. holder: rigid chain → ``SH22 = H22 − H21 (H11 + K_sh⁻¹ + S)⁻¹ H12`` (paper eq. 6);
4. tool: rigid chain → ``G_tt = T_tt − T_tb (T_bb + K_ht⁻¹ + SH22)⁻¹ T_bt`` (paper eq. 7).

Free-free receptances grow like 1/ω² at low frequency, so this path loses digits below
~5 Hz where the dynamic-stiffness path does not (``docs/physics.md`` §2.7).
"""

from __future__ import annotations

from functools import reduce

import numpy as np

from rcsa.model.assembly import AssemblyModel
from rcsa.physics.arrays import ComplexArray, FloatArray
from rcsa.physics.chain import Beam, Chain, Ground, Spring
from rcsa.physics.coupling import couple, couple_general, couple_to_base, modify
from rcsa.physics.segments import free_free_receptance

__all__ = ["component_receptance", "free_free_nodes", "spindle_nose_receptance", "tool_point_receptance"]


def component_receptance(chain: Chain, omega_rad_s: FloatArray) -> ComplexArray:
    """Free-free two-end receptance of a rigid chain of beams, shape (nfreq, 4, 4).

    The paper's path (``docs/physics.md`` §3): each beam's exact free-free receptance, coupled end
    to end rigidly.

    Parameters
    ----------
    chain : Chain
        Beams only (a component: the holder or the tool).
    omega_rad_s : numpy.ndarray, shape (nfreq,)
        Angular frequencies, rad/s.

    Returns
    -------
    numpy.ndarray of complex, shape (nfreq, 4, 4)
        DOFs ``(w1, ψ1, w2, ψ2)`` of the chain's two ends, m/N, 1/N, rad/N, rad/(N·m).

    Raises
    ------
    ValueError
        A chain holding anything but beams.
    """
    beams = [item for item in chain if isinstance(item, Beam)]
    if len(beams) != len(chain):
        raise ValueError("a rigid component holds beams only")
    parts = [free_free_receptance(omega_rad_s, b.section, float(b.length_m)) for b in beams]
    return reduce(couple, parts)


def free_free_nodes(beams: list[Beam], omega_rad_s: FloatArray) -> ComplexArray:
    """Free-free receptance of a rigid chain of beams with every node retained.

    Block-diagonal ``Y`` of the segments, a signed Boolean ``B`` joining end 2 of each beam to
    end 1 of the next, ``G = Y − Y Bᵀ (B Y Bᵀ)⁻¹ B Y`` (``docs/physics.md`` §3.1–3.2), then one
    representative of each node kept.

    Parameters
    ----------
    beams : list of Beam
    omega_rad_s : numpy.ndarray, shape (nfreq,)
        Angular frequencies, rad/s.

    Returns
    -------
    numpy.ndarray, shape (nfreq, 2(m+1), 2(m+1))
        Node order along the chain, DOFs ``(w, ψ)`` per node.
    """
    m = len(beams)
    y = np.zeros((omega_rad_s.size, 4 * m, 4 * m), dtype=complex)
    for j, b in enumerate(beams):
        y[:, 4 * j:4 * j + 4, 4 * j:4 * j + 4] = free_free_receptance(omega_rad_s, b.section, float(b.length_m))
    rows = []
    for j in range(m - 1):  # end 2 of beam j == end 1 of beam j+1, both DOFs
        for dof in range(2):
            r = np.zeros(4 * m)
            r[4 * j + 2 + dof], r[4 * (j + 1) + dof] = 1.0, -1.0
            rows.append(r)
    g = couple_general(y, np.array(rows).reshape(-1, 4 * m)) if rows else y
    keep = [0, 1] + [4 * j + 2 + d for j in range(m) for d in range(2)]
    return g[:, keep][:, :, keep]


def spindle_nose_receptance(spindle: Chain, omega_rad_s: FloatArray) -> ComplexArray:
    """Receptance at the last node (the nose) of a spindle chain with grounded bearings.

    The beams are coupled rigidly with every node retained (:func:`free_free_nodes`); the
    grounds then modify their nodes (Özgüven, :func:`rcsa.physics.coupling.modify`).

    Parameters
    ----------
    spindle : Chain
        Beams and grounds, from the rear to the nose.
    omega_rad_s : numpy.ndarray, shape (nfreq,)
        Angular frequencies, rad/s.

    Returns
    -------
    numpy.ndarray, shape (nfreq, 2, 2)
    """
    beams: list[Beam] = []
    grounds: list[tuple[int, Ground]] = []  # (node index, ground)
    for item in spindle:
        if isinstance(item, Beam):
            beams.append(item)
        elif isinstance(item, Ground):
            grounds.append((len(beams), item))
        else:
            raise ValueError("a spindle chain holds beams and grounds only")
    g = free_free_nodes(beams, omega_rad_s)
    if grounds:
        dofs = [2 * node + d for node, _ in grounds for d in range(2)]
        delta = np.zeros((omega_rad_s.size, len(dofs), len(dofs)), dtype=complex)
        for i, (_, ground) in enumerate(grounds):
            delta[:, 2 * i:2 * i + 2, 2 * i:2 * i + 2] = ground.stiffness(omega_rad_s)
        g = modify(g, dofs, delta)
    nose = [2 * len(beams), 2 * len(beams) + 1]
    return g[:, nose][:, :, nose]


def _compliance(spring: Spring | None, omega_rad_s: FloatArray) -> ComplexArray | None:
    return None if spring is None else spring.compliance(omega_rad_s)


def tool_point_receptance(model: AssemblyModel, omega_rad_s: FloatArray,
                          base_receptance: ComplexArray | None = None) -> ComplexArray:
    """Tool-point receptance by the paper's receptance-coupling steps.

    Parameters
    ----------
    model : AssemblyModel
    omega_rad_s : numpy.ndarray, shape (nfreq,)
    base_receptance : numpy.ndarray, shape (nfreq, 2, 2), optional
        Measured spindle-side receptance (replaces the analytical spindle).

    Returns
    -------
    numpy.ndarray, shape (nfreq, 2, 2)
    """
    s = base_receptance if base_receptance is not None else spindle_nose_receptance(model.spindle, omega_rad_s)
    if model.holder:
        s = couple_to_base(component_receptance(model.holder, omega_rad_s), s,
                           _compliance(model.spindle_holder, omega_rad_s))
    return couple_to_base(component_receptance(model.tool, omega_rad_s), s,
                          _compliance(model.holder_tool, omega_rad_s))
