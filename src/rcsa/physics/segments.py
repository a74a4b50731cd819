"""Exact end receptances and dynamic stiffness of a uniform Timoshenko segment.

The field transfer matrix of a uniform Timoshenko segment is written with the entire
functions ``C(s, x) = cos(√s x)`` and ``S(s, x) = sin(√s x)/√s`` of the squared wavenumbers
``s₁, s₂`` (``domain.md`` §2.2–2.3). They are even in √s, so no branch switch is needed at
the shear cut-off ω_c = √(κGA/ρI), and complex moduli (hysteretic damping) need no special
case. Euler–Bernoulli is the same code with zero shear flexibility and zero rotary inertia.

State ``y = [w, ψ, V, M]`` with ``V = κGA (w' − ψ)`` and ``M = EI ψ'``; external end loads
``f₀ = −[V, M](0)`` and ``f_L = +[V, M](L)``; DOF order ``(w₀, ψ₀, w_L, ψ_L)`` (§2.4).
"""

from __future__ import annotations

import math
from typing import TypeAlias

import numpy as np

from rcsa.physics.algebra2x2 import inv2
from rcsa.physics.arrays import ComplexArray, FloatArray, RealParam
from rcsa.physics.sections import Section

__all__ = [
    "MAX_DECAY_PER_PIECE",
    "SixTerms",
    "Waves",
    "dynamic_stiffness",
    "free_free_receptance",
    "segment_terms",
    "static_stiffness",
    "stiffness_terms",
    "transfer_matrix",
    "wavenumbers",
]

#: The six distinct entries ``(A, B, C, E, F, G)`` of a uniform segment's dynamic stiffness
#: (:func:`stiffness_terms`), each shape (nfreq,), complex.
SixTerms: TypeAlias = tuple[ComplexArray, ComplexArray, ComplexArray, ComplexArray, ComplexArray, ComplexArray]

def wavenumbers(omega_rad_s: FloatArray, section: Section) -> tuple[ComplexArray, ComplexArray]:
    """Squared wavenumbers ``s₁, s₂`` (1/m²) of the Timoshenko dispersion relation.

    ``EI s² − (ρIω² + EI ρAω²/κGA) s − ρAω² (1 − ρIω²/κGA) = 0`` (``domain.md`` §2.2),
    solved without cancellation (the larger root first, the other from the product).

    Parameters
    ----------
    omega_rad_s : numpy.ndarray, shape (nfreq,)
    section : Section

    Returns
    -------
    s1, s2 : numpy.ndarray, shape (nfreq,), complex
    """
    w2 = np.asarray(omega_rad_s, dtype=float) ** 2
    ei, fs = section.ei, section.shear_flexibility
    ra, ri = section.rho_a * w2, section.rho_i * w2
    b = ri + ei * ra * fs
    c = ra * (1.0 - ri * fs)
    r = np.sqrt(b * b + 4.0 * ei * c + 0j)
    r = np.where((np.conj(b) * r).real < 0, -r, r)
    s1: ComplexArray = (b + r) / (2.0 * ei)
    s2: ComplexArray = -c / (ei * s1)
    return s1, s2


def _cos_sin(z: ComplexArray) -> tuple[ComplexArray, ComplexArray]:
    """``cos z`` and ``sin z`` of a complex array from one set of real cos, sin, cosh, sinh.

    ``cos(x+iy) = cos x cosh y − i sin x sinh y``, ``sin(x+iy) = sin x cosh y + i cos x sinh y``:
    the formulas libm's ``ccos``/``csin`` use, evaluated once for both (3.5× faster).
    """
    x, y = z.real, z.imag
    cx, sx, ch, sh = np.cos(x), np.sin(x), np.cosh(y), np.sinh(y)
    c = np.empty(z.shape, dtype=complex)
    s = np.empty(z.shape, dtype=complex)
    c.real, c.imag = cx * ch, -sx * sh
    s.real, s.imag = sx * ch, cx * sh
    return c, s


def _c_and_s(k: ComplexArray, length_m: RealParam) -> tuple[ComplexArray, ComplexArray, ComplexArray]:
    """``C = cos(kL)``, ``S = sin(kL)/k`` and ``sS = k sin(kL)`` for ``k = √s``.

    ``sin(z)/k`` keeps full relative precision for small ``z = kL``; only ``k = 0`` exactly
    (a segment at its shear cut-off) needs the limit ``S = L``. The functions are even in
    ``k``, so either square root will do.
    """
    cos_z, sin_z = _cos_sin(k * length_m)
    with np.errstate(invalid="ignore", divide="ignore"):
        s_fun = sin_z / k
    zero = k == 0
    if zero.any():
        s_fun = np.where(zero, length_m, s_fun)
    return cos_z, s_fun, k * sin_z


