"""Craig–Bampton reduction and the vectorised frequency response.

Basis (interior DOFs i, base DOFs q):

* fixed-interface modes Φ of (K_ii, M_ii) (base held, real undamped stiffness) up to a
  cut-off frequency (≥ 2.5 × the highest frequency asked for);
* constraint modes Ψ = −K_ii⁻¹ K_iq (static shapes of unit base motions);
* the static responses to the two tip loads with the base held, made M-orthogonal to Φ
  (the tip treated as a boundary: the modal truncation then leaves no static error at
  the tip), and, with base DOFs, to the inertia loads of base motion (M_ii Ψ + M_iq).

The reduced stiffness keeps each part's matrix with its own loss factor, so the damping is
exactly the full model's hysteretic damping projected on the basis. The response at all
frequencies is one stacked dense solve ``(nfreq, n, n)``. :func:`direct_tip_receptance`
is the unreduced sparse complex solve the truncation is checked against.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from tests.oracles.solid3d.assembly import Matrices

__all__ = ["ReducedModel", "base_block", "direct_tip_receptance", "free_frequencies_hz", "reduce",
           "reduced_arrays", "reduced_from_arrays", "tip_receptance"]

_CHUNK = 256


def _factor(a: sp.spmatrix) -> spla.SuperLU:
    return spla.splu(a.tocsc(), permc_spec="MMD_AT_PLUS_A", options={"SymmetricMode": True})


def _modes(k: sp.spmatrix, m: sp.spmatrix, lu: spla.SuperLU, sigma: float, cutoff_hz: float,
           start: int = 16) -> tuple[np.ndarray, np.ndarray]:
    """Modes of (k, m) with frequency ≤ cutoff (at least ``start``), ascending; shift-invert at sigma."""
    n = k.shape[0]
    op = spla.LinearOperator((n, n), matvec=lu.solve, dtype=float)
    count = min(start, n - 2)
    while True:
        lam, vec = spla.eigsh(k, k=count, M=m, sigma=sigma, OPinv=op, which="LM")
        order = np.argsort(lam)
        lam, vec = lam[order], vec[:, order]
        freq = np.sqrt(np.maximum(lam, 0.0)) / (2 * np.pi)
        if freq[-1] >= cutoff_hz or count >= n - 2:
            keep = freq <= cutoff_hz
            return freq[keep], vec[:, keep]
        count = min(2 * count, n - 2)


@dataclass(frozen=True, slots=True)
class ReducedModel:
    """A Craig–Bampton model of the body.

    Attributes
    ----------
    stiffness : tuple of (numpy.ndarray, float)
        Reduced real stiffness matrices (n, n) with their loss factors.
    mass : numpy.ndarray, shape (n, n)
    tip_loads : numpy.ndarray, shape (n, 2)
    n_boundary : int
        The last ``n_boundary`` reduced DOFs are the base DOFs q (physical).
    multiplicity : int
        See :class:`~tests.oracles.solid3d.assembly.Matrices`.
    fixed_base_frequencies_hz : numpy.ndarray, shape (nmodes,)
        Undamped natural frequencies with the base held (q = 0), Hz, up to the cut-off.
    cutoff_hz : float
    """

    stiffness: tuple[tuple[np.ndarray, float], ...]
    mass: np.ndarray
    tip_loads: np.ndarray
    n_boundary: int
    multiplicity: int
    fixed_base_frequencies_hz: np.ndarray
    cutoff_hz: float

    @property
    def n_modes(self) -> int:
        """Fixed-interface modes kept."""
        return int(self.fixed_base_frequencies_hz.size)


def reduce(mats: Matrices, cutoff_hz: float) -> ReducedModel:
    """Craig–Bampton reduction with the tip loads' static shapes.

    Parameters
    ----------
    mats : Matrices
        Base clamped (``n_boundary = 0``) or elastic.
    cutoff_hz : float
        Keep every fixed-interface mode up to this frequency, Hz.

    Returns
    -------
    ReducedModel
    """
    k = mats.real_stiffness().tocsc()
    m = mats.mass.tocsc()
    nq = mats.n_boundary
    ni = k.shape[0] - nq
    k_ii, m_ii = k[:ni, :ni], m[:ni, :ni]
    lu = _factor(k_ii)
    freq, phi = _modes(k_ii, m_ii, lu, 0.0, cutoff_hz)
    loads = np.asarray(mats.tip_loads[:ni])
    if nq:
        psi = -lu.solve(k[:ni, ni:].toarray())
        # static responses to the inertia loads of base motion (their modal truncation error
        # grows like ω²; without them the coupled h is off by 2 % at 6 kHz on a spindle)
        loads = np.hstack([loads, m_ii @ psi + m[:ni, ni:].toarray()])
    x = lu.solve(loads)
    x = x - phi @ (phi.T @ (m_ii @ x))
    x, _ = np.linalg.qr(x / np.linalg.norm(x, axis=0))
    parts = [phi, x]
    if nq:
        parts.append(psi)
    v_i = np.hstack(parts)
    n_red = v_i.shape[1]
    v = np.zeros((ni + nq, n_red))
    v[:ni] = v_i
    if nq:
        v[ni:, n_red - nq:] = np.eye(nq)          # q are the last reduced DOFs

    def project(a: sp.spmatrix) -> np.ndarray:
        r = v.T @ (a @ v)
        return 0.5 * (r + r.T)

    return ReducedModel(stiffness=tuple((project(a), eta) for a, eta in mats.stiffness), mass=project(m),
                        tip_loads=v.T @ mats.tip_loads, n_boundary=nq, multiplicity=mats.multiplicity,
                        fixed_base_frequencies_hz=freq, cutoff_hz=cutoff_hz)


def reduced_arrays(red: ReducedModel, prefix: str = "reduced_") -> dict[str, np.ndarray]:
    """A reduced model as named arrays (to store in an ``.npz``; :func:`reduced_from_arrays` reads them).

    Parameters
    ----------
    red : ReducedModel
    prefix : str
        Put before every name.

    Returns
    -------
    dict of str to numpy.ndarray
        ``stiffness_<i>`` (one per part), ``loss_factors``, ``mass``, ``tip_loads``,
        ``fixed_base_frequencies_hz``, ``meta`` (n_boundary, multiplicity, cutoff_hz).
    """
    out = {f"{prefix}stiffness_{i}": a for i, (a, _) in enumerate(red.stiffness)}
    out.update({f"{prefix}loss_factors": np.array([eta for _, eta in red.stiffness]), f"{prefix}mass": red.mass,
                f"{prefix}tip_loads": red.tip_loads, f"{prefix}fixed_base_frequencies_hz": red.fixed_base_frequencies_hz,
                f"{prefix}meta": np.array([red.n_boundary, red.multiplicity, red.cutoff_hz], dtype=float)})
    return out


def reduced_from_arrays(arrays: dict[str, np.ndarray], prefix: str = "reduced_") -> ReducedModel:
    """The reduced model :func:`reduced_arrays` wrote.

    Parameters
    ----------
    arrays : mapping of str to numpy.ndarray
    prefix : str

    Returns
    -------
    ReducedModel
    """
    etas = arrays[f"{prefix}loss_factors"]
    nq, mult, cutoff = arrays[f"{prefix}meta"]
    return ReducedModel(stiffness=tuple((np.asarray(arrays[f"{prefix}stiffness_{i}"]), float(eta))
                                        for i, eta in enumerate(etas)),
                        mass=np.asarray(arrays[f"{prefix}mass"]), tip_loads=np.asarray(arrays[f"{prefix}tip_loads"]),
                        n_boundary=int(nq), multiplicity=int(mult),
                        fixed_base_frequencies_hz=np.asarray(arrays[f"{prefix}fixed_base_frequencies_hz"]),
                        cutoff_hz=float(cutoff))


def base_block(base_stiffness: np.ndarray, n_boundary: int, multiplicity: int) -> np.ndarray:
    """The base's dynamic stiffness on q, shape (nfreq, nq, nq).

    Parameters
    ----------
    base_stiffness : numpy.ndarray, shape (nfreq, 2, 2)
        Inverse of the base receptance in the x–z plane, on (u_x, ψ = θ_y).
    n_boundary : int
        2 (quarter model: q = (u_x, θ_y)) or 4 (full: q = (u_x, θ_y, u_y, θ_x)).
    multiplicity : int
        The model is this fraction of the body: its share of the base stiffness.

    Returns
    -------
    numpy.ndarray
    """
    d = base_stiffness / multiplicity
    if n_boundary == 2:
        return d
    out = np.zeros((d.shape[0], 4, 4), dtype=d.dtype)
    out[:, :2, :2] = d
    # y–z plane: w = u_y, ψ = du_y/dz = −θ_x, so on (u_y, θ_x) the block is S D S, S = diag(1, −1)
    sign = np.array([1.0, -1.0])
    out[:, 2:, 2:] = d * sign[None, :, None] * sign[None, None, :]
    return out


def tip_receptance(red: ReducedModel, omega_rad_s: np.ndarray, base_stiffness: np.ndarray | None = None,
                   damped: bool = True) -> np.ndarray:
    """Tip receptance ``[[h, l], [n, p]]`` of the reduced model, shape (nfreq, 2, 2).

    Parameters
    ----------
    red : ReducedModel
    omega_rad_s : numpy.ndarray, shape (nfreq,)
    base_stiffness : numpy.ndarray, shape (nfreq, 2, 2), optional
        Inverse base receptance (x–z plane); without it the base is held (q = 0).
    damped : bool
        False drops every loss factor.

    Returns
    -------
    numpy.ndarray, complex
    """
    k = sum(a * (1 + 1j * eta if damped else 1.0) for a, eta in red.stiffness)
    mass = red.mass
    omega = np.asarray(omega_rad_s, dtype=float)
    nq = red.n_boundary
    out = np.empty((omega.size, 2, 2), dtype=complex)
    f = red.tip_loads
    if nq and base_stiffness is None:       # base held: q = 0, the Craig–Bampton model of the clamped body
        k, mass, f, nq = k[:-nq, :-nq], mass[:-nq, :-nq], f[:-nq], 0
    for lo in range(0, omega.size, _CHUNK):
        w = omega[lo:lo + _CHUNK]
        z = k[None] - (w**2)[:, None, None] * mass[None]
        if nq:
            assert base_stiffness is not None
            z = z.astype(complex)
            z[:, -nq:, -nq:] += base_block(base_stiffness[lo:lo + _CHUNK], nq, red.multiplicity)
        x = np.linalg.solve(z, np.broadcast_to(f.astype(complex), (w.size, *f.shape)))
        out[lo:lo + _CHUNK] = red.multiplicity * np.einsum("ia,fib->fab", f, x)
    return out


def direct_tip_receptance(mats: Matrices, omega_rad_s: np.ndarray, base_stiffness: np.ndarray | None = None
                          ) -> np.ndarray:
    """Tip receptance of the unreduced model by a sparse complex solve per frequency (a check).

    Parameters
    ----------
    mats : Matrices
    omega_rad_s : numpy.ndarray, shape (nfreq,)
        A few frequencies.
    base_stiffness : numpy.ndarray, shape (nfreq, 2, 2), optional

    Returns
    -------
    numpy.ndarray, shape (nfreq, 2, 2), complex
    """
    k = mats.complex_stiffness().tocsc()
    m = mats.mass.tocsc()
    nq, n = mats.n_boundary, k.shape[0]
    loads = mats.tip_loads
    if nq and base_stiffness is None:       # base held
        n -= nq
        k, m, loads, nq = k[:n, :n], m[:n, :n], loads[:n], 0
    out = np.empty((len(omega_rad_s), 2, 2), dtype=complex)
    for j, w in enumerate(omega_rad_s):  # an oracle's loop: a handful of sparse factorisations
        z = k - w**2 * m
        if nq:
            assert base_stiffness is not None
            d = base_block(base_stiffness[j:j + 1], nq, mats.multiplicity)[0]
            rows, cols = np.meshgrid(np.arange(n - nq, n), np.arange(n - nq, n), indexing="ij")
            z = z + sp.csc_matrix((d.ravel(), (rows.ravel(), cols.ravel())), shape=(n, n))
        # SuperLU's complex factorisation is ~10x slower than the real one of [[Re, −Im], [Im, Re]]
        z = z.tocsc()
        big = sp.bmat([[z.real, -z.imag], [z.imag, z.real]]).tocsc()
        lu = spla.splu(big, permc_spec="MMD_AT_PLUS_A", options={"SymmetricMode": True})
        xx = lu.solve(np.vstack([loads, np.zeros_like(loads)]))
        x = xx[:n] + 1j * xx[n:]
        out[j] = mats.multiplicity * (loads.T @ x)
    return out


def free_frequencies_hz(mats: Matrices, count: int) -> np.ndarray:
    """The lowest ``count`` elastic natural frequencies of a free body (rigid modes dropped), Hz.

    Parameters
    ----------
    mats : Matrices
        Built with ``base="free"``.
    count : int

    Returns
    -------
    numpy.ndarray, shape (count,)
    """
    k, m = mats.real_stiffness().tocsc(), mats.mass.tocsc()
    sigma = -((2 * np.pi * 10.0) ** 2)
    lu = _factor(k - sigma * m)
    n = k.shape[0]
    op = spla.LinearOperator((n, n), matvec=lu.solve, dtype=float)
    lam = np.sort(spla.eigsh(k, k=count + 6, M=m, sigma=sigma, OPinv=op, which="LM", return_eigenvectors=False))
    freq = np.sqrt(np.maximum(lam, 0.0)) / (2 * np.pi)
    return freq[freq > 1.0][:count]
