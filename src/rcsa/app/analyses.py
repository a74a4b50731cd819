"""Analyses as the CLI and the REST service ask for them: lobes, effects, identification, diagnosis."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from rcsa.analysis.lobes.request import parse_lobes_request
from rcsa.analysis.lobes.zoa import LobeResult
from rcsa.analysis.progress import Progress
from rcsa.analysis.sensitivity import effects as _effects
from rcsa.app.predictions import predict
from rcsa.app.stores import MeasurementSource, resolver
from rcsa.measured.store import MeasurementStore
from rcsa.model.bounds import MAX_FREQUENCY_LINES

__all__ = ["Progress", "diagnose", "effects", "identify", "stability_lobes", "stability_lobes_result"]


def stability_lobes_result(request: Mapping[str, Any], *, store: MeasurementStore | None = None,
                           max_lines: int = MAX_FREQUENCY_LINES) -> LobeResult:
    """Stability lobes (``contract.md`` "Stability lobes") from inline FRFs or an assembly.

    With an ``assembly``, its tool-point ``h`` is predicted first and used in x and y (the
    result says so: ``same_frf_in_y``).

    Returns
    -------
    rcsa.analysis.lobes.zoa.LobeResult
    """
    parsed = parse_lobes_request(request)
    if parsed.assembly is None:
        return parsed.solve()
    prediction = predict(parsed.assembly, store=store, max_lines=max_lines)
    return parsed.solve(prediction.frequency_hz, prediction.tool_point.h)


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
        the extras of :class:`rcsa.analysis.lobes.zoa.LobeResult` (``frf_y_source``, minimum depth, …).
    """
    return stability_lobes_result(request, store=store, max_lines=max_lines).to_dict()


def effects(request: Mapping[str, Any], *, store: MeasurementSource | None = None,
            progress: Progress | None = None) -> dict[str, Any]:
    """Effect analysis: sensitivity of each mode to every bearing and joint parameter.

    See :func:`rcsa.analysis.sensitivity.effects` (request: an assembly, or ``{"assembly",
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


def diagnose(request: Mapping[str, Any], *, progress: Progress | None = None, **kwargs: Any) -> dict[str, Any]:
    """Sim-to-real gap diagnosis (``contract.md`` "Diagnosis").

    Parameters
    ----------
    request : dict
        The diagnosis request: ``{"assembly", "measurements", "tolerances"?, "options"?}``.
    progress : callable, optional
        ``progress(done, total)`` at each step (:mod:`rcsa.analysis.progress`).
    **kwargs
        Passed on to :func:`rcsa.analysis.diagnosis.diagnose.diagnose`.

    Returns
    -------
    dict
        The contract's diagnosis response (see :func:`rcsa.analysis.diagnosis.diagnose.diagnose`).
    """
    # scipy.stats and scipy.optimize (~0.9 s to import): only when a diagnosis is asked for
    from rcsa.analysis.diagnosis.diagnose import diagnose as run

    return run(request, progress=progress, **kwargs)
