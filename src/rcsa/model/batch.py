"""Tool-point FRFs of many tool–holder combinations on one spindle.

The spindle (and each distinct spindle + holder + insertion) is condensed once and reused;
on an analytical spindle the tools are then solved together, stacked
(:func:`rcsa.model.prediction.predict_tools`): FRFs and static stiffnesses in passes of many
tools, exact natural frequencies in one lockstep search. Results come in input order, each
with its own ``status``; a bad combination never fails the others.

An ``uncertainty`` option (:mod:`rcsa.model.uncertainty`) applies to every combination: each
gets its own band, drawn from the same seed (common random numbers: two tools' bands differ
by their geometry, not by the luck of their draws).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import replace
from typing import Any, Literal

from rcsa.errors import InputError
from rcsa.model.assembly import AssemblyModel, assembly_notes, build_model
from rcsa.model.bounds import MAX_BATCH_COMBINATIONS, MAX_FREQUENCY_LINES
from rcsa.model.contract import (
    AssemblySpec,
    CommonSpec,
    MeasuredSpindleSpec,
    assemble,
    parse_combination,
    parse_common,
)
from rcsa.model.prediction import Prediction, predict_tools
from rcsa.model.spindle_side import BaseResolver, SpindleSide
from rcsa.model.uncertainty import UncertaintyOptions, parse_uncertainty

__all__ = ["BATCH_FIELDS", "Progress", "parse_batch", "predict_batch"]

#: Called as ``progress(done, total)``.
Progress = Callable[[int, int], None]

#: Fields of a batch request.
BATCH_FIELDS = ("frequency", "beam_theory", "shear_coefficient", "materials", "spindle", "combinations",
                "natural_frequencies", "uncertainty")

_Slot = dict[str, Any] | tuple[str, AssemblyModel, Prediction]


def parse_batch(request: Mapping[str, Any], *, max_lines: int = MAX_FREQUENCY_LINES,
                max_combinations: int = MAX_BATCH_COMBINATIONS) -> tuple[list[Any], bool, CommonSpec]:
    """What :func:`predict_batch` checks before computing anything (its errors, exactly).

    Parameters
    ----------
    request : mapping
        A batch request (see :func:`predict_batch`).
    max_lines, max_combinations : int
        Largest accepted number of frequency lines and of combinations.

    Returns
    -------
    combinations : list
        As given (each is parsed when it is computed).
    natural_frequencies : bool
    common : CommonSpec
        The grid, spindle, materials and beam theory the combinations share.

    Raises
    ------
    InputError
        Not an object, an unknown field, no or too many combinations, or an invalid shared part.
    """
    if not isinstance(request, Mapping):
        raise InputError("", "the batch request must be a JSON object")
    unknown = sorted(set(request) - set(BATCH_FIELDS))
    if unknown:
        raise InputError(unknown[0], f"unknown field (allowed: {', '.join(BATCH_FIELDS)})")
    combos = request.get("combinations")
    if not isinstance(combos, list) or not combos:
        raise InputError("combinations", "must be a non-empty list")
    if len(combos) > max_combinations:
        raise InputError("combinations", f"at most {max_combinations} combinations per request, got {len(combos)}")
    with_modes = request.get("natural_frequencies", True)
    if not isinstance(with_modes, bool):
        raise InputError("natural_frequencies", "must be true or false")
    common = parse_common({k: v for k, v in request.items()
                           if k not in ("combinations", "natural_frequencies", "uncertainty")}, max_lines=max_lines)
    _batch_uncertainty(request, common)
    return combos, with_modes, common


def _batch_uncertainty(request: Mapping[str, Any], common: CommonSpec) -> UncertaintyOptions | None:
    """The batch's ``uncertainty`` option, checked against its spindle and grid."""
    return parse_uncertainty(request.get("uncertainty"), measured_spindle=isinstance(common.spindle,
                                                                                   MeasuredSpindleSpec),
                             lines=int(common.frequency_hz.size))


