"""Finite-element matrices of the mesh (scikit-fem), the interface and the constraints.

The mesh is isoparametric (10-node tetrahedra, curved faces) with quadratic Lagrange
displacements. Each part's stiffness and mass are assembled on its own elements, so each
can carry its own loss factor. The interface between shank and bore is handled by giving
the tool its own copy of the interface nodes where they are not bonded, and by a
zero-thickness spring layer ∫ [u]ᵀ k [u] dA (consistent P2 surface integral, normal
stiffness k_n, tangential k_t) between the copies over the contact region.

All constraints are one sparse transformation u = T ũ (no penalty): the symmetry planes of
the quarter model (bending in x: u_y = 0 on y = 0; u_y = u_z = 0 on x = 0) or of the half
model (u_y = 0 on y = 0), the rigid base face (RBE2-type: its nodes follow the base's
rigid-body DOFs q), optionally a rigid holder (all its nodes follow q). ``q = (u_x, θ_y)`` in
the quarter and half models and ``(u_x, θ_y, u_y, θ_x)`` in the full one; axial translation
and torsion of the base are clamped.

Which shank–bore facets are joined (bonded, or sprung by the layer): those of the bore
surface inside the contact region (its depths, and its arc ``arc_deg`` centred on −x), the
shank's end face if ``bottom`` is connected, and any other face the two parts share (a
side-lock screw's face on the flat) always.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np
import scipy.sparse as sp
from skfem import Basis, ElementTetP2, FacetBasis, MeshTet2

from tests.oracles.solid3d.case import Interface, SolidMaterial
from tests.oracles.solid3d.geometry import SolidMesh

__all__ = ["BaseKind", "Matrices", "assemble", "interface_facets", "layer_matrix", "tip_loads"]

BaseKind = Literal["clamped", "elastic", "free"]
_INTORDER = 4


@dataclass(frozen=True, slots=True)
class Matrices:
    """The constrained model in the DOFs ũ = [interior, q].

    Attributes
    ----------
    stiffness : tuple of (scipy.sparse.csr_matrix, float)
        Real stiffness matrices (N/m) with their loss factors: holder, tool, interface.
    mass : scipy.sparse.csr_matrix
        kg.
    tip_loads : numpy.ndarray, shape (ndof, 2)
        Generalised tip loads of the whole (unsymmetrised) body restricted to this
        model: a unit force in x spread uniformly over the tip face, and a unit moment
        about +y as a linear axial traction; the same vectors read the tip's mean
        x displacement and rotation (reciprocal).
    n_boundary : int
        Number of base DOFs q, the last ones of ũ.
    multiplicity : int
        Copies of this model in the whole body (4 quarter, 2 half, else 1): the
        base's dynamic stiffness is divided by it, tip receptances multiplied.
    n_dof_mesh : int
        Unconstrained DOF count of the mesh (3 per node), for the record.
    """

    stiffness: tuple[tuple[sp.csr_matrix, float], ...]
    mass: sp.csr_matrix
    tip_loads: np.ndarray
    n_boundary: int
    multiplicity: int
    n_dof_mesh: int

    @property
    def n_dof(self) -> int:
        """DOFs after the constraints (interior + q)."""
        return self.mass.shape[0]

    def complex_stiffness(self) -> sp.csr_matrix:
        """Σ K_part (1 + iη_part), N/m."""
        return sum((k * (1 + 1j * eta) for k, eta in self.stiffness), sp.csr_matrix(self.mass.shape))

    def real_stiffness(self) -> sp.csr_matrix:
        """Σ K_part (undamped), N/m."""
        return sum((k for k, _ in self.stiffness), sp.csr_matrix(self.mass.shape))


def _scatter(local: np.ndarray, dofs: np.ndarray, n: int) -> sp.csr_matrix:
    """Sum element matrices (nel, 30, 30) on vector DOFs ``dofs`` (nel, 30) into an (n, n) matrix."""
    rows = np.repeat(dofs, dofs.shape[1], axis=1).ravel()
    cols = np.tile(dofs, (1, dofs.shape[1])).ravel()
    return sp.csr_matrix((local.ravel(), (rows, cols)), shape=(n, n))


def _vector_dofs(scalar_dofs: np.ndarray) -> np.ndarray:
    """(nel, 30) vector DOFs 3·node + component, ordered (node, component)."""
    return (3 * scalar_dofs.T[:, :, None] + np.arange(3)[None, None, :]).reshape(scalar_dofs.shape[1], -1)


def _elasticity(basis: Basis, material: SolidMaterial, n: int) -> tuple[sp.csr_matrix, sp.csr_matrix]:
    """Isotropic stiffness and consistent mass of the basis' elements, vectorised in chunks."""
    e, nu, rho = material.youngs_modulus_pa, material.poisson_ratio, material.density_kg_m3
    lam, mu = e * nu / ((1 + nu) * (1 - 2 * nu)), e / (2 * (1 + nu))
    grads = np.stack([b[0].grad for b in basis.basis], axis=-1)      # (3, nel, nq, 10)
    values = np.stack([np.asarray(b[0]) for b in basis.basis], axis=-1)    # (nel, nq, 10)
    dx = basis.dx                                                    # (nel, nq)
    dofs = _vector_dofs(basis.element_dofs)
    eye = np.eye(3)
    ks, ms = [], []
    for lo in range(0, dx.shape[0], 4096):
        g, w, v = grads[:, lo:lo + 4096], dx[lo:lo + 4096], values[lo:lo + 4096]
        a = np.einsum("aeqi,beqj,eq->eiajb", g, g, w, optimize=True)   # ∫ ∂_a φ_i ∂_b φ_j
        trace = np.einsum("eicjc->eij", a)
        k = (lam * a + mu * np.einsum("eij,ab->eiajb", trace, eye)
             + mu * a.transpose(0, 1, 4, 3, 2))
        mm = rho * np.einsum("eqi,eqj,eq,ab->eiajb", v, v, w, eye, optimize=True)
        nel = w.shape[0]
        ks.append(k.reshape(nel, 30, 30))
        ms.append(mm.reshape(nel, 30, 30))
    return _scatter(np.concatenate(ks), dofs, n), _scatter(np.concatenate(ms), dofs, n)


