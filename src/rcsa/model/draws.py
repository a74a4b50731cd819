"""Many drawn assemblies solved at once: tool-point receptances, natural frequencies, a band.

The draws of an uncertainty request (:mod:`rcsa.model.uncertainty`) differ only in their
numbers, so they are solved like the tools of a batch: their chains are stacked into one
chain with one row of parameters per draw (:mod:`rcsa.model.draw_chains`), and that chain
is condensed over every (draw, frequency line) pair in one vectorised march
(:func:`rcsa.physics.elimination.march`, one row per pair) — in blocks of
:data:`BLOCK_LINES` pairs, to bound the memory. The natural frequencies of all draws come
from one lockstep search (:func:`rcsa.physics.natural_frequencies.natural_frequencies_batch`).
These are the exact draws; :mod:`rcsa.model.reduced_draws` solves each draw at a few lines
only (the band's default).

Readable form of :func:`tool_point_h_draws` (the code is its vectorised equivalent)::

    for d in draws:
        h[d] = predict(perturbed_spec(spec, knobs[d])).tool_point.h

Natural frequencies are matched **by order**: mode ``g`` of a draw is its ``g``-th natural
frequency counted from 0 Hz (the Wittrick–Williams count below the search band plus the
position in it), the same order the nominal prediction lists its modes in. Each draw is
searched in the band widened by :data:`BAND_MARGIN` on both sides, so a mode near an edge
is still followed when it leaves the requested band in some draws; ``in_band_fraction``
says in how many of them it stayed inside, and a mode that enters the band only in some
draws is reported apart (``modes_entering_band``). A mode that leaves even the widened
band in a draw is left out of that mode's mean and sd.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from rcsa.model.assembly import AssemblyModel, build_model
from rcsa.model.contract import AssemblySpec
from rcsa.model.draw_chains import DrawGroup, DrawnChains
from rcsa.model.tolerances import NuisanceDraws, perturbed_spec
from rcsa.physics.arrays import ComplexArray, FloatArray, IntArray
from rcsa.physics.chain import undamped
from rcsa.physics.elimination import march, subdivide, wittrick_williams_count
from rcsa.physics.natural_frequencies import natural_frequencies_batch
from rcsa.physics.stacking import take_rows

__all__ = [
    "BAND_MARGIN",
    "BLOCK_LINES",
    "NATURAL_FREQUENCY_RTOL",
    "ModeStatistics",
    "counts_below",
    "drawn_models",
    "magnitude_percentiles",
    "mode_statistics",
    "order_statistics",
    "peak_statistics",
    "tool_point_h_draws",
    "tool_point_h_pairs",
]

#: (draw, line) pairs condensed per march: enough to amortise the per-item overhead, few enough
#: that the work arrays stay in cache (4 000–8 000 measured fastest; 400 000 at once is 1.7× slower).
BLOCK_LINES = 8192
#: The band searched for each draw's modes: the requested one widened by this factor.
BAND_MARGIN = 1.15
#: Relative width of the final bracket of every drawn natural frequency (far below any
#: spread a tolerance gives).
NATURAL_FREQUENCY_RTOL = 1e-9

_TWO_PI = 2.0 * np.pi


def drawn_models(spec: AssemblySpec, knobs: NuisanceDraws, base_plane: str | None = None) -> list[AssemblyModel]:
    """The chain model of every draw (:func:`rcsa.model.tolerances.perturbed_spec`, configuration 0).

    Parameters
    ----------
    spec : AssemblySpec
        The nominal assembly.
    knobs : NuisanceDraws
    base_plane : {None, "spindle_nose", "holder_tip"}
        Plane of a measured spindle (:func:`rcsa.model.assembly.build_model`).

    Returns
    -------
    list of AssemblyModel
        One per draw, in draw order.
    """
    return [build_model(perturbed_spec(spec, knobs.fields(d)), base_plane) for d in range(knobs.n_draws)]


def tool_point_h_draws(drawn: DrawnChains, frequency_hz: FloatArray,
                       base_receptance: ComplexArray | None = None) -> ComplexArray:
    """Tool-point ``h`` of every draw on every line, all draws in one stacked march.

    Parameters
    ----------
    drawn : DrawnChains
        The draws' chains (:func:`rcsa.model.draw_chains.drawn_chains`).
    frequency_hz : numpy.ndarray, shape (nfreq,)
        Grid, Hz.
    base_receptance : numpy.ndarray, shape (ndraws, nfreq, 2, 2), optional
        Each draw's measured spindle-side receptance (hybrid), coupled without inverting it.

    Returns
    -------
    numpy.ndarray, shape (ndraws, nfreq), complex
        m/N.
    """
    omega = _TWO_PI * np.asarray(frequency_hz, dtype=float)
    nfreq = omega.size
    out = np.empty((drawn.n_draws, nfreq), dtype=complex)
    per_block = max(1, BLOCK_LINES // nfreq)
    for group in drawn.groups:  # a loop over structures (one, unless a stickout moved a split)
        members = group.draws
        for b0 in range(0, members.size, per_block):  # blocks of draws, not draws
            b1 = min(b0 + per_block, members.size)
            rows = np.repeat(np.arange(b0, b1), nfreq)
            start = None if base_receptance is None else base_receptance[members[b0:b1]].reshape(-1, 2, 2)
            k = march(take_rows(group.chain, rows), np.tile(omega, b1 - b0), start_compliance=start)[0]
            h = k[:, 1, 1] / (k[:, 0, 0] * k[:, 1, 1] - k[:, 0, 1] * k[:, 1, 0])
            out[members[b0:b1]] = h.reshape(b1 - b0, nfreq)
    return out


def tool_point_h_pairs(drawn: DrawnChains, draw: IntArray, frequency_hz: FloatArray,
                       base_receptance: ComplexArray | None = None) -> ComplexArray:
    """Tool-point ``h`` of draw ``draw[j]`` at ``frequency_hz[j]``: any (draw, line) pairs at once.

    Parameters
    ----------
    drawn : DrawnChains
        The draws' chains (:func:`rcsa.model.draw_chains.drawn_chains`).
    draw : numpy.ndarray of int, shape (npairs,)
        Which draw each pair solves.
    frequency_hz : numpy.ndarray, shape (npairs,)
        The frequency of each pair, Hz.
    base_receptance : numpy.ndarray, shape (npairs, 2, 2), optional
        Each pair's measured spindle-side receptance (hybrid).

    Returns
    -------
    numpy.ndarray, shape (npairs,), complex
        m/N.
    """
    omega = _TWO_PI * np.asarray(frequency_hz, dtype=float)
    d = np.asarray(draw)
    out = np.empty(d.size, dtype=complex)
    for group in drawn.groups:  # a loop over structures (one, unless a stickout moved a split)
        local = np.full(drawn.n_draws, -1)
        local[group.draws] = np.arange(group.draws.size)
        sel = np.flatnonzero(local[d] >= 0)
        for b0 in range(0, sel.size, BLOCK_LINES):  # blocks of pairs
            part = sel[b0:b0 + BLOCK_LINES]
            start = None if base_receptance is None else base_receptance[part]
            k = march(take_rows(group.chain, local[d[part]]), omega[part], start_compliance=start)[0]
            out[part] = k[:, 1, 1] / (k[:, 0, 0] * k[:, 1, 1] - k[:, 0, 1] * k[:, 1, 0])
    return out


def magnitude_percentiles(h: ComplexArray, percentiles: Sequence[float]) -> FloatArray:
    """Percentiles of ``|h|`` over the draws at every line.

    numpy's default (linear interpolation between order statistics: the q-th percentile of
    ``n`` values is at position ``q/100 · (n − 1)`` of the sorted values), from one sort of
    every line (several times faster than :func:`numpy.percentile` on 200 × 2 000 values).

    Parameters
    ----------
    h : numpy.ndarray, shape (ndraws, nfreq), complex
    percentiles : sequence of float
        In [0, 100].

    Returns
    -------
    numpy.ndarray, shape (len(percentiles), nfreq)

    Examples
    --------
    >>> h = np.array([[1.0], [4.0], [2.0], [3.0]]) + 0j
    >>> magnitude_percentiles(h, [0.0, 50.0, 95.0]).ravel().tolist()
    [1.0, 2.5, 3.85]
    """
    x = np.sort(np.abs(h), axis=0)
    pos = np.asarray(percentiles, dtype=float) / 100.0 * (x.shape[0] - 1)
    lo = np.floor(pos).astype(int)
    hi = np.minimum(lo + 1, x.shape[0] - 1)
    frac = (pos - lo)[:, None]
    out: FloatArray = x[lo] + frac * (x[hi] - x[lo])
    return out


@dataclass(frozen=True)
class ModeStatistics:
    """Each nominal mode over the draws, and the modes that enter the band in some draws.

    Attributes
    ----------
    mean_hz, sd_hz : numpy.ndarray, shape (nmodes,)
        Mean and sample sd (``ddof = 1``; 0 with fewer than two values) of each nominal
        mode over the draws that have it in the widened band, Hz.
    in_band_fraction : numpy.ndarray, shape (nmodes,)
        Fraction of all draws in which the mode lies in the requested band.
    entering : tuple of dict
        ``{"mean_hz", "sd_hz", "in_band_fraction"}`` of every mode outside the band
        nominally but inside it in at least one draw, ascending.
    """

    mean_hz: FloatArray
    sd_hz: FloatArray
    in_band_fraction: FloatArray
    entering: tuple[dict[str, float], ...] = ()


def order_statistics(values_hz: FloatArray, nominal: IntArray, start_hz: float, stop_hz: float) -> ModeStatistics:
    """:class:`ModeStatistics` of a table of every draw's modes by order.

    Parameters
    ----------
    values_hz : numpy.ndarray, shape (ndraws, nmodes_all)
        Column ``g``: each draw's g-th mode (of those tabulated), Hz; NaN where a draw lacks it.
    nominal : numpy.ndarray of int
        The columns of the nominal in-band modes.
    start_hz, stop_hz : float
        The requested band, Hz.

    Returns
    -------
    ModeStatistics
    """
    finite = np.isfinite(values_hz)
    inside = finite & (values_hz >= start_hz) & (values_hz <= stop_hz)
    count = finite.sum(axis=0)
    # about a value of the column (its first finite one): identical draws give sd 0 and their value exactly
    ref = np.where(count > 0, values_hz[np.argmax(finite, axis=0), np.arange(values_hz.shape[1])], 0.0)
    dev = np.where(finite, values_hz - ref, 0.0)
    mean_dev = dev.sum(axis=0) / np.maximum(count, 1)
    centred = np.where(finite, dev - mean_dev, 0.0)
    sd = np.where(count > 1, np.sqrt((centred * centred).sum(axis=0) / np.maximum(count - 1, 1)), 0.0)
    mean = np.where(count > 0, ref + mean_dev, np.nan)
    fraction = inside.mean(axis=0) if values_hz.shape[0] else np.zeros(values_hz.shape[1])
    others = np.setdiff1d(np.flatnonzero(inside.any(axis=0)), nominal)
    entering = tuple({"mean_hz": float(mean[g]), "sd_hz": float(sd[g]), "in_band_fraction": float(fraction[g])}
                     for g in others)  # a loop over the few entering modes
    return ModeStatistics(mean[nominal], sd[nominal], fraction[nominal], entering)


def counts_below(drawn: DrawnChains, f_hz: float) -> IntArray:
    """Wittrick–Williams count of natural frequencies below ``f_hz`` of every draw.

    Parameters
    ----------
    drawn : DrawnChains
    f_hz : float
        Hz.

    Returns
    -------
    numpy.ndarray of int, shape (ndraws,)
    """
    w = _TWO_PI * f_hz
    out = np.empty(drawn.n_draws, dtype=int)
    for group in drawn.groups:
        n = group.draws.size
        stacked = subdivide(undamped(group.chain), w)
        out[group.draws] = wittrick_williams_count(take_rows(stacked, np.arange(n)), np.full(n, w))
    return out


def mode_statistics(nominal: AssemblyModel, drawn: DrawnChains, start_hz: float, stop_hz: float) -> ModeStatistics:
    """Natural frequencies of every draw, matched by order to the nominal model's in-band modes.

    The nominal model and every draw are searched together (one lockstep search) in
    ``[start_hz / BAND_MARGIN, stop_hz · BAND_MARGIN]``; see the module docstring for the
    matching.

    Parameters
    ----------
    nominal : AssemblyModel
        The model predicted (analytical spindle).
    drawn : DrawnChains
        The draws' chains.
    start_hz, stop_hz : float
        The requested band, Hz.

    Returns
    -------
    ModeStatistics
    """
    lo, hi = start_hz / BAND_MARGIN, stop_hz * BAND_MARGIN
    chains = [nominal.chain(), *(drawn.chain(d) for d in range(drawn.n_draws))]
    found = natural_frequencies_batch((), chains, lo, hi, rtol=NATURAL_FREQUENCY_RTOL)
    nominal_only = DrawnChains((DrawGroup(np.array([0]), nominal.chain()),), 1)
    below = np.concatenate([counts_below(nominal_only, lo), counts_below(drawn, lo)])
    sizes = np.array([f.size for f in found])
    flat = np.concatenate(found)
    row = np.repeat(np.arange(len(chains)), sizes)
    order = below[row] + (np.arange(flat.size) - np.repeat(np.cumsum(sizes) - sizes, sizes))  # mode number from 0 Hz
    first = int(order.min(initial=0))
    table = np.full((len(chains), int(order.max(initial=-1)) + 1 - first), np.nan)
    table[row, order - first] = flat
    nominal_modes = table[0]
    columns = np.flatnonzero(np.isfinite(nominal_modes) & (nominal_modes >= start_hz) & (nominal_modes <= stop_hz))
    return order_statistics(table[1:], columns, start_hz, stop_hz)


def peak_statistics(frequency_hz: FloatArray, h: ComplexArray, h_nominal: ComplexArray,
                    modes_hz: FloatArray, bands_hz: Sequence[tuple[float, float]]) -> ModeStatistics:
    """Natural frequencies of draws without exact eigenvalues (hybrid): peaks of ``|h|``.

    For each nominal modal-fit frequency, every draw's largest ``|h|`` inside that mode's
    fitting band, refined by a parabola through ``ln|h|`` at the three lines around it; the
    draw's natural frequency is the nominal one moved by the draw's peak minus the nominal
    ``h``'s peak found the same way.

    Parameters
    ----------
    frequency_hz : numpy.ndarray, shape (nfreq,)
    h : numpy.ndarray, shape (ndraws, nfreq), complex
        The draws' tool-point ``h``.
    h_nominal : numpy.ndarray, shape (nfreq,), complex
    modes_hz : numpy.ndarray, shape (nmodes,)
        The nominal modal-fit natural frequencies, Hz.
    bands_hz : sequence of (float, float)
        Each mode's fitting band, Hz.

    Returns
    -------
    ModeStatistics
        ``in_band_fraction`` 1 and no entering modes (peaks are looked for in each band only).
    """
    f = np.asarray(frequency_hz, dtype=float)
    log_h = np.log(np.maximum(np.abs(np.vstack([h_nominal[None, :], h])), 1e-300))
    values = np.full((log_h.shape[0], len(bands_hz)), np.nan)
    for m, (b0, b1) in enumerate(bands_hz):  # a loop over the few modes
        lo = int(np.searchsorted(f, b0))
        hi = int(np.searchsorted(f, b1, side="right"))
        if hi - lo < 3:
            continue
        i = lo + np.argmax(log_h[:, lo:hi], axis=1)
        i = np.clip(i, 1, f.size - 2)
        y0, y1, y2 = (np.take_along_axis(log_h, (i + k)[:, None], axis=1)[:, 0] for k in (-1, 0, 1))
        curv = y0 - 2.0 * y1 + y2
        with np.errstate(invalid="ignore", divide="ignore"):
            shift = np.where(curv < 0, 0.5 * (y0 - y2) / curv, 0.0)
        step = np.where(shift >= 0, f[np.minimum(i + 1, f.size - 1)] - f[i], f[i] - f[i - 1])
        peak = f[i] + np.clip(shift, -0.5, 0.5) * step
        values[:, m] = modes_hz[m] + (peak - peak[0])
    return order_statistics(values[1:], np.arange(len(bands_hz)), -np.inf, np.inf)
