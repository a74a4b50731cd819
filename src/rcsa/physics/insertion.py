"""The tool shank inside the holder nose: two beams sharing load through a distributed interface.

Over the inserted length a shank and the holder around it are two concentric Timoshenko
beams (the holder annulus, index h, and the solid shank core, index t) joined along their
length by a distributed elastic interface: a translational stiffness per unit length
``k_w`` (N/m per m, i.e. N/m²) acting on their relative deflection, and a rotational one
``k_θ`` (N·m/rad per m, i.e. N) acting on their relative rotation. This is how a clamped
shank hands its shear force and bending moment over to the holder: not at one section, as a
composite beam with a point joint at the holder face assumes, but over a transfer length of
about ``(4 EI / k_w)^¼``, in which the steel around the bore deforms. With ``k_w → ∞`` the
pair tends to the composite section; with ``k_w = k_θ = 0`` (a gap) the two beams are free of
each other.

Equations (time dependence e^{iωt}, state ``y = [w_h, ψ_h, V_h, M_h, w_t, ψ_t, V_t, M_t]``
with ``V = κGA (w' − ψ)`` and ``M = EI ψ'`` as in :mod:`rcsa.physics.segments`)::

    w_i' = ψ_i + V_i / κGA_i
    ψ_i' = M_i / EI_i
    V_i' = k_w (w_i − w_j) − ρA_i ω² w_i
    M_i' = −V_i − ρI_i ω² ψ_i + k_θ (ψ_i − ψ_j)

They follow from the energies of the two beams plus ``½∫ k_w (w_h − w_t)² + k_θ (ψ_h − ψ_t)² dx``,
so the dynamic stiffness they give is symmetric. A uniform piece has the exact transfer
matrix ``T = exp(A L)`` (a matrix exponential of the constant 8×8 state matrix, computed in
dimensionless variables, one per frequency line); end loads and DOF order follow
:mod:`rcsa.physics.segments`: loads ``−[V, M](0)`` and ``+[V, M](L)``, DOFs
``(w_h, ψ_h, w_t, ψ_t)`` at each end. A piece whose waves decay by more than
``e^MAX_DECAY_PER_PIECE`` is cut into equal sub-pieces, joined by condensation.

A matrix exponential per frequency line would cost far more than the rest of a prediction,
so each piece is evaluated through its Chebyshev interpolant in ω²: with no viscous damper
inside, the dynamic stiffness of a piece depends on ω only through ω², and a piece short
enough that neither of its beams, clamped at both ends, has a natural frequency below
2 ω_fit (Rayleigh's bound, :meth:`rcsa.physics.chain.Beam.max_piece_length_m`) has no pole
below 4 ω_fit²: on ``[0, ω_fit²]`` the interpolant converges geometrically (by a factor ≥ 13.9
per degree). It is built from exact matrix exponentials at the Chebyshev nodes, checked
against exact values between them (relative error ≤ :data:`INTERPOLATION_RTOL`, else the
degree doubles) and cached per piece and frequency band.

:class:`Insertion` is the chain item (:class:`rcsa.physics.chain.ChainItem`) of the whole
inserted length: it enters at the holder node where the insertion starts (toward the
spindle), where the shank's inner end is free, and leaves at the shank node in the holder's
tool-end face, where the holder's front end is free. Its internal DOFs are condensed onto
those two nodes (a 4×4 two-port, like a beam's); every internal pivot is reported for the
Wittrick–Williams count.
"""

from __future__ import annotations

import math
import threading
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, replace
from typing import Any, Generic, Self, TypeVar

import numpy as np

from rcsa.physics.algebra2x2 import Pivots, inv2
from rcsa.physics.arrays import ComplexArray, ComplexParam, FloatArray, IntArray, RealParam
from rcsa.physics.chain import Beam, Grid, Sym
from rcsa.physics.sections import Section
from rcsa.physics.segments import MAX_DECAY_PER_PIECE
from rcsa.physics.subassembly_cache import LruStore

__all__ = ["INTERPOLATION_RTOL", "Insertion", "InsertionPiece", "contact_per_length", "contact_stiffness_n_m3",
           "expm_stack", "piece_stiffness", "unit_stiffness"]

_EYE2 = np.eye(2)
#: state indices of the displacements ``(w_h, ψ_h, w_t, ψ_t)`` and forces ``(V_h, M_h, V_t, M_t)``
_U = np.array([0, 1, 4, 5])
_F = np.array([2, 3, 6, 7])