def layer_matrix(fb: FacetBasis, kn: float, kt: float, n: int) -> sp.csr_matrix:
    """The spring layer ∫ φ_i φ_j [k_t δ_ab + (k_n − k_t) n_a n_b] dA on the facets of ``fb``.

    Parameters
    ----------
    fb : skfem.FacetBasis
        Scalar P2 basis on the interface facets.
    kn, kt : float
        Normal and tangential stiffness per unit area, N/m³.
    n : int
        3 × number of nodes (DOF k = 3·node + component).

    Returns
    -------
    scipy.sparse.csr_matrix, shape (n, n)
        Acting on the jump [u] in the mesh's own (unduplicated) numbering.
    """
    values = np.stack([np.asarray(b[0]) for b in fb.basis], axis=-1)       # (nf, nq, 10)
    normal = fb.normals                                              # (3, nf, nq)
    tensor = kt * np.eye(3)[:, :, None, None] + (kn - kt) * np.einsum("afq,bfq->abfq", normal, normal)
    local = np.einsum("fqi,fqj,fq,abfq->fiajb", values, values, fb.dx, tensor, optimize=True)
    nf = values.shape[0]
    return _scatter(local.reshape(nf, 30, 30), _vector_dofs(fb.element_dofs), n)


def _rigid_rows(xyz: np.ndarray, comp: np.ndarray, quarter: bool) -> np.ndarray:
    """Rows of u = R q for points ``xyz`` (3, n) and components ``comp`` (n,).

    q = (t_x, θ_y) quarter; (t_x, θ_y, t_y, θ_x) full. u = t + θ × r.
    """
    x, y, z = xyz
    rows = np.zeros((comp.size, 2 if quarter else 4))
    cx, cy, cz = comp == 0, comp == 1, comp == 2
    rows[cx, 0] = 1.0
    rows[cx, 1] = z[cx]                      # u_x = t_x + θ_y z
    rows[cz, 1] = -x[cz]                     # u_z = −θ_y x + θ_x y
    if not quarter:
        rows[cy, 2] = 1.0
        rows[cy, 3] = -z[cy]                 # u_y = t_y − θ_x z
        rows[cz, 3] = y[cz]
    return rows


