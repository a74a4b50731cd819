"""Independent Timoshenko beam finite-element model (test oracle and truth generator).

This module deliberately shares no code with the ``rcsa`` library: it is the independent
check of it. It provides

* beam sections ``(EI, kappa*G*A, rho*A, rho*I)`` for solid, hollow, custom and composite
  cross-sections, with the Hutchinson and Cowper shear coefficients;
* the two-node Timoshenko element with interdependent interpolation (Friedman & Kosmatka
  1993): static-exact stiffness, consistent translational and rotary mass;
* :class:`BeamModel`, a small assembler of beams, springs (grounded or between two nodes),
  distributed (Winkler) springs between two parallel beams, lumped masses and fixed DOFs;
* solvers: undamped natural frequencies (``scipy.linalg.eigh``) and harmonic receptances
  by a banded solve per frequency.

Conventions (``docs/physics.md`` §2.1): global axis x from the spindle rear to the tool tip; per
node a lateral displacement ``w`` (m) and a section rotation ``psi`` (rad, counter-clockwise
positive, ``psi = dw/dx`` for Euler-Bernoulli); time dependence ``exp(i omega t)``. Material
damping is hysteretic, ``E(1 + i eta)`` and ``G(1 + i eta)``, i.e. complex ``EI`` and
``kappa*G*A``; springs carry viscous damping ``k + i omega c``.

References
----------
Friedman Z., Kosmatka J.B., "An improved two-node Timoshenko beam finite element",
Computers & Structures 47 (1993) 473-481.
Hutchinson J.R., J. Appl. Mech. 68 (2001) 87-92; Cowper G.R., J. Appl. Mech. 33 (1966) 335-340.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Literal

import numpy as np
import scipy.linalg

BeamTheory = Literal["timoshenko", "euler_bernoulli"]
BEAM_THEORIES: tuple[str, ...] = ("timoshenko", "euler_bernoulli")

__all__ = [
    "BEAM_THEORIES",
    "BeamModel",
    "Section",
    "circular_section",
    "cowper_shear_coefficient",
    "element_mass",
    "element_stiffness",
    "element_winkler",
    "harmonic_receptance",
    "hutchinson_shear_coefficient",
    "shape_functions",
    "shear_parameter",
    "solid_circle_section_properties",
    "undamped_natural_frequencies_hz",
]

# ---------------------------------------------------------------------------------------
# Sections
# ---------------------------------------------------------------------------------------


@dataclass(frozen=True)
class Section:
    """Beam cross-section as the four numbers the element needs.

    Parameters
    ----------
    bending_stiffness_nm2 : complex
        ``EI`` in N·m² (complex with hysteretic damping, ``E(1 + i eta) I``).
    shear_stiffness_n : complex
        ``kappa G A`` in N (complex with hysteretic damping).
    mass_per_length_kg_m : float
        ``rho A`` in kg/m.
    rotary_inertia_kg_m : float
        ``rho I`` in kg·m (rotary inertia per unit length).
    """

    bending_stiffness_nm2: complex
    shear_stiffness_n: complex
    mass_per_length_kg_m: float
    rotary_inertia_kg_m: float

    def __add__(self, other: Section) -> Section:
        """Parallel (composite) stacking: every property adds (``docs/physics.md`` §2.6)."""
        return Section(
            self.bending_stiffness_nm2 + other.bending_stiffness_nm2,
            self.shear_stiffness_n + other.shear_stiffness_n,
            self.mass_per_length_kg_m + other.mass_per_length_kg_m,
            self.rotary_inertia_kg_m + other.rotary_inertia_kg_m,
        )


def hutchinson_shear_coefficient(poisson_ratio: float, diameter_ratio: float = 0.0) -> float:
    """Hutchinson (2001) shear coefficient of a (hollow) circular section.

    Parameters
    ----------
    poisson_ratio : float
        Poisson's ratio ``nu``.
    diameter_ratio : float
        ``m = d_inner / d_outer`` (0 for a solid circle).

    Returns
    -------
    float
        ``6(1+nu)^2 (1+m^2)^2 / [(7+12nu+4nu^2)(1+m^2)^2 + 4(5+6nu+2nu^2) m^2]``
        (0.925185 for a solid circle at ``nu = 0.3``).
    """
    nu, m2 = poisson_ratio, diameter_ratio**2
    s = (1.0 + m2) ** 2
    return 6.0 * (1.0 + nu) ** 2 * s / ((7.0 + 12.0 * nu + 4.0 * nu**2) * s
                                        + 4.0 * (5.0 + 6.0 * nu + 2.0 * nu**2) * m2)


def cowper_shear_coefficient(poisson_ratio: float, diameter_ratio: float = 0.0) -> float:
    """Cowper (1966) shear coefficient of a (hollow) circular section.

    Parameters
    ----------
    poisson_ratio : float
        Poisson's ratio ``nu``.
    diameter_ratio : float
        ``m = d_inner / d_outer`` (0 for a solid circle).

    Returns
    -------
    float
        ``6(1+nu)(1+m^2)^2 / [(7+6nu)(1+m^2)^2 + (20+12nu) m^2]`` (0.8864 solid, ``nu = 0.3``).
    """
    nu, m2 = poisson_ratio, diameter_ratio**2
    s = (1.0 + m2) ** 2
    return 6.0 * (1.0 + nu) * s / ((7.0 + 6.0 * nu) * s + (20.0 + 12.0 * nu) * m2)


def solid_circle_section_properties(outer_diameter_m: float,
                                    inner_diameter_m: float = 0.0) -> tuple[float, float]:
    """Area (m²) and second moment of area (m⁴) of a tube (solid if ``inner_diameter_m == 0``)."""
    do, di = outer_diameter_m, inner_diameter_m
    return math.pi * (do**2 - di**2) / 4.0, math.pi * (do**4 - di**4) / 64.0


def circular_section(youngs_modulus_pa: float, poisson_ratio: float, density_kg_m3: float,
                     *, area_m2: float, second_moment_m4: float, shear_coefficient: float,
                     loss_factor: float = 0.0) -> Section:
    """Section of one homogeneous material from area, second moment and shear coefficient.

    Parameters
    ----------
    youngs_modulus_pa, poisson_ratio, density_kg_m3 : float
        Material; ``G = E / (2 (1 + nu))``.
    area_m2, second_moment_m4 : float
        Cross-section area and second moment of area.
    shear_coefficient : float
        ``kappa`` (see :func:`hutchinson_shear_coefficient`).
    loss_factor : float
        Hysteretic loss factor ``eta``; both E and G are multiplied by ``1 + i eta``.

    Returns
    -------
    Section
    """
    damping = 1.0 + 1j * loss_factor
    shear_modulus_pa = youngs_modulus_pa / (2.0 * (1.0 + poisson_ratio))
    return Section(
        bending_stiffness_nm2=youngs_modulus_pa * second_moment_m4 * damping,
        shear_stiffness_n=shear_coefficient * shear_modulus_pa * area_m2 * damping,
        mass_per_length_kg_m=density_kg_m3 * area_m2,
        rotary_inertia_kg_m=density_kg_m3 * second_moment_m4,
    )


# ---------------------------------------------------------------------------------------
# Element matrices
# ---------------------------------------------------------------------------------------


def _check_theory(theory: str) -> None:
    if theory not in BEAM_THEORIES:
        raise ValueError(f"beam theory must be one of {BEAM_THEORIES}, got {theory!r}")


def shear_parameter(length_m: float, section: Section, theory: BeamTheory = "timoshenko") -> complex:
    """Shear deformation parameter ``Phi = 12 EI / (kappa G A L^2)`` (0 for Euler-Bernoulli)."""
    _check_theory(theory)
    if theory == "euler_bernoulli":
        return 0.0
    return 12.0 * section.bending_stiffness_nm2 / (section.shear_stiffness_n * length_m**2)


def element_stiffness(length_m: float, section: Section,
                      theory: BeamTheory = "timoshenko") -> np.ndarray:
    """Static-exact two-node Timoshenko stiffness matrix (``docs/physics.md`` §2.4).

    Parameters
    ----------
    length_m : float
        Element length.
    section : Section
        Section (complex ``EI`` and ``kappa G A`` give a complex, hysteretically damped matrix).
    theory : {"timoshenko", "euler_bernoulli"}
        Euler-Bernoulli sets ``Phi = 0`` (no shear deformation).

    Returns
    -------
    numpy.ndarray, shape (4, 4), complex
        Ordered ``(w1, psi1, w2, psi2)``.
    """
    ell = length_m
    phi = shear_parameter(ell, section, theory)
    pattern = np.array([
        [12.0, 6.0 * ell, -12.0, 6.0 * ell],
        [6.0 * ell, (4.0 + phi) * ell**2, -6.0 * ell, (2.0 - phi) * ell**2],
        [-12.0, -6.0 * ell, 12.0, -6.0 * ell],
        [6.0 * ell, (2.0 - phi) * ell**2, -6.0 * ell, (4.0 + phi) * ell**2],
    ], dtype=complex)
    return section.bending_stiffness_nm2 / ((1.0 + phi) * ell**3) * pattern


def shape_functions(xi: np.ndarray, length_m: float, phi: float) -> tuple[np.ndarray, np.ndarray]:
    """Interdependent interpolation (Friedman & Kosmatka 1993) at ``xi = x / L``.

    Parameters
    ----------
    xi : numpy.ndarray, shape (nq,)
        Local coordinates in [0, 1].
    length_m : float
        Element length.
    phi : float
        Shear parameter ``Phi`` (0 gives the cubic Hermite functions, ``N_psi = dN_w/dx``).

    Returns
    -------
    n_w, n_psi : numpy.ndarray, shape (nq, 4)
        ``w(xi) = n_w @ d`` and ``psi(xi) = n_psi @ d`` for ``d = (w1, psi1, w2, psi2)``.
    """
    xi = np.asarray(xi, dtype=float)
    ell, a = length_m, 1.0 / (1.0 + phi)
    n_w = np.stack([
        a * (2 * xi**3 - 3 * xi**2 - phi * xi + 1 + phi),
        a * ell * (xi**3 - (2 + phi / 2) * xi**2 + (1 + phi / 2) * xi),
        a * (-2 * xi**3 + 3 * xi**2 + phi * xi),
        a * ell * (xi**3 - (1 - phi / 2) * xi**2 - (phi / 2) * xi),
    ], axis=-1)
    n_psi = np.stack([
        6 * a / ell * (xi**2 - xi),
        a * (3 * xi**2 - (4 + phi) * xi + 1 + phi),
        -6 * a / ell * (xi**2 - xi),
        a * (3 * xi**2 - (2 - phi) * xi),
    ], axis=-1)
    return n_w, n_psi


# 4-point Gauss-Legendre on [0, 1]: exact for the degree-6 products of cubic shape functions.
_GAUSS_POINTS, _GAUSS_WEIGHTS = np.polynomial.legendre.leggauss(4)
_GAUSS_XI = 0.5 * (_GAUSS_POINTS + 1.0)
_GAUSS_W = 0.5 * _GAUSS_WEIGHTS


def _consistent_matrices(length_m: float, phi: float) -> tuple[np.ndarray, np.ndarray]:
    """``(int N_w^T N_w dx, int N_psi^T N_psi dx)`` over one element, each (4, 4)."""
    n_w, n_psi = shape_functions(_GAUSS_XI, length_m, phi)
    weights = _GAUSS_W * length_m
    return (np.einsum("q,qi,qj->ij", weights, n_w, n_w),
            np.einsum("q,qi,qj->ij", weights, n_psi, n_psi))


def element_mass(length_m: float, section: Section, theory: BeamTheory = "timoshenko") -> np.ndarray:
    """Consistent translational + rotary mass matrix of the interdependent-interpolation element.

    ``M = rho A int N_w^T N_w dx + rho I int N_psi^T N_psi dx``, integrated exactly by Gauss
    quadrature. The interpolation uses the real (undamped) ``Phi``, so ``M`` stays real when
    the moduli are complex. Euler-Bernoulli: ``Phi = 0`` and no rotary inertia.

    Parameters
    ----------
    length_m : float
        Element length.
    section : Section
        Section.
    theory : {"timoshenko", "euler_bernoulli"}
        Beam theory.

    Returns
    -------
    numpy.ndarray, shape (4, 4), float
    """
    _check_theory(theory)
    undamped = Section(section.bending_stiffness_nm2.real, section.shear_stiffness_n.real,
                       section.mass_per_length_kg_m, section.rotary_inertia_kg_m)
    phi_real = float(np.real(shear_parameter(length_m, undamped, theory)))
    translational, rotary = _consistent_matrices(length_m, phi_real)
    mass = section.mass_per_length_kg_m * translational
    if theory == "timoshenko":
        mass = mass + section.rotary_inertia_kg_m * rotary
    return mass


def element_winkler(length_m: float, translational_per_length: complex,
                    rotational_per_length: complex = 0.0) -> np.ndarray:
    """Consistent matrix of a distributed (Winkler) spring layer over one element.

    The layer acts on the *relative* motion of two parallel beams; this is the 4×4 block
    ``k' int N_w^T N_w dx + k'_r int N_psi^T N_psi dx`` with cubic Hermite interpolation. Use
    it as ``[[B, -B], [-B, B]]`` over the two beams' element DOFs.

    Parameters
    ----------
    length_m : float
        Element length.
    translational_per_length : complex
        Translational stiffness per unit length (N/m², or ``i omega c'`` with c' in N·s/m²).
    rotational_per_length : complex
        Rotational stiffness per unit length (N·m/rad per m).

    Returns
    -------
    numpy.ndarray, shape (4, 4), complex
    """
    translational, rotary = _consistent_matrices(length_m, 0.0)
    return translational_per_length * translational + rotational_per_length * rotary


# ---------------------------------------------------------------------------------------
# Model assembly
# ---------------------------------------------------------------------------------------


class BeamModel:
    """Global FE model: nodes with (w, psi) DOFs, stiffness K (complex), viscous C and mass M.

    DOFs may be shared between nodes (a rigid connection of one direction only), which is
    how a joint with rigid rotation but elastic translation is represented. The matrices
    are dense ``(ndof, ndof)``; the harmonic solver converts them to banded form.
    """

    def __init__(self) -> None:
        self.node_x_m: list[float] = []
        self.node_dofs: list[tuple[int, int]] = []
        self.n_dof = 0
        self._k: dict[tuple[int, int], complex] = {}
        self._c: dict[tuple[int, int], float] = {}
        self._m: dict[tuple[int, int], float] = {}
        self.fixed_dofs: set[int] = set()

    # -- nodes -----------------------------------------------------------------------
    def add_node(self, x_m: float, *, share_w_with: int | None = None,
                 share_psi_with: int | None = None) -> int:
        """Add a node at ``x_m``; optionally reuse the ``w`` or ``psi`` DOF of another node.

        Returns
        -------
        int
            The node index.
        """
        dofs = []
        for share, position in ((share_w_with, 0), (share_psi_with, 1)):
            if share is None:
                dofs.append(self.n_dof)
                self.n_dof += 1
            else:
                dofs.append(self.node_dofs[share][position])
        self.node_x_m.append(float(x_m))
        self.node_dofs.append((dofs[0], dofs[1]))
        return len(self.node_x_m) - 1

    def dofs_of(self, nodes: Sequence[int]) -> list[int]:
        """Global DOF indices ``[w_a, psi_a, w_b, psi_b, ...]`` of the given nodes."""
        return [d for node in nodes for d in self.node_dofs[node]]

    # -- matrix contributions --------------------------------------------------------
    @staticmethod
    def _scatter(target: dict, dofs: Sequence[int], block: np.ndarray) -> None:
        for a, i in enumerate(dofs):
            for b, j in enumerate(dofs):
                if block[a, b] != 0:
                    target[(i, j)] = target.get((i, j), 0.0) + block[a, b]

    def add_stiffness(self, dofs: Sequence[int], block: np.ndarray) -> None:
        """Add a (complex) stiffness block on the given global DOFs."""
        self._scatter(self._k, dofs, np.asarray(block, dtype=complex))

    def add_damping(self, dofs: Sequence[int], block: np.ndarray) -> None:
        """Add a viscous damping block (N·s/m etc.) on the given global DOFs."""
        self._scatter(self._c, dofs, np.asarray(block, dtype=float))

    def add_mass(self, dofs: Sequence[int], block: np.ndarray) -> None:
        """Add a mass block on the given global DOFs."""
        self._scatter(self._m, dofs, np.asarray(block, dtype=float))

    # -- structural items ------------------------------------------------------------
    def add_beam(self, start_node: int, length_m: float, section: Section,
                 theory: BeamTheory = "timoshenko", *, n_elements: int,
                 end_node: int | None = None) -> list[int]:
        """Mesh a uniform beam piece from ``start_node`` toward +x with equal elements.

        Parameters
        ----------
        start_node : int
            Existing node at the start of the piece.
        length_m : float
            Piece length.
        section : Section
            Uniform section of the piece.
        theory : {"timoshenko", "euler_bernoulli"}
            Beam theory of this piece.
        n_elements : int
            Number of equal elements.
        end_node : int, optional
            Existing node to end on (otherwise a new node is created).

        Returns
        -------
        list of int
            The ``n_elements + 1`` nodes of the piece, start node first.
        """
        if length_m <= 0 or n_elements < 1:
            raise ValueError(f"beam piece needs length > 0 and >= 1 element, got {length_m}, {n_elements}")
        x0 = self.node_x_m[start_node]
        ell = length_m / n_elements
        k_el = element_stiffness(ell, section, theory)
        m_el = element_mass(ell, section, theory)
        nodes = [start_node]
        for i in range(1, n_elements + 1):
            if i == n_elements and end_node is not None:
                nodes.append(end_node)
            else:
                nodes.append(self.add_node(x0 + i * ell))
            dofs = self.dofs_of(nodes[-2:])
            self.add_stiffness(dofs, k_el)
            self.add_mass(dofs, m_el)
        return nodes

    def add_spring(self, node_a: int, node_b: int | None, *, translational_n_m: complex = 0.0,
                   translational_ns_m: float = 0.0, rotational_nm_rad: complex = 0.0,
                   rotational_nms_rad: float = 0.0) -> None:
        """Spring-damper ``diag(k_t + i omega c_t, k_r + i omega c_r)`` between two nodes.

        ``node_b = None`` grounds the spring (bearing). DOFs shared by both nodes are skipped.
        """
        pairs = ((0, translational_n_m, translational_ns_m), (1, rotational_nm_rad, rotational_nms_rad))
        for position, k, c in pairs:
            i = self.node_dofs[node_a][position]
            if node_b is None:
                self.add_stiffness([i], np.array([[k]]))
                self.add_damping([i], np.array([[c]]))
                continue
            j = self.node_dofs[node_b][position]
            if i == j:
                continue
            pattern = np.array([[1.0, -1.0], [-1.0, 1.0]])
            self.add_stiffness([i, j], k * pattern)
            self.add_damping([i, j], c * pattern)

    def add_lumped_mass(self, node: int, mass_kg: float, rotary_inertia_kg_m2: float = 0.0,
                        offset_m: float = 0.0) -> None:
        """Rigid body of mass ``m`` and inertia ``J`` (about its centre) at ``x_node + offset_m``.

        The body is rigidly linked to the node: its lateral motion is ``w + offset * psi``,
        so the mass block is ``[[m, m e], [m e, m e^2 + J]]``.
        """
        e = offset_m
        self.add_mass(list(self.node_dofs[node]),
                      np.array([[mass_kg, mass_kg * e], [mass_kg * e, mass_kg * e**2 + rotary_inertia_kg_m2]]))

    def add_distributed_springs(self, nodes_a: Sequence[int], nodes_b: Sequence[int], *,
                                translational_n_m2: complex = 0.0, translational_ns_m2: float = 0.0,
                                rotational_nm_rad_m: complex = 0.0,
                                rotational_nms_rad_m: float = 0.0) -> None:
        """Distributed spring layer between two parallel, identically meshed beams.

        The layer's energy is ``½∫ k (w_a − w_b)² + k_r (psi_a − psi_b)² dx``, both beams' fields
        interpolated alike (so that the layer can vanish: a stiff layer ties the beams without
        locking): ``w`` by the cubic Hermite functions of the nodal ``w`` and ``psi``, the section
        rotation ``psi`` linearly between its nodal values (not as the slope ``w'``, which a
        shear-flexible beam's rotation is not).

        Parameters
        ----------
        nodes_a, nodes_b : sequence of int
            Node chains of the two beams over the contact, at equal x positions.
        translational_n_m2, translational_ns_m2 : complex, float
            Stiffness and viscous damping per unit length of the lateral contact.
        rotational_nm_rad_m, rotational_nms_rad_m : complex, float
            Stiffness and damping per unit length acting on the relative section rotation.
        """
        if len(nodes_a) != len(nodes_b) or len(nodes_a) < 2:
            raise ValueError("distributed springs need two node chains of equal length >= 2")
        xa = np.array([self.node_x_m[n] for n in nodes_a])
        xb = np.array([self.node_x_m[n] for n in nodes_b])
        if not np.allclose(xa, xb, rtol=0.0, atol=1e-12):
            raise ValueError("distributed springs need the two beams meshed at the same x positions")
        linear = np.zeros((_GAUSS_XI.size, 4))
        linear[:, 1], linear[:, 3] = 1.0 - _GAUSS_XI, _GAUSS_XI  # psi between its nodal values
        for i in range(len(nodes_a) - 1):
            ell = xa[i + 1] - xa[i]
            n_w, _ = shape_functions(_GAUSS_XI, ell, 0.0)
            q = _GAUSS_W * ell
            ww = np.einsum("q,qi,qj->ij", q, n_w, n_w)
            pp = np.einsum("q,qi,qj->ij", q, linear, linear)
            stiff = translational_n_m2 * ww + rotational_nm_rad_m * pp
            damp = (translational_ns_m2 * ww + rotational_nms_rad_m * pp).real
            dofs = self.dofs_of(nodes_a[i:i + 2]) + self.dofs_of(nodes_b[i:i + 2])
            self.add_stiffness(dofs, np.block([[stiff, -stiff], [-stiff, stiff]]))
            self.add_damping(dofs, np.block([[damp, -damp], [-damp, damp]]))

    def fix(self, node: int, *, w: bool = True, psi: bool = True) -> None:
        """Clamp (remove) the node's ``w`` and/or ``psi`` DOF."""
        if w:
            self.fixed_dofs.add(self.node_dofs[node][0])
        if psi:
            self.fixed_dofs.add(self.node_dofs[node][1])

    # -- matrices --------------------------------------------------------------------
    def _dense(self, entries: dict, dtype: type) -> np.ndarray:
        out = np.zeros((self.n_dof, self.n_dof), dtype=dtype)
        for (i, j), value in entries.items():
            out[i, j] += value
        return out

    def matrices(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Dense ``(K, C, M)`` over all DOFs (fixed DOFs included), ``K`` complex."""
        return self._dense(self._k, complex), self._dense(self._c, float), self._dense(self._m, float)

    def free_dofs_in_x_order(self) -> np.ndarray:
        """Free DOFs sorted by the x of the first node owning them (gives a narrow band)."""
        owner_x = np.full(self.n_dof, np.inf)
        for x, dofs in zip(self.node_x_m, self.node_dofs, strict=True):
            for d in dofs:
                owner_x[d] = min(owner_x[d], x)
        order = np.argsort(owner_x, kind="stable")
        return np.array([d for d in order if d not in self.fixed_dofs], dtype=int)


# ---------------------------------------------------------------------------------------
# Solvers
# ---------------------------------------------------------------------------------------


def undamped_natural_frequencies_hz(model: BeamModel, fmax_hz: float) -> np.ndarray:
    """Natural frequencies up to ``fmax_hz`` of an undamped model, ascending.

    Solves ``K phi = omega^2 M phi`` over the free DOFs in shift-and-invert form: with a
    negative shift ``sigma`` (so that ``K - sigma M`` is positive definite even for a free
    beam) and ``M = L L^T``, the symmetric matrix ``L^T (K - sigma M)^-1 L`` has eigenvalues
    ``1 / (lambda - sigma)`` (``scipy.linalg.eigh``). Unlike a direct ``eigh(K, M)`` this keeps
    the low modes accurate on fine meshes, whose stiffest element modes reach
    ``omega^2 ~ 1e17``. Rigid-body modes of an unsupported model appear as (numerically) zero
    frequencies.

    Parameters
    ----------
    model : BeamModel
        Must carry no damping (real ``K``, zero ``C``); build it with damping switched off.
    fmax_hz : float
        Upper frequency limit.

    Returns
    -------
    numpy.ndarray, shape (nmodes,)
    """
    k, c, m = model.matrices()
    if np.any(k.imag != 0) or np.any(c != 0):
        raise ValueError("natural frequencies need an undamped model (real K, C = 0)")
    free = model.free_dofs_in_x_order()
    k_free, m_free = k.real[np.ix_(free, free)], m[np.ix_(free, free)]
    sigma = -((2.0 * np.pi * 0.1 * fmax_hz) ** 2)
    lower = scipy.linalg.cholesky(m_free, lower=True)
    reduced = lower.T @ scipy.linalg.solve(k_free - sigma * m_free, lower, assume_a="pos")
    mu = scipy.linalg.eigh(0.5 * (reduced + reduced.T), eigvals_only=True)
    omega2 = np.sort(sigma + 1.0 / mu[mu > 0])
    omega2 = omega2[omega2 <= (2.0 * np.pi * fmax_hz) ** 2]
    return np.sqrt(np.clip(omega2, 0.0, None)) / (2.0 * np.pi)


def _to_banded(matrix: np.ndarray, bandwidth: int) -> np.ndarray:
    """LAPACK band storage ``ab[bw + i - j, j] = A[i, j]`` for equal lower/upper bandwidth."""
    n = matrix.shape[0]
    ab = np.zeros((2 * bandwidth + 1, n), dtype=matrix.dtype)
    for offset in range(-bandwidth, bandwidth + 1):
        diagonal = np.diagonal(matrix, offset)
        if offset >= 0:
            ab[bandwidth - offset, offset:] = diagonal
        else:
            ab[bandwidth - offset, :n + offset] = diagonal
    return ab


def harmonic_receptance(model: BeamModel, frequency_hz: np.ndarray, response_dofs: Sequence[int],
                        excitation_dofs: Sequence[int]) -> np.ndarray:
    """Receptances ``u_r / f_e`` from ``(K + i omega C - omega^2 M) u = f``, frequency first.

    One banded LU solve per frequency (DOFs ordered along x, so the band is a few DOFs wide).

    Parameters
    ----------
    model : BeamModel
        The assembled model.
    frequency_hz : array_like, shape (nfreq,)
        Frequencies in Hz, > 0.
    response_dofs, excitation_dofs : sequence of int
        Global DOF indices (free DOFs only).

    Returns
    -------
    numpy.ndarray, shape (nfreq, len(response_dofs), len(excitation_dofs)), complex
    """
    frequency_hz = np.atleast_1d(np.asarray(frequency_hz, dtype=float))
    if frequency_hz.ndim != 1 or np.any(frequency_hz <= 0):
        raise ValueError("frequency_hz must be a 1-D array of frequencies > 0 Hz")
    k, c, m = model.matrices()
    free = model.free_dofs_in_x_order()
    position = np.full(model.n_dof, -1)
    position[free] = np.arange(free.size)
    rows_out, cols_in = position[list(response_dofs)], position[list(excitation_dofs)]
    if np.any(rows_out < 0) or np.any(cols_in < 0):
        raise ValueError("response and excitation DOFs must be free (not fixed)")
    k, c, m = (a[np.ix_(free, free)] for a in (k, c, m))
    rows, cols = np.nonzero((k != 0) | (c != 0) | (m != 0))
    bandwidth = int(np.max(np.abs(rows - cols))) if rows.size else 0
    k_band, c_band, m_band = (_to_banded(a, bandwidth) for a in (k, c.astype(complex), m.astype(complex)))
    rhs = np.zeros((free.size, cols_in.size), dtype=complex)
    rhs[cols_in, np.arange(cols_in.size)] = 1.0
    out = np.empty((frequency_hz.size, rows_out.size, cols_in.size), dtype=complex)
    for i, omega in enumerate(2.0 * np.pi * frequency_hz):
        band = k_band + (1j * omega) * c_band - omega**2 * m_band
        solution = scipy.linalg.solve_banded((bandwidth, bandwidth), band, rhs,
                                             overwrite_ab=True, check_finite=False)
        out[i] = solution[rows_out]
    return out
