"""Predictions as the CLI and the REST service ask for them: one assembly, or a batch.

Each function takes and returns plain contract documents (dicts) or the library's own
objects, validates at the edge, and never depends on how it was reached.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any, Literal

from rcsa.app.stores import resolver
from rcsa.errors import InputError, NotFoundError
from rcsa.libraries.library_prediction import select_tool_point
from rcsa.measured.store import MeasurementStore
from rcsa.model import batch
from rcsa.model.bounds import MAX_BATCH_COMBINATIONS, MAX_FREQUENCY_LINES
from rcsa.model.contract import AssemblySpec, CommonSpec, MeasuredSpindleSpec
from rcsa.model.prediction import Prediction
from rcsa.model.reference import ra1
from rcsa.model.spindle_side import SpindleSide, ToolPointDraws
from rcsa.model.uncertainty import UncertaintyOptions, parse_prediction_request, parse_uncertainty

__all__ = ["EXAMPLE_ASSEMBLIES", "example_assembly", "predict", "predict_batch", "predict_draws", "prediction_document"]

#: The example assemblies the doors offer by name (``GET /v1/examples/{name}``, the web
#: page's defaults, the schemas' examples), each built by :mod:`rcsa.model.reference`.
EXAMPLE_ASSEMBLIES = {"ra1": ra1}


def example_assembly(name: str, frequency: Mapping[str, Any] | None = None) -> dict[str, Any]:
    """An example assembly by name, as a contract document the caller may edit.

    Parameters
    ----------
    name : str
        One of :data:`EXAMPLE_ASSEMBLIES` (``"ra1"``: the reference assembly RA-1).
    frequency : mapping, optional
        Replaces the example's frequency grid.

    Raises
    ------
    NotFoundError
        No example of that name.

    Examples
    --------
    >>> example_assembly("ra1", {"start_hz": 100.0, "stop_hz": 200.0, "step_hz": 50.0})["frequency"]
    {'start_hz': 100.0, 'stop_hz': 200.0, 'step_hz': 50.0}
    """
    build = EXAMPLE_ASSEMBLIES.get(name)
    if build is None:
        raise NotFoundError("example", name)
    return build(dict(frequency) if frequency is not None else None)


def predict(assembly: Mapping[str, Any] | AssemblySpec, *, store: MeasurementStore | None = None,
            max_lines: int = MAX_FREQUENCY_LINES) -> Prediction:
    """Tool-point prediction of one assembly (``contract.md`` "Python API").

    Parameters
    ----------
    assembly : dict or AssemblySpec
        The contract's assembly document (SI units), or an already parsed spec. The document
        may carry ``"uncertainty": {"draws", "seed", "tolerances"}`` (each optional): the
        result then gains the band of :mod:`rcsa.model.uncertainty`.
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
    spec, uncertainty = (assembly, None) if isinstance(assembly, AssemblySpec) else \
        parse_prediction_request(assembly, max_lines)
    common = CommonSpec(spec.frequency_hz, spec.beam_theory, spec.shear_coefficient, spec.materials,
                        spec.spindle)
    return SpindleSide(common, resolver(store)).predict(spec, uncertainty=uncertainty)


def prediction_document(prediction: Prediction, tool_point: Sequence[str] | None = None) -> dict[str, Any]:
    """A prediction as the contract's JSON mapping with numpy arrays (for orjson).

    Parameters
    ----------
    prediction : Prediction
    tool_point : sequence of str, optional
        Keep only these receptances of ``tool_point`` (e.g. ``["h"]``: a third of the bytes).

    Raises
    ------
    InputError
        Field ``tool_point``: a name other than h, l, n, p.
    """
    out = prediction.to_dict(arrays="numpy")
    return select_tool_point(out, list(tool_point)) if tool_point is not None else out


def predict_draws(assembly: Mapping[str, Any], uncertainty: object, *, store: MeasurementStore | None = None,
                  max_lines: int = MAX_FREQUENCY_LINES, path: str = "uncertainty"
                  ) -> tuple[Prediction, ToolPointDraws, UncertaintyOptions]:
    """The nominal prediction of an assembly and its drawn assemblies' tool-point ``h``.

    For analyses built on many draws (robust stability lobes): the draws of
    :meth:`rcsa.model.spindle_side.SpindleSide.tool_point_draws`, without the band's
    statistics.

    Parameters
    ----------
    assembly : dict
        The contract's assembly document (without an ``uncertainty`` of its own).
    uncertainty : dict
        The ``uncertainty`` option (:func:`rcsa.model.uncertainty.parse_uncertainty`).
    store : MeasurementStore, optional
        Where a measured spindle is looked up (the default store when omitted).
    max_lines : int
        Largest accepted number of frequency lines.
    path : str
        Where the option sits in the request, for error messages.

    Returns
    -------
    prediction : Prediction
        The nominal assembly's.
    draws : ToolPointDraws
    options : UncertaintyOptions
    """
    spec, nested = parse_prediction_request(assembly, max_lines)
    if nested is not None:
        raise InputError("assembly.uncertainty", f"give the option once, as {path}")
    options = parse_uncertainty(uncertainty, path, measured_spindle=isinstance(spec.spindle, MeasuredSpindleSpec),
                                lines=int(spec.frequency_hz.size))
    if options is None:
        raise InputError(path, "is required")
    side = SpindleSide(CommonSpec(spec.frequency_hz, spec.beam_theory, spec.shear_coefficient, spec.materials,
                                  spec.spindle), resolver(store))
    return side.predict(spec), side.tool_point_draws(spec, options), options


def predict_batch(request: Mapping[str, Any], *, store: MeasurementStore | None = None,
                  max_lines: int = MAX_FREQUENCY_LINES, max_combinations: int = MAX_BATCH_COMBINATIONS,
                  progress: batch.Progress | None = None,
                  arrays: Literal["list", "numpy"] = "list") -> dict[str, Any]:
    """Tool-point FRFs of many tool–holder combinations on one spindle.

    Parameters
    ----------
    request : dict
        ``{"spindle", "frequency", "combinations": [...]}`` and the optional common fields
        (see :func:`rcsa.model.batch.predict_batch`).
    store : MeasurementStore, optional
        Where a measured spindle is looked up (the default store when omitted).
    max_lines, max_combinations : int
        Largest accepted number of frequency lines and of combinations.
    progress : callable, optional
        Called as ``progress(done, total)`` after each combination.
    arrays : {"list", "numpy"}
        Long arrays of the results as lists (JSON-ready) or numpy arrays (for orjson).

    Returns
    -------
    dict
        ``{"results": [...], "summary": {"ok", "error"}}``, one result per combination in
        input order (see :func:`rcsa.model.batch.predict_batch`).
    """
    return batch.predict_batch(request, resolve_base=resolver(store), max_lines=max_lines,
                               max_combinations=max_combinations, progress=progress, arrays=arrays)