def interface_facets(m: MeshTet2, part: np.ndarray, interface: Interface, insertion: tuple[float, float] | None,
                     tol: float) -> tuple[np.ndarray, np.ndarray]:
    """The facets between a holder and a tool element, and which of them are joined.

    Parameters
    ----------
    m : skfem.MeshTet2
    part : numpy.ndarray, shape (nelements,)
        0 = holder, 1 = tool.
    interface : Interface
    insertion : (float, float) or None
        z of the shank's end and of the holder face, m; None: every shared facet is joined.
    tol : float
        Distance tolerance, m.

    Returns
    -------
    between : numpy.ndarray of int
        Facet indices.
    connected : numpy.ndarray of bool, shape like ``between``
        Joined (module docstring); the rest are a gap.
    """
    f2t = m.f2t
    inner = f2t[1] >= 0
    between = np.flatnonzero(inner & (part[np.maximum(f2t[0], 0)] != part[np.maximum(f2t[1], 0)]))
    fz = m.p[2][m.facets[:, between]]                      # (3, nfacets) vertex z
    bottom = np.ptp(fz, axis=0) < tol
    centre_z = fz.mean(axis=0)
    connected = np.ones(between.size, dtype=bool)          # no insertion given: all bonded/sprung
    if insertion is not None and between.size:
        start, face = insertion
        z_hi = face - interface.contact_start_m
        z_lo = start if interface.contact_stop_m is None else max(start, face - interface.contact_stop_m)
        fx, fy = m.p[0][m.facets[:, between]], m.p[1][m.facets[:, between]]
        radius = np.hypot(fx, fy)                          # the bore's facets have every vertex on it
        on_bore = ~bottom & (radius.min(axis=0) > radius.max() * (1 - 1e-6))
        back = np.abs(np.angle(-(fx.mean(axis=0) + 1j * fy.mean(axis=0)), deg=True))   # 0 on −x
        in_arc = back <= interface.arc_deg / 2 + 1e-6
        connected = on_bore & in_arc & (centre_z > z_lo - tol) & (centre_z < z_hi + tol)
        connected |= ~on_bore & ~bottom                    # a face the parts share off the bore: a screw's
        if interface.bottom == "connected":
            connected |= bottom
    return between, connected


