"""The spindle side of predictions: an analytical spindle chain, or a measured base receptance.

Every tool of a batch sits on one spindle. :class:`SpindleSide` holds what they share — the
condensed spindle (analytical) or the measured spindle-side receptance at its plane
(hybrid), and the cache of spindle + holder condensations — and predicts one assembly
after the other on it. How a measured base is obtained from a store is the measured layer's
business (:func:`rcsa.measured.hybrid.measured_base`); here it is just a
:class:`MeasuredBase`.

With an ``uncertainty`` option (:mod:`rcsa.model.uncertainty`) a prediction also draws the
assembly — and a measured base, under its own uncertainty — and solves every draw
(:meth:`SpindleSide.tool_point_draws`): by the reduced model of :mod:`rcsa.model.reduced_draws`
(each draw exactly at a few lines, fitted rationally, checked) or, with ``"solver": "exact"``,
exactly on every line (:mod:`rcsa.model.draws`). A measured base drawn with noise on every
line has no rational structure to fit; its draws are solved exactly, line by line (a note says
so).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field, replace
from typing import Any, Protocol

import numpy as np

from rcsa.errors import InputError
from rcsa.model.assembly import AssemblyModel, assembly_notes, build_model, spindle_chain
from rcsa.model.contract import AssemblySpec, CommonSpec, MeasuredSpindleSpec, SpindleSpec
from rcsa.model.draw_chains import DrawGroup, DrawnChains, drawn_chains
from rcsa.model.draws import (
    BAND_MARGIN,
    ModeStatistics,
    counts_below,
    magnitude_percentiles,
    mode_statistics,
    peak_statistics,
    tool_point_h_draws,
)
from rcsa.model.prediction import Prediction, predict_model, tool_point_receptance
from rcsa.model.reduced_draws import (
    CALIBRATION_DRAWS,
    ESTIMATE_TOLERANCE,
    HELD_OUT_DRAWS,
    NOMINAL_FIT_TOLERANCE,
    ReducedDraws,
    frequency_ratio_bounds,
    nominal_structure,
    reduced_draws,
    reduced_mode_statistics,
)
from rcsa.model.tolerances import MEASURED_SPINDLE_TOLERANCES, NuisanceDraws, draw_nuisance
from rcsa.model.uncertainty import PERCENTILES, UncertaintyBand, UncertaintyOptions
from rcsa.model.wire import complex_to_wire
from rcsa.physics.arrays import ComplexArray, FloatArray, IntArray
from rcsa.physics.natural_frequencies import natural_frequencies_batch
from rcsa.physics.subassembly_cache import SubassemblyCache

__all__ = ["BaseResolver", "BaseUncertainty", "MeasuredBase", "SpindleSide", "ToolPointDraws", "measured_base_draws",
           "spread_of_bounds"]


class BaseUncertainty(Protocol):
    """How uncertain a measured spindle-side receptance is: draws of it, and what was assumed.

    Implemented by the measured layer per kind of measurement (:mod:`rcsa.measured.hybrid`):
    measurement noise from the stored coherence (or a default), propagated through the
    artifact identification where there is one.
    """

    def draw(self, rng: np.random.Generator, n: int, default_noise_rel: float) -> ComplexArray:
        """Equally likely receptances under the measurement's own noise.

        Parameters
        ----------
        rng : numpy.random.Generator
        n : int
            Number of draws.
        default_noise_rel : float
            Relative sd of the magnitude and of the phase (per real and imaginary part) used for FRFs
            stored without coherence.

        Returns
        -------
        numpy.ndarray, shape (n, nfreq, 2, 2), complex
            On the base's grid, ``[[h, l], [n, p]]`` in m/N, m/(N·m), rad/N, rad/(N·m).
        """
        ...

    def summary(self, default_noise_rel: float) -> dict[str, Any]:
        """What the draws assume (noise source and level, conditioning), JSON-ready.

        Parameters
        ----------
        default_noise_rel : float
            As for :meth:`draw`.

        Returns
        -------
        dict
        """
        ...


@dataclass(frozen=True)
class MeasuredBase:
    """Spindle-side receptance of a measured spindle on the requested grid.

    Attributes
    ----------
    plane : {"spindle_nose", "holder_tip"}
    receptance : numpy.ndarray, shape (nfreq, 2, 2)
    alternatives : tuple of numpy.ndarray
        Receptances bounding an estimate's uncertainty (``direct_frf``), else empty.
    notes : tuple of str
    report : dict
        What was done (kind, method, conditioning, interpolation), JSON-ready.
    artifact_diameter_m : float or None
        Shank diameter a holder-tip measurement was taken with (to check the tool's shank).
    uncertainty : BaseUncertainty or None
        Draws of the receptance under the measurement's own noise (used by analyses that
        propagate it, e.g. the diagnosis's expected scatter); None when unknown.
    effective_length_m : float or None
        ``direct_frf``: the equivalent-cantilever length of the rotation estimate, m.
    """

    plane: str
    receptance: ComplexArray
    alternatives: tuple[ComplexArray, ...] = ()
    notes: tuple[str, ...] = ()
    report: dict[str, Any] = field(default_factory=dict)
    artifact_diameter_m: float | None = None
    uncertainty: BaseUncertainty | None = None
    effective_length_m: float | None = None


@dataclass(frozen=True)
class ToolPointDraws:
    """The drawn assemblies of an uncertainty option and their tool-point ``h``.

    Attributes
    ----------
    h : numpy.ndarray, shape (ndraws, nfreq), complex
        Tool-point ``h`` of every draw, m/N.
    drawn : DrawnChains
        Every draw's chain, stacked.
    knobs : NuisanceDraws
        The drawn knobs.
    measured_spindle : dict or None
        What a measured spindle's draws assumed (:func:`measured_base_draws`).
    reduced : ReducedDraws or None
        The reduced model of the draws (None: solved exactly on every line).
    ratio_bounds : tuple of numpy.ndarray or None
        Each draw's min–max bounds on its natural frequencies relative to the nominal
        (:func:`rcsa.model.reduced_draws.frequency_ratio_bounds`), with ``reduced``.
    notes : tuple of str
        How the draws were solved where it is not the option's ``solver``.
    """

    h: ComplexArray
    drawn: DrawnChains
    knobs: NuisanceDraws
    measured_spindle: dict[str, Any] | None = None
    reduced: ReducedDraws | None = None
    ratio_bounds: tuple[FloatArray, FloatArray] | None = None
    notes: tuple[str, ...] = ()


#: Turns a measured spindle of a request into its base receptance on a grid (Hz).
BaseResolver = Callable[[MeasuredSpindleSpec, FloatArray], MeasuredBase]


class SpindleSide:
    """The spindle side shared by all combinations: plane, base receptance and cache.

    Parameters
    ----------
    common : CommonSpec
        Grid, materials, beam theory and spindle of the request.
    resolve_base : callable, optional
        Needed when ``common.spindle`` is measured (:data:`BaseResolver`).
    """

    def __init__(self, common: CommonSpec, resolve_base: BaseResolver | None = None) -> None:
        self.base: MeasuredBase | None = None
        omega = 2 * np.pi * common.frequency_hz
        if isinstance(common.spindle, MeasuredSpindleSpec):
            if resolve_base is None:
                raise InputError("spindle.measurement_id", "a measured spindle needs a measurement store")
            self.base = resolve_base(common.spindle, common.frequency_hz)
        self.cache = SubassemblyCache(omega, None if self.base is None else self.base.receptance)
        self.spindle = (spindle_chain(common.spindle, common.materials, common.shear_coefficient, common.beam_theory)
                        if isinstance(common.spindle, SpindleSpec) else ())
        self.alt_caches = [] if self.base is None else [SubassemblyCache(omega, r) for r in self.base.alternatives]

    def predict(self, spec: AssemblySpec, natural_frequencies: bool = True,
                uncertainty: UncertaintyOptions | None = None) -> Prediction:
        """Tool-point prediction of one assembly on this spindle side.

        Parameters
        ----------
        spec : AssemblySpec
            An assembly on this spindle side's grid and spindle.
        natural_frequencies : bool
            Compute the exact natural frequencies (analytical spindles).
        uncertainty : UncertaintyOptions, optional
            Also draw the assembly and give the band (:meth:`uncertainty_band`).
        """
        return self.predict_with_model(spec, natural_frequencies, uncertainty)[1]

    def predict_with_model(self, spec: AssemblySpec, natural_frequencies: bool = True,
                           uncertainty: UncertaintyOptions | None = None) -> tuple[AssemblyModel, Prediction]:
        """The solved chain model and its prediction.

        Parameters
        ----------
        spec : AssemblySpec
            An assembly on this spindle side's grid and spindle.
        natural_frequencies : bool
            Compute the exact natural frequencies (analytical spindles).
        uncertainty : UncertaintyOptions, optional
            Also draw the assembly and give the band (:meth:`uncertainty_band`).
        """
        model, prediction = self._predict(spec, natural_frequencies)
        if uncertainty is not None:
            band = self.uncertainty_band(spec, model, prediction, uncertainty, natural_frequencies)
            prediction = replace(prediction, uncertainty=band)
        return model, prediction

    def _predict(self, spec: AssemblySpec, natural_frequencies: bool) -> tuple[AssemblyModel, Prediction]:
        base = self.base
        if base is None:
            model = build_model(spec, spindle=self.spindle)
            return model, predict_model(model, spec.frequency_hz, cache=self.cache,
                                        natural_frequencies=natural_frequencies, notes=assembly_notes(spec))
        if base.plane == "holder_tip" and base.artifact_diameter_m is not None and \
                abs(spec.tool.shank_diameter_m - base.artifact_diameter_m) > 1e-6 * base.artifact_diameter_m:
            raise InputError("tool.shank_diameter_m",
                             f"must match the shank the holder-tip measurement was taken with "
                             f"({base.artifact_diameter_m:g} m); got {spec.tool.shank_diameter_m:g} m")
        model = build_model(spec, base.plane)
        extra: dict[str, Any] = {"spindle_measurement": base.report}
        if self.alt_caches:
            h = [tool_point_receptance(model, c)[:, 0, 0] for c in self.alt_caches]
            extra["uncertainty"] = spread_of_bounds(spec.frequency_hz, h)
        return model, predict_model(model, spec.frequency_hz, base_receptance=base.receptance, cache=self.cache,
                                    natural_frequencies=natural_frequencies, notes=(*base.notes, *assembly_notes(spec)),
                                    extra=extra)

    def tool_point_draws(self, spec: AssemblySpec, options: UncertaintyOptions,
                         nominal: Prediction | None = None) -> ToolPointDraws:
        """Draw the assembly (and a measured base) ``options.draws`` times and solve every draw.

        The generator ``default_rng(options.seed)`` gives the nuisance knobs of all draws
        first (:func:`rcsa.model.tolerances.draw_nuisance`), then a measured spindle's noise
        and rotation lengths (:func:`measured_base_draws`). With ``options.solver`` "reduced"
        the draws are solved by :func:`rcsa.model.reduced_draws.reduced_draws` (the nominal
        prediction's ``h`` gives the structure), else exactly on every line.

        Parameters
        ----------
        spec : AssemblySpec
            An assembly on this spindle side (as for :meth:`predict`).
        options : UncertaintyOptions
        nominal : Prediction, optional
            The nominal prediction of ``spec`` on this side, if already made.

        Returns
        -------
        ToolPointDraws
        """
        rng = np.random.default_rng(options.seed)
        knobs = draw_nuisance(rng, options.tolerances, options.draws)
        base = self.base
        drawn = drawn_chains(spec, knobs, None if base is None else base.plane)
        f = spec.frequency_hz
        receptances, summary = None, None
        if base is not None:
            receptances, summary = measured_base_draws(base.receptance, base.uncertainty, base.effective_length_m,
                                                       options.tolerances, rng, options.draws)
        if options.solver == "exact":
            return ToolPointDraws(tool_point_h_draws(drawn, f, receptances), drawn, knobs, summary)
        if receptances is not None and base is not None and not _smooth_draws(receptances, base.receptance):
            note = ("the measured spindle is drawn with noise on every line, which no rational model of the "
                    "draws follows: every draw was solved exactly on every line")
            return ToolPointDraws(tool_point_h_draws(drawn, f, receptances), drawn, knobs, summary, notes=(note,))
        if nominal is None:
            nominal = self._predict(spec, natural_frequencies=False)[1]
        if _all_nominal(knobs) and (receptances is None or base is None or
                                    bool(np.all(receptances == base.receptance[None]))):
            note = "every draw is the nominal assembly (zero tolerances): the band is the nominal receptance"
            return ToolPointDraws(np.array(np.broadcast_to(nominal.tool_point.h, (options.draws, f.size))), drawn,
                                  knobs, summary, notes=(note,))
        low, high = frequency_ratio_bounds(knobs, spec.tool.stickout_m)
        modes, order = self._structure_modes(spec, nominal, float(np.min(low)), float(np.max(high)))
        structure = nominal_structure(f, nominal.tool_point.h, modes, order)
        if structure.fit_error > NOMINAL_FIT_TOLERANCE:
            note = (f"the nominal receptance has no rational fit within {NOMINAL_FIT_TOLERANCE:g} of its peak "
                    f"({structure.fit_error:.2g}): every draw was solved exactly on every line")
            return ToolPointDraws(tool_point_h_draws(drawn, f, receptances), drawn, knobs, summary, notes=(note,))
        reduced = reduced_draws(drawn, f, structure, low, high, receptances)
        return ToolPointDraws(reduced.h, drawn, knobs, summary, reduced, (low, high))

    def _structure_modes(self, spec: AssemblySpec, nominal: Prediction, low: float, high: float
                         ) -> tuple[FloatArray, IntArray]:
        """The nominal modes the draws' modes may come from, and their numbers from 0 Hz.

        Analytical spindle: the exact natural frequencies in the band widened by
        :data:`~rcsa.model.draws.BAND_MARGIN` and by the draws' min–max bounds. Measured
        spindle: every peak of ``|h|`` (the modal fit keeps only those above the noise) and
        two frequencies above the band, for what lies beyond it.
        """
        f = spec.frequency_hz
        if self.base is not None:
            y = np.abs(nominal.tool_point.h)
            peaks = f[np.flatnonzero((y[1:-1] > y[:-2]) & (y[1:-1] >= y[2:])) + 1]
            start = np.unique(np.concatenate([peaks, nominal.natural_frequencies_hz, float(f[-1]) * ABOVE_BAND]))
            start = start[np.concatenate([[True], np.diff(start) > 0.01 * start[1:]])]
            return start, np.arange(start.size)
        lo, hi = float(f[0]) / BAND_MARGIN / high, float(f[-1]) * BAND_MARGIN / low
        chain = build_model(spec, spindle=self.spindle).chain()
        inside = np.asarray(nominal.natural_frequencies_hz, dtype=float)
        nominal_only = DrawnChains((DrawGroup(np.zeros(1, dtype=int), chain),), 1)
        below = counts_below(nominal_only, lo)[0]
        if inside.size:  # the prediction's own (exact, in the band): search only the band's two extensions
            parts = [inside]
            if float(f[0]) > lo and counts_below(nominal_only, float(f[0]))[0] > below:
                parts.append(natural_frequencies_batch((), [chain], lo, float(f[0]), rtol=STRUCTURE_RTOL,
                                                       scan_points=STRUCTURE_SCAN_POINTS)[0])
            if hi > float(f[-1]):
                parts.append(natural_frequencies_batch((), [chain], float(f[-1]), hi, rtol=STRUCTURE_RTOL,
                                                       scan_points=STRUCTURE_SCAN_POINTS)[0])
            modes = np.sort(np.concatenate(parts))
        else:
            modes = natural_frequencies_batch((), [chain], lo, hi, rtol=STRUCTURE_RTOL,
                                              scan_points=STRUCTURE_SCAN_POINTS)[0]
        return modes, below + np.arange(modes.size)

    def uncertainty_band(self, spec: AssemblySpec, model: AssemblyModel, prediction: Prediction,
                         options: UncertaintyOptions, natural_frequencies: bool = True) -> UncertaintyBand:
        """The band of a prediction: percentiles of ``|h|`` and natural frequencies over the draws.

        Parameters
        ----------
        spec : AssemblySpec
        model : AssemblyModel
            The nominal model (:meth:`predict_with_model`).
        prediction : Prediction
            Its prediction.
        options : UncertaintyOptions
        natural_frequencies : bool
            Also the natural frequencies of every draw (analytical spindles).

        Returns
        -------
        UncertaintyBand
        """
        drawn = self.tool_point_draws(spec, options, prediction)
        f = spec.frequency_hz
        notes = []
        stats = ModeStatistics(np.empty(0), np.empty(0), np.empty(0))
        if self.base is None:
            matching = "by order: exact natural frequencies of every draw, the k-th counted from 0 Hz matched to " \
                       "the nominal k-th"
            if natural_frequencies:
                if drawn.reduced is not None and drawn.ratio_bounds is not None:
                    stats, how = reduced_mode_statistics(drawn.drawn, drawn.reduced, drawn.knobs, *drawn.ratio_bounds,
                                                         float(f[0]), float(f[-1]), BAND_MARGIN)
                    matching += (f" (exact in {min(CALIBRATION_DRAWS + HELD_OUT_DRAWS, options.draws)} draws; in the "
                                 f"others, per mode, a least-squares fit on {CALIBRATION_DRAWS} of them of its "
                                 f"logarithm on its pole's in the reduced model (pole) or on the drawn knobs' "
                                 f"(regression), where it held within {ESTIMATE_TOLERANCE:g} of the mode's spread "
                                 f"there and in the others, else exact: "
                                 + ", ".join(f"{k} {[round(x, 1) for x in v]}" for k, v in how.items() if v) + ")")
                else:
                    stats = mode_statistics(model, drawn.drawn, float(f[0]), float(f[-1]))
                    matching += " (one lockstep search)"
        else:
            matching = "by order within each modal-fit band: every draw's |h| peak in the band of each modal-fit " \
                       "mode (parabolic refinement), moved by the nominal h's own peak offset"
            bands = [(float(m["band_hz"][0]), float(m["band_hz"][1])) for m in prediction.extra.get("modal_fit", [])]
            stats = peak_statistics(f, drawn.h, prediction.tool_point.h, prediction.natural_frequencies_hz, bands)
            inside = ("the bearings" if self.base.plane == "spindle_nose"
                      else "the bearings, the spindle–holder joint and the holder")
            notes.append(f"measured spindle: {inside} are inside the measurement, so their tolerances do not apply; "
                         f"the measurement is drawn under its own uncertainty instead (measured_spindle)")
        notes += drawn.notes
        reduced = None
        if drawn.reduced is not None:
            r = drawn.reduced
            reduced = r.summary()
            notes.append(f"reduced model of the draws: each draw solved exactly at {np.mean(r.lines_per_draw):.0f} of "
                         f"{f.size} lines and fitted by a rational function with its own poles; largest error at the "
                         f"lines kept aside to check it {np.max(r.check_error, initial=0.0):.2g} of the draw's |h| there "
                         f"(draws above {reduced['check_tolerance']:g} solved on every line: "
                         f"{int(np.sum(r.exact))})")
        return UncertaintyBand(options, magnitude_percentiles(drawn.h, list(PERCENTILES.values())), stats.mean_hz,
                               stats.sd_hz, stats.in_band_fraction, matching, stats.entering, drawn.measured_spindle,
                               tuple(notes), reduced)


#: Points of the geometric scan that brackets the nominal modes of a reduced band (a bracket
#: holding two modes is split by the search; fewer points are fewer eliminations).
STRUCTURE_SCAN_POINTS = 24
#: Their relative precision (starting poles, and the nominal of modes outside the band).
STRUCTURE_RTOL = 1e-9
#: Starting poles above a measured spindle's band, relative to its top (they take up what lies
#: beyond it: without them the nominal fit of RA-1 on a direct FRF was 5 % off, with them 0.14 %).
ABOVE_BAND = np.array([1.2, 1.5])


def _all_nominal(knobs: NuisanceDraws) -> bool:
    """True when no knob of any draw moves the assembly (scales 1, stickout offset 0)."""
    return all(bool(np.all(v == (0.0 if name == "stickout_offset_m" else 1.0))) for name, v in knobs.values.items())


def _smooth_draws(draws: ComplexArray, nominal: ComplexArray) -> bool:
    """True when every drawn base receptance is the nominal one times a constant per draw and entry."""
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = draws / nominal
    ratio = np.where(np.isfinite(ratio), ratio, ratio[:, :1])
    return bool(np.all(np.abs(ratio - ratio[:, :1]) <= 1e-12 * np.maximum(np.abs(ratio[:, :1]), 1.0)))


def measured_base_draws(receptance: ComplexArray, uncertainty: BaseUncertainty | None,
                        effective_length_m: float | None, tolerances: Mapping[str, float],
                        rng: np.random.Generator, n: int) -> tuple[ComplexArray, dict[str, Any]]:
    """Draws of a measured spindle's receptance: its noise, then (``direct_frf``) its rotations.

    * Noise: ``uncertainty.draw`` with ``spindle_noise_rel`` for FRFs without a coherence
      (none when ``uncertainty`` is None or the tolerance is 0).
    * ``direct_frf`` (``effective_length_m`` given): the equivalent-cantilever estimate
      ``l = n = 3h/2L``, ``p = 3h/L²`` redone with ``ln L' ~ N(ln L, σ²)``, ``σ =
      spindle_effective_length_log``, kept within the bounds L/2 … 2L the prediction
      reports: ``l, n × L/L'`` and ``p × (L/L')²``.

    Parameters
    ----------
    receptance : numpy.ndarray, shape (nfreq, 2, 2)
        The measured base as predicted with (m/N, 1/N, rad/N, rad/(N·m)).
    uncertainty : BaseUncertainty or None
    effective_length_m : float or None
        The rotation estimate's length L, m (``direct_frf`` only).
    tolerances : mapping of str to float
        With the names of :data:`~rcsa.model.tolerances.MEASURED_SPINDLE_TOLERANCES`.
    rng : numpy.random.Generator
    n : int
        Number of draws.

    Returns
    -------
    draws : numpy.ndarray, shape (n, nfreq, 2, 2)
    summary : dict
        What was drawn, JSON-ready.
    """
    tol = {**MEASURED_SPINDLE_TOLERANCES, **tolerances}
    noise_rel = float(tol["spindle_noise_rel"])
    summary: dict[str, Any] = {}
    if uncertainty is not None:
        out = uncertainty.draw(rng, n, noise_rel)
        summary["noise"] = uncertainty.summary(noise_rel)
    else:
        out = np.array(np.broadcast_to(receptance, (n, *receptance.shape)))
        summary["noise"] = None
    if effective_length_m is not None:
        sd = float(tol["spindle_effective_length_log"])
        ln_ratio = np.clip(sd * rng.standard_normal(n), -math.log(2.0), math.log(2.0))  # ln(L'/L)
        s = np.exp(-ln_ratio)  # L / L'
        out[:, :, 0, 1] *= s[:, None]
        out[:, :, 1, 0] *= s[:, None]
        out[:, :, 1, 1] *= (s * s)[:, None]
        summary["effective_length_m"] = {"nominal": effective_length_m, "bounds": [effective_length_m / 2,
                                                                                   effective_length_m * 2],
                                         "log_sd": sd}
    return out, summary


def spread_of_bounds(frequency_hz: FloatArray, bounds: list[ComplexArray]) -> dict[str, Any]:
    """Envelope of the tool-point h over an estimate's bounds, relative to its peak.

    Parameters
    ----------
    frequency_hz : numpy.ndarray, shape (nfreq,)
    bounds : list of two numpy.ndarray, shape (nfreq,)
        Tool-point ``h`` (m/N) at the low and high end of the estimate.

    Returns
    -------
    dict
        ``h_bounds`` (wire form), ``max_relative_spread_of_peak`` and where it occurs.
    """
    lo, hi = bounds
    ref = max(float(np.max(np.abs(lo))), float(np.max(np.abs(hi))))
    rel = np.abs(hi - lo) / ref
    return {"h_bounds": {"low": complex_to_wire(lo), "high": complex_to_wire(hi)},
            "max_relative_spread_of_peak": float(rel.max()),
            "frequency_of_max_spread_hz": float(frequency_hz[int(np.argmax(rel))])}
