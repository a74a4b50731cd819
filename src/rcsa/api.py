"""The application layer: what the CLI and the REST service both call.

Each function takes and returns plain contract documents (dicts) or the library's own
objects, validates at the edge, and never depends on how it was reached. The service's
routes and the CLI's commands are thin doors onto these functions.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import replace
from typing import Any

import numpy as np

from .assembly import AssemblyModel, build_model, spindle_chain
from .errors import InputError
from .modes import natural_frequencies_batch
from .prediction import (
    Prediction,
    SubassemblyCache,
    complex_to_json,
    predict_model,
    tool_point_receptance,
)
from .spec import (
    MAX_FREQUENCY_LINES,
    AssemblySpec,
    CommonSpec,
    MeasuredSpindleSpec,
    SpindleSpec,
    assemble,
    parse_assembly,
    parse_combination,
    parse_common,
)

__all__ = [
    "MAX_BATCH_COMBINATIONS",
    "diagnose",
    "effects",
    "identify",
    "predict",
    "predict_batch",
    "stability_lobes",
    "stability_lobes_result",
]

MAX_BATCH_COMBINATIONS = 10_000

Progress = Callable[[int, int], None]


class _SpindleContext:
    """The spindle side shared by all combinations: plane, base receptance and cache."""

    def __init__(self, common: CommonSpec, store: Any = None) -> None:
        self.base = None
        omega = 2 * np.pi * common.frequency_hz
        if isinstance(common.spindle, MeasuredSpindleSpec):
            from .hybrid import measured_base  # local: only hybrid requests need the store

            sp = common.spindle
            self.base = measured_base(sp.measurement_id, common.frequency_hz, store,
                                      artifact_method=sp.artifact_method, effective_length_m=sp.effective_length_m)
        self.cache = SubassemblyCache(omega, None if self.base is None else self.base.receptance)
        self.spindle = (spindle_chain(common.spindle, common.materials, common.shear_coefficient, common.beam_theory)
                        if isinstance(common.spindle, SpindleSpec) else ())
        self.alt_caches = [] if self.base is None else [SubassemblyCache(omega, r) for r in self.base.alternatives]

    def predict(self, spec: AssemblySpec, natural_frequencies: bool = True) -> Prediction:
        return self.predict_with_model(spec, natural_frequencies)[1]

    def predict_with_model(self, spec: AssemblySpec, natural_frequencies: bool = True
                           ) -> tuple[AssemblyModel, Prediction]:
        base = self.base
        if base is None:
            model = build_model(spec, spindle=self.spindle)
            return model, predict_model(model, spec.frequency_hz, cache=self.cache,
                                        natural_frequencies=natural_frequencies)
        if base.plane == "holder_tip" and base.artifact_diameter_m is not None and \
                abs(spec.tool.shank_diameter_m - base.artifact_diameter_m) > 1e-6 * base.artifact_diameter_m:
            raise InputError("tool.shank_diameter_m",
                             f"must match the shank the holder-tip measurement was taken with "
                             f"({base.artifact_diameter_m:g} m); got {spec.tool.shank_diameter_m:g} m")
        model = build_model(spec, base.plane)
        extra: dict[str, Any] = {"spindle_measurement": base.report}
        if self.alt_caches:
            h = [tool_point_receptance(model, c)[:, 0, 0] for c in self.alt_caches]
            extra["uncertainty"] = _spread(spec.frequency_hz, h)
        return model, predict_model(model, spec.frequency_hz, base_receptance=base.receptance, cache=self.cache,
                                    natural_frequencies=natural_frequencies, notes=base.notes, extra=extra)


def _spread(frequency_hz: np.ndarray, bounds: list[np.ndarray]) -> dict[str, Any]:
    """Envelope of the tool-point h over an estimate's bounds, relative to its peak."""
    lo, hi = bounds
    ref = max(float(np.max(np.abs(lo))), float(np.max(np.abs(hi))))
    rel = np.abs(hi - lo) / ref
    return {"h_bounds": {"low": complex_to_json(lo), "high": complex_to_json(hi)},
            "max_relative_spread_of_peak": float(rel.max()),
            "frequency_of_max_spread_hz": float(frequency_hz[int(np.argmax(rel))])}