def assemble(mesh: SolidMesh, materials: tuple[SolidMaterial, SolidMaterial], interface: Interface,
             base: BaseKind, tip_z_m: float, insertion: tuple[float, float] | None = None,
             rigid_holder: bool = False) -> Matrices:
    """Assemble and constrain the model.

    Parameters
    ----------
    mesh : SolidMesh
    materials : (SolidMaterial, SolidMaterial)
        Holder, tool.
    interface : Interface
    base : {"clamped", "elastic", "free"}
        The base face z = 0: fixed; rigid with DOFs q kept (to couple a receptance); free.
    tip_z_m : float
        z of the tip face, m.
    insertion : (float, float) or None
        z of the shank's end in the bore and of the holder's tool-end face, m (where the
        contact region's depths are measured from); None when there is no insertion.
    rigid_holder : bool
        Tie every holder node to q (needs a clamped or elastic base).

    Returns
    -------
    Matrices
    """
    m = MeshTet2(mesh.points_m, mesh.tets)
    element = ElementTetP2()
    parts = [np.flatnonzero(mesh.part == k) for k in (0, 1)]
    bases = [Basis(m, element, elements=idx, intorder=_INTORDER) if idx.size else None for idx in parts]
    full = Basis(m, element, intorder=0)
    nnodes = full.N
    ndof = 3 * nnodes
    xyz = full.doflocs                                      # (3, nnodes)
    scale = float(np.max(np.abs(xyz)))
    tol = 1e-9 * scale

    kk, mm = [], []
    for b, mat in zip(bases, materials, strict=True):
        if b is None:
            kk.append(sp.csr_matrix((ndof, ndof)))
            mm.append(sp.csr_matrix((ndof, ndof)))
        else:
            k, mass = _elasticity(b, mat, ndof)
            kk.append(k)
            mm.append(mass)

    # --- interface facets: between a holder and a tool element
    between, connected = interface_facets(m, mesh.part, interface, insertion, tol)
    springs = between[connected] if interface.model == "layer" else between[:0]
    bonded = between[connected] if interface.model == "bonded" else between[:0]
    loose = np.setdiff1d(between, bonded)
    def nodes_of(facets: np.ndarray) -> np.ndarray:
        return np.unique(full.get_dofs(facets=facets).all()) if facets.size else np.array([], dtype=np.int64)

    dup_nodes = np.setdiff1d(nodes_of(loose), nodes_of(bonded))
    dup_dofs = (3 * dup_nodes[:, None] + np.arange(3)).ravel()

    # --- the new DOFs: classify every node for each view (holder = original, tool = copies)
    comp_of = np.tile(np.arange(3), nnodes)
    node_of = np.repeat(np.arange(nnodes), 3)
    dof_xyz = xyz[:, node_of]
    fixed_sym = np.zeros(ndof, dtype=bool)
    if mesh.quarter:
        on_y0 = np.abs(dof_xyz[1]) < tol
        on_x0 = np.abs(dof_xyz[0]) < tol
        fixed_sym = (on_y0 & (comp_of == 1)) | (on_x0 & ((comp_of == 1) | (comp_of == 2)))
    elif mesh.half:
        fixed_sym = (np.abs(dof_xyz[1]) < tol) & (comp_of == 1)
    reduced_q = mesh.quarter or mesh.half                  # q = (u_x, θ_y): bending in x only
    holder_dof = np.zeros(ndof, dtype=bool)
    if bases[0] is not None:
        holder_dof[_vector_dofs(full.element_dofs[:, parts[0]]).ravel()] = True
    on_base = (np.abs(dof_xyz[2]) < tol) & holder_dof
    rigid = on_base if base != "free" else np.zeros(ndof, dtype=bool)
    if rigid_holder:
        if base == "free":
            raise ValueError("rigid_holder needs a clamped or elastic base")
        rigid = rigid | holder_dof
    nq = (2 if reduced_q else 4) if base == "elastic" else 0

    free_holder = ~(rigid | fixed_sym)
    is_dup = np.zeros(ndof, dtype=bool)
    is_dup[dup_dofs] = True
    dup_free = is_dup & ~fixed_sym
    n_free = int(free_holder.sum())
    n_dup = int(dup_free.sum())
    col_holder = np.full(ndof, -1)
    col_holder[free_holder] = np.arange(n_free)
    col_dup = np.full(ndof, -1)
    col_dup[dup_free] = n_free + np.arange(n_dup)
    n_new = n_free + n_dup + nq

    def view(dup: bool) -> sp.csr_matrix:
        rows, cols, vals = [], [], []
        own = free_holder & ~(is_dup if dup else np.zeros(ndof, bool))
        idx = np.flatnonzero(own)
        rows.append(idx)
        cols.append(col_holder[idx])
        vals.append(np.ones(idx.size))
        if dup:
            idx = np.flatnonzero(dup_free)
            rows.append(idx)
            cols.append(col_dup[idx])
            vals.append(np.ones(idx.size))
        if nq:
            sel = rigid & ~fixed_sym & ~(is_dup if dup else np.zeros(ndof, bool))
            idx = np.flatnonzero(sel)
            r = _rigid_rows(dof_xyz[:, idx], comp_of[idx], reduced_q)
            for j in range(nq):
                nz = r[:, j] != 0
                rows.append(idx[nz])
                cols.append(np.full(int(nz.sum()), n_free + n_dup + j))
                vals.append(r[nz, j])
        return sp.csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
                             shape=(ndof, n_new))

    t_h, t_t = view(False), view(True)
    stiff = [((t_h.T @ kk[0] @ t_h).tocsr(), materials[0].loss_factor),
             ((t_t.T @ kk[1] @ t_t).tocsr(), materials[1].loss_factor)]
    mass = (t_h.T @ mm[0] @ t_h + t_t.T @ mm[1] @ t_t).tocsr()
    if springs.size:
        kn = float(interface.interface_stiffness_n_m3 or 0.0)
        kt = kn * interface.tangential_ratio
        a = layer_matrix(FacetBasis(m, element, facets=springs, intorder=_INTORDER), kn, kt, ndof)
        jump = (t_t - t_h).tocsr()
        stiff.append(((jump.T @ a @ jump).tocsr(), interface.loss_factor))
    for k, (mat, eta) in enumerate(stiff):
        stiff[k] = ((0.5 * (mat + mat.T)).tocsr(), eta)

    loads = tip_loads(m, element, tip_z_m, tol, mesh.multiplicity)
    tip = np.column_stack([t_t.T @ loads[:, 0], t_t.T @ loads[:, 1]])
    return Matrices(stiffness=tuple(stiff), mass=(0.5 * (mass + mass.T)).tocsr(), tip_loads=tip,
                    n_boundary=nq, multiplicity=mesh.multiplicity, n_dof_mesh=ndof)


