"""``diagnose(request) -> dict``: where model and measurement part, which effect, how far it shrinks.

The steps (:func:`rcsa.analysis.diagnosis.state.analyse`) and the response
(:func:`rcsa.analysis.diagnosis.report.build_response`), as the contract's one call.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import TYPE_CHECKING, Any

from rcsa.analysis.diagnosis.report import build_response
from rcsa.analysis.diagnosis.state import Analysis, analyse
from rcsa.analysis.progress import Progress

if TYPE_CHECKING:  # types only: the measured spindle's module loads with a measured spindle
    from rcsa.model.spindle_side import BaseResolver

__all__ = ["Analysis", "analyse", "diagnose"]


def diagnose(request: Mapping[str, Any], resolve_base: BaseResolver | None = None,
             progress: Progress | None = None) -> dict[str, Any]:
    """Diagnose the gap between a base model and tap-test measurements.

    Parameters
    ----------
    request : dict
        ``{"assembly", "measurements": [{"tool", "frequency_hz", "h", "coherence", ...}],
        "tolerances"?, "options"?}`` (``docs/contract.md`` "Diagnosis"; optional fields in
        :mod:`rcsa.analysis.diagnosis.request`).
    resolve_base : callable, optional
        Looks a measured spindle (``assembly.spindle = {"measurement_id": ...}``) up
        (:data:`rcsa.model.spindle_side.BaseResolver`; the application layer passes one on its
        store). Without it only analytical spindles are accepted.
    progress : callable, optional
        ``progress(done, total)`` at each step (:mod:`rcsa.analysis.progress`).

    Returns
    -------
    dict
        ``{"gap": {"bands", "modes", ...}, "verdict": {"effect", "status", "ambiguous_with"},
        "effects": [...], "ranking": [...], "not_applicable": [{"effect", "reason"}],
        "not_observable_at_standstill": [...], "spindle_measurement"?, ...}``.

    Raises
    ------
    rcsa.errors.InputError
        For an invalid request (the field and the rule are named).
    """
    a = analyse(request, resolve_base, progress)
    return build_response(a)

