"""Exact end receptances and dynamic stiffness of a uniform Timoshenko segment.

The field transfer matrix of a uniform Timoshenko segment is written with the entire
functions ``C(s, x) = cos(√s x)`` and ``S(s, x) = sin(√s x)/√s`` of the squared wavenumbers
``s₁, s₂`` (``docs/physics.md`` §2.2–2.3). They are even in √s, so no branch switch is needed at
the shear cut-off ω_c = √(κGA/ρI), and complex moduli (hysteretic damping) need no special
case. Euler–Bernoulli is the same code with zero shear flexibility and zero rotary inertia.

State ``y = [w, ψ, V, M]`` with ``V = κGA (w' − ψ)`` and ``M = EI ψ'``; external end loads
``f₀ = −[V, M](0)`` and ``f_L = +[V, M](L)``; DOF order ``(w₀, ψ₀, w_L, ψ_L)`` (§2.4).
"""

from __future__ import annotations

import math
from typing import TypeAlias

import numpy as np

from rcsa.physics.algebra2x2 import Pivots, inv2
from rcsa.physics.arrays import BoolArray, ComplexArray, FloatArray, RealParam
from rcsa.physics.elementwise import WORK, Scratch, sqrt_any, vers_sin
from rcsa.physics.sections import Section

__all__ = [
    "MAX_DECAY_PER_PIECE",
    "RealTerms",
    "RealWaves",
    "SixTerms",
    "Waves",
    "dynamic_stiffness",
    "free_free_receptance",
    "segment_terms",
    "static_stiffness",
    "static_terms",
    "stiffness_terms",
    "double",
    "six_terms",
    "stiffness_terms_reference",
    "transfer_matrix",
    "undamped_segment_terms",
    "wavenumbers",
]

#: The six distinct entries ``(A, B, C, E, F, G)`` of a uniform segment's dynamic stiffness
#: (:func:`stiffness_terms`), each shape (nfreq,), complex.
SixTerms: TypeAlias = tuple[ComplexArray, ComplexArray, ComplexArray, ComplexArray, ComplexArray, ComplexArray]
#: The six terms of an undamped segment, real (:func:`undamped_segment_terms`).
RealTerms: TypeAlias = tuple[FloatArray, FloatArray, FloatArray, FloatArray, FloatArray, FloatArray]

def wavenumbers(omega_rad_s: FloatArray, section: Section) -> tuple[ComplexArray, ComplexArray]:
    """Squared wavenumbers ``s₁, s₂`` (1/m²) of the Timoshenko dispersion relation.

    ``EI s² − (ρIω² + EI ρAω²/κGA) s − ρAω² (1 − ρIω²/κGA) = 0`` (``docs/physics.md`` §2.2),
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

    Closed form of ``B(L) B(0)⁻¹`` (``docs/physics.md`` §2.3) with ``q_j = s_j − ρAω²/κGA``.

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


def _doublings(decay_per_m: float, length_m: RealParam) -> int:
    """``m`` such that ``2^m`` equal pieces keep each piece's decay exponent ≤ MAX_DECAY_PER_PIECE."""
    pieces = max(1, math.ceil(decay_per_m * float(np.max(length_m)) / MAX_DECAY_PER_PIECE))
    return math.ceil(math.log2(pieces))


