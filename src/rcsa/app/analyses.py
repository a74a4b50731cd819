"""Analyses as the CLI and the REST service ask for them: lobes, effects, identification, diagnosis."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from rcsa.analysis.effects.sensitivities import effects as _effects
from rcsa.analysis.lobes.modal_model import modal_model_from_assembly
from rcsa.analysis.lobes.request import LobesRequest, parse_lobes_request
from rcsa.analysis.lobes.robust import (
    RobustLobes,
    RobustRequest,
    robust_lobes,
    split_robust_request,
)
from rcsa.analysis.lobes.zoa import LobeResult
from rcsa.analysis.progress import Progress
from rcsa.app.predictions import predict, predict_draws
from rcsa.app.stores import resolver
from rcsa.errors import InputError
from rcsa.measured.hybrid import MeasurementSource
from rcsa.measured.store import MeasurementStore
from rcsa.model.bounds import MAX_FREQUENCY_LINES
from rcsa.model.contract import SpindleSpec, parse_assembly
from rcsa.model.uncertainty import parse_prediction_request

__all__ = ["ANALYSIS_KINDS", "diagnose", "effects", "identify", "run_analysis", "stability_lobes",
           "stability_lobes_result", "stability_lobes_results", "validate"]

#: Single computations that may also run as jobs (``Prefer: respond-async``), by the name of
#: their cost model in :mod:`rcsa.app.budget`.
ANALYSIS_KINDS = ("prediction", "lobes", "effects", "identification", "diagnosis")


def _parse_lobes(request: Mapping[str, Any]) -> tuple[LobesRequest, RobustRequest | None]:
    """A stability-lobes request and its robust part; robust lobes are zero-order only."""
    body, robust = split_robust_request(request)
    parsed = parse_lobes_request(body)
    if robust is not None and parsed.method.name != "zoa":
        raise InputError("uncertainty", f"robust lobes are computed with method 'zoa' only, not "
                                        f"{parsed.method.name!r} (one semi-discretization per draw is too slow)")
    if parsed.assembly is not None and "uncertainty" in parsed.assembly:
        raise InputError("assembly.uncertainty", "give uncertainty at the top of a stability-lobes request "
                                                 "(it asks for robust lobes there)")
    return parsed, robust


def stability_lobes_results(request: Mapping[str, Any], *, store: MeasurementStore | None = None,
                            max_lines: int = MAX_FREQUENCY_LINES) -> tuple[LobeResult, RobustLobes | None]:
    """Stability lobes (``contract.md`` "Stability lobes") and, when asked for, robust ones.

    With an ``assembly``, its tool-point ``h`` is predicted first and used in x and y (the
    result says so: ``same_frf_in_y``). With ``"method": "semi_discretization"`` an
    analytical assembly gives its exact modes (:func:`~rcsa.analysis.lobes.modal_model.
    modal_model_from_assembly`); a measured spindle's predicted ``h`` is fitted instead.
    With ``uncertainty`` (and optionally ``robust``: ``{"confidence"}``; method ``zoa``) the
    assembly is also drawn and every draw's lobes computed (:mod:`rcsa.analysis.lobes.robust`).

    Returns
    -------
    nominal : rcsa.analysis.lobes.zoa.LobeResult
    robust : rcsa.analysis.lobes.robust.RobustLobes or None
    """
    parsed, robust = _parse_lobes(request)
    if parsed.assembly is None:
        return parsed.solve(), None
    if robust is not None:
        prediction, draws, options = predict_draws(parsed.assembly, robust.uncertainty, store=store,
                                                   max_lines=max_lines)
        nominal = parsed.solve(prediction.frequency_hz, prediction.tool_point.h)
        return nominal, robust_lobes(parsed, nominal, prediction.frequency_hz, draws.h, options, robust.confidence)
    spec = parse_assembly(parsed.assembly, max_lines)
    prediction = predict(spec, store=store, max_lines=max_lines)
    frequency_hz, h = prediction.frequency_hz, prediction.tool_point.h
    modes = None
    if parsed.method.name == "semi_discretization" and isinstance(spec.spindle, SpindleSpec):
        modes = modal_model_from_assembly(spec, modes_per_direction=parsed.method.modes_per_direction,
                                          frequency_hz=frequency_hz, h=h)
    return parsed.solve(frequency_hz, h, modal_model=modes), None


def stability_lobes_result(request: Mapping[str, Any], *, store: MeasurementStore | None = None,
                           max_lines: int = MAX_FREQUENCY_LINES) -> LobeResult:
    """The nominal stability lobes of a request (:func:`stability_lobes_results`, robust ones left out).

    Returns
    -------
    rcsa.analysis.lobes.zoa.LobeResult
    """
    return stability_lobes_results(request, store=store, max_lines=max_lines)[0]


def stability_lobes(request: Mapping[str, Any], *, store: MeasurementStore | None = None,
                    max_lines: int = MAX_FREQUENCY_LINES) -> dict[str, Any]:
    """The contract's stability-lobes response (see :func:`stability_lobes_result`).

    Parameters
    ----------
    request : dict
        Inline FRFs or an ``assembly``, with the cutting parameters (contract "Stability lobes").
    store : MeasurementStore, optional
        Where a measured spindle of the assembly is looked up (the default store when omitted).
    max_lines : int
        Largest accepted number of frequency lines.

    Returns
    -------
    dict
        ``spindle_speed_rpm``, ``depth_limit_m``, ``chatter_frequency_hz``, ``lobes`` and
        the extras of :class:`rcsa.analysis.lobes.zoa.LobeResult` (``frf_y_source``, minimum depth, …);
        with ``uncertainty``, also ``depth_limit_robust_m`` and ``robust``
        (:class:`rcsa.analysis.lobes.robust.RobustLobes`).
    """
    nominal, robust = stability_lobes_results(request, store=store, max_lines=max_lines)
    return nominal.to_dict() if robust is None else {**nominal.to_dict(), **robust.to_dict()}


def effects(request: Mapping[str, Any], *, store: MeasurementSource | None = None,
            progress: Progress | None = None) -> dict[str, Any]:
    """Effect analysis: sensitivity of each mode to every bearing and joint parameter.

    See :func:`rcsa.analysis.effects.sensitivities.effects` (request: an assembly, or ``{"assembly",
    "parameters", "relative_step", "band_hz"}``). ``store`` is where a measured spindle
    (``"spindle": {"measurement_id": ...}``) is looked up (the default store when omitted);
    ``progress(done, total)`` is called at each step (:mod:`rcsa.analysis.progress`).
    """
    return _effects(request, resolver(store), progress)


def identify(request: Mapping[str, Any], *, store: MeasurementSource | None = None,
             progress: Progress | None = None) -> dict[str, Any]:
    """Joint identification from measured tool-point FRFs (``contract.md`` "Joint identification").

    See :func:`rcsa.analysis.joint_identification.identify.identify`; ``store`` is where a
    measured spindle is looked up (the default store when omitted); ``progress(done, total)``
    is called at each step (:mod:`rcsa.analysis.progress`).
    """
    # scipy.optimize (~0.4 s to import): only when an identification is asked for
    from rcsa.analysis.joint_identification.identify import identify as run

    return run(request, resolver(store), progress)


def diagnose(request: Mapping[str, Any], *, store: MeasurementSource | None = None,
             progress: Progress | None = None) -> dict[str, Any]:
    """Sim-to-real gap diagnosis (``contract.md`` "Diagnosis").

    Parameters
    ----------
    request : dict
        The diagnosis request: ``{"assembly", "measurements", "tolerances"?, "options"?}``.
    store : MeasurementSource, optional
        Where a measured spindle (``assembly.spindle = {"measurement_id": ...}``) is looked
        up; the default store when omitted (opened only if the request has one).
    progress : callable, optional
        ``progress(done, total)`` at each step (:mod:`rcsa.analysis.progress`).

    Returns
    -------
    dict
        The contract's diagnosis response (see :func:`rcsa.analysis.diagnosis.diagnose.diagnose`).
    """
    # scipy.stats and scipy.optimize (~0.9 s to import): only when a diagnosis is asked for
    from rcsa.analysis.diagnosis.diagnose import diagnose as run

    return run(request, resolver(store), progress)


def validate(kind: str, request: Mapping[str, Any], *, store: MeasurementSource | None = None) -> None:
    """Refuse an invalid request before it is queued as a job (the checks its run makes
    first), so that a bad request is a 422 at once instead of a failed job."""
    if kind == "diagnosis":
        from rcsa.analysis.diagnosis.state import validate as validate_diagnosis

        validate_diagnosis(request, resolver(store))
    elif kind == "identification":
        from rcsa.analysis.joint_identification.request import parse_identification_request

        parse_identification_request(request, resolver(store))
    elif kind == "lobes":
        _parse_lobes(request)
    elif kind == "prediction" and isinstance(request, Mapping) and "uncertainty" in request:
        parse_prediction_request(request)  # the option is checked against the spindle and the grid
    # prediction and effects: the budget's estimate already parsed the assembly


def run_analysis(kind: str, request: Mapping[str, Any], *, store: MeasurementStore | None = None,
                 max_lines: int = MAX_FREQUENCY_LINES) -> dict[str, Any]:
    """Run one of :data:`ANALYSIS_KINDS` and return its result document (a job's result).

    Raises
    ------
    InputError
        An unknown kind, or an invalid request.
    """
    if kind == "prediction":
        return predict(request, store=store, max_lines=max_lines).to_dict()
    if kind == "lobes":
        return stability_lobes(request, store=store, max_lines=max_lines)
    if kind == "effects":
        return effects(request, store=store)
    if kind == "identification":
        return identify(request, store=store)
    if kind == "diagnosis":
        return diagnose(request, store=store)
    raise InputError("kind", f"no analysis {kind!r} (known: {', '.join(ANALYSIS_KINDS)})")
