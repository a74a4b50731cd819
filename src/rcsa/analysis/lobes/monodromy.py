"""The period map (monodromy matrix) of milling by first-order semi-discretization.

Model (Insperger & Stépán 2004; Altintas 2012 §4.4 for the forces): the tool point moves
``r = (x, y)`` (x feed, y normal) through real modes ``q_r`` (``ModalModel``),

    q̈_r + 2ζ_r ω_r q̇_r + ω_r² q_r = φ_r F_dir(r),      r(t) = Σ_r φ_r q_r e_dir(r),
    F(t) = −b Kt W(t) (r(t) − r(t − T)),                 T = 60/(N n) (tooth period),

with ``φ_r = √R_r`` (residue, 1/kg), axial depth ``b`` and the directional matrix
``W(t) = −½ Σ_j g(φ_j) [[sin2φ + Kr(1 − cos2φ), 1 + cos2φ + Kr sin2φ],
[−(1 − cos2φ) + Kr sin2φ, −sin2φ + Kr(1 + cos2φ)]]`` (``φ_j`` clockwise from +y, screen
``g = 1`` while tooth ``j`` cuts; :func:`rcsa.analysis.lobes.zoa.directional_factors` is its
integral). In the scaled state ``u = [ω q; q̇]`` (n = 2·nmodes) this reads
``u̇ = A(t) u + B(t) r(t − T)``.

Semi-discretization: the period is cut into ``k`` steps ``h = T/k``; on step ``i`` the
coefficients are replaced by their step means ``A_i``, ``B_i`` (exact integral of ``W``)
and the delayed term by the line through its samples (first order)::

    r(t − T) ≈ r_{i−k} + (t − t_i)/h · (r_{i−k+1} − r_{i−k})       t ∈ [t_i, t_{i+1}]
    u_{i+1} = P_i u_i + (G1_i − G2_i) r_{i−k} + G2_i r_{i−k+1}
    P_i = e^{A_i h},  G1_i = h φ1(A_i h) B_i,  G2_i = h φ2(A_i h) B_i

(``φ1(Z) = (e^Z − I)/Z``, ``φ2(Z) = (e^Z − I − Z)/Z²``). The state of the map is
``z = [u_0; r_{−k}, …, r_{−1}]``; only the delayed samples that a cutting step reads are
kept (the others give zero columns, i.e. zero multipliers), and the free flight between two
cuts is one exponential. Everything is vectorised over a batch of (speed, depth) pairs; the
loop runs over the steps of one period only.

References
----------
.. [1] T. Insperger, G. Stépán, "Updated semi-discretization method for periodic
   delay-differential equations with discrete delay", Int. J. Numer. Meth. Engng
   61:117–141, 2004 (the method and its milling model).
.. [2] T. Insperger, G. Stépán, J. Turi, "On the higher-order semi-discretizations for
   periodic delayed systems", J. Sound Vib. 313:334–341, 2008 (the first-order form).
.. [3] T. Insperger, G. Stépán, *Semi-Discretization for Time-Delay Systems*, Springer,
   2011, ch. 3 and 5.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Literal

import numpy as np

from rcsa.analysis.lobes.modal_model import ModalModel
from rcsa.analysis.lobes.zoa import directional_factors
from rcsa.physics.subassembly_cache import LruStore

__all__ = [
    "CuttingPlan",
    "PeriodMaps",
    "StateSpace",
    "BLOCK_STEPS",
    "BlockedPeriodMap",
    "apply_period",
    "blockable",
    "blocked_period_map",
    "chatter_frequency",
    "critical_multipliers",
    "cut_window_fraction",
    "cut_window_plan",
    "cutting_plan",
    "displacement_samples",
    "free_maps",
    "matrix_free_cheaper",
    "monodromy_matrix",
    "padded_cut_window",
    "period_displacement",
    "period_maps",
    "state_space",
    "state_spaces",
    "step_exponentials",
    "trajectory",
]

_TWO_PI = 2.0 * np.pi
# Taylor degree of the step exponentials on arguments scaled to ‖Z‖₁ <= 1: tail < 1/13! ≈ 2e-10.
_TAYLOR_DEGREE = 12
# Reduced sizes up to this use a dense eigensolver; larger ones a Krylov (Arnoldi) basis.
DENSE_MAX_SIZE = 48
KRYLOV_DIM = 20
KRYLOV_EXTRA = 12
# A Ritz value is accepted when its residual is below this (relative to max(|μ|, 1)).
RITZ_TOL = 1e-9
_KRYLOV_SEED = 20040117


# --------------------------------------------------------------------------- cutting


@dataclass(frozen=True)
class CuttingPlan:
    """Where the teeth cut during one tooth period of ``steps`` equal steps (speed-free).

    Attributes
    ----------
    steps : int
        ``k``, steps per tooth period.
    force : numpy.ndarray, shape (ncut, 2, 2)
        Step mean of ``W(t)`` on the cutting steps (dimensionless; times ``b Kt``, N/m).
    cut_step : numpy.ndarray, shape (ncut,)
        Index of each cutting step.
    segments : tuple of (int, int, int)
        The period in order as ``(cut, start, length)``: a cutting step (``cut`` indexes
        ``force``, length 1) or a free stretch (``cut = −1 − f``, ``f`` its free index).
    slot : numpy.ndarray, shape (steps,)
        Position of the delayed sample ``r_{s−k}`` in the reduced state, −1 if unread.
    free_length : numpy.ndarray, shape (nfree,)
        Length of each free stretch in steps (a float: the free flight of a cut-window plan is
        not a whole number of steps).
    step_fraction : float
        One step ``h`` over the tooth period ``T`` (``1/steps`` for a full-period plan).
    scheme : {"full_period", "cut_window"}
        :func:`cutting_plan` (equal steps over the whole period) or :func:`cut_window_plan`
        (equal steps over the time in the cut, the free flight as one exact step).
    """

    steps: int
    force: np.ndarray
    cut_step: np.ndarray
    segments: tuple[tuple[int, int, int], ...]
    slot: np.ndarray
    free_length: np.ndarray
    step_fraction: float
    scheme: str = "full_period"

    @property
    def n_samples(self) -> int:
        """Delayed samples kept in the reduced state."""
        return int(np.count_nonzero(self.slot >= 0))


def cutting_plan(teeth: int, steps: int, phi_start_rad: float, phi_exit_rad: float,
                 radial_ratio: float) -> CuttingPlan:
    """Step means of the directional matrix over one tooth period.

    Tooth ``j`` is at ``φ_j = 2π(i + s)/(N k) + 2πj/N`` during step ``i`` (``s ∈ [0, 1)``);
    the mean over the step is the exact integral of ``W`` over the part of the step inside
    ``[φst, φex]`` (:func:`~rcsa.analysis.lobes.zoa.directional_factors`) over the step's
    angle. Partly cutting steps are therefore weighted exactly (Insperger & Stépán integrate
    the same mean numerically with 20 points).

    Examples
    --------
    Slotting with two teeth: one tooth always cuts, and the period mean is ZOA's ``α/2π``
    (times −½ for ``W``):

    >>> plan = cutting_plan(2, 40, 0.0, np.pi, 0.3)
    >>> plan.force.shape, plan.n_samples
    ((40, 2, 2), 40)
    >>> bool(np.allclose(plan.force.mean(axis=0) * np.pi,
    ...                  -0.5 * directional_factors(0.0, np.pi, 0.3)))
    True
    """
    dphi = _TWO_PI / (teeth * steps)
    force = np.zeros((steps, 2, 2))
    start = np.arange(steps) * dphi
    for j in range(teeth):  # a loop over teeth; the steps are one array
        a = start + j * _TWO_PI / teeth
        lo, hi = np.clip(a, phi_start_rad, phi_exit_rad), np.clip(a + dphi, phi_start_rad, phi_exit_rad)
        for i in np.flatnonzero(hi > lo):
            force[i] += directional_factors(float(lo[i]), float(hi[i]), radial_ratio)
    force *= -0.5 / dphi
    cutting = np.abs(force).reshape(steps, 4).max(axis=1) > 0.0
    cut_step = np.flatnonzero(cutting)
    read = np.unique(np.concatenate([cut_step, cut_step + 1]))
    read = read[read < steps]
    slot = np.full(steps, -1)
    slot[read] = np.arange(read.size)
    segments: list[tuple[int, int, int]] = []
    free: list[int] = []
    i = 0
    while i < steps:
        if cutting[i]:
            segments.append((int(np.searchsorted(cut_step, i)), i, 1))
            i += 1
            continue
        j = i
        while j < steps and not cutting[j]:
            j += 1
        segments.append((-1 - len(free), i, j - i))
        free.append(j - i)
        i = j
    return CuttingPlan(steps, force[cut_step], cut_step, tuple(segments), slot,
                       np.array(free, dtype=float), 1.0 / steps)


def cut_window_fraction(teeth: int, phi_start_rad: float, phi_exit_rad: float) -> float:
    """Share of the tooth period spent in the cut, ``N (φex − φst) / 2π`` (below 1: one tooth at a time).

    Examples
    --------
    >>> round(cut_window_fraction(1, float(np.arccos(-0.9)), np.pi), 4)  # one flute, a_e/D = 0.05, down
    0.0718
    """
    return teeth * (phi_exit_rad - phi_start_rad) / _TWO_PI


def cut_window_plan(teeth: int, cut_steps: int, phi_start_rad: float, phi_exit_rad: float,
                    radial_ratio: float) -> CuttingPlan:
    """A period map that discretises only the time in the cut (fewer than one tooth in the cut).

    While no tooth cuts, the tool vibrates freely: that stretch, ``T (1 − w)`` long (``w``:
    :func:`cut_window_fraction`), is one exact step (the exponential of the free system). The
    cut, ``w T`` long, is cut into ``cut_steps`` equal steps that start where the tooth enters
    (``φst``) and end where it leaves (``φex``), so no step is partly in the cut. The delay is
    one tooth period, so the delayed displacement a cutting step reads lies in the previous
    period's cut window, at the same nodes: the state keeps those ``cut_steps + 1`` samples only
    (Insperger & Stépán 2011, §5.2 on the free-flight part; Bayly et al. 2003 treat the
    interrupted cut as a free flight and a short cut in the same way). Plans are cached (their
    arrays are read-only).

    The period starts at the tooth's entry: steps ``0 … cut_steps − 1`` cut, step
    ``cut_steps`` is the free flight (its sample ``r`` at the exit is the last one a cutting step
    reads).

    Examples
    --------
    A single flute at 5 % immersion spends 7.2 % of its period in the cut:

    >>> st, ex = float(np.arccos(-0.9)), np.pi
    >>> plan = cut_window_plan(1, 20, float(st), ex, 0.3)
    >>> plan.scheme, plan.steps, plan.n_samples, round(plan.step_fraction * 20, 4)
    ('cut_window', 21, 21, 0.0718)
    >>> bool(np.allclose(plan.force.sum(axis=0) * (ex - st) / 20, -0.5 * directional_factors(st, ex, 0.3)))
    True
    """
    key = (teeth, cut_steps, phi_start_rad, phi_exit_rad, radial_ratio)
    return _CUT_WINDOW_PLANS.get(key, lambda: _cut_window_plan(*key))


#: Cut-window plans kept (the one eviction policy, :class:`rcsa.physics.subassembly_cache.LruStore`).
_CUT_WINDOW_PLANS: LruStore[tuple[int, int, float, float, float], CuttingPlan] = LruStore(512)


def _cut_window_plan(teeth: int, cut_steps: int, phi_start_rad: float, phi_exit_rad: float,
                     radial_ratio: float) -> CuttingPlan:
    fraction = cut_window_fraction(teeth, phi_start_rad, phi_exit_rad)
    if not 0.0 < fraction < 1.0:
        raise ValueError(f"a cut-window plan needs fewer than one tooth in the cut, got {fraction:.3f}")
    dphi = (phi_exit_rad - phi_start_rad) / cut_steps
    edges = phi_start_rad + dphi * np.arange(cut_steps + 1)
    edges[-1] = phi_exit_rad
    force = np.stack([directional_factors(float(lo), float(hi), radial_ratio)
                      for lo, hi in zip(edges[:-1], edges[1:], strict=True)]) * (-0.5 / dphi)
    steps = cut_steps + 1
    segments = tuple((i, i, 1) for i in range(cut_steps)) + ((-1, cut_steps, 1),)
    free = np.array([(1.0 - fraction) / fraction * cut_steps])
    plan = CuttingPlan(steps, force, np.arange(cut_steps), segments, np.arange(steps), free,
                       fraction / cut_steps, "cut_window")
    for array in (plan.force, plan.cut_step, plan.slot, plan.free_length):
        array.flags.writeable = False  # shared: the plans are cached
    return plan


# --------------------------------------------------------------------------- dynamics


@dataclass(frozen=True)
class StateSpace:
    """The modal model in scaled coordinates ``u = [ω q; q̇]``.

    One system (arrays as below), or one per member of a batch (a leading axis of size
    ``nb`` on every array: :func:`state_spaces`, then :meth:`take`), so that the period maps
    of many tools are built and solved together.

    Attributes
    ----------
    a0 : numpy.ndarray, shape (n, n) or (nb, n, n)
        Free dynamics (block ``[[0, Ω], [−Ω, −2ZΩ]]``), 1/s.
    c_out : numpy.ndarray, shape (2, n) or (nb, 2, n)
        ``r = c_out u`` (m per scaled unit).
    c_in : numpy.ndarray, shape (nmodes, 2) or (nb, nmodes, 2)
        Modal force per N in x and y (``φ_r``, 1/√kg).
    """

    a0: np.ndarray
    c_out: np.ndarray
    c_in: np.ndarray

    @property
    def n(self) -> int:
        """State size ``2·nmodes``."""
        return int(self.a0.shape[-1])

    @property
    def batched(self) -> bool:
        """One system per batch member (a leading axis)."""
        return self.a0.ndim == 3

    def take(self, idx: np.ndarray) -> StateSpace:
        """The systems of the batch members ``idx`` (a single system is shared: itself)."""
        if not self.batched:
            return self
        return StateSpace(self.a0[idx], self.c_out[idx], self.c_in[idx])

    def per_step(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``a0``, ``c_out``, ``c_in`` shaped to broadcast against (nb, steps, ·, ·) arrays."""
        if not self.batched:
            return self.a0, self.c_out, self.c_in
        return self.a0[:, None], self.c_out[:, None], self.c_in[:, None]