class Waves:
    """Wavenumber data of one section on one frequency grid, shared by the segments of that section.

    Everything of :func:`stiffness_terms` that depends on the section and ω but not on the
    length, so equal sections along a chain (and the pieces of a long segment) compute it once.
    The two waves are stacked on a leading axis of length 2 (one elementwise call serves both).

    Parameters
    ----------
    omega_rad_s : numpy.ndarray, shape (nfreq,)
        Angular frequencies, rad/s.
    section : Section
    scratch : Scratch, optional
        Where the arrays live (named with ``slot``); fresh arrays by default.
    slot : str
        Prefix of this section's arrays in ``scratch``.

    Attributes
    ----------
    ra : numpy.ndarray, shape (nfreq,)
        ρAω², N/m².
    ei : complex or numpy.ndarray
        EI, N·m².
    s : numpy.ndarray, shape (2, nfreq), complex
        Squared wavenumbers ``s₁, s₂`` (:func:`wavenumbers`), 1/m².
    q : numpy.ndarray, shape (2, nfreq), complex
        ``s_j − ρAω²/κGA``, 1/m².
    qq : numpy.ndarray, shape (nfreq,), complex
        ``q₁ q₂``, 1/m⁴.
    d : numpy.ndarray, shape (nfreq,), complex
        ``s₁ − s₂``, 1/m².
    k : numpy.ndarray, shape (2, nfreq), complex
        A square root of each ``s_j`` (the segment functions are even in it), 1/m.
    inv_k : numpy.ndarray, shape (2, nfreq), complex
        ``1/k``, m (``k`` is at least 1e-150 in modulus: a section exactly at its shear
        cut-off has ``s₂ = 0``, and then ``sin(kL)/k = L`` comes out of the same formulas).
    decay_per_m : float
        Largest ``|Im √s|`` over the grid, 1/m (how fast the evanescent waves decay).
    """

    __slots__ = ("d", "decay_per_m", "decay_rows", "ei", "inv_k", "k", "n", "q", "qq", "ra", "s", "slot")

    slot: str
    n: tuple[int, ...]
    ei: complex | ComplexArray
    ra: FloatArray
    s: ComplexArray
    q: ComplexArray
    qq: ComplexArray
    d: ComplexArray
    k: ComplexArray
    inv_k: ComplexArray
    decay_rows: FloatArray | None
    decay_per_m: float

    def __init__(self, omega_rad_s: FloatArray, section: Section, scratch: Scratch | None = None,
                 slot: str = "") -> None:
        sc = Scratch() if scratch is None else scratch
        self.slot = slot
        w = np.asarray(omega_rad_s, dtype=float)
        n = self.n = _shape(w, section)
        ei, fs = _param(section.ei), _param(section.shear_flexibility)
        self.ei = ei
        # b = ρIω² + EI ρAω²/κGA,  c = ρAω² (1 − ρIω²/κGA),  s = (b ± √(b² + 4 EI c)) / (2 EI)
        ra = self.ra = sc.real(slot + "ra", n)
        ri = sc.real("wv.ri", n)
        np.multiply(w, w, out=ra)
        np.multiply(ra, section.rho_i, out=ri)
        np.multiply(ra, section.rho_a, out=ra)
        b, c, t = sc.complex("wv.b", n), sc.complex("wv.c", n), sc.complex("wv.t", n)
        np.multiply(ra, ei * fs, out=b)
        np.add(b, ri, out=b)
        np.multiply(ri, -fs, out=c)
        np.add(c, 1.0, out=c)
        np.multiply(c, ra, out=c)
        disc, r, m = sc.complex("wv.disc", n), sc.complex("wv.r", n), sc.real("wv.m", n)
        np.multiply(b, b, out=disc)
        np.multiply(c, 4.0 * ei, out=t)
        np.add(disc, t, out=disc)
        sqrt_any(disc, r, m, sc)
        # the root on b's side (Re(b̄ r) ≥ 0): the larger root first, without cancellation
        g = sc.real("wv.g", n)
        np.multiply(b.real, r.real, out=g)
        np.multiply(b.imag, r.imag, out=m)
        np.add(g, m, out=g)
        if g.size and float(g.min()) < 0.0:
            np.negative(r, out=r, where=g < 0.0)
        s = self.s = sc.complex2(slot + "s", n)
        np.add(b, r, out=s[0])
        np.multiply(s[0], 0.5 / ei, out=s[0])
        np.divide(c, s[0], out=s[1])                      # s₂ = −c / (EI s₁)
        np.multiply(s[1], -1.0 / ei, out=s[1])
        np.multiply(ra, fs, out=t)
        q = self.q = sc.complex2(slot + "q", n)
        np.subtract(s, t, out=q)
        self.qq = sc.complex(slot + "qq", n)
        np.multiply(q[0], q[1], out=self.qq)
        self.d = sc.complex(slot + "d", n)
        np.subtract(s[0], s[1], out=self.d)
        k, inv_k, ms = sc.complex2(slot + "k", n), sc.complex2(slot + "ik", n), sc.real2("wv.ms", n)
        sqrt_any(s, k, ms, sc)                            # |k| ≥ 1e-150 (s = 0: at the cut-off)
        np.maximum(ms, 1e-300, out=ms)
        np.divide(1.0, ms, out=ms)                        # 1/|s| = 1/|k|²
        np.conjugate(k, out=inv_k)
        np.multiply(inv_k, ms, out=inv_k)
        self.k, self.inv_k = k, inv_k
        np.abs(k.imag, out=ms)
        self.decay_rows = ms.max(axis=(0, ms.ndim - 1), initial=0.0) if ms.ndim == 3 else None
        self.decay_per_m = float(ms.max(initial=0.0))

    @classmethod
    def tiled(cls, base: Waves, reps: int, scratch: Scratch, slot: str) -> Waves:
        """``base`` repeated ``reps`` times along the lines (every tool of a stacked solve on one grid).

        Parameters
        ----------
        base : Waves
            The waves on the grid repeated.
        reps : int
            How many times it is repeated.
        scratch : Scratch
            Where the repeated arrays live.
        slot : str
            Prefix of their names in ``scratch``.
        """
        out = cls.__new__(cls)
        _tile_into(base, out, reps, scratch, slot, ("ra", "s", "q", "qq", "d", "k", "inv_k"))
        return out

    @property
    def s1(self) -> ComplexArray:
        """``s₁`` (propagating), shape (nfreq,)."""
        out: ComplexArray = self.s[0]
        return out

    @property
    def s2(self) -> ComplexArray:
        """``s₂`` (evanescent below the shear cut-off), shape (nfreq,)."""
        out: ComplexArray = self.s[1]
        return out

    @property
    def k1(self) -> ComplexArray:
        """A square root of ``s₁``, shape (nfreq,)."""
        out: ComplexArray = self.k[0]
        return out

    @property
    def k2(self) -> ComplexArray:
        """A square root of ``s₂``, shape (nfreq,)."""
        out: ComplexArray = self.k[1]
        return out

    def pieces(self, length_m: RealParam) -> int:
        """Number of equal pieces keeping each piece's decay exponent ≤ MAX_DECAY_PER_PIECE.

        Parameters
        ----------
        length_m : float or numpy.ndarray
            Segment length, m (the longest when stacked).
        """
        return max(1, math.ceil(self.decay_per_m * float(np.max(length_m)) / MAX_DECAY_PER_PIECE))

    def functions(self, length_m: RealParam, scratch: Scratch) -> tuple[ComplexArray, ComplexArray, ComplexArray]:
        """``V = 1 − cos kL``, ``S = sin(kL)/k`` and ``kS·k = k sin kL`` of both waves, each (2, nfreq).

        With ``kL = x + iy``: ``cos = cos x cosh y − i sin x sinh y``,
        ``sin = sin x cosh y + i cos x sinh y``; the versine is formed as
        ``(1 − cos x) cosh y − (cosh y − 1) + i sin x sinh y`` with ``cosh y − 1 =
        sinh²y/(cosh y + 1)``, so it keeps full relative precision for small ``kL``.

        Parameters
        ----------
        length_m : float or numpy.ndarray
            Piece length, m (one per row for a stacked section).
        scratch : Scratch
            Work arrays (the results live there).
        """
        n, sc = self.n, scratch
        x, y = sc.real2("f.x", n), sc.real2("f.y", n)
        np.multiply(self.k.real, length_m, out=x)
        np.multiply(self.k.imag, length_m, out=y)
        vx, sx, w, t = sc.real2("f.vx", n), sc.real2("f.sx", n), sc.real2("f.w", n), sc.real2("f.t", n)
        vers_sin(x, vx, sx, sc)
        ch, sh = x, y
        np.cosh(y, out=ch)
        np.sinh(y, out=sh)
        np.add(ch, 1.0, out=w)
        np.multiply(sh, sh, out=t)
        np.divide(t, w, out=w)                            # cosh y − 1
        v, z, sf = sc.complex2("f.V", n), sc.complex2("f.Z", n), sc.complex2("f.S", n)
        np.multiply(vx, ch, out=v.real)
        np.subtract(v.real, w, out=v.real)
        np.multiply(sx, sh, out=v.imag)
        np.multiply(sx, ch, out=z.real)                   # z = sin kL
        np.subtract(1.0, vx, out=t)
        np.multiply(t, sh, out=z.imag)
        np.multiply(z, self.inv_k, out=sf)
        np.multiply(z, self.k, out=z)
        return v, sf, z


