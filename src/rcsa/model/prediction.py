"""Tool-point prediction of an assembly: the receptance and what users read from it.

:func:`predict_model` solves an :class:`~rcsa.model.assembly.AssemblyModel` and returns a
:class:`Prediction`, which is both a typed object (numpy arrays) and a read-only mapping in
exactly the contract's JSON shape (``docs/contract.md`` "Prediction result").
"""

from __future__ import annotations

from collections.abc import Callable, Iterator, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any, Literal

import numpy as np

from rcsa.model.assembly import AssemblyModel
from rcsa.model.modal_fit import kept_modal_fit
from rcsa.model.peaks import find_frf_peaks
from rcsa.model.uncertainty import UncertaintyBand
from rcsa.model.wire import complex_to_wire
from rcsa.physics.algebra2x2 import inv2
from rcsa.physics.arrays import ComplexArray, FloatArray
from rcsa.physics.chain import Beam, Chain
from rcsa.physics.elimination import (
    march_tools,
    static_condense_rows,
    static_tip_receptance,
    static_tip_receptance_rows,
)
from rcsa.physics.natural_frequencies import natural_frequencies_batch
from rcsa.physics.receptance import Receptance
from rcsa.physics.stacking import chain_signature, stack_chains
from rcsa.physics.subassembly_cache import SubassemblyCache

__all__ = ["COUNT_LINES", "TOOLS_PER_PASS", "Prediction", "count_lines_hz", "predict_model",
           "predict_tools", "tool_point_receptance"]

#: Most lines of the requested grid counted (Wittrick–Williams) before the natural frequencies
#: are refined: counting costs a real elimination per line, a refinement step a fixed ~0.5 ms;
#: every k-th line up to this many keeps both small (see ``benchmarks/bench_engine.py``).
COUNT_LINES = 256