def transfer_matrix(omega_rad_s: FloatArray, section: Section, length_m: float) -> ComplexArray:
    """Field transfer matrix ``T(L)`` with ``y(L) = T y(0)``, ``y = [w, ψ, V, M]``.

    Closed form of ``B(L) B(0)⁻¹`` (``domain.md`` §2.3) with ``q_j = s_j − ρAω²/κGA``.

    Parameters
    ----------
    omega_rad_s : numpy.ndarray, shape (nfreq,)
        Angular frequencies > 0, rad/s.
    section : Section
    length_m : float

    Returns
    -------
    numpy.ndarray, shape (nfreq, 4, 4), complex
    """
    w2 = np.asarray(omega_rad_s, dtype=float) ** 2
    ei = section.ei
    ra = section.rho_a * w2
    s1, s2 = wavenumbers(omega_rad_s, section)
    q1 = s1 - ra * section.shear_flexibility
    q2 = s2 - ra * section.shear_flexibility
    c1, sf1, ss1 = _c_and_s(np.sqrt(s1), length_m)
    c2, sf2, ss2 = _c_and_s(np.sqrt(s2), length_m)
    d = s1 - s2
    qq = q1 * q2
    t = np.empty((w2.size, 4, 4), dtype=complex)
    # column w0
    t[:, 0, 0] = (q1 * c2 - q2 * c1) / d
    t[:, 1, 0] = qq * (sf1 - sf2) / d
    t[:, 2, 0] = ra * (q2 * sf1 - q1 * sf2) / d
    t[:, 3, 0] = ei * qq * (c1 - c2) / d
    # column psi0
    t[:, 0, 1] = (ss1 - ss2) / d
    t[:, 1, 1] = (q1 * c1 - q2 * c2) / d
    t[:, 2, 1] = ra * (c1 - c2) / d
    t[:, 3, 1] = -ei * (q1 * ss1 - q2 * ss2) / d
    # column V0
    t[:, 0, 2] = (q1 * ss2 - q2 * ss1) / (ra * d)
    t[:, 1, 2] = qq * (c2 - c1) / (ra * d)
    t[:, 2, 2] = (q1 * c2 - q2 * c1) / d
    t[:, 3, 2] = ei * qq * (ss1 - ss2) / (ra * d)
    # column M0
    t[:, 0, 3] = (c2 - c1) / (ei * d)
    t[:, 1, 3] = (q1 * sf1 - q2 * sf2) / (ei * d)
    t[:, 2, 3] = ra * (sf1 - sf2) / (ei * d)
    t[:, 3, 3] = (q1 * c1 - q2 * c2) / d
    return t


def _blocks(t: ComplexArray) -> tuple[ComplexArray, ComplexArray, ComplexArray, ComplexArray]:
    return t[:, :2, :2], t[:, :2, 2:], t[:, 2:, :2], t[:, 2:, 2:]


#: Largest decay exponent |Im √s|·L of one piece: the closed forms subtract terms of size
#: e^{2|Im √s| L} whose difference is O(1), so a piece keeps ~e^{2·3}·ε ≈ 1e-13 relative accuracy.
MAX_DECAY_PER_PIECE = 3.0


class Waves:
    """Wavenumber data of one section on one frequency grid, shared by the segments of that section.

    Everything of :func:`stiffness_terms` that depends on the section and ω but not on the
    length, so equal sections along a chain (and the pieces of a long segment) compute it once.

    Parameters
    ----------
    omega_rad_s : numpy.ndarray, shape (nfreq,)
        Angular frequencies, rad/s.
    section : Section

    Attributes
    ----------
    ra : numpy.ndarray, shape (nfreq,)
        ρAω², N/m².
    s1, s2 : numpy.ndarray, shape (nfreq,), complex
        Squared wavenumbers (:func:`wavenumbers`), 1/m².
    q1, q2 : numpy.ndarray, shape (nfreq,), complex
        ``s_j − ρAω²/κGA``, 1/m².
    d : numpy.ndarray, shape (nfreq,), complex
        ``s₁ − s₂``, 1/m².
    k1, k2 : numpy.ndarray, shape (nfreq,), complex
        Wavenumbers ``√s_j``, 1/m.
    decay_per_m : float
        Largest ``|Im √s|`` over the grid, 1/m (how fast the evanescent waves decay).
    """

    __slots__ = ("d", "decay_per_m", "k1", "k2", "q1", "q2", "ra", "s1", "s2")

    def __init__(self, omega_rad_s: FloatArray, section: Section) -> None:
        self.ra = section.rho_a * np.asarray(omega_rad_s, dtype=float) ** 2
        self.s1, self.s2 = wavenumbers(omega_rad_s, section)
        self.q1 = self.s1 - self.ra * section.shear_flexibility
        self.q2 = self.s2 - self.ra * section.shear_flexibility
        self.d = self.s1 - self.s2
        self.k1, self.k2 = np.sqrt(self.s1), np.sqrt(self.s2)
        self.decay_per_m = float(max(np.abs(self.k1.imag).max(initial=0.0), np.abs(self.k2.imag).max(initial=0.0)))

    def pieces(self, length_m: RealParam) -> int:
        """Number of equal pieces keeping each piece's decay exponent ≤ MAX_DECAY_PER_PIECE."""
        return max(1, math.ceil(self.decay_per_m * float(np.max(length_m)) / MAX_DECAY_PER_PIECE))


