"""Time-domain simulation of regenerative milling (an oracle written apart from ``rcsa``).

Nothing here imports ``rcsa``: the cut, the forces and the dynamics are written from the
textbook model (Altintas, *Manufacturing Automation*, 2nd ed. 2012, §3.3 and §4.4; Schmitz &
Smith, *Machining Dynamics*, 2nd ed. 2019, §4.4 "time-domain simulation"):

* **Tool.** Real modes, each acting in x (feed) or y (normal to the feed):
  ``q̈ + 2ζω q̇ + ω² q = F_dir / m`` with the modal mass ``m`` (``1/residue``); ``x`` and ``y``
  are the sums of their modes. Each mode is advanced exactly over a time step with the force
  held constant over it (zero-order hold: the 2×2 state-transition matrix of the mode and its
  step-force column, from the closed-form free response).
* **Teeth and angles.** ``N`` teeth equally spaced; tooth ``j`` is at ``φ_j = Ω t + 2πj/N``
  measured clockwise from +y; it is in the workpiece for ``φ_st <= φ <= φ_ex`` (down milling:
  ``φ_st = acos(2a/D − 1)``, ``φ_ex = π``; up milling: ``φ_st = 0``, ``φ_ex = acos(1 − 2a/D)``).
* **Chip and surface (the tooth leaves the cut).** The revolution is cut into ``N·M`` angular
  bins (``M`` steps per tooth period), so a bin is visited again exactly one tooth period
  later by the next tooth. Each bin keeps the outward (radial) position of the surface left
  there, measured from the nominal path of the tooth that left it. The tooth tip is displaced
  outward by ``n = x sin φ + y cos φ``, and its nominal path lies ``f_z sin φ`` beyond the
  previous one, so it removes the chip ``h = f_z sin φ + n − s`` (moving the tool outward
  thickens the chip). If ``h > 0`` it cuts and leaves the surface at ``n``; else it cuts nothing
  (no force) and the surface stays where it was, ``s − f_z sin φ`` from this tooth's path. This
  is the nonlinearity that bounds chatter.
* **Forces.** ``F_t = K_t b h``, ``F_r = K_r F_t``; on the tool ``F_x = −F_t cos φ − F_r sin φ``,
  ``F_y = F_t sin φ − F_r cos φ``.

**Stable or not (in the small).** Stability lobes answer whether a small disturbance of the
steady cut dies out. A cut started abruptly (a full chip against a fresh surface) can be
thrown onto a large chatter orbit that the tooth leaving the cut sustains even below the
linear limit (the bistable zone of milling), so the depth is ramped up from zero over the
first ``ramp`` of the run (the tool follows the steady forced motion), then the tool gets a
small velocity kick. Once per tooth period the tool position is sampled (a Poincaré
section): a stable cut returns to the forced periodic motion, so successive samples stop
moving; a chattering one keeps moving (quasi-periodic or period-doubled motion, bounded by the
tooth leaving the cut). :func:`simulate` returns the rms step between successive samples
over the last fifth of the run divided by the size of the kick (its velocity over the lowest
natural frequency, rad/s): far below 1 when stable (the kick has died out), 1 or more when
not (it grew, and chatter is bounded far above it).

All cases of a call run together (arrays over cases); the loop runs over time steps only.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

__all__ = ["Cut", "Mode", "Outcome", "resolving_steps", "simulate"]


@dataclass(frozen=True)
class Mode:
    """A real mode of the tool point: natural frequency (Hz), damping ratio, modal mass (kg), 0 = x / 1 = y."""

    frequency_hz: float
    damping_ratio: float
    mass_kg: float
    direction: int


@dataclass(frozen=True)
class Cut:
    """One milling case: spindle speed (rpm), axial depth (m) and the cut's constants."""

    speed_rpm: float
    depth_m: float
    teeth: int
    kt_n_m2: float
    kr: float
    radial_immersion: float
    milling: str
    feed_per_tooth_m: float = 1e-4


@dataclass(frozen=True)
class Outcome:
    """Per case: the once-per-tooth sample steps at the end over the kick's size, and their rms (m)."""

    ratio: np.ndarray
    amplitude_m: np.ndarray

    @property
    def stable(self) -> np.ndarray:
        """Cases whose once-per-tooth samples settled (ratio below 0.1)."""
        return np.asarray(self.ratio < 0.1)

    @property
    def chatter(self) -> np.ndarray:
        """Cases whose disturbance grew (ratio above 1)."""
        return np.asarray(self.ratio > 1.0)


def _angles(immersion: float, milling: str) -> tuple[float, float]:
    if milling == "down":
        return math.acos(2.0 * immersion - 1.0), math.pi
    return 0.0, math.acos(1.0 - 2.0 * immersion)


def resolving_steps(modes: list[Mode], cuts: list[Cut], per_cycle: float = 30.0, least: int = 192) -> int:
    """Time steps per tooth period that put ``per_cycle`` steps in a cycle of 1.2 × the highest
    mode's frequency at the slowest cut (the force is held over a step: a chatter cycle of
    fewer than ~20 steps shifts the limit by several %), at least ``least``."""
    top = 1.2 * max(m.frequency_hz for m in modes)
    period = max(60.0 / (c.speed_rpm * c.teeth) for c in cuts)
    return max(least, math.ceil(per_cycle * top * period))