def count_lines_hz(frequency_hz: FloatArray, most: int = COUNT_LINES) -> FloatArray:
    """Lines of the requested grid at which the modes are first counted: every k-th, at most ``most``.

    Parameters
    ----------
    frequency_hz : numpy.ndarray, shape (nfreq,)
        The requested grid, Hz, increasing.
    most : int
        Largest number of lines returned (the first and last are always among them).

    Returns
    -------
    numpy.ndarray, shape (ncount,)
    """
    f = np.asarray(frequency_hz, dtype=float)
    step = max(1, -(-(f.size - 1) // max(most - 1, 1)))
    return np.unique(np.concatenate([f[::step], f[-1:]]))


@dataclass(frozen=True)
class Prediction(Mapping[str, Any]):
    """Result of a tool-point prediction.

    Attributes
    ----------
    tool_point : Receptance
        ``[[h, l], [n, p]]`` at the tool tip, shape (nfreq, 2, 2).
    natural_frequencies_hz : numpy.ndarray, shape (nmodes,)
        Exact undamped natural frequencies in the band (analytical), or modal-fit estimates
        (hybrid; ``natural_frequencies_method == "modal_fit"``, :func:`rcsa.model.modal_fit.modal_fit`:
        sorted, distinct, each with its standard uncertainty in ``extra["natural_frequencies_sd_hz"]``
        and its fit in ``extra["modal_fit"]``).
    natural_frequencies_method : str
        How they were found: ``"wittrick_williams"`` (exact, analytical) or ``"modal_fit"`` (hybrid).
    peaks : list of dict
        ``{"frequency_hz", "magnitude_m_n"}`` local maxima of ``|h|`` (hybrid: those that
        stand out of the noise of the predicted ``h``).
    static_stiffness_n_m : float or None
        1 / h at 0 Hz of the undamped model; ``None`` when it cannot be given.
    min_real_m_n, min_real_frequency_hz : float
        Most negative real part of h and where it occurs.
    notes : tuple of str
        What the numbers mean where it is not obvious (hybrid estimates, uncertainty).
    extra : dict
        Further JSON fields (e.g. the hybrid identification report).
    uncertainty : UncertaintyBand or None
        The band over the draws of an ``uncertainty`` option (:mod:`rcsa.model.uncertainty`);
        written as the result's ``uncertainty`` (merged with a ``direct_frf`` spindle's
        bounds, which ``extra`` may already hold under that name).
    """

    tool_point: Receptance
    natural_frequencies_hz: FloatArray
    natural_frequencies_method: str
    peaks: list[dict[str, float]]
    static_stiffness_n_m: float | None
    min_real_m_n: float
    min_real_frequency_hz: float
    notes: tuple[str, ...] = ()
    extra: Mapping[str, Any] = field(default_factory=dict)
    uncertainty: UncertaintyBand | None = None

    @property
    def frequency_hz(self) -> FloatArray:
        """Frequency grid, Hz, shape (nfreq,)."""
        return self.tool_point.frequency_hz

    def to_dict(self, arrays: Literal["list", "numpy"] = "list") -> dict[str, Any]:
        """The contract's prediction result.

        Parameters
        ----------
        arrays : {"list", "numpy"}
            ``"list"``: JSON-ready Python lists. ``"numpy"``: the same document with numpy
            arrays in place of the long lists (for fast serialisers such as orjson).
        """
        tp = self.tool_point

        out: dict[str, Any] = {
            "frequency_hz": tp.frequency_hz.tolist() if arrays == "list" else np.ascontiguousarray(tp.frequency_hz),
            "tool_point": {k: complex_to_wire(getattr(tp, k), arrays) for k in ("h", "l", "n", "p")},
            "natural_frequencies_hz": self.natural_frequencies_hz.tolist(),
            "natural_frequencies_method": self.natural_frequencies_method,
            "peaks": [dict(p) for p in self.peaks],
            "static_stiffness_n_m": self.static_stiffness_n_m,
            "min_real_m_n": self.min_real_m_n,
            "min_real_frequency_hz": self.min_real_frequency_hz,
            "notes": list(self.notes),
        }
        out.update(self.extra)
        if self.uncertainty is not None:
            out["uncertainty"] = {**out.get("uncertainty", {}), **self.uncertainty.to_dict(arrays)}
        return out

    def _dict(self) -> dict[str, Any]:
        cached = self.__dict__.get("_cached")
        if cached is None:
            cached = self.to_dict()
            object.__setattr__(self, "_cached", cached)
        return cached

    def __getitem__(self, key: str) -> Any:
        return self._dict()[key]

    def __iter__(self) -> Iterator[str]:
        return iter(self._dict())

    def __len__(self) -> int:
        return len(self._dict())


def tool_point_receptance(model: AssemblyModel, cache: SubassemblyCache) -> ComplexArray:
    """Tool-point ``[[h, l], [n, p]]`` of a model on the cache's grid, shape (nfreq, 2, 2).

    The spindle + holder condensation comes from (and stays in) ``cache``; a measured spindle
    at the holder tip couples only the tool, straight onto its receptance.

    Parameters
    ----------
    model : AssemblyModel
    cache : SubassemblyCache
        Grid, base receptance and the cached condensations
        (:mod:`rcsa.physics.subassembly_cache`).
    """
    prefix, rest = model.to_holder_tip(), model.tool_side()
    if any(isinstance(item, Beam) for item in prefix):
        return cache.tip_receptance(cache.condensed((prefix,)), rest)
    return cache.tip_receptance(cache.condensed(()), prefix + rest)


def predict_model(model: AssemblyModel, frequency_hz: FloatArray, *,
                  base_receptance: ComplexArray | None = None,
                  cache: SubassemblyCache | None = None,
                  natural_frequencies: bool = True,
                  notes: tuple[str, ...] = (), extra: Mapping[str, Any] | None = None) -> Prediction:
    """Solve a chain model for its tool-point receptance and derived quantities.

    Parameters
    ----------
    model : AssemblyModel
    frequency_hz : numpy.ndarray, shape (nfreq,)
    base_receptance : numpy.ndarray, shape (nfreq, 2, 2), optional
        Measured spindle-side receptance at the first node (hybrid); then natural
        frequencies are modal-fit estimates and the static stiffness is not given.
    cache : SubassemblyCache, optional
        Reuse of the spindle + holder condensation across calls on the same grid.
    natural_frequencies : bool
        Compute the exact natural frequencies (analytical models).
    notes : tuple of str
        Notes passed on to the result (e.g. how a measured base was obtained).
    extra : mapping, optional
        Further JSON fields of the result.

    Returns
    -------
    Prediction
    """
    f = np.asarray(frequency_hz, dtype=float)
    omega = 2.0 * np.pi * f
    if cache is None:
        cache = SubassemblyCache(omega, base_receptance)
    prefix, rest = model.to_holder_tip(), model.tool_side()
    g = tool_point_receptance(model, cache)
    if base_receptance is not None:
        h = g[:, 0, 0]
        fit = kept_modal_fit(f, h)  # the same h asked again: the fit kept, not redone
        peaks = [{"frequency_hz": float(f[i]), "magnitude_m_n": float(abs(h[i]))} for i in fit.peak_lines]
        notes_out = (*notes, "hybrid assembly: natural_frequencies_hz are modal-fit estimates from the predicted "
                     "tool-point h (one pole per peak that stands out of the noise, fitted with residual "
                     "terms on ±2.5 half-power half-widths), not exact eigenvalues; natural_frequencies_sd_hz "
                     "gives each one's standard uncertainty (fit covariance and spread over band choices), "
                     "modal_fit the details; peaks lists only peaks above the noise; static stiffness is not "
                     "available from a measured spindle")
        return _prediction(f, g, fit.frequency_hz, "modal_fit", None, notes_out,
                           {**(extra or {}), "natural_frequencies_sd_hz": fit.sd_hz.tolist(),
                            "modal_fit": [m.to_dict() for m in fit.modes]}, peaks)
    nat = natural_frequencies_batch(prefix, [rest], float(f[0]), float(f[-1]), grid_hz=count_lines_hz(f))[0] \
        if natural_frequencies else np.empty(0)
    static = static_tip_receptance(rest, cache.static(prefix))
    return _prediction(f, g, nat, "wittrick_williams", static, notes, extra)


#: Tools solved together in one stacked elimination by :func:`predict_tools` (bounds the
#: memory of a pass and sets the granularity of progress reports).
TOOLS_PER_PASS = 64


def predict_tools(models: Sequence[AssemblyModel], frequency_hz: FloatArray, cache: SubassemblyCache, *,
                  natural_frequencies: bool = True, done: Callable[[int], None] | None = None,
                  notes: Sequence[tuple[str, ...]] | None = None) -> list[Prediction]:
    """Predictions of many analytical models (tools) on one grid, solved together.

    Tools whose spindle + holder is the same chain and whose tool sides have one structure
    are stacked (:func:`rcsa.physics.stacking.stack_chains`) and solved in one elimination
    over tools × lines (:func:`rcsa.physics.elimination.march_tools`), up to
    :data:`TOOLS_PER_PASS` at a time, on the cached spindle + holder condensation; their
    static stiffnesses likewise, and their exact natural frequencies in one lockstep search
    per spindle + holder (:func:`rcsa.physics.natural_frequencies.natural_frequencies_batch`).
    Each result equals :func:`predict_model` of that model.

    Parameters
    ----------
    models : sequence of AssemblyModel
        Analytical models (no measured base).
    frequency_hz : numpy.ndarray, shape (nfreq,)
        The grid of ``cache``, Hz.
    cache : SubassemblyCache
        Spindle + holder condensations on the grid (shared with other calls).
    natural_frequencies : bool
        Compute the exact natural frequencies.
    done : callable, optional
        Called with the number of models finished so far, after each pass.
    notes : sequence of tuple of str, optional
        Notes passed on to each model's result (e.g. :func:`rcsa.model.assembly.assembly_notes`).

    Returns
    -------
    list of Prediction
        In the order of ``models``.
    """
    f = np.asarray(frequency_hz, dtype=float)
    omega = cache.omega_rad_s
    groups: dict[tuple[Chain, tuple[tuple[object, ...], ...]], list[int]] = {}
    for i, model in enumerate(models):
        groups.setdefault((model.to_holder_tip(), chain_signature(model.tool_side())), []).append(i)
    g_all: list[ComplexArray | None] = [None] * len(models)
    static_all: list[FloatArray | None] = [None] * len(models)
    finished = 0
    for (prefix, _), members in groups.items():
        k0 = cache.stiffness(prefix)
        s0 = cache.static(prefix)
        for c0 in range(0, len(members), TOOLS_PER_PASS):
            chunk = members[c0:c0 + TOOLS_PER_PASS]
            stacked = stack_chains([models[i].tool_side() for i in chunk])
            g = inv2(march_tools(stacked, omega, len(chunk), k0).reshape(-1, 2, 2)).reshape(len(chunk), -1, 2, 2)
            statics = static_tip_receptance_rows(static_condense_rows(stacked, len(chunk), s0))
            for j, i in enumerate(chunk):
                g_all[i], static_all[i] = g[j], statics[j]
            finished += len(chunk)
            if done is not None:
                done(finished)
    nat_all: list[FloatArray] = [np.empty(0)] * len(models)
    if natural_frequencies:
        by_prefix: dict[Chain, list[int]] = {}
        for i, model in enumerate(models):
            by_prefix.setdefault(model.to_holder_tip(), []).append(i)
        for prefix, members in by_prefix.items():
            found = natural_frequencies_batch(prefix, [models[i].tool_side() for i in members], float(f[0]),
                                              float(f[-1]), grid_hz=count_lines_hz(f))
            for i, nat in zip(members, found, strict=True):
                nat_all[i] = nat
    out = []
    for i in range(len(models)):
        g_i = g_all[i]
        assert g_i is not None
        out.append(_prediction(f, g_i, nat_all[i], "wittrick_williams", static_all[i],
                               () if notes is None else notes[i], None))
    return out


def _prediction(f: FloatArray, g: ComplexArray, nat: FloatArray, method: str, static: FloatArray | None,
                notes: Sequence[str], extra: Mapping[str, Any] | None,
                peaks: list[dict[str, float]] | None = None) -> Prediction:
    """The :class:`Prediction` of a tool-point receptance ``g`` (nfreq, 2, 2) and what was found for it.

    ``peaks`` defaults to every peak of ``h`` (:func:`rcsa.model.peaks.find_frf_peaks`).
    """
    h = g[:, 0, 0]
    notes_out = list(notes)
    static_k = None
    if method == "wittrick_williams":
        if static is None:
            notes_out.append("static_stiffness_n_m is null: the assembly is not grounded (no bearings)")
        else:
            static_k = float(1.0 / static[0, 0])
    i_min = int(np.argmin(h.real))
    return Prediction(tool_point=Receptance(f, g), natural_frequencies_hz=np.asarray(nat, dtype=float),
                      natural_frequencies_method=method, peaks=find_frf_peaks(f, h) if peaks is None else peaks,
                      static_stiffness_n_m=static_k, min_real_m_n=float(h.real[i_min]),
                      min_real_frequency_hz=float(f[i_min]), notes=tuple(notes_out), extra=dict(extra or {}))
