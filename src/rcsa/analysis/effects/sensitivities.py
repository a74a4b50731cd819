"""Effect analysis: which bearing, joint or tool parameter moves which mode, and how.

For an analytical assembly, every mode inside a band is described by four features of the
exact model:

* ``frequency_hz`` — the undamped natural frequency (Wittrick–Williams, exact);
* ``peak_magnitude_m_n`` — the local maximum of the damped tool-point ``|h|`` next to it;
* ``peak_frequency_hz`` — where that maximum sits;
* ``damping_ratio`` — from a single-mode (Levy) fit of the damped ``h`` around the peak.

Their normalised (logarithmic) sensitivities ``S = d ln(feature) / d ln(parameter)`` to each
bearing's k and c, each joint's k_t, c_t, k_r, c_r, the stickout and the fluted diameter
ratio are central finite differences of the exact model::

    S ≈ [ln q(p·e^{+δ}) − ln q(p·e^{−δ})] / (2δ),      δ = relative_step (default 1e-3)

Step: the truncation error is ``δ²/6 · d³ln q/d(ln p)³``. The most curved entry on RA-1,
the stickout's effect on the 1384 Hz peak height (next to its veering with the 1445 Hz
mode), has ``S(δ) − S(0) ≈ −390 δ²`` (measured: −0.304 at δ = 0.01 against −0.265), so
δ = 1e-3 keeps it within 0.04 % of S = −0.27; the features themselves are computed to
~1e-10 relative (natural frequencies bracketed to 1e-11, peaks refined to sub-ppm, fits
linear), so the rounding part ``1e-10/δ`` stays near 1e-7. A 0.1 % change moves every
mode by far less than the gap to its neighbours (RA-1's closest pair, 1384/1445 Hz, is
4 % apart), so modes are tracked between the ± runs by proximity of their exact natural
frequencies. Halving the step changes the sensitivities by less than 0.2 % (tested).

This is the quantitative form of the "effect analysis" of Ertürk, Özgüven & Budak,
IJMTM 47 (2007) 23–32 (``docs/diagnosis.md`` §3.3): bearings act on the lowest spindle modes,
the interfaces on the higher holder/tool modes; stiffness moves frequencies, damping moves
peaks.

Examples
--------
>>> from rcsa.reference import ra1
>>> doc = ra1({"start_hz": 300.0, "stop_hz": 1500.0, "step_hz": 1.0})
>>> report = effect_analysis(doc, parameters=["holder_tool.stiffness_n_m"])
>>> [round(float(f), 1) for f in report.frequency_hz]
[599.9, 921.7, 1115.5, 1383.6, 1444.7]
>>> round(report.controls("holder_tool.stiffness_n_m"), 1)
1383.6
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from rcsa.analysis.effects.measured_spindle import hybrid_effect_analysis, split_parameters
from rcsa.analysis.effects.mode_features import (
    ModeFeatures,
    mode_features,
)
from rcsa.analysis.effects.report import FEATURES, EffectReport
from rcsa.analysis.progress import Progress, report
from rcsa.analysis.tool_point_model import MeasuredSpindle, ToolPointModel
from rcsa.errors import InputError
from rcsa.model import fields
from rcsa.model.assembly import build_model
from rcsa.model.bounds import (
    MAX_FREQUENCY_HZ,
    MAX_RELATIVE_STEP,
    MIN_FREQUENCY_HZ,
    MIN_RELATIVE_STEP,
)
from rcsa.model.contract import AssemblySpec, MeasuredSpindleSpec, SpindleSpec, parse_assembly
from rcsa.model.parameters import (
    chosen_parameters,
    get_parameter,
    is_damping,
    parameter_names,
    set_parameter,
)
from rcsa.model.spindle_side import BaseResolver
from rcsa.physics.chain import Chain
from rcsa.physics.natural_frequencies import natural_frequencies_hz

__all__ = [
    "DEFAULT_RELATIVE_STEP",
    "effect_analysis",
    "effects",
    "effects_report",
    "nominal_features",
]

_TWO_PI = 2.0 * np.pi

#: Relative (logarithmic) finite-difference step δ; see the module docstring.
DEFAULT_RELATIVE_STEP = 0.001



# ---------------------------------------------------------------------------- effect analysis


def _band_modes(chain: Chain, band_hz: tuple[float, float], margin: float = 0.12) -> np.ndarray:
    """Natural frequencies in the band widened by ``margin`` (relative) on both sides."""
    return natural_frequencies_hz(chain, band_hz[0] / (1 + margin), band_hz[1] * (1 + margin))


def _track(base_hz: np.ndarray, other_hz: np.ndarray, window_rel: np.ndarray) -> np.ndarray:
    """Index in ``other_hz`` of each base mode (−1 where no unique nearest mode in its window)."""
    out = np.full(base_hz.size, -1)
    if other_hz.size == 0:
        return out
    d = np.abs(np.log(other_hz[None, :]) - np.log(base_hz[:, None]))
    nearest = np.argmin(d, axis=1)
    back = np.argmin(d, axis=0)
    for i, j in enumerate(nearest):
        within = d[i, j] < np.log1p(min(window_rel[i]))
        if within and back[j] == i:
            out[i] = j
    return out


def _features_at(spec: AssemblySpec, base: ModeFeatures, band_hz: tuple[float, float],
                 reuse_frequencies: bool) -> tuple[ModeFeatures, bool]:
    """Features of a perturbed model, for the base modes (tracked); ``ok`` = all tracked."""
    chain = build_model(spec).chain()
    if reuse_frequencies:  # damping never moves the undamped natural frequencies
        fn, ok = base.frequency_hz, True
    else:
        all_hz = _band_modes(chain, band_hz)
        idx = _track(base.frequency_hz, all_hz, base.window_rel)
        ok = bool(np.all(idx >= 0))
        fn = np.where(idx >= 0, all_hz[np.maximum(idx, 0)] if all_hz.size else np.nan, np.nan)
    good = np.isfinite(fn)
    feats = mode_features(chain, fn[good], base.window_rel[good])
    if good.all():
        return feats, ok
    full = {k: np.full(fn.size, np.nan) for k in ("tip_residue_1_kg", "peak_frequency_hz",
                                                  "peak_magnitude_m_n", "damping_ratio")}
    for k, arr in full.items():
        arr[good] = getattr(feats, k)
    return ModeFeatures(fn, full["tip_residue_1_kg"], full["peak_frequency_hz"], full["peak_magnitude_m_n"],
                        full["damping_ratio"], base.window_rel), ok


def _band_of(spec: AssemblySpec, band_hz: Sequence[float] | None) -> tuple[float, float]:
    if band_hz is None:
        return float(spec.frequency_hz[0]), float(spec.frequency_hz[-1])
    if len(band_hz) != 2 or not MIN_FREQUENCY_HZ <= band_hz[0] < band_hz[1] <= MAX_FREQUENCY_HZ:
        raise InputError("band_hz", f"must be [start_hz, stop_hz] with {MIN_FREQUENCY_HZ:g} <= start < stop <= "
                                    f"{MAX_FREQUENCY_HZ:g} (0 Hz is singular), got {list(band_hz)}")
    return float(band_hz[0]), float(band_hz[1])


def nominal_features(spec: AssemblySpec, band_hz: Sequence[float] | None = None) -> ModeFeatures:
    """Features of the modes of ``spec`` whose natural frequency lies in the band.

    Parameters
    ----------
    spec : AssemblySpec
        Analytical assembly.
    band_hz : (float, float), optional
        Default: the assembly's frequency range.
    """
    band = _band_of(spec, band_hz)
    chain = build_model(spec).chain()
    all_hz = _band_modes(chain, band)
    fn = all_hz[(all_hz >= band[0]) & (all_hz <= band[1])]
    return mode_features(chain, fn, neighbours_hz=all_hz)


def effect_analysis(assembly: Mapping[str, Any] | AssemblySpec, *, parameters: Sequence[str] | None = None,
                    relative_step: float = DEFAULT_RELATIVE_STEP,
                    band_hz: Sequence[float] | None = None,
                    resolve_base: BaseResolver | None = None, progress: Progress | None = None) -> EffectReport:
    """Normalised sensitivities of every mode in a band to bearing, joint and tool parameters.

    On a measured spindle (``"spindle": {"measurement_id": ...}``, with ``resolve_base``)
    the modes come from a modal fit of the hybrid model and bearings are not applicable
    (:mod:`rcsa.analysis.effects.measured_spindle`).

    Parameters
    ----------
    assembly : dict or AssemblySpec
        Contract assembly document.
    parameters : sequence of str, optional
        Names as in :func:`parameter_names` (default: all of them).
    relative_step : float
        δ of the central difference in ln(parameter), in [1e-6, 0.1].
    band_hz : (float, float), optional
        Modes whose undamped natural frequency lies here (default: the assembly's grid range).
    resolve_base : BaseResolver, optional
        Looks a measured spindle up (the application layer passes the store's).
    progress : callable, optional
        ``progress(done, total)`` after the nominal modes and after each parameter
        (:mod:`rcsa.analysis.progress`).

    Returns
    -------
    EffectReport

    References
    ----------
    Ertürk, Özgüven, Budak, IJMTM 47 (2007) 23–32 ("effect analysis").
    """
    spec = assembly if isinstance(assembly, AssemblySpec) else parse_assembly(assembly)
    if not isinstance(spec.spindle, SpindleSpec) and resolve_base is None:
        raise InputError("spindle", "an effect analysis on a measured spindle needs a measurement store: call "
                         "rcsa.app.analyses.effects (the CLI's --store, or the service), which knows it")
    if not MIN_RELATIVE_STEP <= relative_step <= MAX_RELATIVE_STEP:
        raise InputError("relative_step", f"must be in [{MIN_RELATIVE_STEP:g}, {MAX_RELATIVE_STEP:g}] (below, the "
                                          f"bisection's rounding swamps the difference), got {relative_step:g}")
    if isinstance(spec.spindle, MeasuredSpindleSpec) and resolve_base is not None:
        spindle = MeasuredSpindle.from_base(spec.frequency_hz, resolve_base(spec.spindle, spec.frequency_hz))
        tpm = ToolPointModel(spec, spindle)
        tpm.model_at({})  # the assembly's shape on this spindle's plane (holder present or not) is checked here
        names, not_applicable = split_parameters(spec, spindle.plane, parameters)
        return hybrid_effect_analysis(tpm, names, not_applicable, relative_step, _band_of(spec, band_hz), progress)
    names = chosen_parameters(spec, parameters, parameter_names(spec))
    band = _band_of(spec, band_hz)
    base = nominal_features(spec, band)
    report(progress, 1, len(names) + 1)
    values = np.array([get_parameter(spec, n) for n in names], dtype=float)
    nm = base.frequency_hz.size
    sens = {q: np.full((nm, len(names)), np.nan) for q in FEATURES}
    notes: list[str] = []
    for j, name in enumerate(names):
        runs = []
        for sign in (+1.0, -1.0):
            perturbed = set_parameter(spec, name, values[j] * math.exp(sign * relative_step))
            feats, ok = _features_at(perturbed, base, band, reuse_frequencies=is_damping(name))
            if not ok:
                notes.append(f"{name}: some modes could not be tracked between the perturbed runs")
            runs.append(feats)
        for q in FEATURES:
            with np.errstate(invalid="ignore", divide="ignore"):
                sens[q][:, j] = (np.log(runs[0].feature(q)) - np.log(runs[1].feature(q))) / (2 * relative_step)
        report(progress, j + 2, len(names) + 1)
    if nm == 0:
        notes.append(f"no natural frequency lies in the band {band[0]:g}–{band[1]:g} Hz: nothing to analyse")
    hidden = [f"{f:.1f}" for f, p in zip(base.frequency_hz, base.peak_magnitude_m_n, strict=True)
              if not math.isfinite(p)]
    if hidden:
        notes.append(f"modes at {', '.join(hidden)} Hz show no peak of |h| at the tool point: peak and "
                     "damping sensitivities are null there")
    return EffectReport(band, relative_step, base, names, values, sens, tuple(dict.fromkeys(notes)))


# ---------------------------------------------------------------------------- application layer


_REQUEST_FIELDS = ("assembly", "parameters", "relative_step", "band_hz")


def effects_report(request: Mapping[str, Any], resolve_base: BaseResolver | None = None,
                   progress: Progress | None = None) -> EffectReport:
    """Parse an effect-analysis request and run it (see :func:`effects` for the request).

    ``progress(done, total)``, when given, reports each step (:func:`effect_analysis`).

    Returns
    -------
    EffectReport
    """
    if not isinstance(request, Mapping):
        raise InputError("", "the request must be a JSON object")
    if "assembly" not in request:
        return effect_analysis(request, resolve_base=resolve_base, progress=progress)
    o = fields.Fields(request, "", _REQUEST_FIELDS)
    params = request.get("parameters")
    if params is not None and (not isinstance(params, list) or not all(isinstance(p, str) for p in params)):
        raise InputError("parameters", "must be a list of parameter names")
    step = o.number("relative_step", gt=0.0, ge=MIN_RELATIVE_STEP, le=MAX_RELATIVE_STEP, default=DEFAULT_RELATIVE_STEP)
    band = request.get("band_hz")
    if band is not None and (not isinstance(band, list) or len(band) != 2
                             or not all(isinstance(b, int | float) and not isinstance(b, bool) for b in band)):
        raise InputError("band_hz", "must be [start_hz, stop_hz]")
    try:
        spec = parse_assembly(request["assembly"])
    except InputError as exc:
        raise InputError(f"assembly.{exc.field}".rstrip("."), exc.rule) from None
    return effect_analysis(spec, parameters=params, relative_step=step, band_hz=band, resolve_base=resolve_base,
                           progress=progress)


def effects(request: Mapping[str, Any], resolve_base: BaseResolver | None = None,
            progress: Progress | None = None) -> dict[str, Any]:
    """Effect analysis as a JSON document (the CLI's and the REST route's entry point).

    Parameters
    ----------
    request : dict
        Either a contract assembly document (all parameters, the assembly's frequency
        range, δ = 1e-3), or ``{"assembly": {...}, "parameters": [names] (optional, default
        all, see :func:`parameter_names`), "relative_step": 0.001 (optional, in (0, 0.1]),
        "band_hz": [start, stop] (optional, default the assembly's frequency range)}``.
        The spindle is analytical (segments and bearings), or a stored measurement when
        ``resolve_base`` is given (modal-fit modes; bearings not applicable).
    resolve_base : BaseResolver, optional
        Looks a measured spindle up (the application layer passes the store's).
    progress : callable, optional
        ``progress(done, total)`` at each step (:mod:`rcsa.analysis.progress`).

    Returns
    -------
    dict
        :meth:`EffectReport.to_dict`: ``band_hz``, ``relative_step``, ``modes`` (each with
        ``frequency_hz``, ``tip_residue_1_kg``, ``tip_participation``, peak, damping ratio,
        ``controlled_by`` and ``controlled_by_interface`` per feature) and ``parameters``
        (each with its ``value`` and a list of sensitivities per feature, one per mode).

    Raises
    ------
    InputError
        For a malformed request.
    """
    return effects_report(request, resolve_base, progress).to_dict()