def contact_stiffness_n_m3(contact_pressure_pa: float, surface_roughness_m: float) -> float:
    """Normal interface stiffness per unit area of a rough contact, ``k_n = p / σ``, N/m³.

    Greenwood–Williamson asperity contact with exponentially distributed heights of scale
    σ: the real contact area, the load and the normal stiffness all grow in proportion
    to ``exp(−h/σ)`` with the separation h, so ``k_n = −dp/dh = p/σ``.

    Parameters
    ----------
    contact_pressure_pa : float
        Nominal contact pressure p, Pa (a shrink fit: tens of MPa).
    surface_roughness_m : float
        Scale σ of the asperity heights, m (about the combined RMS roughness).

    Returns
    -------
    float

    Examples
    --------
    >>> contact_stiffness_n_m3(50e6, 1e-6)
    50000000000000.0
    """
    return contact_pressure_pa / surface_roughness_m


def contact_per_length(normal_n_m3: ComplexParam, tangential_n_m3: ComplexParam,
                       shank_diameter_m: float) -> tuple[ComplexParam, ComplexParam]:
    """Stiffness per unit length of a shank–bore contact from its stiffness per unit area.

    A lateral relative displacement δ of the shank opens the gap by ``δ cos θ`` and slides it
    by ``δ sin θ`` around the circumference of radius r = d/2; integrating the projected
    tractions gives ``k_w = π r (k_n + k_t)``. A relative rotation φ slides the surface axially
    by ``φ r cos θ``: ``k_θ = π r³ k_t``.

    Parameters
    ----------
    normal_n_m3, tangential_n_m3 : complex
        Interface stiffness per unit area, normal and tangential, N/m³.
    shank_diameter_m : float
        Shank diameter, m.

    Returns
    -------
    k_w : complex
        N/m per m.
    k_theta : complex
        N·m/rad per m.

    Examples
    --------
    >>> kw, kt = contact_per_length(1e14, 1e14, 0.010)
    >>> round(kw / 1e12, 4), round(kt / 1e6, 4)
    (3.1416, 39.2699)
    """
    r = shank_diameter_m / 2.0
    return math.pi * r * (normal_n_m3 + tangential_n_m3), math.pi * r**3 * tangential_n_m3


@dataclass(frozen=True, slots=True)
class InsertionPiece:
    """A uniform length of holder annulus around a shank core, with the interface between them.

    Parameters
    ----------
    holder : Section
        The holder annulus around the bore.
    core : Section
        The tool shank inside it (a solid circle).
    length_m : float
        Axial length, m (> 0).
    interface_n_m2 : complex
        Translational interface stiffness per unit length, N/m per m (complex: ``k(1 + iη)``);
        0 where the shank does not touch the bore.
    interface_rotational_n : complex
        Rotational interface stiffness per unit length, N·m/rad per m.
    """

    holder: Section
    core: Section
    length_m: RealParam
    interface_n_m2: ComplexParam
    interface_rotational_n: ComplexParam = 0.0

    def undamped(self) -> InsertionPiece:
        """The piece with real moduli and a real interface."""
        return InsertionPiece(self.holder.undamped(), self.core.undamped(), self.length_m,
                              _real_part(self.interface_n_m2), _real_part(self.interface_rotational_n))

    def decay_per_m(self, omega_max_rad_s: float) -> float:
        """An upper estimate of the fastest spatial decay rate of the piece's waves up to ω_max, 1/m.

        The largest of the relative (interface) mode ``(k_w (1/EI_h + 1/EI_t))^¼``, the rotational
        coupling ``(k_θ (1/EI_h + 1/EI_t))^½``, each beam's evanescent bending wave
        ``(ρA ω² / EI)^¼`` and, for Timoshenko beams, the shear boundary layer ``(κGA / EI)^½``
        that a stiff interface excites.

        Parameters
        ----------
        omega_max_rad_s : float
            Highest angular frequency, rad/s.
        """
        flex = sum(1.0 / np.abs(np.asarray(s.ei)) for s in (self.holder, self.core))
        rates = [(np.abs(np.asarray(self.interface_n_m2)) * flex) ** 0.25,
                 (np.abs(np.asarray(self.interface_rotational_n)) * flex) ** 0.5]
        for s in (self.holder, self.core):
            ei = np.abs(np.asarray(s.ei))
            rates.append((np.asarray(s.rho_a, dtype=float) * omega_max_rad_s**2 / ei) ** 0.25)
            f = np.abs(np.asarray(s.shear_flexibility))
            if np.all(f > 0):
                rates.append((1.0 / (f * ei)) ** 0.5)
        return float(max(np.max(r) for r in rates))


def _real_part(value: ComplexParam) -> ComplexParam:
    """The real part of a (stacked) complex parameter, kept complex."""
    if isinstance(value, np.ndarray):
        out: ComplexArray = value.real.astype(complex)
        return out
    return complex(complex(value).real)


def _broadcast(value: Any, n: int) -> np.ndarray:
    return np.broadcast_to(np.asarray(value), (n,))


#: Coefficients of the [13/13] Padé approximant of exp (Higham 2005), and its scaling threshold.
_PADE13 = (64764752532480000.0, 32382376266240000.0, 7771770303897600.0, 1187353796428800.0,
           129060195264000.0, 10559470521600.0, 670442572800.0, 33522128640.0, 1323241920.0, 40840800.0,
           960960.0, 16380.0, 182.0, 1.0)
