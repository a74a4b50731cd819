"""Analyses as the CLI and the REST service ask for them: lobes, effects, identification, diagnosis."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from rcsa.analysis.lobes.request import parse_lobes_request
from rcsa.analysis.lobes.robust import RobustLobes, robust_lobes, split_robust_request
from rcsa.analysis.lobes.zoa import LobeResult
from rcsa.analysis.sensitivity import effects as _effects
from rcsa.app.predictions import predict, predict_draws
from rcsa.app.stores import MeasurementSource, resolver
from rcsa.errors import InputError
from rcsa.measured.store import MeasurementStore
from rcsa.model.bounds import MAX_FREQUENCY_LINES

__all__ = ["diagnose", "effects", "identify", "stability_lobes", "stability_lobes_result", "stability_lobes_results"]


def stability_lobes_results(request: Mapping[str, Any], *, store: MeasurementStore | None = None,
                            max_lines: int = MAX_FREQUENCY_LINES) -> tuple[LobeResult, RobustLobes | None]:
    """Stability lobes (``contract.md`` "Stability lobes") and, when asked for, robust ones.

    With an ``assembly``, its tool-point ``h`` is predicted first and used in x and y (the
    result says so: ``same_frf_in_y``). With ``uncertainty`` (and optionally ``robust``:
    ``{"confidence"}``) the assembly is also drawn and every draw's lobes computed
    (:mod:`rcsa.analysis.lobes.robust`).

    Returns
    -------
    nominal : rcsa.analysis.lobes.zoa.LobeResult
    robust : rcsa.analysis.lobes.robust.RobustLobes or None
    """
    body, robust = split_robust_request(request)
    parsed = parse_lobes_request(body)
    if parsed.assembly is None:
        return parsed.solve(), None
    if "uncertainty" in parsed.assembly:
        raise InputError("assembly.uncertainty", "give uncertainty at the top of a stability-lobes request "
                                                 "(it asks for robust lobes there)")
    if robust is None:
        prediction = predict(parsed.assembly, store=store, max_lines=max_lines)
        return parsed.solve(prediction.frequency_hz, prediction.tool_point.h), None
    prediction, draws, options = predict_draws(parsed.assembly, robust.uncertainty, store=store, max_lines=max_lines)
    nominal = parsed.solve(prediction.frequency_hz, prediction.tool_point.h)
    return nominal, robust_lobes(parsed, nominal, prediction.frequency_hz, draws.h, options, robust.confidence)


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


def effects(request: Mapping[str, Any], *, store: MeasurementSource | None = None) -> dict[str, Any]:
    """Effect analysis: sensitivity of each mode to every bearing and joint parameter.

    See :func:`rcsa.analysis.sensitivity.effects` (request: an assembly, or ``{"assembly",
    "parameters", "relative_step", "band_hz"}``). ``store`` is where a measured spindle
    (``"spindle": {"measurement_id": ...}``) is looked up (the default store when omitted).
    """
    return _effects(request, resolver(store))


def identify(request: Mapping[str, Any], *, store: MeasurementSource | None = None) -> dict[str, Any]:
    """Joint identification from measured tool-point FRFs (``contract.md`` "Joint identification").

    See :func:`rcsa.analysis.joint_identification.identify.identify`; ``store`` is where a
    measured spindle is looked up (the default store when omitted).
    """
    # scipy.optimize (~0.4 s to import): only when an identification is asked for
    from rcsa.analysis.joint_identification.identify import identify as run

    return run(request, resolver(store))


def diagnose(request: Mapping[str, Any], **kwargs: Any) -> dict[str, Any]:
    """Sim-to-real gap diagnosis (``contract.md`` "Diagnosis").

    Parameters
    ----------
    request : dict
        The diagnosis request: ``{"assembly", "measurements", "tolerances"?, "options"?}``.
    **kwargs
        Passed on to :func:`rcsa.analysis.diagnosis.diagnose.diagnose`.

    Returns
    -------
    dict
        The contract's diagnosis response (see :func:`rcsa.analysis.diagnosis.diagnose.diagnose`).
    """
    # scipy.stats and scipy.optimize (~0.9 s to import): only when a diagnosis is asked for
    from rcsa.analysis.diagnosis.diagnose import diagnose as run

    return run(request, **kwargs)