class RealWaves:
    """:class:`Waves` of an undamped section, in real arithmetic.

    ``s₁ > 0`` always; ``s₂ < 0`` below the shear cut-off (an evanescent wave: cosh and
    sinh of ``k₂ = √(−s₂)``) and ``s₂ > 0`` above it (cos and sin of ``k₂ = √s₂``).
    The imaginary parts of the section's moduli are ignored: pass an undamped section.

    Parameters
    ----------
    omega_rad_s : numpy.ndarray, shape (nfreq,)
        Angular frequencies, rad/s.
    section : Section
        Undamped section (the imaginary parts of its moduli are ignored).
    scratch : Scratch, optional
        Where the arrays live (named with ``slot``); fresh arrays by default.
    slot : str
        Prefix of this section's arrays in ``scratch``.

    Attributes
    ----------
    ra, s, q, qq, d, decay_per_m
        As in :class:`Waves`, real.
    ei : float or numpy.ndarray
    k : numpy.ndarray, shape (2, nfreq)
        ``√s₁`` and ``√|s₂|``, 1/m.
    below : numpy.ndarray of bool, shape (nfreq,)
        ``s₂ < 0``.
    """

    __slots__ = ("below", "d", "decay_per_m", "decay_rows", "ei", "inv_k", "k", "n", "q", "qq", "ra", "s", "slot",
                 "split")

    slot: str
    n: tuple[int, ...]
    ei: float | FloatArray
    ra: FloatArray
    s: FloatArray
    q: FloatArray
    qq: FloatArray
    d: FloatArray
    k: FloatArray
    inv_k: FloatArray
    below: BoolArray
    split: int
    decay_rows: FloatArray | None
    decay_per_m: float

    def __init__(self, omega_rad_s: FloatArray, section: Section, scratch: Scratch | None = None,
                 slot: str = "") -> None:
        sc = Scratch() if scratch is None else scratch
        self.slot = slot
        w = np.asarray(omega_rad_s, dtype=float)
        n = self.n = _shape(w, section)
        ei, fs = _real_param(section.ei), _real_param(section.shear_flexibility)
        self.ei = ei
        ra = self.ra = sc.real(slot + "ra", n)
        ri, b, c, t = sc.real("wv.ri", n), sc.real("wv.b", n), sc.real("wv.c", n), sc.real("wv.t", n)
        np.multiply(w, w, out=ra)
        np.multiply(ra, section.rho_i, out=ri)
        np.multiply(ra, section.rho_a, out=ra)
        np.multiply(ra, ei * fs, out=b)
        np.add(b, ri, out=b)                              # b ≥ 0
        np.multiply(ri, -fs, out=c)
        np.add(c, 1.0, out=c)
        np.multiply(c, ra, out=c)
        np.multiply(b, b, out=t)
        s = self.s = sc.real2(slot + "s", n)
        np.multiply(c, 4.0 * ei, out=s[1])
        np.add(t, s[1], out=t)                            # b² + 4 EI c > 0
        np.sqrt(t, out=t)
        np.add(b, t, out=s[0])
        np.multiply(s[0], 0.5 / ei, out=s[0])
        np.divide(c, s[0], out=s[1])
        np.multiply(s[1], -1.0 / ei, out=s[1])
        np.multiply(ra, fs, out=t)
        q = self.q = sc.real2(slot + "q", n)
        np.subtract(s, t, out=q)
        self.qq = sc.real(slot + "qq", n)
        np.multiply(q[0], q[1], out=self.qq)
        self.d = sc.real(slot + "d", n)
        np.subtract(s[0], s[1], out=self.d)
        k, inv_k = self.k, self.inv_k = sc.real2(slot + "k", n), sc.real2(slot + "ik", n)
        np.abs(s, out=k)
        np.sqrt(k, out=k)
        np.maximum(k, 1e-150, out=k)                      # s₂ = 0 at the cut-off: the limits below follow
        np.divide(1.0, k, out=inv_k)
        below = self.below = s[1] < 0.0
        n_below = int(np.count_nonzero(below))
        #: 0: every line below the cut-off, 1: every line above, 2: both
        self.split = 0 if n_below == below.size else (1 if n_below == 0 else 2)
        decay = np.max(k[1], axis=-1, initial=0.0, where=below)
        self.decay_rows = decay if np.ndim(decay) else None
        self.decay_per_m = float(np.max(decay))

    def pieces(self, length_m: RealParam) -> int:
        """Number of equal pieces keeping each piece's decay exponent ≤ MAX_DECAY_PER_PIECE.

        Parameters
        ----------
        length_m : float or numpy.ndarray
            Segment length, m.
        """
        return max(1, math.ceil(self.decay_per_m * float(np.max(length_m)) / MAX_DECAY_PER_PIECE))

    @classmethod
    def tiled(cls, base: RealWaves, reps: int, scratch: Scratch, slot: str) -> RealWaves:
        """``base`` repeated ``reps`` times along the lines (see :meth:`Waves.tiled`).

        Parameters
        ----------
        base : RealWaves
            The waves on the grid repeated.
        reps : int
            How many times it is repeated.
        scratch : Scratch
            Where the repeated arrays live.
        slot : str
            Prefix of their names in ``scratch``.
        """
        out = cls.__new__(cls)
        _tile_into(base, out, reps, scratch, slot, ("ra", "s", "q", "qq", "d", "k", "inv_k", "below"))
        out.split = base.split
        return out

    def functions(self, length_m: RealParam, scratch: Scratch) -> tuple[FloatArray, FloatArray, FloatArray]:
        """``V = 1 − cos kL``, ``S = sin(kL)/k`` and ``k sin kL = s S`` of both waves, each (2, nfreq).

        The second wave below the cut-off (``k = i√(−s₂)``): ``V = 1 − cosh``,
        ``S = sinh/√(−s₂)``, ``k sin kL = −√(−s₂) sinh``.

        Parameters
        ----------
        length_m : float or numpy.ndarray
            Piece length, m (one per row for a stacked section).
        scratch : Scratch
            Work arrays (the results live there).
        """
        n, sc = self.n, scratch
        x = sc.real2("f.x", n)
        np.multiply(self.k, length_m, out=x)
        v, sf, ss = sc.real2("f.V", n), sc.real2("f.S", n), sc.real2("f.sS", n)
        if self.split == 1:
            vers_sin(x, v, sf, sc)
        else:
            vers_sin(x[0], v[0], sf[0], sc)
            ch, sh, t = sc.real("f.ch", n), sc.real("f.sh", n), sc.real("f.t", n)
            np.cosh(x[1], out=ch)
            np.sinh(x[1], out=sh)
            np.add(ch, 1.0, out=t)
            np.multiply(sh, sh, out=v[1])
            np.divide(v[1], t, out=v[1])
            np.negative(v[1], out=v[1])                   # 1 − cosh = −sinh²/(cosh + 1)
            np.copyto(sf[1], sh)
            if self.split == 2:                           # lines above the cut-off: cos and sin
                va, sa = sc.real("f.va", n), sc.real("f.sa", n)
                vers_sin(x[1], va, sa, sc, tag="vs2")
                above = ~self.below
                np.copyto(v[1], va, where=above)
                np.copyto(sf[1], sa, where=above)
        np.multiply(sf, self.k, out=ss)                   # k sin kL (sinh below: sign below)
        np.multiply(sf, self.inv_k, out=sf)
        if self.split == 0:
            np.negative(ss[1], out=ss[1])
        elif self.split == 2:
            np.negative(ss[1], out=ss[1], where=self.below)
        return v, sf, ss