_THETA13 = 5.371920351148152


def expm_stack(a: ComplexArray) -> ComplexArray:
    """Matrix exponentials of a stack of square matrices, shape (n, k, k).

    Scaling and squaring with the [13/13] Padé approximant (Higham 2005), one scaling for the
    whole stack (the largest 1-norm): a few batched products and one batched solve.

    Parameters
    ----------
    a : numpy.ndarray, shape (n, k, k)
        The matrices (complex).

    Returns
    -------
    numpy.ndarray, shape (n, k, k), complex

    Examples
    --------
    >>> a = np.array([[[0.0, 1.0], [-1.0, 0.0]]]) * np.pi / 2
    >>> np.round(expm_stack(a).real, 12)
    array([[[ 0.,  1.],
            [-1.,  0.]]])
    """
    norm = float(np.max(np.sum(np.abs(a), axis=-2), initial=0.0))
    squarings = max(0, math.ceil(math.log2(norm / _THETA13))) if norm > _THETA13 else 0
    if squarings:
        a = a / 2.0**squarings
    b = _PADE13
    eye = np.eye(a.shape[-1])
    a2 = a @ a
    a4 = a2 @ a2
    a6 = a2 @ a4
    u = a @ (a6 @ (b[13] * a6 + b[11] * a4 + b[9] * a2) + b[7] * a6 + b[5] * a4 + b[3] * a2 + b[1] * eye)
    v = a6 @ (b[12] * a6 + b[10] * a4 + b[8] * a2) + b[6] * a6 + b[4] * a4 + b[2] * a2 + b[0] * eye
    r: ComplexArray = np.linalg.solve(v - u, v + u)
    for _ in range(squarings):
        r = r @ r
    return r


def _state_matrix(omega_rad_s: FloatArray, piece: InsertionPiece, length_m: FloatArray,
                  ei_ref: ComplexArray) -> ComplexArray:
    """Dimensionless state matrix ``Â`` of a piece, shape (nfreq, 8, 8), so that ``T̂ = exp(Â)``.

    Scaled state ``ŷ = [w/L, ψ, V L²/EI₀, M L/EI₀]`` per beam, along ``ξ = x/L``.
    """
    n = omega_rad_s.size
    w2 = omega_rad_s**2
    el = length_m
    a = np.zeros((n, 8, 8), dtype=complex)
    kw = _broadcast(piece.interface_n_m2, n) * el**4 / ei_ref
    kr = _broadcast(piece.interface_rotational_n, n) * el**2 / ei_ref
    for i, s in ((0, piece.holder), (4, piece.core)):
        j = 4 - i
        ei = _broadcast(s.ei, n)
        a[:, i, i + 1] = 1.0                                                       # w' = ψ + f V
        a[:, i, i + 2] = _broadcast(s.shear_flexibility, n) * ei_ref / el**2
        a[:, i + 1, i + 3] = ei_ref / ei                                           # ψ' = M / EI
        a[:, i + 2, i] = kw - _broadcast(s.rho_a, n) * w2 * el**4 / ei_ref         # V' = k_w Δw − ρAω² w
        a[:, i + 2, j] = -kw
        a[:, i + 3, i + 2] = -1.0                                                  # M' = −V − ρIω²ψ + k_θ Δψ
        a[:, i + 3, i + 1] = kr - _broadcast(s.rho_i, n) * w2 * el**2 / ei_ref
        a[:, i + 3, j + 1] = -kr
    return a


def piece_stiffness(omega_rad_s: FloatArray, piece: InsertionPiece) -> ComplexArray:
    """Exact dynamic stiffness of a uniform piece, shape (nfreq, 8, 8).

    DOFs ``(w_h, ψ_h, w_t, ψ_t)`` at ``x = 0`` then at ``x = L``; units N/m, N/rad, N·m/rad.
    From ``T = exp(A L)``: ``D = [[T_uf⁻¹ T_uu, −T_uf⁻¹], [T_fu − T_ff T_uf⁻¹ T_uu, T_ff T_uf⁻¹]]``.
    Accurate while the piece's decay exponent is at most a few units
    (:meth:`InsertionPiece.decay_per_m`; :func:`unit_stiffness` cuts longer ones).

    Parameters
    ----------
    omega_rad_s : numpy.ndarray, shape (nfreq,)
        Angular frequencies ≥ 0, rad/s.
    piece : InsertionPiece
        Its parameters: numbers, or arrays of shape (nfreq,) (one per line).

    Returns
    -------
    numpy.ndarray, shape (nfreq, 8, 8), complex
    """
    omega = np.asarray(omega_rad_s, dtype=float)
    n = omega.size
    el = _broadcast(piece.length_m, n).astype(float)
    ei_ref = _broadcast(piece.holder.ei, n).astype(complex)
    t_hat = expm_stack(_state_matrix(omega, piece, el, ei_ref))
    # back to physical units: y = S ŷ with S = diag(L, 1, EI₀/L², EI₀/L) per beam
    scale = np.stack([el, np.ones(n), ei_ref / el**2, ei_ref / el] * 2, axis=-1)
    t = scale[:, :, None] * t_hat / scale[:, None, :]
    tuu, tuf = t[:, _U][:, :, _U], t[:, _U][:, :, _F]
    tfu, tff = t[:, _F][:, :, _U], t[:, _F][:, :, _F]
    g = np.linalg.inv(tuf)
    d = np.empty((n, 8, 8), dtype=complex)
    d[:, :4, :4] = g @ tuu
    d[:, :4, 4:] = -g
    d[:, 4:, 4:] = tff @ g
    d[:, 4:, :4] = tfu - d[:, 4:, 4:] @ tuu
    d += np.swapaxes(d, -1, -2).copy()  # symmetric in exact arithmetic (reciprocity)
    d *= 0.5
    return d