def predict(assembly: Mapping[str, Any] | AssemblySpec, *, store: Any = None,
            max_lines: int = MAX_FREQUENCY_LINES) -> Prediction:
    """Tool-point prediction of one assembly (``contract.md`` "Python API").

    Parameters
    ----------
    assembly : dict or AssemblySpec
        The contract's assembly document (SI units), or an already parsed spec.
    store : MeasurementStore, optional
        Where ``"spindle": {"measurement_id": ...}`` is looked up; the default store
        (``RCSA_STORE`` or the per-user location) when omitted.
    max_lines : int
        Largest accepted number of frequency lines.

    Returns
    -------
    Prediction
        Typed result; also a read-only mapping in the contract's JSON shape
        (``result["natural_frequencies_hz"]``, ``result.to_dict()``).

    Examples
    --------
    >>> from rcsa.reference import ra1
    >>> result = predict(ra1({"start_hz": 500.0, "stop_hz": 1500.0, "step_hz": 1.0}))
    >>> [round(f, 2) for f in result["natural_frequencies_hz"]]
    [599.85, 921.69, 1115.51, 1383.61, 1444.68]
    """
    spec = assembly if isinstance(assembly, AssemblySpec) else parse_assembly(assembly, max_lines)
    common = CommonSpec(spec.frequency_hz, spec.beam_theory, spec.shear_coefficient, spec.materials,
                        spec.spindle)
    return _SpindleContext(common, store).predict(spec)


_BATCH_FIELDS = ("frequency", "beam_theory", "shear_coefficient", "materials", "spindle", "combinations",
                 "natural_frequencies")


def _fill_natural_frequencies(slots: list, frequency_hz: np.ndarray) -> None:
    """Exact natural frequencies of every ok combination, all tools on one spindle solved together.

    The spindle (with its joint to the holder) is the shared prefix; holders and tools are
    the stacked tails, so tools in different holders or with different shanks still share
    one lockstep bisection (:func:`rcsa.modes.natural_frequencies_batch`).
    """
    groups: dict[Any, list[int]] = {}
    for i, slot in enumerate(slots):
        if not isinstance(slot, dict):
            model = slot[1]
            groups.setdefault(model.spindle_side(), []).append(i)
    for prefix, members in groups.items():
        tails = [slots[i][1].holder + slots[i][1].tool_side() for i in members]
        found = natural_frequencies_batch(prefix, tails, float(frequency_hz[0]), float(frequency_hz[-1]))
        for i, nat in zip(members, found, strict=True):
            ident, model, prediction = slots[i]
            slots[i] = (ident, model, replace(prediction, natural_frequencies_hz=nat))