def state_space(model: ModalModel) -> StateSpace:
    """Scaled state-space form of a modal model (well balanced: ``‖A0‖ ~ ω``)."""
    w = _TWO_PI * np.asarray(model.frequency_hz, dtype=float)
    z = np.asarray(model.damping_ratio, dtype=float)
    phi = np.sqrt(np.asarray(model.residue_1_kg, dtype=float))
    d = w.size
    a0 = np.zeros((2 * d, 2 * d))
    a0[:d, d:] = np.diag(w)
    a0[d:, :d] = -np.diag(w)
    a0[d:, d:] = -np.diag(2.0 * z * w)
    c_out = np.zeros((2, 2 * d))
    c_in = np.zeros((d, 2))
    modes = np.arange(d)
    c_out[model.direction, modes] = phi / w
    c_in[modes, model.direction] = phi
    return StateSpace(a0, c_out, c_in)


#: Damping ratio of the inert modes that pad a smaller modal model in a stack of systems.
PAD_DAMPING_RATIO = 0.5


def state_spaces(models: Sequence[ModalModel]) -> StateSpace:
    """The systems of several modal models stacked on a leading axis (one per model).

    A model with fewer modes than the largest is padded with inert modes: no residue (no
    force in, no displacement out), the model's lowest natural frequency and damping ratio
    :data:`PAD_DAMPING_RATIO`, so their multipliers ``e^{−ζωT}`` stay far inside the unit
    circle and the exponentials' norms do not grow.

    Examples
    --------
    >>> a = ModalModel.of([500.0], [0.02], [1.0], [0])
    >>> b = ModalModel.of([600.0, 900.0], [0.03, 0.02], [2.0, 1.0], [0, 1])
    >>> s = state_spaces([a, b])
    >>> s.a0.shape, s.c_out.shape, s.c_in.shape
    ((2, 4, 4), (2, 2, 4), (2, 2, 2))
    >>> bool(np.all(s.c_in[0, 1] == 0) and np.all(s.c_out[0][:, [1, 3]] == 0))
    True
    """
    d = max(m.n_modes for m in models)
    a0 = np.zeros((len(models), 2 * d, 2 * d))
    c_out = np.zeros((len(models), 2, 2 * d))
    c_in = np.zeros((len(models), d, 2))
    for i, m in enumerate(models):  # a loop over models (tools), each a few small arrays
        pad = d - m.n_modes
        w = np.concatenate([_TWO_PI * m.frequency_hz, np.full(pad, _TWO_PI * float(m.frequency_hz.min()))])
        z = np.concatenate([m.damping_ratio, np.full(pad, PAD_DAMPING_RATIO)])
        one = state_space(m)
        modes = np.arange(d)
        a0[i, modes, d + modes] = w
        a0[i, d + modes, modes] = -w
        a0[i, d + modes, d + modes] = -2.0 * z * w
        real = np.arange(m.n_modes)
        c_out[i][:, real] = one.c_out[:, real]
        c_in[i][real] = one.c_in
    return StateSpace(a0, c_out, c_in)


