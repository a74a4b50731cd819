"""A spindle–holder–tool assembly as a chain of beams, joints and grounded attachments.

The assembly is one line of nodes along the global axis (spindle rear → tool tip,
``domain.md`` §2.1). Between consecutive nodes sits a :class:`Beam` (uniform Timoshenko
segment) or a :class:`Spring` (an elastic joint of zero length); a :class:`Ground` adds a
spring/damper to rigid ground and/or a lumped mass at the current node (bearings,
sensors). A chain is a plain tuple of these immutable items, so sub-chains can be shared
and cached (the spindle and holder are reused across tools).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from rcsa.physics.sections import Section

__all__ = ["Beam", "Chain", "Ground", "Spring", "undamped"]


@dataclass(frozen=True, slots=True)
class Beam:
    """A uniform segment between two nodes.

    Parameters
    ----------
    section : Section
    length_m : float
        Segment length, m (> 0).
    """

    section: Section
    length_m: float


@dataclass(frozen=True, slots=True)
class Spring:
    """An elastic joint between two coincident nodes: ``K = diag(k_t + iωc_t, k_r + iωc_r)``.

    ``None`` for a stiffness means that DOF is rigid (the two nodes share it).

    Parameters
    ----------
    stiffness_n_m : float or None
        Translational stiffness k_t, N/m.
    damping_ns_m : float
        Translational viscous damping c_t, N·s/m.
    rotational_stiffness_nm_rad : float or None
        Rotational stiffness k_r, N·m/rad.
    rotational_damping_nms_rad : float
        Rotational viscous damping c_r, N·m·s/rad.
    """

    stiffness_n_m: float | None
    damping_ns_m: float = 0.0
    rotational_stiffness_nm_rad: float | None = None
    rotational_damping_nms_rad: float = 0.0

    def translational(self, omega_rad_s: np.ndarray) -> np.ndarray | None:
        """``k_t + iωc_t`` (N/m), shape (nfreq,), or ``None`` if rigid.

        Parameters
        ----------
        omega_rad_s : numpy.ndarray, shape (nfreq,)
            Angular frequencies, rad/s.
        """
        if self.stiffness_n_m is None:
            return None
        return self.stiffness_n_m + 1j * omega_rad_s * self.damping_ns_m

    def rotational(self, omega_rad_s: np.ndarray) -> np.ndarray | None:
        """``k_r + iωc_r`` (N·m/rad), shape (nfreq,), or ``None`` if rigid.

        Parameters
        ----------
        omega_rad_s : numpy.ndarray, shape (nfreq,)
            Angular frequencies, rad/s.
        """
        if self.rotational_stiffness_nm_rad is None:
            return None
        return self.rotational_stiffness_nm_rad + 1j * omega_rad_s * self.rotational_damping_nms_rad

    def compliance(self, omega_rad_s: np.ndarray) -> np.ndarray:
        """Joint compliance ``K⁻¹``, shape (nfreq, 2, 2); zero for rigid DOFs.

        Parameters
        ----------
        omega_rad_s : numpy.ndarray, shape (nfreq,)
            Angular frequencies, rad/s.
        """
        out = np.zeros((omega_rad_s.size, 2, 2), dtype=complex)
        kt, kr = self.translational(omega_rad_s), self.rotational(omega_rad_s)
        if kt is not None:
            out[:, 0, 0] = 1.0 / kt
        if kr is not None:
            out[:, 1, 1] = 1.0 / kr
        return out


@dataclass(frozen=True, slots=True)
class Ground:
    """Grounded spring/damper and lumped mass at the current node.

    Its dynamic stiffness is ``diag(k_t + iωc_t − ω²m, k_r + iωc_r − ω²J)``.

    Parameters
    ----------
    stiffness_n_m, damping_ns_m : float
        Translational spring to ground (N/m) and damper (N·s/m).
    rotational_stiffness_nm_rad, rotational_damping_nms_rad : float
        Rotational spring (N·m/rad) and damper (N·m·s/rad).
    mass_kg : float
        Lumped mass, kg.
    rotary_inertia_kg_m2 : float
        Lumped rotary inertia about the bending axis, kg·m².
    """

    stiffness_n_m: float = 0.0
    damping_ns_m: float = 0.0
    rotational_stiffness_nm_rad: float = 0.0
    rotational_damping_nms_rad: float = 0.0
    mass_kg: float = 0.0
    rotary_inertia_kg_m2: float = 0.0

    def stiffness(self, omega_rad_s: np.ndarray) -> np.ndarray:
        """Dynamic stiffness, shape (nfreq, 2, 2).

        Parameters
        ----------
        omega_rad_s : numpy.ndarray, shape (nfreq,)
            Angular frequencies, rad/s.
        """
        w = omega_rad_s
        out = np.zeros((w.size, 2, 2), dtype=complex)
        out[:, 0, 0] = self.stiffness_n_m + 1j * w * self.damping_ns_m - w**2 * self.mass_kg
        out[:, 1, 1] = (self.rotational_stiffness_nm_rad + 1j * w * self.rotational_damping_nms_rad
                        - w**2 * self.rotary_inertia_kg_m2)
        return out


Chain = tuple[Beam | Spring | Ground, ...]


def undamped(chain: Chain) -> Chain:
    """The chain with every damper removed and real moduli (for natural frequencies).

    Parameters
    ----------
    chain : Chain
    """
    out: list[Beam | Spring | Ground] = []
    for item in chain:
        if isinstance(item, Beam):
            out.append(Beam(item.section.undamped(), item.length_m))
        elif isinstance(item, Spring):
            out.append(replace(item, damping_ns_m=0.0, rotational_damping_nms_rad=0.0))
        else:
            out.append(replace(item, damping_ns_m=0.0, rotational_damping_nms_rad=0.0))
    return tuple(out)