def _tile_into(base: Waves | RealWaves, out: Waves | RealWaves, reps: int, scratch: Scratch, slot: str,
               names: tuple[str, ...]) -> None:
    """Fill ``out`` with ``base``'s arrays repeated ``reps`` times along the last (line) axis."""
    for name in names:
        src = getattr(base, name)
        if src.dtype == bool:
            dst = np.tile(src, reps)
        else:
            get = scratch.complex if np.iscomplexobj(src) else scratch.real
            dst = get(slot + name, (*src.shape[:-1], reps * src.shape[-1]))
            dst.reshape(*src.shape[:-1], reps, src.shape[-1])[...] = src[..., None, :]
        setattr(out, name, dst)
    out.n = (reps * base.n[-1],) if isinstance(base.n, tuple) else reps * base.n
    out.ei, out.decay_per_m, out.decay_rows, out.slot = base.ei, base.decay_per_m, base.decay_rows, slot


def _shape(omega_rad_s: FloatArray, section: Section) -> tuple[int, ...]:
    """Shape of the wave arrays: ω broadcast against the section's parameters (one per row, or
    a column of sections of a terms table)."""
    return np.broadcast_shapes(omega_rad_s.shape, np.shape(section.ei), np.shape(section.shear_flexibility),
                               np.shape(section.rho_a), np.shape(section.rho_i))


