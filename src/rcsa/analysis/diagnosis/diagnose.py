"""``diagnose(request) -> dict``: where model and measurement part, which effect, how far it shrinks.

The steps (:func:`rcsa.analysis.diagnosis.state.analyse`) and the response
(:func:`rcsa.analysis.diagnosis.report.build_response`), as the contract's one call.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from rcsa.analysis.diagnosis.report import build_response
from rcsa.analysis.diagnosis.state import Analysis, analyse
from rcsa.analysis.progress import Progress

__all__ = ["Analysis", "analyse", "diagnose"]


def diagnose(request: Mapping[str, Any], progress: Progress | None = None) -> dict[str, Any]:
    """Diagnose the gap between a base model and tap-test measurements.

    Parameters
    ----------
    request : dict
        ``{"assembly", "measurements": [{"tool", "frequency_hz", "h", "coherence", ...}],
        "tolerances"?, "options"?}`` (``contract.md`` "Diagnosis"; optional fields in
        :mod:`rcsa.analysis.diagnosis.request`).
    progress : callable, optional
        ``progress(done, total)`` at each step (:mod:`rcsa.analysis.progress`).

    Returns
    -------
    dict
        ``{"gap": {"bands", "modes", ...}, "verdict": {"effect", "status", "ambiguous_with"},
        "effects": [...], "ranking": [...], "not_observable_at_standstill": [...], ...}``.

    Raises
    ------
    rcsa.errors.InputError
        For an invalid request (the field and the rule are named).
    """
    a = analyse(request, progress)
    return build_response(a)