def predict_batch(request: Mapping[str, Any], *, store: Any = None, max_lines: int = MAX_FREQUENCY_LINES,
                  max_combinations: int = MAX_BATCH_COMBINATIONS, progress: Progress | None = None,
                  arrays: str = "list") -> dict[str, Any]:
    """Tool-point FRFs of many tool–holder combinations on one spindle.

    The spindle (and each distinct spindle + holder + insertion) is condensed once and
    reused. Results come in input order, each with its own ``status``; a bad combination
    never fails the others.

    Parameters
    ----------
    request : dict
        ``{"spindle", "frequency", "combinations": [{"id", "holder", "tool", "joints"}]}``,
        optionally ``materials``, ``beam_theory``, ``shear_coefficient`` and
        ``natural_frequencies`` (bool, default true).
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
    if not isinstance(request, Mapping):
        raise InputError("", "the batch request must be a JSON object")
    unknown = sorted(set(request) - set(_BATCH_FIELDS))
    if unknown:
        raise InputError(unknown[0], f"unknown field (allowed: {', '.join(_BATCH_FIELDS)})")
    combos = request.get("combinations")
    if not isinstance(combos, list) or not combos:
        raise InputError("combinations", "must be a non-empty list")
    if len(combos) > max_combinations:
        raise InputError("combinations", f"at most {max_combinations} combinations per request, got {len(combos)}")
    with_modes = request.get("natural_frequencies", True)
    if not isinstance(with_modes, bool):
        raise InputError("natural_frequencies", "must be true or false")
    common = parse_common({k: v for k, v in request.items() if k not in ("combinations", "natural_frequencies")},
                          max_lines=max_lines)
    context = _SpindleContext(common, store)
    slots: list[dict[str, Any] | tuple[str, AssemblyModel, Prediction]] = []
    for i, raw in enumerate(combos):
        ident = raw.get("id") if isinstance(raw, Mapping) else None
        path = f"combinations[{i}]"
        try:
            if not isinstance(ident, str) or not ident:
                raise InputError(f"{path}.id", "is required (a non-empty string)")
            spec = assemble(common, parse_combination(raw, common.materials, path, extra_fields=("id",)))
            # exact modes come afterwards for all tools at once (natural_frequencies_batch)
            model, prediction = context.predict_with_model(spec, natural_frequencies=False)
            slots.append((ident, model, prediction))
        except InputError as exc:
            field = exc.field if exc.field.startswith(path) else f"{path}.{exc.field}".rstrip(".")
            slots.append({"id": ident if isinstance(ident, str) else None, "status": "error",
                          "error": {"field": field, "detail": exc.rule}})
        if progress is not None:
            progress(i + 1, len(combos))
    if with_modes and context.base is None:
        _fill_natural_frequencies(slots, common.frequency_hz)
    results = [s if isinstance(s, dict) else {"id": s[0], "status": "ok", **s[2].to_dict(arrays)} for s in slots]
    ok = sum(r["status"] == "ok" for r in results)
    return {"results": results, "summary": {"ok": ok, "error": len(results) - ok}}


def stability_lobes_result(request: Mapping[str, Any], *, store: Any = None,
                           max_lines: int = MAX_FREQUENCY_LINES) -> Any:
    """Stability lobes (``contract.md`` "Stability lobes") from inline FRFs or an assembly.

    With an ``assembly``, its tool-point ``h`` is predicted first and used in x and y (the
    result says so: ``same_frf_in_y``).

    Returns
    -------
    rcsa.lobes.LobeResult
    """
    from .lobes_request import parse_lobes_request

    parsed = parse_lobes_request(request)
    if parsed.assembly is None:
        return parsed.solve()
    prediction = predict(parsed.assembly, store=store, max_lines=max_lines)
    return parsed.solve(prediction.frequency_hz, prediction.tool_point.h)


def stability_lobes(request: Mapping[str, Any], *, store: Any = None,
                    max_lines: int = MAX_FREQUENCY_LINES) -> dict[str, Any]:
    """The contract's stability-lobes response (see :func:`stability_lobes_result`).

    Returns
    -------
    dict
        ``spindle_speed_rpm``, ``depth_limit_m``, ``chatter_frequency_hz``, ``lobes`` and
        the extras of :class:`rcsa.lobes.LobeResult` (``frf_y_source``, minimum depth, …).
    """
    return stability_lobes_result(request, store=store, max_lines=max_lines).to_dict()


def effects(request: Mapping[str, Any]) -> dict[str, Any]:
    """Effect analysis: sensitivity of each mode to every bearing and joint parameter.

    See :func:`rcsa.effects.effects` (request: an assembly, or ``{"assembly", "parameters",
    "relative_step", "band_hz"}``).
    """
    from .effects import effects as _effects

    return _effects(request)


def identify(request: Mapping[str, Any]) -> dict[str, Any]:
    """Joint identification from measured tool-point FRFs (``contract.md`` "Joint identification").

    See :func:`rcsa.jointid.identify`.
    """
    from .jointid import identify as _identify

    return _identify(request)


def diagnose(request: Mapping[str, Any]) -> dict[str, Any]:
    """Sim-to-real gap diagnosis (``contract.md`` "Diagnosis").

    See :func:`rcsa.diagnosis.api.diagnose` (imported on first use: it draws with matplotlib).
    """
    from .diagnosis.api import diagnose as _diagnose

    return _diagnose(request)