def _real_param(value: complex | ComplexArray) -> float | FloatArray:
    """The real part of a section parameter: a Python float (one value) or an array (one per row)."""
    if np.ndim(value) == 0:
        return complex(value).real
    out: FloatArray = np.real(np.asarray(value))
    return out


def _param(value: complex | ComplexArray) -> complex | ComplexArray:
    """A section parameter as a Python complex (one value) or an array (one per row)."""
    if isinstance(value, (complex, float, int)):
        return complex(value)
    return complex(value) if np.ndim(value) == 0 else np.asarray(value)


def six_terms(waves: Waves | RealWaves, funcs: tuple[np.ndarray, np.ndarray, np.ndarray],
               out: SixTerms | RealTerms, scratch: Scratch) -> None:
    """Assemble ``(A, B, C, E, F, G)`` from the wave functions (complex or real alike).

    With ``V_j = 1 − C_j`` the transfer-matrix entries of §2.3 times ``(s₁ − s₂)`` are::

        t_ww = d + q₂V₁ − q₁V₂       t_pp = d − q₁V₁ + q₂V₂      t_wp = k₁S₁k₁ − k₂S₂k₂
        u_wv = q₁ s₂S₂ − q₂ s₁S₁    (= ρAω² t_wv)              u_pm = q₁S₁ − q₂S₂  (= EI t_pm)
        u_pv = q₁q₂ (V₁ − V₂)       (= ρAω² t_pv)              t_pw = q₁q₂ (S₁ − S₂)

    and with ``R = 1/(u_wv u_pm − (V₁ − V₂) u_pv)``, ``ρ = ρAω² R``, ``η = EI R``::

        A = ρ (u_pm t_ww − (V₁−V₂) t_pw)     E = −ρ d u_pm
        B = ρ (u_pm t_wp − (V₁−V₂) t_pp)     F =  ρ d (V₁ − V₂)
        C = η (u_wv t_pp − u_pv t_wp)        G = −η d u_wv

    (the readable form is :func:`stiffness_terms_reference`).

    Parameters
    ----------
    waves : Waves or RealWaves
        The section's waves on the grid.
    funcs : tuple of three numpy.ndarray
        ``V``, ``S`` and ``sS`` of both waves (:meth:`Waves.functions`), each (2, nfreq).
    out : tuple of six numpy.ndarray
        Where the terms are written (complex for :class:`Waves`, real for :class:`RealWaves`).
    scratch : Scratch
        Work arrays.
    """
    real = isinstance(waves, RealWaves)
    n = waves.n
    v, sf, ss = funcs
    q1, q2 = waves.q
    dc, dsf, tww, tpp, twp, uwv, upm, upv, tpw, u1, u2, u3 = scratch.many(WORK, n, real)
    mul, sub = np.multiply, np.subtract
    sub(v[0], v[1], out=dc)                               # C₂ − C₁
    sub(sf[0], sf[1], out=dsf)
    sub(ss[0], ss[1], out=twp)
    mul(q2, v[0], out=u1)
    mul(q1, v[1], out=u2)
    sub(u1, u2, out=tww)
    np.add(tww, waves.d, out=tww)
    mul(q2, v[1], out=u1)
    mul(q1, v[0], out=u2)
    sub(u1, u2, out=tpp)
    np.add(tpp, waves.d, out=tpp)
    mul(q1, ss[1], out=u1)
    mul(q2, ss[0], out=u2)
    sub(u1, u2, out=uwv)
    mul(q1, sf[0], out=u1)
    mul(q2, sf[1], out=u2)
    sub(u1, u2, out=upm)
    mul(waves.qq, dc, out=upv)
    mul(waves.qq, dsf, out=tpw)
    mul(uwv, upm, out=u1)
    mul(dc, upv, out=u2)
    sub(u1, u2, out=u1)
    np.divide(1.0, u1, out=u1)                            # R
    rho, eta = u2, u1
    mul(u1, waves.ra, out=rho)
    mul(u1, waves.ei, out=eta)
    a, b, c, e, f, g = out
    mul(upm, tww, out=a)
    mul(dc, tpw, out=u3)
    sub(a, u3, out=a)
    mul(a, rho, out=a)
    mul(upm, twp, out=b)
    mul(dc, tpp, out=u3)
    sub(b, u3, out=b)
    mul(b, rho, out=b)
    mul(uwv, tpp, out=c)
    mul(upv, twp, out=u3)
    sub(c, u3, out=c)
    mul(c, eta, out=c)
    mul(rho, waves.d, out=rho)
    mul(rho, upm, out=e)
    np.negative(e, out=e)
    mul(rho, dc, out=f)
    mul(eta, waves.d, out=eta)
    mul(eta, uwv, out=g)
    np.negative(g, out=g)