def _report(pivots: Pivots | None, p: np.ndarray) -> None:
    """Report a real symmetric pivot block, shape (n, k, k), to a Wittrick–Williams accumulator."""
    if pivots is None:
        return
    p = np.real(p)
    pivots.negatives += np.sum(np.linalg.eigvalsh(p) < 0.0, axis=-1)
    sign, logdet = np.linalg.slogdet(p)
    pivots.log_abs_det += np.where(sign == 0, math.log(1e-300), logdet)


def _schur(m: np.ndarray, keep: np.ndarray, drop: np.ndarray, pivots: Pivots | None = None) -> np.ndarray:
    """Condense the DOFs ``drop`` of stiffness matrices ``m`` (n, k, k) onto ``keep``."""
    p = m[:, drop][:, :, drop]
    _report(pivots, p)
    mk = m[:, keep]
    out: np.ndarray = mk[:, :, keep] - mk[:, :, drop] @ np.linalg.solve(p, m[:, drop][:, :, keep])
    return out


_ENDS = np.arange(4), np.arange(4, 8)
_JOIN_KEEP, _JOIN_DROP = np.array([0, 1, 2, 3, 8, 9, 10, 11]), np.array([4, 5, 6, 7])


def _chain_units(units: Sequence[np.ndarray]) -> np.ndarray:
    """Two-end stiffness (n, 8, 8) of equal-DOF pieces joined end to end (middle nodes condensed)."""
    out = units[0]
    for d in units[1:]:
        m = np.zeros((out.shape[0], 12, 12), dtype=complex)
        m[:, :8, :8] = out
        m[:, 4:, 4:] += d
        out = _schur(m, _JOIN_KEEP, _JOIN_DROP)
    return out


def unit_stiffness(omega_rad_s: FloatArray, piece: InsertionPiece) -> ComplexArray:
    """Exact dynamic stiffness of a piece of any length, shape (nfreq, 8, 8).

    Cut into equal sub-pieces whose decay exponent is at most ``MAX_DECAY_PER_PIECE`` at the
    highest frequency, each computed by :func:`piece_stiffness` (one set, reused) and joined.

    Parameters
    ----------
    omega_rad_s : numpy.ndarray, shape (nfreq,)
        Angular frequencies ≥ 0, rad/s.
    piece : InsertionPiece
        Scalar parameters.

    Returns
    -------
    numpy.ndarray, shape (nfreq, 8, 8), complex
    """
    omega = np.asarray(omega_rad_s, dtype=float)
    w_max = float(np.max(omega, initial=0.0))
    cuts = max(1, math.ceil(piece.decay_per_m(w_max) * float(piece.length_m) / MAX_DECAY_PER_PIECE))
    d = piece_stiffness(omega, replace(piece, length_m=float(piece.length_m) / cuts))
    return _chain_units([d] * cuts)


#: Largest relative interpolation error of a piece's dynamic stiffness (each 2×2 block against
#: its largest magnitude over the band), checked between the Chebyshev nodes.
INTERPOLATION_RTOL = 1e-9
_DEGREES = (8, 16, 32, 64)


@dataclass(frozen=True, slots=True)
class _Interpolant:
    """Chebyshev coefficients of a dynamic stiffness in ``t = (ω/ω_fit)²`` on [0, 1]."""

    omega_fit_rad_s: float
    coefficients: ComplexArray  # (degree + 1, k, k)

    def __call__(self, omega_rad_s: FloatArray) -> ComplexArray:
        """The interpolant at ``omega_rad_s``, shape (nfreq, k, k): one product of the
        Chebyshev–Vandermonde matrix with the coefficients."""
        x = 2.0 * (np.asarray(omega_rad_s, dtype=float) / self.omega_fit_rad_s) ** 2 - 1.0
        c = self.coefficients
        vander = np.polynomial.chebyshev.chebvander(x, c.shape[0] - 1)
        out: ComplexArray = (vander @ c.reshape(c.shape[0], -1)).reshape(-1, *c.shape[1:])
        return out


