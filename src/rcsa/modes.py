"""Natural frequencies of a chain, and peaks of an FRF.

:func:`natural_frequencies_hz` is exact for the analytical model: the Wittrick–Williams
count ``J(f)`` of the undamped, subdivided chain (:mod:`rcsa.dsm`) tells how many natural
frequencies lie below any f, so every mode in the band is bracketed (none missed, none
spurious, even when a mode barely shows at the tool point) and then located by bisection on
the count — not a peak pick.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import fields
from typing import Any

import numpy as np
from scipy.signal import find_peaks

from .chain import Beam, Chain, Ground, Spring, undamped
from .dsm import march, subdivide, wittrick_williams_count
from .sections import Section

__all__ = [
    "chain_signature",
    "find_frf_peaks",
    "modal_fit_peaks",
    "natural_frequencies_batch",
    "natural_frequencies_hz",
    "single_mode_fit",
    "stack_chains",
    "take_rows",
]

_TWO_PI = 2.0 * np.pi


def natural_frequencies_hz(chain: Chain, start_hz: float, stop_hz: float, *, rtol: float = 1e-11,
                           scan_points: int = 64) -> np.ndarray:
    """Undamped natural frequencies of a chain in ``[start_hz, stop_hz]``.

    Parameters
    ----------
    chain : Chain
        Damping is removed before counting.
    start_hz, stop_hz : float
        Band, Hz (``0 < start_hz < stop_hz``).
    rtol : float
        Relative width of the final bracket of every frequency.
    scan_points : int
        Points of the first vectorised count over the band (brackets all modes at once).

    Returns
    -------
    numpy.ndarray, shape (nmodes,)
        Ascending, Hz. A repeated frequency appears as often as its multiplicity.
    """
    return natural_frequencies_batch(chain, [()], start_hz, stop_hz, rtol=rtol, scan_points=scan_points)[0]


def natural_frequencies_batch(prefix: Chain, tails: Sequence[Chain], start_hz: float, stop_hz: float, *,
                              rtol: float = 1e-11, scan_points: int = 64) -> list[np.ndarray]:
    """Natural frequencies of many assemblies sharing a prefix (``prefix + tail`` for each tail).

    All assemblies are bracketed and bisected in lockstep: each step counts (Wittrick–Williams)
    at every open bracket of every assembly at once — the shared prefix in one vectorised
    pass, the tails stacked into one chain with per-row parameters (:func:`stack_chains`).
    This is how a batch of tools on one spindle + holder gets exact modes cheaply.

    Returns
    -------
    list of numpy.ndarray
        Natural frequencies (Hz, ascending) of each assembly, in the order of ``tails``.
    """
    w_max = _TWO_PI * stop_hz
    head = subdivide(undamped(prefix), w_max)
    grid = np.geomspace(start_hz, stop_hz, scan_points)
    k_grid, n_grid = march(head, _TWO_PI * grid, count=True)
    out: list[np.ndarray] = [np.empty(0)] * len(tails)
    groups: dict[tuple, list[int]] = {}
    for i, tail in enumerate(tails):
        groups.setdefault(chain_signature(tail), []).append(i)
    for members in groups.values():
        stacked = subdivide(undamped(stack_chains([tails[i] for i in members])), w_max)
        n_tools = len(members)
        t_rows = np.repeat(np.arange(n_tools), scan_points)
        g_rows = np.tile(np.arange(scan_points), n_tools)
        j = _count_tail(stacked, t_rows, grid[g_rows], k_grid[g_rows], n_grid[g_rows]).reshape(n_tools, scan_points)
        row_tool, row_mode, lo, hi = [], [], [], []
        for t in range(n_tools):
            modes = np.arange(j[t, 0], j[t, -1])
            idx = np.searchsorted(j[t], modes, side="right")
            row_tool.append(np.full(modes.size, t))
            row_mode.append(modes)
            lo.append(grid[idx - 1])
            hi.append(grid[idx])
        rt, rm = np.concatenate(row_tool), np.concatenate(row_mode)
        lo_a, hi_a = np.concatenate(lo), np.concatenate(hi)
        while rt.size and np.any(hi_a - lo_a > rtol * hi_a):
            mid = 0.5 * (lo_a + hi_a)
            k_mid, n_mid = march(head, _TWO_PI * mid, count=True)
            above = _count_tail(stacked, rt, mid, k_mid, n_mid) > rm
            hi_a = np.where(above, mid, hi_a)
            lo_a = np.where(above, lo_a, mid)
        found = 0.5 * (lo_a + hi_a)
        for t, i in enumerate(members):
            out[i] = found[rt == t]
    return out


def _count_tail(stacked: Chain, rows: np.ndarray, f_hz: np.ndarray, k0: np.ndarray, n0: np.ndarray) -> np.ndarray:
    """Wittrick–Williams count: prefix negatives ``n0`` plus the stacked tail's, per row."""
    return n0 + wittrick_williams_count(take_rows(stacked, rows), _TWO_PI * f_hz, k0)


def chain_signature(chain: Chain) -> tuple:
    """Structure of a chain (item kinds, rigid joint DOFs): chains with equal signatures stack."""
    sig = []
    for item in chain:
        if isinstance(item, Spring):
            sig.append(("spring", item.stiffness_n_m is None, item.rotational_stiffness_nm_rad is None))
        else:
            sig.append((type(item).__name__,))
    return tuple(sig)


