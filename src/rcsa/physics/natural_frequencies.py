"""Exact natural frequencies of a chain (analytical models).

:func:`natural_frequencies_hz` is exact: the Wittrick–Williams count ``J(f)`` of the
undamped, subdivided chain (:mod:`rcsa.physics.elimination`) tells how many natural
frequencies lie below any f, so every mode in the band is bracketed (none missed, none
spurious, even when a mode barely shows at the tool point) and then located by bisection on
the count — not a peak pick.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from rcsa.physics.arrays import ComplexArray, FloatArray, IntArray
from rcsa.physics.chain import Chain, undamped
from rcsa.physics.elimination import march, subdivide, wittrick_williams_count
from rcsa.physics.stacking import chain_signature, stack_chains, take_rows

__all__ = ["natural_frequencies_batch", "natural_frequencies_hz"]

_TWO_PI = 2.0 * np.pi


def natural_frequencies_hz(chain: Chain, start_hz: float, stop_hz: float, *, rtol: float = 1e-11,
                           scan_points: int = 64) -> FloatArray:
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
                              rtol: float = 1e-11, scan_points: int = 64) -> list[FloatArray]:
    """Natural frequencies of many assemblies sharing a prefix (``prefix + tail`` for each tail).

    All assemblies are bracketed and bisected in lockstep: each step counts (Wittrick–Williams)
    at every open bracket of every assembly at once — the shared prefix in one vectorised
    pass, the tails stacked into one chain with per-row parameters (:func:`stack_chains`).
    This is how a batch of tools on one spindle + holder gets exact modes cheaply.

    Parameters
    ----------
    prefix : Chain
        The part every assembly shares (e.g. spindle and holder), from the first node.
    tails : sequence of Chain
        What follows the prefix in each assembly (e.g. each tool); ``()`` for the prefix alone.
    start_hz, stop_hz : float
        The band searched, Hz.
    rtol : float
        Relative width of the final bracket of every frequency.
    scan_points : int
        Points of the first vectorised count over the band (brackets all modes at once).

    Returns
    -------
    list of numpy.ndarray
        Natural frequencies (Hz, ascending) of each assembly, in the order of ``tails``.
    """
    w_max = _TWO_PI * stop_hz
    head = subdivide(undamped(prefix), w_max)
    grid = np.geomspace(start_hz, stop_hz, scan_points)
    k_grid, n_grid = _march_counting(head, _TWO_PI * grid)
    out: list[FloatArray] = [np.empty(0)] * len(tails)
    groups: dict[tuple[tuple[object, ...], ...], list[int]] = {}
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
            k_mid, n_mid = _march_counting(head, _TWO_PI * mid)
            above = _count_tail(stacked, rt, mid, k_mid, n_mid) > rm
            hi_a = np.where(above, mid, hi_a)
            lo_a = np.where(above, lo_a, mid)
        found = 0.5 * (lo_a + hi_a)
        for t, i in enumerate(members):
            out[i] = found[rt == t]
    return out


def _march_counting(chain: Chain, omega_rad_s: FloatArray) -> tuple[ComplexArray, IntArray]:
    """:func:`march` with the negative pivot count (never None when asked for)."""
    k, negatives = march(chain, omega_rad_s, count=True)
    assert negatives is not None
    return k, negatives


def _count_tail(stacked: Chain, rows: IntArray, f_hz: FloatArray, k0: ComplexArray, n0: IntArray) -> IntArray:
    """Wittrick–Williams count: prefix negatives ``n0`` plus the stacked tail's, per row."""
    out: IntArray = n0 + wittrick_williams_count(take_rows(stacked, rows), _TWO_PI * f_hz, k0)
    return out