def _chebyshev(values: ComplexArray) -> ComplexArray:
    """Chebyshev coefficients from values at the first-kind nodes ``cos(π(j + ½)/m)``, j = 0…m−1."""
    m = values.shape[0]
    j = np.arange(m)
    basis = np.cos(np.pi * np.outer(np.arange(m), j + 0.5) / m)  # (k, j)
    coef: ComplexArray = 2.0 / m * np.tensordot(basis, values, axes=(1, 0))
    coef[0] /= 2.0
    return coef


def _interpolant(exact: Callable[[FloatArray], ComplexArray], omega_fit_rad_s: float) -> _Interpolant | None:
    """A checked interpolant of ``exact(ω)`` (stiffness matrices of 2×2 blocks) on ``[0, ω_fit]``,
    or None if none converges."""
    for m in _DEGREES:
        nodes = np.cos(np.pi * (np.arange(m) + 0.5) / m)
        mids = np.cos(np.pi * np.arange(1, m) / m)
        t = np.concatenate([nodes, mids])
        values = exact(omega_fit_rad_s * np.sqrt((t + 1.0) / 2.0))
        fit = _Interpolant(omega_fit_rad_s, _chebyshev(values[:m]))
        k = values.shape[-1] // 2
        scale = np.max(np.abs(values).reshape(-1, k, 2, k, 2).max(axis=(2, 4)), axis=0)  # per 2×2 block
        err = np.abs(fit(omega_fit_rad_s * np.sqrt((mids + 1.0) / 2.0)) - values[m:])
        if np.all(err.reshape(-1, k, 2, k, 2).max(axis=(2, 4)) <= INTERPOLATION_RTOL * scale):
            return fit
    return None


def _fit_band_rad_s(omega_max_rad_s: float) -> float:
    """The interpolation band's top: the grid's highest frequency rounded up to 2^(k/2) rad/s."""
    return float(2.0 ** (math.ceil(2.0 * math.log2(max(omega_max_rad_s, 1.0))) / 2.0))


def _units(piece: InsertionPiece, omega_fit_rad_s: float) -> tuple[InsertionPiece, int]:
    """The equal units a piece is cut into, so that no beam of a unit has a clamped–clamped mode
    below ``2 ω_fit``, and their number."""
    length = float(piece.length_m)
    shortest = min(Beam(s, length).max_piece_length_m(2.0 * omega_fit_rad_s) for s in (piece.holder, piece.core))
    n = max(1, math.ceil(length / shortest))
    return (replace(piece, length_m=length / n) if n > 1 else piece), n


@dataclass(frozen=True, slots=True)
class _PieceFit:
    """How a piece is evaluated up to ``omega_fit_rad_s``: ``count`` equal units and their interpolant."""

    omega_fit_rad_s: float
    unit: InsertionPiece
    count: int
    interpolant: _Interpolant | None

    def stiffness(self, omega_rad_s: FloatArray) -> ComplexArray:
        """The unit's dynamic stiffness (interpolated, or exact where no interpolant converged)."""
        if self.interpolant is not None:
            return self.interpolant(omega_rad_s)
        return unit_stiffness(omega_rad_s, self.unit)


_FitKey = TypeVar("_FitKey")
_FitValue = TypeVar("_FitValue")


class _BandFits(Generic[_FitKey, _FitValue]):
    """Fits per key, each valid up to its band's top; keys least recently used dropped first
    (:class:`LruStore`), thread-safe."""

    def __init__(self, size: int) -> None:
        self._store: LruStore[_FitKey, list[tuple[float, _FitValue]]] = LruStore(size)
        self._lock = threading.Lock()

    def get(self, key: _FitKey, omega_max_rad_s: float, make: Callable[[float], _FitValue]) -> _FitValue:
        """The fit of ``key`` with the narrowest band covering ``omega_max_rad_s``, else ``make(top)``
        on the band :func:`_fit_band_rad_s` gives (kept)."""
        with self._lock:
            fits = self._store.peek(key)
            usable = [f for f in fits or [] if f[0] >= omega_max_rad_s]
            if usable:
                return min(usable, key=lambda f: f[0])[1]
        top = _fit_band_rad_s(omega_max_rad_s)
        fit = make(top)
        with self._lock:
            fits = self._store.peek(key)
            self._store.put(key, [*(fits or []), (top, fit)])
        return fit


#: Fits kept per piece and per whole insertion (each valid up to its band's top).
_FITS_MAX = 256
_PIECE_FITS: _BandFits[InsertionPiece, _PieceFit] = _BandFits(_FITS_MAX)