def stack_chains(chains: Sequence[Chain]) -> Chain:
    """One chain whose parameters are arrays over ``chains`` (which share one signature)."""
    if not chains or not chains[0]:
        return ()
    out: list[Beam | Spring | Ground] = []
    for items in zip(*chains, strict=True):
        first = items[0]
        if isinstance(first, Beam):
            sec = Section(*(np.array([getattr(i.section, f) for i in items]) for f in ("ei", "shear_flexibility",
                                                                                      "rho_a", "rho_i")))
            out.append(Beam(sec, np.array([i.length_m for i in items])))
        else:
            names = [f.name for f in fields(first)]
            values = {n: None if getattr(first, n) is None else np.array([getattr(i, n) for i in items])
                      for n in names}
            out.append(type(first)(**values))
    return tuple(out)


def take_rows(chain: Chain, rows: np.ndarray) -> Chain:
    """The stacked chain with its parameter arrays indexed by ``rows`` (one row per frequency).

    Scalar parameters (shared by all rows, e.g. a damping set to zero) are kept as they are.
    """

    def pick(value: Any) -> Any:
        return value if value is None or np.ndim(value) == 0 else np.asarray(value)[rows]

    out: list[Beam | Spring | Ground] = []
    for item in chain:
        if isinstance(item, Beam):
            s = item.section
            out.append(Beam(Section(pick(s.ei), pick(s.shear_flexibility), pick(s.rho_a), pick(s.rho_i)),
                            pick(item.length_m)))
        else:
            out.append(type(item)(**{f.name: pick(getattr(item, f.name)) for f in fields(item)}))
    return tuple(out)


def find_frf_peaks(frequency_hz: np.ndarray, h: np.ndarray, *, rel_prominence: float = 0.01
                   ) -> list[dict[str, float]]:
    """Local maxima of ``|h|`` on the grid, with a prominence of at least ``rel_prominence·max|h|``.

    Parameters
    ----------
    frequency_hz : numpy.ndarray, shape (nfreq,)
    h : numpy.ndarray, shape (nfreq,), complex
        Receptance, m/N.

    Returns
    -------
    list of dict
        ``{"frequency_hz", "magnitude_m_n"}`` in ascending frequency.
    """
    mag = np.abs(h)
    if mag.size < 3:
        return []
    idx, _ = find_peaks(mag, prominence=rel_prominence * float(mag.max()))
    return [{"frequency_hz": float(frequency_hz[i]), "magnitude_m_n": float(mag[i])} for i in idx]


def modal_fit_peaks(frequency_hz: np.ndarray, h: np.ndarray, *, rel_prominence: float = 0.01,
                    half_width_lines: int = 6) -> list[dict[str, float]]:
    """Single-mode fits around each peak of ``h`` (for FRFs without an exact model).

    Around every peak, ``h ≈ (c₀ + c₁ iω + c₂ (iω)²) / (ω_n² + 2ζω_n iω + (iω)²)`` is fitted by
    Levy's linearised least squares (one mode plus residual terms). Used for hybrid
    predictions, where the spindle is known only through measured FRFs.

    Returns
    -------
    list of dict
        ``{"frequency_hz", "damping_ratio"}`` per peak whose fit is a stable mode.
    """
    out = []
    for peak in find_frf_peaks(frequency_hz, h, rel_prominence=rel_prominence):
        i = int(np.searchsorted(frequency_hz, peak["frequency_hz"]))
        lo, hi = max(0, i - half_width_lines), min(frequency_hz.size, i + half_width_lines + 1)
        if hi - lo < 5:
            continue
        fit = single_mode_fit(frequency_hz[lo:hi], h[lo:hi])
        if fit is None:
            continue
        (a0, a1, *_), scale = fit
        out.append({"frequency_hz": float(np.sqrt(a0) * scale / _TWO_PI),
                    "damping_ratio": float(a1 / (2 * np.sqrt(a0)))})
    return out


def single_mode_fit(frequency_hz: np.ndarray, h: np.ndarray) -> tuple[np.ndarray, float] | None:
    """One mode with residual terms fitted by Levy's linearised least squares.

    ``h ≈ (c₀ + c₁s + c₂s²)/(s² + a₁s + a₀)`` with the scaled ``s = iω/scale``.

    Parameters
    ----------
    frequency_hz : numpy.ndarray, shape (n,)
    h : numpy.ndarray, shape (n,), complex

    Returns
    -------
    (numpy.ndarray, float) or None
        ``([a0, a1, c0, c1, c2], scale)`` with scale in rad/s (natural frequency
        ``√a0·scale``, damping ratio ``a1/(2√a0)``), or None when the fitted pole is not a
        stable oscillator.
    """
    s = 2j * np.pi * np.asarray(frequency_hz, dtype=float)
    scale = float(np.abs(s).max())
    sn = s / scale
    cols = np.stack([h, h * sn, -np.ones_like(sn), -sn, -(sn**2)], axis=1)
    rhs = -h * sn**2
    a = np.concatenate([cols.real, cols.imag])
    b = np.concatenate([rhs.real, rhs.imag])
    col_scale = np.linalg.norm(a, axis=0)
    x = np.linalg.lstsq(a / col_scale, b, rcond=None)[0] / col_scale
    if x[0] <= 0 or x[1] <= 0:
        return None
    return x, scale