def tip_loads(m: MeshTet2, element: ElementTetP2, tip_z_m: float, tol: float, multiplicity: int) -> np.ndarray:
    """Unit x force (uniform traction) and unit moment about +y (linear axial traction) on the tip face.

    Parameters
    ----------
    m : skfem.MeshTet2
    element : skfem.ElementTetP2
    tip_z_m : float
        z of the tip face, m.
    tol : float
        Distance within which a node lies on the face, m.
    multiplicity : int
        Copies of the mesh in the whole body (4 quarter, 2 half): the face's area
        and second moment are those of the whole face.

    Returns
    -------
    numpy.ndarray, shape (3 · nnodes, 2)
        Consistent nodal loads (DOF k = 3·node + component).
    """
    bf = m.boundary_facets()
    on_tip = bf[np.all(np.abs(m.p[2][m.facets[:, bf]] - tip_z_m) < tol, axis=0)]
    if on_tip.size == 0:
        raise ValueError("no tip face found at z = tip_z_m")
    fb = FacetBasis(m, element, facets=on_tip, intorder=_INTORDER)
    x = np.asarray(fb.global_coordinates())[0]                             # (nf, nq)
    area = multiplicity * float(np.sum(fb.dx))
    second = multiplicity * float(np.sum(fb.dx * x**2))
    values = np.stack([np.asarray(b[0]) for b in fb.basis], axis=-1)       # (nf, nq, 10)
    out = np.zeros((3 * m.nvertices + 3 * m.nedges, 2))
    dofs = fb.element_dofs.T                                         # (nf, 10) nodes
    np.add.at(out[:, 0], 3 * dofs, np.einsum("fqi,fq->fi", values, fb.dx) / area)
    np.add.at(out[:, 1], 3 * dofs + 2, np.einsum("fqi,fq->fi", values, -x * fb.dx) / second)
    return out