def _make_piece_fit(piece: InsertionPiece, top: float) -> _PieceFit:
    unit, count = _units(piece, top)
    return _PieceFit(top, unit, count, _interpolant(lambda w: unit_stiffness(w, unit), top))


def piece_fit(piece: InsertionPiece, omega_max_rad_s: float) -> _PieceFit:
    """The evaluation plan of a scalar piece on grids up to ``omega_max_rad_s`` (cached).

    Any cached fit whose band covers ``omega_max_rad_s`` serves (the narrowest such); otherwise
    one is built on the band :func:`_fit_band_rad_s` gives.

    Parameters
    ----------
    piece : InsertionPiece
        Scalar parameters.
    omega_max_rad_s : float
        Highest angular frequency it will be evaluated at, rad/s.
    """
    return _PIECE_FITS.get(piece, omega_max_rad_s, lambda top: _make_piece_fit(piece, top))


#: An insertion is interpolated whole when its own clamped modes lie above this many band tops.
_INTERNAL_MARGIN = 1.25
#: Two-port fits of whole insertions (None: not interpolable whole on that band).
_WHOLE_FITS: _BandFits[Any, _Interpolant | None] = _BandFits(_FITS_MAX)


def _make_insertion_fit(insertion: Insertion, top: float) -> _Interpolant | None:
    count = Pivots(1)
    insertion.undamped().condensed(np.array([_INTERNAL_MARGIN * top]), count, exact=True)
    return None if count.negatives[0] else _interpolant(lambda w: insertion.condensed(w, exact=True), top)


def insertion_fit(insertion: Insertion, omega_max_rad_s: float) -> _Interpolant | None:
    """The whole insertion's two-port as one checked interpolant up to ``omega_max_rad_s`` (cached), or None.

    Only where the insertion, clamped at its entry and exit nodes, has no natural frequency of
    its own below 1.25 times the band's top (counted by Wittrick–Williams on its exact units at
    that frequency): then its two-port has no pole in or near the band (the interpolant in ω²
    converges by a factor ≥ 4 per degree, and is checked), and no internal pivot turns negative
    in it. Otherwise None, and the units are condensed line by line.

    Parameters
    ----------
    insertion : Insertion
        Scalar parameters.
    omega_max_rad_s : float
        Highest angular frequency it will be evaluated at, rad/s.
    """
    return _WHOLE_FITS.get(insertion, omega_max_rad_s, lambda top: _make_insertion_fit(insertion, top))


def _scalar(piece: InsertionPiece) -> bool:
    return not any(np.ndim(v) for v in (piece.length_m, piece.interface_n_m2, piece.interface_rotational_n,
                                        *_section_values(piece.holder), *_section_values(piece.core)))


def _section_values(s: Section) -> tuple[Any, ...]:
    return s.ei, s.shear_flexibility, s.rho_a, s.rho_i