def double(terms: SixTerms | RealTerms, scratch: Scratch, pivots: Pivots | None = None, multiplicity: int = 1) -> None:
    """Six-term stiffness of two equal pieces in a row, the middle node condensed, in place.

    For equal pieces the middle pivot is ``P = D22 + D11 = diag(2A, 2C)``, so
    ``D11' = D11 − D12 P⁻¹ D21`` and ``D12' = −D12 P⁻¹ D12`` reduce to (``α = 1/2A``, ``γ = 1/2C``)::

        A' = A − αE² − γF²     B' = B + αEF − γFG     C' = C − αF² − γG²
        E' = γF² − αE²         F' = −(αE + γG) F     G' = αF² − γG²

    An undamped caller passes ``pivots`` to count the middle pivot (``multiplicity`` times).

    Parameters
    ----------
    terms : tuple of six numpy.ndarray
        One piece's six terms (complex or real), overwritten by those of two pieces.
    scratch : Scratch
        Work arrays.
    pivots : Pivots, optional
        Where the middle pivots are counted (undamped).
    multiplicity : int
        How many equal pairs this doubling stands for (each pivot counted that often).
    """
    a, b, c, e, f, g = terms
    get = scratch.real if np.isrealobj(a) else scratch.complex
    n = a.shape
    u, v, w, z, t1, t2, t3 = (get(f"dbl.{i}", n) for i in range(7))
    if pivots is not None:
        np.multiply(a, 2.0, out=t1)
        pivots.add_scalar(t1.real, multiplicity)                  # real when counting: no copy
        np.multiply(c, 2.0, out=t1)
        pivots.add_scalar(t1.real, multiplicity)
    np.divide(0.5, a, out=w)                              # α
    np.divide(0.5, c, out=z)                              # γ
    np.multiply(e, w, out=u)                              # αE
    np.multiply(f, z, out=v)                              # γF
    np.multiply(f, w, out=w)                              # αF
    np.multiply(g, z, out=z)                              # γG
    np.multiply(e, u, out=t1)                             # αE²
    np.multiply(f, v, out=t2)                             # γF²
    np.subtract(a, t1, out=a)
    np.subtract(a, t2, out=a)
    np.subtract(t2, t1, out=t1)                           # E'
    np.multiply(f, u, out=t2)                             # αEF
    np.multiply(g, v, out=t3)                             # γFG
    np.add(b, t2, out=b)
    np.subtract(b, t3, out=b)
    np.multiply(f, w, out=t2)                             # αF²
    np.multiply(g, z, out=t3)                             # γG²
    np.subtract(c, t2, out=c)
    np.subtract(c, t3, out=c)
    np.add(u, z, out=u)
    np.multiply(u, f, out=f)
    np.negative(f, out=f)                                 # F'
    np.subtract(t2, t3, out=g)                            # G'
    np.copyto(e, t1)