def predict_batch(request: Mapping[str, Any], *, resolve_base: BaseResolver | None = None,
                  max_lines: int = MAX_FREQUENCY_LINES, max_combinations: int = MAX_BATCH_COMBINATIONS,
                  progress: Progress | None = None, arrays: Literal["list", "numpy"] = "list") -> dict[str, Any]:
    """Tool-point FRFs of many tool–holder combinations on one spindle.

    Parameters
    ----------
    request : dict
        ``{"spindle", "frequency", "combinations": [{"id", "holder", "tool", "joints"}]}``,
        optionally ``materials``, ``beam_theory``, ``shear_coefficient``,
        ``natural_frequencies`` (bool, default true) and ``uncertainty`` (every combination's
        band, :mod:`rcsa.model.uncertainty`).
    resolve_base : callable, optional
        Turns a measured spindle into its base receptance
        (:func:`rcsa.measured.hybrid.base_resolver`); needed for ``{"measurement_id"}``.
    max_lines, max_combinations : int
        Largest accepted number of frequency lines and of combinations.
    progress : callable, optional
        Called as ``progress(done, total)`` after each combination.
    arrays : {"list", "numpy"}
        Long arrays of the results as lists (JSON-ready) or numpy arrays (for orjson).

    Returns
    -------
    dict
        ``{"results": [{"id", "status": "ok", ...prediction} | {"id", "status": "error",
        "error": {"field", "detail"}}], "summary": {"ok", "error"}}``
    """
    combos, with_modes, common = parse_batch(request, max_lines=max_lines, max_combinations=max_combinations)
    uncertainty = _batch_uncertainty(request, common)
    side = SpindleSide(common, resolve_base)
    total = len(combos)
    slots: list[_Slot | None] = []
    pending: dict[int, tuple[str, AssemblyModel, tuple[str, ...]]] = {}  # analytical: solved below, all together
    specs: dict[int, AssemblySpec] = {}
    for i, raw in enumerate(combos):
        ident = raw.get("id") if isinstance(raw, Mapping) else None
        path = f"combinations[{i}]"
        try:
            if not isinstance(ident, str) or not ident:
                raise InputError(f"{path}.id", "is required (a non-empty string)")
            spec = assemble(common, parse_combination(raw, common.materials, path, extra_fields=("id",)))
            if side.base is None:
                pending[i] = (ident, build_model(spec, spindle=side.spindle), assembly_notes(spec))
                specs[i] = spec
                slots.append(None)
            else:
                model, prediction = side.predict_with_model(spec)
                if uncertainty is not None:
                    band = side.uncertainty_band(spec, model, prediction, uncertainty, natural_frequencies=with_modes)
                    prediction = replace(prediction, uncertainty=band)
                slots.append((ident, model, prediction))
        except InputError as exc:
            field = exc.field if exc.field.startswith(path) else f"{path}.{exc.field}".rstrip(".")
            slots.append({"id": ident if isinstance(ident, str) else None, "status": "error",
                          "error": {"field": field, "detail": exc.rule}})
        if progress is not None and side.base is not None:
            progress(i + 1, total)
    if pending:
        errors = len(slots) - len(pending)

        def done(n: int) -> None:
            if progress is not None:
                progress(errors + n, total)

        predictions = predict_tools([model for _, model, _ in pending.values()], common.frequency_hz, side.cache,
                                    natural_frequencies=with_modes, done=done,
                                    notes=[notes for _, _, notes in pending.values()])
        for (i, (ident, model, _)), prediction in zip(pending.items(), predictions, strict=True):
            if uncertainty is not None:
                band = side.uncertainty_band(specs[i], model, prediction, uncertainty, natural_frequencies=with_modes)
                prediction = replace(prediction, uncertainty=band)
            slots[i] = (ident, model, prediction)
    elif progress is not None and side.base is None:
        progress(total, total)
    results = [s if isinstance(s, dict) else {"id": s[0], "status": "ok", **s[2].to_dict(arrays)}
               for s in slots if s is not None]
    ok = sum(r["status"] == "ok" for r in results)
    return {"results": results, "summary": {"ok": ok, "error": len(results) - ok}}