def _transition(w: np.ndarray, z: np.ndarray, dt: np.ndarray) -> tuple[np.ndarray, ...]:
    """Exact one-step maps of ``q̈ + 2ζω q̇ + ω² q = u`` (u constant over the step): q, q̇ from q, q̇, u."""
    wd = w * np.sqrt(1.0 - z**2)
    e = np.exp(-z * w * dt)
    c, s = np.cos(wd * dt), np.sin(wd * dt)
    a11 = e * (c + z * w / wd * s)
    a12 = e * s / wd
    a21 = -e * w**2 / wd * s
    a22 = e * (c - z * w / wd * s)
    b1 = (1.0 - a11) / w**2  # response to a unit step force (per unit mass)
    b2 = -a21 / w**2
    return a11, a12, a21, a22, b1, b2


def simulate(modes: list[Mode], cuts: list[Cut], *, periods: int = 300, steps_per_period: int = 192,
             ramp: float = 0.25, kick_m_s: float = 1e-3) -> Outcome:
    """Simulate every cut (same modes, same teeth count) and judge its stability.

    Parameters
    ----------
    modes : list of Mode
    cuts : list of Cut
        All with the same ``teeth`` (the angular bins are shared).
    periods : int
        Tooth periods simulated.
    steps_per_period : int
        Time steps per tooth period (``M``).
    ramp : float
        Fraction of the run over which the depth grows from 0 to the cut's.
    kick_m_s : float
        Velocity added to every mode when the ramp ends, m/s (a small disturbance: ~0.1 µm).

    Returns
    -------
    Outcome
    """
    teeth = cuts[0].teeth
    assert all(c.teeth == teeth for c in cuts)
    nc, m = len(cuts), steps_per_period
    speed = np.array([c.speed_rpm for c in cuts])
    dt = 60.0 / (speed * teeth) / m  # (nc,)
    w = np.array([2 * math.pi * md.frequency_hz for md in modes])
    z = np.array([md.damping_ratio for md in modes])
    mass = np.array([md.mass_kg for md in modes])
    dirn = np.array([md.direction for md in modes])
    a11, a12, a21, a22, b1, b2 = _transition(w[None, :], z[None, :], dt[:, None])  # (nc, nmodes)
    depth = np.array([c.depth_m for c in cuts])
    kt = np.array([c.kt_n_m2 for c in cuts])
    kr = np.array([c.kr for c in cuts])
    fz = np.array([c.feed_per_tooth_m for c in cuts])
    lims = np.array([_angles(c.radial_immersion, c.milling) for c in cuts])  # (nc, 2)
    bins = teeth * m
    bin_angle = 2 * math.pi * np.arange(bins) / bins
    sin_b, cos_b = np.sin(bin_angle), np.cos(bin_angle)
    inside = (bin_angle[None, :] >= lims[:, :1] - 1e-12) & (bin_angle[None, :] <= lims[:, 1:] + 1e-12)  # (nc, bins)
    surface = np.zeros((nc, bins))
    q = np.zeros((nc, modes.__len__()))
    v = np.zeros_like(q)
    samples = np.empty((periods, nc, 2))
    tooth_offset = np.arange(teeth) * m
    rows = np.arange(nc)[:, None]
    ramp_steps = int(ramp * periods) * m
    for i in range(periods * m):  # a loop over time steps (an oracle)
        if i == ramp_steps:
            v = v + kick_m_s
        grow = min(1.0, i / ramp_steps) if ramp_steps else 1.0
        x = (q * (dirn == 0)).sum(axis=1)
        y = (q * (dirn == 1)).sum(axis=1)
        if i % m == 0:
            samples[i // m, :, 0], samples[i // m, :, 1] = x, y
        b = (i + tooth_offset) % bins  # (teeth,) bins of the teeth now
        sn, cs = sin_b[b][None, :], cos_b[b][None, :]
        active = inside[:, b]  # (nc, teeth)
        normal = x[:, None] * sn + y[:, None] * cs
        chip = fz[:, None] * sn + normal - surface[rows, b]
        cutting = active & (chip > 0.0)
        surface[rows, b] = np.where(active, np.where(cutting, normal, surface[rows, b] - fz[:, None] * sn),
                                    surface[rows, b])
        ft = np.where(cutting, kt[:, None] * (grow * depth[:, None]) * chip, 0.0)
        fr = kr[:, None] * ft
        fx = (-ft * cs - fr * sn).sum(axis=1)
        fy = (ft * sn - fr * cs).sum(axis=1)
        u = np.where(dirn[None, :] == 0, fx[:, None], fy[:, None]) / mass[None, :]
        q, v = a11 * q + a12 * v + b1 * u, a21 * q + a22 * v + b2 * u
    steps = np.linalg.norm(np.diff(samples, axis=0), axis=2)  # (periods − 1, nc)
    after = periods - ramp_steps // m
    late = np.sqrt(np.mean(steps[-max(after // 5, 2):] ** 2, axis=0))
    scale = kick_m_s / float(w.min())
    return Outcome(late / scale, late)