def _fresh_real(n: tuple[int, ...]) -> RealTerms:
    return (np.empty(n), np.empty(n), np.empty(n), np.empty(n), np.empty(n), np.empty(n))


def _fresh_out(n: tuple[int, ...]) -> SixTerms:
    c = complex
    return (np.empty(n, c), np.empty(n, c), np.empty(n, c), np.empty(n, c), np.empty(n, c), np.empty(n, c))


def stiffness_terms(omega_rad_s: FloatArray, section: Section, length_m: RealParam,
                    waves: Waves | None = None, *, scratch: Scratch | None = None,
                    out: SixTerms | None = None) -> SixTerms:
    """The six distinct entries ``(A, B, C, E, F, G)`` of a uniform segment's dynamic stiffness.

    By reciprocity and the mirror symmetry of a uniform segment::

        D = [[ A,  B,  E,  F],
             [ B,  C, -F,  G],
             [ E, -F,  A, -B],
             [ F,  G, -B,  C]]

    computed from the transfer-matrix entries of :func:`transfer_matrix` (their common
    factor 1/(s₁ − s₂) cancels): ``D11 = T_ds⁻¹ T_dd`` and ``D12 = −T_ds⁻¹`` (``docs/physics.md``
    §2.4), in the versine form of :func:`six_terms` (no division by ρAω² or EI, full
    precision at low frequency). Accurate for pieces whose decay exponent ``|Im √s| L`` is at
    most ``MAX_DECAY_PER_PIECE``; longer segments: :func:`segment_terms`.

    Parameters
    ----------
    omega_rad_s : numpy.ndarray, shape (nfreq,)
        Angular frequencies, rad/s.
    section : Section
    length_m : float or numpy.ndarray, shape (nfreq,)
        Segment length, m (one per row for a stacked section).
    waves : Waves, optional
        The section's :class:`Waves` on this grid.
    scratch : Scratch, optional
        Work arrays (fresh ones by default).
    out : tuple of six numpy.ndarray, optional
        Where to write the result (fresh arrays by default).

    Returns
    -------
    tuple of numpy.ndarray, each shape (nfreq,), complex
        N/m, N/rad, N·m/rad, N/m, N/rad, N·m/rad.
    """
    sc = Scratch() if scratch is None else scratch
    wv = waves if waves is not None else Waves(omega_rad_s, section, sc, "st.")
    res = out if out is not None else _fresh_out(wv.n)
    six_terms(wv, wv.functions(length_m, sc), res, sc)
    return res


def segment_terms(omega_rad_s: FloatArray, section: Section, length_m: RealParam,
                  waves: Waves | None = None, *, scratch: Scratch | None = None,
                  out: SixTerms | None = None) -> SixTerms:
    """:func:`stiffness_terms` of a whole segment of any length.

    A segment whose decay exponent exceeds ``MAX_DECAY_PER_PIECE`` is computed as ``2^m``
    equal pieces joined by :func:`double`, which is exact and keeps full precision for long,
    strongly evanescent segments.

    Parameters
    ----------
    omega_rad_s : numpy.ndarray, shape (nfreq,)
        Angular frequencies, rad/s.
    section : Section
    length_m : float or numpy.ndarray
        Segment length, m (one per row for a stacked section).
    waves : Waves, optional
        The section's waves on this grid, when the caller already has them.
    scratch : Scratch, optional
        Work arrays (fresh ones by default).
    out : tuple of six numpy.ndarray, optional
        Where to write the result (fresh arrays by default).
    """
    sc = Scratch() if scratch is None else scratch
    wv = waves if waves is not None else Waves(omega_rad_s, section, sc, "st.")
    m = _doublings(wv.decay_per_m, length_m)
    res = stiffness_terms(omega_rad_s, section, length_m / 2**m, wv, scratch=sc, out=out)
    for _ in range(m):
        double(res, sc)
    return res