def stiffness_terms(omega_rad_s: FloatArray, section: Section, length_m: RealParam,
                    waves: Waves | None = None) -> SixTerms:
    """The six distinct entries ``(A, B, C, E, F, G)`` of a uniform segment's dynamic stiffness.

    By reciprocity and the mirror symmetry of a uniform segment::

        D = [[ A,  B,  E,  F],
             [ B,  C, -F,  G],
             [ E, -F,  A, -B],
             [ F,  G, -B,  C]]

    computed from the transfer-matrix entries of :func:`transfer_matrix` (their common
    factor 1/(s₁ − s₂) cancels): ``D11 = T_ds⁻¹ T_dd`` and ``D12 = −T_ds⁻¹`` (``domain.md`` §2.4).
    Accurate for pieces whose decay exponent ``|Im √s| L`` is at most ``MAX_DECAY_PER_PIECE``;
    longer segments are split by the callers (:func:`rcsa.physics.elimination.march`, :func:`dynamic_stiffness`).

    Parameters
    ----------
    omega_rad_s : numpy.ndarray, shape (nfreq,)
        Angular frequencies, rad/s.
    section : Section
    length_m : float
        Segment length, m.
    waves : _Waves, optional
        The section's wavenumbers on this grid, when the caller already has them.

    Returns
    -------
    tuple of numpy.ndarray, each shape (nfreq,), complex
    """
    wv = waves if waves is not None else Waves(omega_rad_s, section)
    ei, ra, q1, q2 = section.ei, wv.ra, wv.q1, wv.q2
    c1, sf1, ss1 = _c_and_s(wv.k1, length_m)
    c2, sf2, ss2 = _c_and_s(wv.k2, length_m)
    dc = c2 - c1
    # transfer-matrix entries times (s1 - s2)
    t_ww = q1 * c2 - q2 * c1
    t_pw = q1 * q2 * (sf1 - sf2)
    t_wp = ss1 - ss2
    t_pp = q1 * c1 - q2 * c2
    t_wv = (q1 * ss2 - q2 * ss1) / ra
    t_pv = q1 * q2 * dc / ra
    t_wm = dc / ei
    t_pm = (q1 * sf1 - q2 * sf2) / ei
    inv_det = 1.0 / (t_wv * t_pm - t_wm * t_pv)
    a = (t_pm * t_ww - t_wm * t_pw) * inv_det
    b = (t_pm * t_wp - t_wm * t_pp) * inv_det
    c = (t_wv * t_pp - t_pv * t_wp) * inv_det
    scale = wv.d * inv_det
    return a, b, c, -t_pm * scale, t_wm * scale, -t_wv * scale


def _double(terms: SixTerms) -> SixTerms:
    """Six-term stiffness of two equal pieces in a row, the middle node condensed.

    For equal pieces the middle pivot is ``P = D22 + D11 = diag(2A, 2C)``, so
    ``D11' = D11 − D12 P⁻¹ D21`` and ``D12' = −D12 P⁻¹ D12`` reduce to the closed forms below.
    """
    a, b, c, e, f, g = terms
    ia, ic = 0.5 / a, 0.5 / c
    return (a - e * e * ia - f * f * ic, b + e * f * ia - f * g * ic, c - f * f * ia - g * g * ic,
            f * f * ic - e * e * ia, -(e * ia + g * ic) * f, f * f * ia - g * g * ic)