def step_exponentials(z: np.ndarray, beta: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``e^Z``, ``φ1(Z) β`` and ``φ2(Z) β`` of stacked matrices (``φ1 = (e^Z − I)/Z``, ``φ2 = (e^Z − I − Z)/Z²``).

    These are the blocks of the exponential of ``M = [[Z, β, 0], [0, 0, I], [0, 0, 0]]``
    (``e^M = [[e^Z, φ1 β, φ2 β], …]``), computed without forming ``M`` and without an
    inverse of ``Z`` (a singular ``A_i``, the cutting stiffness cancelling a mode, is
    harmless): scaling ``Z/2^s`` to ``‖·‖₁ <= 1``, a degree-12 Taylor polynomial in
    Paterson–Stockmeyer form (tail below 1/13! ≈ 2e-10; degree 8 where ``‖Z‖₁ <= 1/4``, tail
    below 7e-12), then ``s`` squarings of the block
    matrix, ``[[E, X, Y], [0, I, cI], [0, 0, I]]² = [[E², EX + X, EY + cX + Y], [0, I, 2cI], …]``,
    which cost one full and one thin product each. Matrices are grouped by ``s`` and degree.

    Parameters
    ----------
    z : numpy.ndarray, shape (..., n, n)
    beta : numpy.ndarray, shape (..., n, t)

    Returns
    -------
    e, x, y : numpy.ndarray, shapes (..., n, n), (..., n, t), (..., n, t)

    Examples
    --------
    >>> from scipy.linalg import expm
    >>> a, b = np.array([[0.0, 1.0], [-4.0, -0.2]]), np.array([[0.0], [2.0]])
    >>> e, x, y = step_exponentials(a[None], b[None])
    >>> m = np.zeros((4, 4)); m[:2, :2] = a; m[:2, 2:3] = b; m[2, 3] = 1.0
    >>> ref = expm(m)
    >>> all(bool(np.allclose(u[0], v, rtol=1e-12, atol=1e-14))
    ...     for u, v in ((e, ref[:2, :2]), (x, ref[:2, 2:3]), (y, ref[:2, 3:4])))
    True
    """
    n, t = z.shape[-1], beta.shape[-1]
    lead = z.shape[:-2]
    zf = z.reshape(-1, n, n)
    bf = beta.reshape(-1, n, t)
    e_out = np.empty_like(zf)
    x_out = np.empty_like(bf)
    y_out = np.empty_like(bf)
    for lo in range(0, zf.shape[0], _CACHE_CHUNK):  # pieces whose sums stay in the CPU's cache
        piece = slice(lo, lo + _CACHE_CHUNK)
        _exponentials_of_piece(zf[piece], bf[piece], e_out[piece], x_out[piece], y_out[piece])
    return (e_out.reshape(lead + (n, n)), x_out.reshape(lead + (n, t)), y_out.reshape(lead + (n, t)))


def _exponentials_of_piece(z: np.ndarray, beta: np.ndarray, e_out: np.ndarray, x_out: np.ndarray,
                           y_out: np.ndarray) -> None:
    """:func:`step_exponentials` of a piece of the batch, written into the ``*_out`` views: grouped by
    squarings and Taylor degree (usually one group, taken as is)."""
    n = z.shape[-1]
    norm = np.abs(z).sum(axis=-2).max(axis=-1)
    squarings = np.ceil(np.log2(np.maximum(norm, 1e-300))).clip(0).astype(np.int64)
    # short steps (‖Z‖₁ <= 1/4, the usual case of a resolving discretisation) need only degree 8:
    # tail below (1/4)^9/9! ≈ 7e-12
    blocks = np.where(norm <= _SHORT_NORM, 2, 3)
    # Z = 0 (the zero-length steps that pad a plan): e^0 = I, φ1(0) β = β, φ2(0) β = β/2, exactly
    zero = norm == 0.0
    group = np.where(zero, -1, 4 * squarings + blocks)
    keys = np.unique(group)
    if keys.size == 1 and keys[0] >= 0:  # one class: no gathering
        e_out[...], x_out[...], y_out[...] = _taylor_class(z, beta, *divmod(int(keys[0]), 4))
        return
    e_out[zero], x_out[zero], y_out[zero] = np.eye(n), beta[zero], 0.5 * beta[zero]
    for key in keys[keys >= 0]:  # a loop over (squarings, degree) classes, a handful
        idx = np.flatnonzero(group == key)
        e_out[idx], x_out[idx], y_out[idx] = _taylor_class(z[idx], beta[idx], *divmod(int(key), 4))


def _taylor_class(z: np.ndarray, beta: np.ndarray, s: int, m: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """:func:`step_exponentials` of stacked ``z`` (k, n, n) and ``beta`` (k, n, t) sharing ``s`` squarings
    and the Taylor degree ``4 m``: Horner in ``Z^4`` over blocks of four terms, summed in place."""
    n = z.shape[-1]
    diag = np.arange(n) * (n + 1)  # the diagonal of a flattened (n, n) matrix
    c = 1.0 / float(2**s)
    zz = z * c
    bb = beta * c
    z2 = zz @ zz
    z3 = z2 @ zz
    w = z2 @ z2  # Z^4
    zb = (bb, zz @ bb, z2 @ bb, z3 @ bb)  # Z^i β
    top = 4 * m  # the Taylor degree
    e = w * (1.0 / _FACT[top])  # Z^4 · I/top!: the first Horner product without a product
    wb = w @ bb
    x = wb * (1.0 / _FACT[top + 1])
    y = wb * (1.0 / _FACT[top + 2])
    for block in range(m - 1, -1, -1):  # Horner in Z^4 over blocks of four Taylor terms
        j = 4 * block
        if block != m - 1:  # e, x, y of the top block already hold Z^4 times the top terms
            e, x, y = w @ e, w @ x, w @ y
        for i, power in enumerate((zz, z2, z3), start=1):
            e += power * (1.0 / _FACT[j + i])
        e.reshape(e.shape[0], -1)[:, diag] += 1.0 / _FACT[j]
        for i, b in enumerate(zb):
            x += b * (1.0 / _FACT[j + i + 1])
            y += b * (1.0 / _FACT[j + i + 2])
    y *= c
    for _ in range(s):
        y = e @ y + c * x + y
        x = e @ x + x
        e = e @ e
        c *= 2.0
    return e, x, y


_SHORT_NORM = 0.25
#: Matrices summed at a time (:func:`step_exponentials`): the Horner sums are memory-bound, and
#: 128 matrices of 16 x 16 (256 kB an array) stay in cache; measured 2.6x faster than the whole batch at once.
_CACHE_CHUNK = 128
_FACT = [float(math.factorial(j)) for j in range(_TAYLOR_DEGREE + 3)]


@dataclass(frozen=True)
class PeriodMaps:
    """Step maps of one tooth period for a batch of (speed, depth) pairs.

    Attributes
    ----------
    p : numpy.ndarray, shape (nb, ncut, n, n)
        ``P_i`` of the cutting steps.
    g : numpy.ndarray, shape (nb, ncut, n, 4)
        ``[G1_i − G2_i | G2_i]``, acting on ``[r_{i−k}; r_{i−k+1}]``.
    free : numpy.ndarray, shape (nb, nfree, n, n)
        Exponential of each free stretch.
    step : numpy.ndarray, shape (nb, n, n)
        ``e^{A0 h}``, one free step (for trajectories).
    active : numpy.ndarray of int, shape (nb,), optional
        Cut-window plans padded to a common step count (:func:`padded_cut_window`): each
        member's own cutting steps, the rest of the cut being steps of zero length (``P = I``,
        ``G = 0``: they repeat the exit state, so the multipliers are the member's own plus zeros).
    """

    p: np.ndarray
    g: np.ndarray
    free: np.ndarray
    step: np.ndarray
    active: np.ndarray | None = None

    def take(self, idx: np.ndarray) -> PeriodMaps:
        """The maps of the members ``idx``."""
        return PeriodMaps(self.p[idx], self.g[idx], self.free[idx], self.step[idx],
                          None if self.active is None else self.active[idx])

    @property
    def batch(self) -> int:
        """Number of (speed, depth) pairs."""
        return int(self.p.shape[0])


def free_maps(system: StateSpace, plan: CuttingPlan, step_s: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Depth-free exponentials: each free stretch, shape (nb, nfree, n, n), and one step."""
    lengths = np.concatenate([plan.free_length, [1]]).astype(float)
    z = system.per_step()[0] * (np.asarray(step_s, dtype=float)[:, None, None, None] * lengths[None, :, None, None])
    e = step_exponentials(z, np.zeros(z.shape[:-1] + (1,)))[0]
    return e[:, :-1], e[:, -1]


def period_maps(system: StateSpace, plan: CuttingPlan, tangential_coefficient_n_m2: float,
                step_s: np.ndarray, depth_m: np.ndarray,
                free: tuple[np.ndarray, np.ndarray], *, force: np.ndarray | None = None,
                active: np.ndarray | None = None) -> PeriodMaps:
    """Step maps ``P_i``, ``G_i`` for each (step length h, depth b) of the batch.

    Parameters
    ----------
    system : StateSpace
    plan : CuttingPlan
    tangential_coefficient_n_m2 : float
        ``Kt``, N/m².
    step_s : numpy.ndarray, shape (nb,) or (nb, ncut)
        ``h``, s: one per member, or one per member and cutting step (padded plans).
    depth_m : numpy.ndarray, shape (nb,)
        Axial depth ``b``, m.
    free : (numpy.ndarray, numpy.ndarray)
        :func:`free_maps` of the same step lengths.
    force, active : numpy.ndarray, optional
        Per-member step means of ``W`` (nb, ncut, 2, 2) and cutting steps (nb,) of a padded
        plan (:func:`padded_cut_window`); default ``plan.force`` for every member.
    """
    n, d = system.n, system.n // 2
    a0, c_out, c_in = system.per_step()
    h_in = np.asarray(step_s, dtype=float)
    h = h_in[:, :, None, None] if h_in.ndim == 2 else h_in[:, None, None, None]
    w = plan.force[None] if force is None else force
    kf = (tangential_coefficient_n_m2 * np.asarray(depth_m, dtype=float))[:, None, None, None] * w
    coupling = c_in @ kf  # (nb, ncut, d, 2): modal force per delayed displacement
    a = np.broadcast_to(a0, coupling.shape[:2] + (n, n)).copy()
    a[..., d:, :] -= coupling @ c_out
    beta = np.zeros(coupling.shape[:2] + (n, 2))
    beta[..., d:, :] = h * coupling  # h B_i
    p, g1, g2 = step_exponentials(a * h, beta)
    return PeriodMaps(p, np.concatenate([g1 - g2, g2], axis=-1), free[0], free[1], active)


def padded_cut_window(teeth: int, steps: np.ndarray, phi_start_rad: float, phi_exit_rad: float,
                      radial_ratio: float) -> tuple[CuttingPlan, np.ndarray, np.ndarray]:
    """Cut-window plans of several step counts as one plan of the largest (members solved together).

    Member ``j`` keeps its own ``steps[j]`` cutting steps (the force of
    :func:`cut_window_plan` with that count) and pads the cut with steps of zero length, which
    change nothing (``P = I``, ``G = 0``); its multipliers are those of its own plan, plus zeros.

    Returns
    -------
    plan : CuttingPlan
        The cut-window plan of ``K = max(steps)`` steps (its structure: segments and samples).
    force : numpy.ndarray, shape (nb, K, 2, 2)
    step_fraction : numpy.ndarray, shape (nb, K)
        Each step's length over the tooth period (0 on padding).

    Examples
    --------
    >>> st = float(np.arccos(-0.9))
    >>> plan, force, frac = padded_cut_window(1, np.array([16, 20]), st, np.pi, 0.3)
    >>> plan.steps, force.shape, bool(np.allclose(frac.sum(axis=1), frac.sum(axis=1)[0]))
    (21, (2, 20, 2, 2), True)
    """
    steps = np.asarray(steps, dtype=np.int64)
    big = int(steps.max())
    plan = cut_window_plan(teeth, big, phi_start_rad, phi_exit_rad, radial_ratio)
    force = np.zeros((steps.size, big, 2, 2))
    frac = np.zeros((steps.size, big))
    for k in np.unique(steps):  # a loop over the few step counts of a batch
        rows = np.flatnonzero(steps == k)
        own = plan if k == big else cut_window_plan(teeth, int(k), phi_start_rad, phi_exit_rad, radial_ratio)
        force[rows, :k] = own.force
        frac[rows, :k] = own.step_fraction
    return plan, force, frac


def apply_period(system: StateSpace, plan: CuttingPlan, maps: PeriodMaps, z: np.ndarray) -> np.ndarray:
    """The period map applied to states ``z``, shape (nb, N, p) → (nb, N, p).

    ``N = n + 2·n_samples``; real or complex ``z``. The delayed inputs of all cutting steps
    are known from ``z`` beforehand, so they are formed in one product; the loop then only
    carries ``u_{i+1} = P_i u_i + (delayed input)_i`` over the steps of one period.
    """
    n, k = system.n, plan.steps
    nb, _, cols = z.shape
    x0 = z[:, :n]
    c = system.c_out
    delay = z[:, n:].reshape(nb, -1, 2, cols)
    last = np.concatenate([delay, (c @ x0)[:, None]], axis=1)  # the sample r_0 = C u_0 closes the period
    reads = np.where(plan.cut_step + 1 < k, plan.slot[np.minimum(plan.cut_step + 1, k - 1)], last.shape[1] - 1)
    both = np.concatenate([last[:, plan.slot[plan.cut_step]], last[:, reads]], axis=2)  # (nb, ncut, 4, p)
    inputs = maps.g @ both  # (nb, ncut, n, p)
    states = np.empty((nb, k, n, cols), dtype=np.result_type(z, maps.p))
    x = x0
    for cut, start, _ in plan.segments:  # the steps of one period
        states[:, start] = x
        x = maps.p[:, cut] @ x + inputs[:, cut] if cut >= 0 else maps.free[:, -1 - cut] @ x
    kept = np.flatnonzero(plan.slot >= 0)  # slots are numbered in step order
    out = system.per_step()[1] @ states[:, kept]  # (nb, ns, 2, p)
    return np.concatenate([x, out.reshape(nb, -1, cols)], axis=1)


#: Steps of one block of :class:`BlockedPeriodMap`.
BLOCK_STEPS = 16


@dataclass(frozen=True)
class BlockedPeriodMap:
    """The period map of a cut-window plan compressed into blocks of ``L`` steps, for matrix-free solvers.

    Over a block of ``L`` cutting steps starting at node ``bL``, the state at the block's end and
    the displacement samples at its ``L`` nodes are linear in the state at its start ``x_b`` and in
    the ``L + 1`` delayed samples it reads (nodes ``bL … bL + L`` of the previous period). Those
    maps are formed once per batch of period maps (one pass over the steps); applying the period
    map is then one product per block instead of one per step — what an Arnoldi iteration repeats
    ``p`` times. Steps past the plan's last (a partial last block) are identities.

    Attributes
    ----------
    steps : int
        Cutting steps ``K`` (nodes ``0 … K``, node ``K`` the exit).
    block : int
        ``L``.
    pi : numpy.ndarray, shape (nb, nblk, n, n)
        State at a block's end from its start.
    w : numpy.ndarray, shape (nb, nblk, n, 2(L+1))
        State at a block's end from its delayed samples.
    o : numpy.ndarray, shape (nb, nblk, 2L, n)
        Samples at a block's nodes from its start state.
    r : numpy.ndarray, shape (nb, nblk, 2L, 2(L+1))
        Samples at a block's nodes from its delayed samples.
    c_out : numpy.ndarray, shape (nb, 2, n)
    free : numpy.ndarray, shape (nb, n, n), or None
        The free flight (None: a full-period plan whose every step cuts; its last step reads the
        sample ``r_0 = C u_0`` that closes the period, and it keeps the samples of nodes
        ``0 … K−1``).
    """

    steps: int
    block: int
    pi: np.ndarray
    w: np.ndarray
    o: np.ndarray
    r: np.ndarray
    c_out: np.ndarray
    free: np.ndarray | None

    def take(self, idx: np.ndarray) -> BlockedPeriodMap:
        """The maps of the members ``idx``."""
        if idx.size == self.pi.shape[0]:
            return self
        return BlockedPeriodMap(self.steps, self.block, self.pi[idx], self.w[idx], self.o[idx], self.r[idx],
                                self.c_out[idx], None if self.free is None else self.free[idx])

    def apply(self, z: np.ndarray) -> np.ndarray:
        """The period map applied to states ``z``, shape (nb, N) → (nb, N) (as :func:`apply_period`)."""
        nb, n, k, ell = z.shape[0], self.pi.shape[-1], self.steps, self.block
        nblk = self.pi.shape[1]
        x = z[:, :n]
        if self.free is None:  # the closing sample r_0 = C u_0 is read by the last step
            delay = np.concatenate([z[:, n:].reshape(nb, k, 2), (self.c_out @ x[:, :, None])[:, None, :, 0]], axis=1)
        else:
            delay = z[:, n:].reshape(nb, k + 1, 2)
        reads = np.minimum(np.arange(nblk)[:, None] * ell + np.arange(ell + 1)[None, :], k)
        dblk = delay[:, reads].reshape(nb, nblk, 2 * (ell + 1), 1)
        px = (self.w @ dblk)[..., 0]
        pr = (self.r @ dblk)[..., 0]
        xs = np.empty((nb, nblk, n), dtype=np.result_type(z, self.pi))
        for b in range(nblk):  # the blocks of one period
            xs[:, b] = x
            x = (self.pi[:, b] @ x[:, :, None])[:, :, 0] + px[:, b]
        nodes = ((self.o @ xs[..., None])[..., 0] + pr).reshape(nb, nblk * ell * 2)[:, : 2 * k]
        if self.free is None:
            return np.concatenate([x, nodes], axis=1)
        exit_r = (self.c_out @ x[:, :, None])[:, :, 0]
        return np.concatenate([(self.free @ x[:, :, None])[:, :, 0], nodes, exit_r], axis=1)


def blocked_period_map(system: StateSpace, plan: CuttingPlan, maps: PeriodMaps,
                       block: int = BLOCK_STEPS) -> BlockedPeriodMap:
    """:class:`BlockedPeriodMap` of a cut-window plan, or of a full-period plan whose every step cuts
    (one pass over its steps, all members at once).

    Examples
    --------
    It applies the same map as :func:`apply_period`:

    >>> from rcsa.analysis.lobes.modal_model import ModalModel
    >>> system = state_space(ModalModel.of([900.0, 2500.0], [0.02, 0.03], [20.0, 5.0], [0, 1]))
    >>> plan = cut_window_plan(1, 37, float(np.arccos(-0.9)), np.pi, 0.3)
    >>> h = np.array([0.02 * plan.step_fraction])
    >>> maps = period_maps(system, plan, 6e8, h, np.array([1e-3]), free_maps(system, plan, h))
    >>> z = np.random.default_rng(1).standard_normal((1, system.n + 2 * plan.n_samples))
    >>> bool(np.allclose(blocked_period_map(system, plan, maps).apply(z),
    ...                  apply_period(system, plan, maps, z[:, :, None])[:, :, 0], rtol=1e-12, atol=1e-14))
    True
    """
    window = plan.scheme == "cut_window"
    if not (window or plan.cut_step.size == plan.steps):
        raise ValueError("blocked_period_map() compresses a cut-window plan or a full-period one that always cuts")
    n, k, ell, nb = system.n, plan.steps - 1 if window else plan.steps, int(block), maps.batch
    nblk = -(-k // ell)
    c = system.c_out
    c = np.broadcast_to(c, (nb, 2, n)) if c.ndim == 2 else c
    width = n + 2 * (ell + 1)
    pi = np.empty((nb, nblk, n, n))
    w = np.empty((nb, nblk, n, width - n))
    rows = np.empty((nb, nblk, 2 * ell, width))
    for b in range(nblk):  # the blocks of one period
        x = np.zeros((nb, n, width))
        x[:, :, :n] = np.eye(n)
        for j in range(ell):  # the steps of one block
            rows[:, b, 2 * j : 2 * j + 2] = c @ x
            step = b * ell + j
            if step < k:
                x = maps.p[:, step] @ x
                x[:, :, n + 2 * j : n + 2 * j + 4] += maps.g[:, step]
        pi[:, b], w[:, b] = x[:, :, :n], x[:, :, n:]
    return BlockedPeriodMap(k, ell, pi, w, np.ascontiguousarray(rows[..., :n]), np.ascontiguousarray(rows[..., n:]),
                            np.ascontiguousarray(c), maps.free[:, 0] if window else None)


def blockable(plan: CuttingPlan) -> bool:
    """Whether :func:`blocked_period_map` takes the plan."""
    return plan.scheme == "cut_window" or plan.cut_step.size == plan.steps


def monodromy_matrix(system: StateSpace, plan: CuttingPlan, maps: PeriodMaps) -> np.ndarray:
    """The reduced monodromy matrix, shape (nb, N, N), ``N = n + 2·n_samples``.

    :func:`apply_period` of the identity, written for it: the state block ``X`` (n × N) is
    carried through the steps of one period (``X ← P_i X``, one product per step), each
    delayed-sample input adds its ``G_i`` block to the two columns of that sample (the
    sample ``r_0 = C u_0`` that closes the period adds ``G_i C`` to the ``u_0`` columns), and
    every kept sample ``r_s = C X_s`` is written as it passes.
    """
    n, k = system.n, plan.steps
    size = n + 2 * plan.n_samples
    nb = maps.batch
    c = system.c_out
    x = np.zeros((nb, n, size))
    x[:, :, :n] = np.eye(n)
    phi = np.empty((nb, size, size))
    slot = plan.slot
    for cut, start, _ in plan.segments:  # the steps of one period
        if slot[start] >= 0:
            phi[:, n + 2 * slot[start] : n + 2 * slot[start] + 2] = c @ x
        if cut < 0:
            x = maps.free[:, -1 - cut] @ x
            continue
        g = maps.g[:, cut]
        x = maps.p[:, cut] @ x
        lo = n + 2 * slot[start]
        x[:, :, lo : lo + 2] += g[:, :, :2]
        if start + 1 < k:
            nxt = n + 2 * slot[start + 1]
            x[:, :, nxt : nxt + 2] += g[:, :, 2:]
        else:
            x[:, :, :n] += g[:, :, 2:] @ c
    phi[:, :n] = x
    return phi


def trajectory(system: StateSpace, plan: CuttingPlan, maps: PeriodMaps, z: np.ndarray) -> np.ndarray:
    """Displacements at the nodes of a full-period plan, ``r_s``, ``s = 0 … k−1``, from states ``z`` (nb, N).

    Returns
    -------
    numpy.ndarray, shape (nb, k, 2)
    """
    if plan.scheme != "full_period":
        raise ValueError("trajectory() samples a full-period plan; use period_displacement()")
    n, k = system.n, plan.steps
    nb = z.shape[0]
    x0 = z[:, :n, None]
    delay = z[:, n:].reshape(nb, -1, 2, 1)
    c = system.c_out
    r = np.empty((nb, k, 2), dtype=z.dtype)
    x = x0
    for cut, start, length in plan.segments:
        if cut >= 0:
            r[:, start] = (c @ x)[..., 0]
            rb = delay[:, plan.slot[start + 1]] if start + 1 < k else c @ x0
            x = maps.p[:, cut] @ x + maps.g[:, cut] @ np.concatenate([delay[:, plan.slot[start]], rb], axis=1)
        else:
            for s in range(start, start + int(length)):
                r[:, s] = (c @ x)[..., 0]
                x = maps.step @ x
    return r


#: :func:`period_displacement` samples the free flight at least this many times per cycle of the
#: model's highest natural frequency (and the period at least this many times).
SAMPLES_PER_CYCLE = 4.0
MIN_PERIOD_SAMPLES = 64


def displacement_samples(system: StateSpace, period_s: np.ndarray) -> np.ndarray:
    """Samples per period a cut-window :func:`period_displacement` takes for each member:
    ``M = 2^⌈log₂ max(64, 4 f_top T)⌉`` with the member's own highest natural frequency and period.

    Parameters
    ----------
    system : StateSpace
        One system, or one per member.
    period_s : numpy.ndarray, shape (nb,)
        Tooth periods ``T``, s.

    Returns
    -------
    numpy.ndarray of int, shape (nb,)

    Examples
    --------
    >>> s = state_space(ModalModel.of([1000.0], [0.02], [1.0], [0]))
    >>> displacement_samples(s, np.array([0.001, 0.06])).tolist()   # 4 samples a cycle of 1 kHz
    [64, 256]
    """
    d = system.n // 2
    w = np.diagonal(system.a0[..., :d, d:], axis1=-2, axis2=-1)  # ω of each mode, (d,) or (nb, d)
    f_top = np.max(w, axis=-1) / _TWO_PI
    need = np.maximum(MIN_PERIOD_SAMPLES, SAMPLES_PER_CYCLE * f_top * np.asarray(period_s, dtype=float))
    return np.asarray(2 ** np.ceil(np.log2(need)), dtype=np.int64)


def period_displacement(system: StateSpace, plan: CuttingPlan, maps: PeriodMaps, z: np.ndarray,
                        period_s: np.ndarray) -> np.ndarray:
    """Displacements at equally spaced times ``t_m = m T / M`` over one period, from states ``z`` (nb, N).

    A full-period plan gives its nodes (``M = k``, :func:`trajectory`). A cut-window plan gives
    the cut at its nodes (linear between them, as the semi-discretization takes the delayed
    displacement) and the free flight in closed form: each mode's damped free vibration from the
    state at the exit (``q(s) = e^{−ζωs}[q₀ cos ω_d s + (q̇₀ + ζω q₀)/ω_d sin ω_d s]``), sampled
    ``M`` times a period: the most any member needs (:func:`displacement_samples`; callers group
    members by it).

    Parameters
    ----------
    system, plan, maps
        As for :func:`critical_multipliers`.
    z : numpy.ndarray, shape (nb, N)
    period_s : numpy.ndarray, shape (nb,)
        Tooth periods ``T``, s.

    Returns
    -------
    numpy.ndarray, shape (nb, M, 2)
    """
    if plan.scheme == "full_period":
        return trajectory(system, plan, maps, z)
    n, d = system.n, system.n // 2
    k = plan.steps - 1  # cutting steps; node k is the exit
    nb = z.shape[0]
    active = np.full(nb, k) if maps.active is None else np.asarray(maps.active)
    a0, c_out, _ = system.per_step()
    a0 = np.broadcast_to(a0, (nb, n, n)) if a0.ndim == 2 else a0[:, 0]
    c_out = np.broadcast_to(c_out, (nb, 2, n)) if c_out.ndim == 2 else c_out[:, 0]
    delay = z[:, n:].reshape(nb, -1, 2, 1)
    x = z[:, :n, None]
    nodes = np.empty((nb, k + 1, 2), dtype=z.dtype)
    for i in range(k):  # the cutting steps of one period
        nodes[:, i] = (c_out @ x)[..., 0]
        x = maps.p[:, i] @ x + maps.g[:, i] @ np.concatenate([delay[:, i], delay[:, i + 1]], axis=1)
    nodes[:, k] = (c_out @ x)[..., 0]
    w = np.diagonal(a0[:, :d, d:], axis1=1, axis2=2)  # ω per mode, (nb, d)
    zeta = -np.diagonal(a0[:, d:, d:], axis1=1, axis2=2) / (2.0 * w)
    period = np.asarray(period_s, dtype=float)
    samples = int(np.max(displacement_samples(system, period)))
    frac = plan.step_fraction * k  # share of the period in the cut (the same for every member)
    t_rel = np.arange(samples) / samples  # t / T
    r = np.empty((nb, samples, 2), dtype=z.dtype)
    inside = t_rel <= frac
    pos = t_rel[inside][None, :] * (active[:, None] / frac)  # in each member's own steps, (nb, m)
    lo = np.minimum(pos.astype(np.int64), active[:, None] - 1)
    frac_step = (pos - lo)[:, :, None]
    rows = np.arange(nb)[:, None]
    r[:, inside] = nodes[rows, lo] * (1.0 - frac_step) + nodes[rows, lo + 1] * frac_step
    s = (t_rel[~inside] - frac)[None, :, None] * period[:, None, None]  # time since the exit, (nb, m, 1)
    q0 = (x[:, :d, 0] / w)[:, None, :]
    v0 = x[:, d:, 0][:, None, :]
    wd = (w * np.sqrt(1.0 - zeta**2))[:, None, :]
    zw = (zeta * w)[:, None, :]
    q = np.exp(-zw * s) * (q0 * np.cos(wd * s) + (v0 + zw * q0) / wd * np.sin(wd * s))  # (nb, m, d)
    r[:, ~inside] = (w[:, None, :] * q) @ c_out[:, :, :d].transpose(0, 2, 1)
    return r


def chatter_frequency(system: StateSpace, plan: CuttingPlan, maps: PeriodMaps, mu: np.ndarray,
                      vec: np.ndarray, period_s: np.ndarray) -> np.ndarray:
    """Dominant vibration frequency (Hz) of critical eigenvectors.

    The motion of a Floquet solution with multiplier ``μ = |μ| e^{iθ}`` contains the frequencies
    ``f_j = (θ/2π + j)/T``; the one with the largest amplitude in the displacement over one
    period (:func:`period_displacement`, the growth ``μ^{t/T}`` removed, a discrete Fourier
    series) is the chatter frequency (Dombovári, Zatarain & Insperger 2010).

    Parameters
    ----------
    system, plan, maps
        As for :func:`critical_multipliers` (the batch of ``vec``).
    mu : numpy.ndarray, shape (nb,), complex
    vec : numpy.ndarray, shape (nb, N), complex
    period_s : numpy.ndarray, shape (nb,)

    Returns
    -------
    numpy.ndarray, shape (nb,)
    """
    period = np.asarray(period_s, dtype=float)
    if plan.scheme == "full_period":
        groups = [np.arange(mu.size)]
    else:  # members that need fewer samples (shorter periods, lower modes) are not sampled at the batch's most
        need = displacement_samples(system, period)
        groups = [np.flatnonzero(need == m) for m in np.unique(need)]
    out = np.empty(mu.size)
    for rows in groups:  # a loop over sample counts (powers of two)
        whole = rows.size == mu.size
        r = period_displacement(system if whole else system.take(rows), plan, maps if whole else maps.take(rows),
                                vec[rows], period[rows])  # (nr, M, 2)
        samples = r.shape[1]
        log_mu = np.log(mu[rows].astype(complex))
        floquet = np.exp(-np.outer(log_mu, np.arange(samples) / samples))  # remove the growth μ^{t/T}
        coef = np.fft.fft(r * floquet[:, :, None], axis=1)
        power = (np.abs(coef) ** 2).sum(axis=2)
        j = np.fft.fftfreq(samples, d=1.0 / samples)[np.argmax(power, axis=1)]
        out[rows] = np.abs(np.angle(mu[rows]) / (2 * np.pi) + j) / period[rows]
    return out


# --------------------------------------------------------------------------- spectra


def critical_multipliers(system: StateSpace, plan: CuttingPlan, maps: PeriodMaps, *,
                         vectors: bool | Literal["unstable"] = False) -> tuple[np.ndarray, np.ndarray | None]:
    """The multiplier of largest modulus of each map in the batch (and its eigenvector).

    Reduced sizes ``N <= DENSE_MAX_SIZE`` form the monodromy matrices
    (:func:`monodromy_matrix`: one pass over the steps of a period for all columns) and solve
    them densely. Larger ones run ``max(KRYLOV_DIM, n + 12)`` steps of Arnoldi (Gram–Schmidt
    twice, fixed seeded start), on the formed matrices or — where a period's steps are many, so
    that forming ``N`` columns costs more than the Arnoldi steps' own passes over the period
    (:func:`_matrix_free_cheaper`) — on :func:`apply_period` directly, without ever forming
    them. A batch member is accepted when its leading Ritz value has a residual below
    ``RITZ_TOL`` and no other Ritz value ``θ`` with residual ``ρ`` could hide a larger
    eigenvalue (``|θ| + ρ`` not above the leading modulus); otherwise it is solved again in a
    Krylov space twice as large, and so on up to ``KRYLOV_MAX`` (:func:`krylov_dims`), and only
    failing that densely, so the answer is always a converged eigenvalue.

    Parameters
    ----------
    system : StateSpace
    plan : CuttingPlan
    maps : PeriodMaps
    vectors : bool or "unstable"
        Also the eigenvectors: of every member, or only of those with ``|μ| >= 1`` (the
        others' rows are NaN; a dense member then costs one more eigen-decomposition only
        when unstable).

    Returns
    -------
    mu : numpy.ndarray, shape (nb,), complex
    vector : numpy.ndarray, shape (nb, N), complex, or None
    """
    size = system.n + 2 * plan.n_samples
    nb = maps.batch
    mu = np.empty(nb, dtype=complex)
    vec = np.full((nb, size), np.nan + 0j) if vectors else None
    want = vectors is not False
    todo = np.arange(nb)
    krylov = min(max(KRYLOV_DIM, system.n + KRYLOV_EXTRA), size)
    free = size > DENSE_MAX_SIZE and matrix_free_cheaper(system.n, plan)
    if free:
        blocked = blocked_period_map(system, plan, maps) if blockable(plan) else None

        def matvec(rows: np.ndarray) -> Callable[[np.ndarray], np.ndarray]:
            if blocked is not None:
                return blocked.take(rows).apply
            sub_sys, sub = system.take(rows), maps.take(rows)
            return lambda v: apply_period(sub_sys, plan, sub, v[:, :, None])[:, :, 0]

        todo = _krylov_solve(matvec, todo, size, krylov, want, mu, vec)
        if not todo.size:
            return mu, vec
    phi = monodromy_matrix(system.take(todo), plan, maps.take(todo))
    dense = np.arange(todo.size)
    if size > DENSE_MAX_SIZE and not free:
        dense = _krylov_solve(lambda rows: lambda v: (phi[rows] @ v[:, :, None])[:, :, 0], dense, size, krylov,
                              want, mu, vec, out_rows=todo)
    if dense.size:
        rows = dense
        ev = np.linalg.eigvals(phi[rows])
        mu[todo[rows]] = ev[np.arange(rows.size), np.argmax(np.abs(ev), axis=1)]
        if vec is not None:
            need = rows if vectors is True else rows[np.abs(mu[todo[rows]]) >= 1.0]
            if need.size:
                vec[todo[need]] = _inverse_iteration(phi[need], mu[todo[need]])
    return mu, vec


#: The largest Krylov space tried before a member is solved densely. A clustered spectrum (many
#: multipliers of nearly one modulus, e.g. half immersion resolved with a thousand delayed
#: states) may need far more than ``2 · KRYLOV_DIM``; 320 Arnoldi steps on N = 1 734 cost a
#: fraction of the dense eigenvalues of that matrix (about 2 s each).
KRYLOV_MAX = 320
#: Working memory of one batch of Arnoldi bases, bytes (larger spaces solve fewer members at a time).
_ARNOLDI_BYTES = 64 * 2**20


def krylov_dims(first: int, size: int) -> list[int]:
    """The Krylov spaces tried in turn: ``first``, doubled each time, up to ``KRYLOV_MAX`` or ``size``.

    >>> krylov_dims(32, 1734), krylov_dims(32, 100)
    ([32, 64, 128, 256, 320], [32, 64, 100])
    """
    dims = [min(first, size)]
    while dims[-1] < min(size, KRYLOV_MAX):
        dims.append(min(2 * dims[-1], size, KRYLOV_MAX))
    return dims


def _krylov_solve(matvec: Callable[[np.ndarray], Callable[[np.ndarray], np.ndarray]], todo: np.ndarray, size: int,
                  first: int, want: bool, mu: np.ndarray, vec: np.ndarray | None,
                  out_rows: np.ndarray | None = None) -> np.ndarray:
    """Arnoldi on the members ``todo`` in growing Krylov spaces (:func:`krylov_dims`), each batch
    within ``_ARNOLDI_BYTES``; converged members' multipliers (and vectors) written into ``mu``
    and ``vec`` (at ``out_rows[member]`` when given); returns the members left unconverged.
    ``matvec(rows)`` is the map applied to the members ``rows``."""
    for dim in krylov_dims(first, size):
        per = max(1, _ARNOLDI_BYTES // (8 * size * (dim + 1) * (2 if want else 1)))
        left = []
        for lo in range(0, todo.size, per):  # a loop over memory-bounded batches of members
            rows = todo[lo : lo + per]
            k_mu, k_vec, ok = _arnoldi(matvec(rows), rows.size, size, dim, want)
            done = rows[ok] if out_rows is None else out_rows[rows[ok]]
            mu[done] = k_mu[ok]
            if vec is not None and k_vec is not None:
                vec[done] = k_vec[ok]
            left.append(rows[~ok])
        todo = np.concatenate(left) if left else todo[:0]
        if not todo.size or dim == size:
            break
    return todo


#: Forming the monodromy matrix costs ``steps · n² · N`` per member; Arnoldi on :func:`apply_period`
#: ``p · steps · n²`` but ``p`` passes of Python steps instead of one. Matrix-free wins once ``N``
#: exceeds ``p`` by this factor (measured in benchmarks/bench_lobes.py on batches of 64–512).
MATRIX_FREE_RATIO = 2.0


def matrix_free_cheaper(n: int, plan: CuttingPlan) -> bool:
    """Whether Arnoldi without forming the matrix beats forming it: always for a plan
    :func:`blocked_period_map` takes (a product per block, not per step), else past
    ``MATRIX_FREE_RATIO``."""
    size = n + 2 * plan.n_samples
    return blockable(plan) or size > MATRIX_FREE_RATIO * max(KRYLOV_DIM, n + KRYLOV_EXTRA)


def _inverse_iteration(phi: np.ndarray, mu: np.ndarray) -> np.ndarray:
    """Eigenvectors of ``phi`` (nb, N, N) for its known eigenvalues ``mu`` (nb,): two steps of
    inverse iteration, shifted by a relative 1e-10 so that the solve is never exactly singular
    (an eigen-decomposition with vectors costs several times more)."""
    size = phi.shape[-1]
    shift = mu * (1.0 + 1e-10) + 1e-14
    a = phi.astype(complex) - shift[:, None, None] * np.eye(size)
    v = np.broadcast_to(np.random.default_rng(_KRYLOV_SEED).standard_normal(size) + 0j, (mu.size, size))
    for _ in range(2):
        v = np.linalg.solve(a, v[:, :, None])[:, :, 0]
        v = v / np.linalg.norm(v, axis=1, keepdims=True)
    return v


def _arnoldi(matvec: Callable[[np.ndarray], np.ndarray], nb: int, size: int, p: int,
             vectors: bool) -> tuple[np.ndarray, np.ndarray | None, np.ndarray]:
    """Batched Arnoldi: ``p`` steps of ``matvec`` (nb, N) → (nb, N) from a fixed seeded start;
    the leading Ritz value (and vector) of each member and whether it converged."""
    basis = np.zeros((nb, size, p + 1))
    hess = np.zeros((nb, p + 1, p))
    start = np.random.default_rng(_KRYLOV_SEED).standard_normal(size)
    basis[:, :, 0] = start / np.linalg.norm(start)
    for j in range(p):
        w = matvec(basis[:, :, j])
        v = basis[:, :, : j + 1]
        vt = v.transpose(0, 2, 1)
        coef = (vt @ w[:, :, None])[:, :, 0]
        w = w - (v @ coef[:, :, None])[:, :, 0]
        again = (vt @ w[:, :, None])[:, :, 0]  # second Gram–Schmidt pass
        w = w - (v @ again[:, :, None])[:, :, 0]
        coef += again
        beta = np.linalg.norm(w, axis=1)
        hess[:, : j + 1, j] = coef
        hess[:, j + 1, j] = beta
        live = beta > 1e-13 * (np.linalg.norm(coef, axis=1) + beta)  # else: invariant subspace
        basis[:, :, j + 1] = np.where(live[:, None], w / np.where(live, beta, 1.0)[:, None], 0.0)
    theta, y = np.linalg.eig(hess[:, :p, :p])
    resid = np.abs(hess[:, p, p - 1])[:, None] * np.abs(y[:, p - 1, :])
    mag = np.abs(theta)
    rows = np.arange(nb)
    lead = np.argmax(mag, axis=1)
    top = mag[rows, lead]
    # the leading pair converged, and no other Ritz value can hide a larger eigenvalue
    # (|θ| + residual bounds the eigenvalues near it; Bauer–Fike for a well-conditioned basis)
    ok = (resid[rows, lead] <= RITZ_TOL * np.maximum(top, 1.0)) & np.all(
        mag + resid <= top[:, None] * (1.0 + RITZ_TOL) + RITZ_TOL, axis=1)
    vec = np.einsum("bnk,bk->bn", basis[:, :, :p], y[rows, :, lead]) if vectors else None
    return theta[rows, lead], vec, ok