def undamped_segment_terms(omega_rad_s: FloatArray, section: Section, length_m: RealParam,
                           waves: RealWaves | None = None, *, scratch: Scratch | None = None,
                           out: RealTerms | None = None, pivots: Pivots | None = None) -> RealTerms:
    """:func:`segment_terms` of an undamped segment in real arithmetic.

    As :func:`segment_terms`, the section's damping ignored. When the
    segment is computed from ``2^m`` pieces the middle pivots are reported to ``pivots``
    (their negatives are the segment's own clamped–clamped natural frequencies below ω).

    Parameters
    ----------
    omega_rad_s : numpy.ndarray, shape (nfreq,)
        Angular frequencies, rad/s.
    section : Section
    length_m : float or numpy.ndarray
        Segment length, m (one per row for a stacked section).
    waves : RealWaves, optional
        The section's waves on this grid, when the caller already has them.
    scratch : Scratch, optional
        Work arrays (fresh ones by default).
    out : tuple of six numpy.ndarray, optional
        Where to write the result (fresh arrays by default).
    pivots : Pivots, optional
        Where the middle pivots of the doublings are counted.

    Returns
    -------
    tuple of numpy.ndarray, each shape (nfreq,), float
    """
    sc = Scratch() if scratch is None else scratch
    wv = waves if waves is not None else RealWaves(omega_rad_s, section, sc, "st.")
    m = _doublings(wv.decay_per_m, length_m)
    res: RealTerms = out if out is not None else _fresh_real(wv.n)
    six_terms(wv, wv.functions(length_m / 2**m, sc), res, sc)
    for level in range(m):
        double(res, sc, pivots, 2 ** (m - 1 - level))
    return res


def stiffness_terms_reference(omega_rad_s: FloatArray, section: Section, length_m: RealParam) -> SixTerms:
    """:func:`stiffness_terms` written plainly from the transfer-matrix entries (a test oracle).

    ``D11 = T_ds⁻¹ T_dd``, ``D12 = −T_ds⁻¹`` with the entries of §2.3 (times ``s₁ − s₂``)
    and numpy's own complex ``cos``, ``sin`` and square roots.

    Parameters
    ----------
    omega_rad_s : numpy.ndarray, shape (nfreq,)
        Angular frequencies, rad/s.
    section : Section
    length_m : float
        Segment length, m.
    """
    w2 = np.asarray(omega_rad_s, dtype=float) ** 2
    ei, ra = section.ei, section.rho_a * w2
    s1, s2 = wavenumbers(omega_rad_s, section)
    q1, q2 = s1 - ra * section.shear_flexibility, s2 - ra * section.shear_flexibility
    c1, sf1, ss1 = _c_and_s(np.sqrt(s1), length_m)
    c2, sf2, ss2 = _c_and_s(np.sqrt(s2), length_m)
    dc = c2 - c1
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
    scale = (s1 - s2) * inv_det
    return a, b, c, -t_pm * scale, t_wm * scale, -t_wv * scale


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

    ``R = [[T_sd⁻¹T_ss, T_sd⁻¹], [·, T_dd T_sd⁻¹]]`` (``docs/physics.md`` §2.4), lower-left block by
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


def static_terms(section: Section, length_m: RealParam) -> SixTerms:
    """The six distinct entries ``(A, B, C, E, F, G)`` of :func:`static_stiffness`.

    ``EI/((1+Φ)L³) · (12, 6L, (4+Φ)L², −12, 6L, (2−Φ)L²)``; each is a scalar, or an array
    over rows for a stacked section or length (complex either way).

    Parameters
    ----------
    section : Section
    length_m : float or numpy.ndarray
        Segment length, m (one per row for a stacked beam).
    """
    ei, lm = section.ei, length_m
    phi = 12.0 * ei * section.shear_flexibility / lm**2
    scale = ei / ((1 + phi) * lm**3)
    a, b, c, e, f, g = (np.asarray(x * scale, dtype=complex)
                        for x in (12.0, 6 * lm, (4 + phi) * lm**2, -12.0, 6 * lm, (2 - phi) * lm**2))
    return a, b, c, e, f, g


def static_stiffness(section: Section, length_m: RealParam) -> ComplexArray:
    """Exact static Timoshenko stiffness matrix (the ω → 0 limit of :func:`dynamic_stiffness`).

    ``EI/((1+Φ)L³) [[12, 6L, −12, 6L], [6L, (4+Φ)L², −6L, (2−Φ)L²], …]``, Φ = 12EI/(κGA L²)
    (``docs/physics.md`` §2.4), with the section's complex moduli (entries :func:`static_terms`).

    Parameters
    ----------
    section : Section
    length_m : float
        Segment length, m.

    Returns
    -------
    numpy.ndarray, shape (4, 4), complex
    """
    a, b, c, e, f, g = (complex(x) for x in static_terms(section, length_m))
    return np.array([[a, b, e, f], [b, c, -b, g], [e, -b, a, -f], [f, g, -f, c]], dtype=complex)