def segment_terms(omega_rad_s: FloatArray, section: Section, length_m: RealParam,
                  waves: Waves | None = None) -> SixTerms:
    """:func:`stiffness_terms` of a whole segment of any length.

    A segment whose decay exponent exceeds ``MAX_DECAY_PER_PIECE`` is computed as ``2^m``
    equal pieces joined by :func:`_double`, which is exact and keeps full precision for long,
    strongly evanescent segments.

    Parameters
    ----------
    omega_rad_s : numpy.ndarray, shape (nfreq,)
        Angular frequencies, rad/s.
    section : Section
    length_m : float
        Segment length, m.
    waves : _Waves, optional
        The section's wavenumbers on this grid, when the caller already has them (they depend
        on the section and ω only, not on the length).
    """
    wv = waves if waves is not None else Waves(omega_rad_s, section)
    m = math.ceil(math.log2(wv.pieces(length_m)))
    terms = stiffness_terms(omega_rad_s, section, length_m / 2**m, wv)
    for _ in range(m):
        terms = _double(terms)
    return terms


def dynamic_stiffness(omega_rad_s: FloatArray, section: Section, length_m: RealParam) -> ComplexArray:
    """Exact dynamic stiffness ``D``: ``[f₀; f_L] = D [d₀; d_L]``, DOFs ``(w₀, ψ₀, w_L, ψ_L)``.

    Assembled from :func:`stiffness_terms`; a segment too long for one piece (strongly
    evanescent waves) is condensed from equal pieces.

    Parameters
    ----------
    omega_rad_s : numpy.ndarray, shape (nfreq,)
        Angular frequencies, rad/s.
    section : Section
    length_m : float
        Segment length, m.

    Returns
    -------
    numpy.ndarray, shape (nfreq, 4, 4), complex
        Units: N/m, N/rad, N·m/m, N·m/rad in the blocks' positions.
    """
    a, b, c, e, f, g = segment_terms(omega_rad_s, section, length_m)
    rows = [[a, b, e, f], [b, c, -f, g], [e, -f, a, -b], [f, g, -b, c]]
    return np.stack([np.stack(r, axis=-1) for r in rows], axis=-2)


def free_free_receptance(omega_rad_s: FloatArray, section: Section, length_m: float) -> ComplexArray:
    """Exact free-free receptance ``R``: ``[d₀; d_L] = R [f₀; f_L]``.

    ``R = [[T_sd⁻¹T_ss, T_sd⁻¹], [·, T_dd T_sd⁻¹]]`` (``domain.md`` §2.4), lower-left block by
    reciprocity. At frequencies where the segment is too long for one piece (strongly
    evanescent waves, where that form cancels catastrophically) ``R = D⁻¹`` is used instead;
    there the free-free rigid-body singularity of ``D`` is far away.

    Parameters
    ----------
    omega_rad_s : numpy.ndarray, shape (nfreq,)
        Angular frequencies, rad/s.
    section : Section
    length_m : float
        Segment length, m.

    Returns
    -------
    numpy.ndarray, shape (nfreq, 4, 4), complex
    """
    w = np.asarray(omega_rad_s, dtype=float)
    wv = Waves(w, section)
    decay = np.maximum(np.abs(wv.k1.imag), np.abs(wv.k2.imag)) * length_m
    long = decay > MAX_DECAY_PER_PIECE
    out = np.empty((w.size, 4, 4), dtype=complex)
    if long.any():
        out[long] = np.linalg.inv(dynamic_stiffness(w[long], section, length_m))
    short = ~long
    t_dd, _, t_sd, t_ss = _blocks(transfer_matrix(w[short], section, length_m))
    inv_sd = inv2(t_sd)
    out[short, :2, :2] = inv_sd @ t_ss
    out[short, :2, 2:] = inv_sd
    out[short, 2:, :2] = np.swapaxes(inv_sd, 1, 2)
    out[short, 2:, 2:] = t_dd @ inv_sd
    return out


def static_stiffness(section: Section, length_m: RealParam) -> ComplexArray:
    """Exact static Timoshenko stiffness matrix (the ω → 0 limit of :func:`dynamic_stiffness`).

    ``EI/((1+Φ)L³) [[12, 6L, −12, 6L], [6L, (4+Φ)L², −6L, (2−Φ)L²], …]``, Φ = 12EI/(κGA L²)
    (``domain.md`` §2.4), with the section's complex moduli.

    Parameters
    ----------
    section : Section
    length_m : float
        Segment length, m.

    Returns
    -------
    numpy.ndarray, shape (4, 4), complex
    """
    ei, lm = section.ei, length_m
    phi = 12.0 * ei * section.shear_flexibility / lm**2
    k = np.array([
        [12.0, 6 * lm, -12.0, 6 * lm],
        [6 * lm, (4 + phi) * lm**2, -6 * lm, (2 - phi) * lm**2],
        [-12.0, -6 * lm, 12.0, -6 * lm],
        [6 * lm, (2 - phi) * lm**2, -6 * lm, (4 + phi) * lm**2],
    ], dtype=complex)
    return ei / ((1 + phi) * lm**3) * k