@dataclass(frozen=True, slots=True)
class Insertion:
    """The inserted length of a tool shank with the holder around it, as one chain item.

    Entered at the holder node where the insertion starts (its spindle-side end), left at the
    shank node in the holder's tool-end face. The shank's inner end and the holder's front
    end are free; everything inside is condensed (:meth:`two_port`).

    Stacked over several tools (:meth:`stack`), its pieces' parameters are arrays with one
    value per tool, and ``line_rows`` (set by :meth:`take_rows`) says which tool each frequency
    line is; each tool's two-port is then computed on its own lines.

    Parameters
    ----------
    pieces : tuple of InsertionPiece
        Uniform pieces from the insertion's inner end to the holder face (a new piece where
        the holder's section or the interface changes).
    line_rows : numpy.ndarray of int, shape (nfreq,), optional
        For a stacked insertion, the tool (row of the parameters) of each line; ``None``: line
        ``i`` is row ``i``.
    """

    pieces: tuple[InsertionPiece, ...]
    line_rows: IntArray | None = field(default=None, compare=False)

    # ------------------------------------------------------------------ the two-port

    def two_port(self, omega_rad_s: FloatArray, pivots: Pivots | None = None) -> ComplexArray:
        """Dynamic stiffness condensed onto the entry and exit nodes, shape (nfreq, 4, 4).

        DOFs ``(w, ψ)`` of the holder where the insertion starts, then ``(w, ψ)`` of the shank
        in the holder face. Each piece is cut into units free of clamped–clamped modes below
        twice the grid's top (:func:`_units`), each evaluated by its checked Chebyshev
        interpolant (exactly, by matrix exponentials, where none converges); the shank's inner
        end, the nodes between units and the holder's front end are condensed in turn, each
        pivot reported to ``pivots`` (undamped items: Wittrick–Williams count and ``log|det|``;
        the units have no clamped–clamped mode of their own below the grid's top).

        Parameters
        ----------
        omega_rad_s : numpy.ndarray, shape (nfreq,)
            Angular frequencies ≥ 0, rad/s.
        pivots : Pivots, optional
            Accumulator of the internal pivots (undamped items only).

        Returns
        -------
        numpy.ndarray, shape (nfreq, 4, 4), complex
        """
        omega = np.asarray(omega_rad_s, dtype=float)
        if not all(_scalar(p) for p in self.pieces):
            return self._two_port_rows(omega, pivots)
        whole = insertion_fit(self, float(np.max(omega, initial=0.0)))
        if whole is not None:
            return whole(omega)  # no internal mode in the band: its pivots have no negative (nor zero)
        return self.condensed(omega, pivots)

    def condensed(self, omega_rad_s: FloatArray, pivots: Pivots | None = None, exact: bool = False) -> ComplexArray:
        """:meth:`two_port` by condensing its units line by line (scalar parameters).

        Parameters
        ----------
        omega_rad_s : numpy.ndarray, shape (nfreq,)
            Angular frequencies ≥ 0, rad/s.
        pivots : Pivots, optional
            Accumulator of the internal pivots (undamped items only).
        exact : bool
            Each unit by matrix exponentials (:func:`unit_stiffness`) instead of its interpolant.

        Returns
        -------
        numpy.ndarray, shape (nfreq, 4, 4), complex
        """
        omega = np.asarray(omega_rad_s, dtype=float)
        top = float(np.max(omega, initial=0.0))
        carried: np.ndarray | None = None  # stiffness over [entry (2), current node (4)]
        for piece in self.pieces:
            if exact:
                unit, count = _units(piece, top)
                d = unit_stiffness(omega, unit)
            else:
                fit = piece_fit(piece, top)
                d, count = fit.stiffness(omega), fit.count
            for _ in range(count):
                if carried is None:  # the first unit: its shank end (inner end) is free
                    carried = _schur(d, np.array([0, 1, 4, 5, 6, 7]), np.array([2, 3]), pivots)
                    continue
                m = np.zeros((omega.size, 10, 10), dtype=complex)
                m[:, :6, :6] = carried
                m[:, 2:, 2:] += d
                carried = _schur(m, np.array([0, 1, 6, 7, 8, 9]), np.array([2, 3, 4, 5]), pivots)
        assert carried is not None, "an insertion has at least one piece"
        return _schur(carried, np.array([0, 1, 4, 5]), np.array([2, 3]), pivots)  # holder front end free

    def _two_port_rows(self, omega: FloatArray, pivots: Pivots | None) -> ComplexArray:
        """:meth:`two_port` of a stacked insertion: each tool's scalar insertion on its own lines."""
        n = omega.size
        rows = np.arange(n) if self.line_rows is None else np.asarray(self.line_rows)
        order = np.argsort(rows, kind="stable")
        starts = np.flatnonzero(np.r_[True, np.diff(rows[order]) != 0])
        out = np.empty((n, 4, 4), dtype=complex)
        for lines in np.split(order, starts[1:]):
            scalar = Insertion(tuple(_row_piece(p, int(rows[lines[0]])) for p in self.pieces))
            part = None if pivots is None else Pivots(lines.size)
            out[lines] = scalar.two_port(omega[lines], part)
            if pivots is not None and part is not None:
                pivots.negatives[lines] += part.negatives
                pivots.log_abs_det[lines] += part.log_abs_det
        return out

    # ------------------------------------------------------------------ chain item protocol

    def _step(self, k: Sym, d: np.ndarray, pivots: Pivots | None) -> Sym:
        """``P = K + D11``; ``K ← D22 − D21 P⁻¹ D12`` on the two-port."""
        p = d[:, :2, :2].astype(np.result_type(d, *k))
        p[:, 0, 0] += k[0]
        p[:, 0, 1] += k[1]
        p[:, 1, 0] += k[1]
        p[:, 1, 1] += k[2]
        _report(pivots, p)
        out = d[:, 2:, 2:] - d[:, 2:, :2] @ inv2(p) @ d[:, :2, 2:]
        return out[:, 0, 0], 0.5 * (out[:, 0, 1] + out[:, 1, 0]), out[:, 1, 1]

    def eliminate(self, k: Sym, grid: Grid, count: bool = False) -> tuple[Sym, IntArray | None]:
        """Carry ``k`` from the holder node where the insertion starts to the shank node in the face.

        Parameters
        ----------
        k : Sym
            Stiffness carried onto the entry node, each shape (nfreq,), N/m, N/rad, N·m/rad.
        grid : Grid
            Frequencies.
        count : bool
            Also return the negative eigenvalues of every pivot eliminated (internal ones included).
        """
        omega = grid.omega_rad_s
        acc = Pivots(omega.size) if count else None
        new = self._step(k, self.two_port(omega, acc), acc)
        return new, (acc.negatives if acc is not None else None)

    def eliminate_undamped(self, k: Sym, grid: Grid) -> Sym:
        """:meth:`eliminate` of the undamped item in real arithmetic; every pivot reported to ``grid.pivots``.

        Parameters
        ----------
        k : Sym
            Stiffness at the entry node, real arrays.
        grid : Grid
            Frequencies and the pivot accumulator.
        """
        d = self.undamped().two_port(grid.omega_rad_s, grid.pivots).real
        new = self._step(k, d, grid.pivots)
        return tuple(np.ascontiguousarray(np.real(x)) for x in new)  # type: ignore[return-value]

    def eliminate_static(self, k: Sym) -> Sym:
        """At ω = 0 without damping (arrays of shape (1,), or (ntools,) stacked).

        Parameters
        ----------
        k : Sym
            Static stiffness at the entry node, N/m, N/rad, N·m/rad.
        """
        n = np.asarray(k[0]).shape[0]
        d = self.undamped().two_port(np.zeros(n)).real
        return tuple(np.real(x) for x in self._step(tuple(np.real(x) for x in k), d, None))  # type: ignore

    def announce(self, grid: Grid) -> None:
        """Nothing to announce: the insertion computes its own two-port.

        Parameters
        ----------
        grid : Grid
            The grid it will be eliminated on.
        """

    def absorb_compliance(self, compliance: ComplexArray, grid: Grid) -> tuple[ComplexArray, bool]:
        """``D22 − D21 S (I + D11 S)⁻¹ D12`` on the two-port: the stiffness at the exit, never inverting ``S``.

        Parameters
        ----------
        compliance : numpy.ndarray, shape (nfreq, 2, 2), complex
            Receptance ``S`` of the grounded base at the entry node, m/N, 1/N, rad/N, rad/(N·m).
        grid : Grid
            Frequencies.
        """
        d = self.two_port(grid.omega_rad_s)
        s = compliance
        return d[:, 2:, 2:] - d[:, 2:, :2] @ s @ inv2(_EYE2 + d[:, :2, :2] @ s) @ d[:, :2, 2:], True

    def undamped(self) -> Insertion:
        """The insertion with real moduli and interfaces."""
        return Insertion(tuple(p.undamped() for p in self.pieces), self.line_rows)

    def subdivided(self, omega_max_rad_s: float) -> tuple[Insertion]:
        """Itself: its units are cut free of clamped–clamped modes below twice any grid's top.

        Parameters
        ----------
        omega_max_rad_s : float
            Highest angular frequency, rad/s.
        """
        return (self,)

    def map_sections(self, fn: Callable[[Section], Section]) -> Self:
        """The insertion with ``fn`` applied to the holder's and the shank's sections.

        Parameters
        ----------
        fn : callable
            ``fn(section) -> Section``.
        """
        return type(self)(tuple(replace(p, holder=fn(p.holder), core=fn(p.core)) for p in self.pieces), self.line_rows)

    def signature(self) -> tuple[object, ...]:
        """Insertions of equally many pieces stack."""
        return ("Insertion", len(self.pieces))

    def stack(self, items: Sequence[Insertion]) -> Insertion:
        """Every parameter as an array over ``items`` (one row per tool).

        Parameters
        ----------
        items : sequence of Insertion
            Insertions with equal :meth:`signature` (``self`` is ``items[0]``).
        """
        pieces = []
        for parts in zip(*(i.pieces for i in items), strict=True):
            pieces.append(InsertionPiece(
                Section.stack([p.holder for p in parts]), Section.stack([p.core for p in parts]),
                np.array([p.length_m for p in parts], dtype=float),
                np.array([p.interface_n_m2 for p in parts], dtype=complex),
                np.array([p.interface_rotational_n for p in parts], dtype=complex)))
        return Insertion(tuple(pieces))

    def take_rows(self, rows: IntArray) -> Insertion:
        """The stacked insertion on lines ``rows`` (each a row of the parameters, or of its lines).

        Parameters
        ----------
        rows : numpy.ndarray of int
            Rows (tools, or lines of an insertion already on lines) to keep, in the order given.
        """
        rows = np.asarray(rows)
        return Insertion(self.pieces, rows if self.line_rows is None else np.asarray(self.line_rows)[rows])

    @property
    def is_stacked(self) -> bool:
        """True when some parameter is an array (one value per row)."""
        return not all(_scalar(p) for p in self.pieces)


def _row_piece(piece: InsertionPiece, row: int) -> InsertionPiece:
    """Row ``row`` of a stacked piece, as numbers."""
    def one(v: Any) -> Any:
        return np.asarray(v).reshape(-1)[row].item() if np.ndim(v) else v

    def sec(s: Section) -> Section:
        return Section(complex(one(s.ei)), complex(one(s.shear_flexibility)), float(np.real(one(s.rho_a))),
                       float(np.real(one(s.rho_i))))

    return InsertionPiece(sec(piece.holder), sec(piece.core), float(np.real(one(piece.length_m))),
                          complex(one(piece.interface_n_m2)), complex(one(piece.interface_rotational_n)))
