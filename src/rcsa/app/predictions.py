"""Predictions as the CLI and the REST service ask for them: one assembly, or a batch.

Each function takes and returns plain contract documents (dicts) or the library's own
objects, validates at the edge, and never depends on how it was reached.
"""

from __future__ import annotations

import threading
from collections.abc import Mapping, Sequence
from typing import Any, Literal

import orjson

from rcsa.app.stores import resolver
from rcsa.errors import InputError, NotFoundError
from rcsa.libraries.library_prediction import select_tool_point
from rcsa.measured.hybrid import MeasurementSource
from rcsa.model import batch
from rcsa.model.bounds import MAX_BATCH_COMBINATIONS, MAX_FREQUENCY_LINES
from rcsa.model.contract import AssemblySpec, CommonSpec, MeasuredSpindleSpec
from rcsa.model.prediction import Prediction
from rcsa.model.reference import ra1
from rcsa.model.spindle_side import SpindleSide, ToolPointDraws
from rcsa.model.uncertainty import UncertaintyOptions, parse_prediction_request, parse_uncertainty
from rcsa.physics.subassembly_cache import LruStore

__all__ = ["EXAMPLE_ASSEMBLIES", "PREFIXES_PER_SIDE", "SIDES", "SIDES_KEPT", "SpindleSides", "example_assembly",
           "predict", "predict_batch", "predict_draws", "prediction_document"]

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


#: Spindle sides :func:`predict` keeps across calls in a process (least recently used dropped).
SIDES_KEPT = 8
#: Condensed chains (spindle + holder prefixes) one kept side may hold before it is dropped.
PREFIXES_PER_SIDE = 64
_SHARED_FIELDS = ("frequency", "beam_theory", "shear_coefficient", "materials", "spindle")


class SpindleSides:
    """What predictions on one spindle share, kept across calls (per process).

    A prediction's costliest part is the condensation of the spindle and holder onto the
    holder's tip (RA-1 at 10 000 lines: 13 of 15 ms; a measured spindle: its base receptance
    on the grid, then the holder on it); requests for other tools on the same spindle and
    holder — a CAM system asking tool after tool — reuse them. A side is keyed by the
    request's grid, beam theory, shear coefficient, materials and spindle (canonical JSON) and
    the store; a measured spindle's side is used only while its measurement's file is the one
    it was computed from (``file_identity``: inode, size, modification time — a file deleted,
    replaced or damaged since is read again, and fails as a fresh request would). Results are those of a fresh side, bit for bit: the same arrays are computed
    once instead of each time.

    Parameters
    ----------
    size : int
        Sides kept; 0 keeps none.
    """

    def __init__(self, size: int = SIDES_KEPT) -> None:
        self.size = int(size)
        # the package's one eviction policy (least recently used first), as the sides' own caches
        self._items: LruStore[tuple[int, bytes], tuple[Any, SpindleSide]] = LruStore(self.size)
        self._lock = threading.Lock()

    def side(self, document: Mapping[str, Any], common: CommonSpec,
             store: MeasurementSource | None) -> SpindleSide:
        """The kept side of a request, or a new one (kept for the next).

        Parameters
        ----------
        document : mapping
            The request (its shared fields make the key).
        common : CommonSpec
            The same, parsed.
        store : MeasurementStore, optional
            Where a measured spindle is read (None: the default store; such sides are not kept).
        """
        measured = isinstance(common.spindle, MeasuredSpindleSpec)
        if not self.size or (measured and store is None):
            return SpindleSide(common, resolver(store))
        key = (id(store), orjson.dumps({k: document.get(k) for k in _SHARED_FIELDS}, option=orjson.OPT_SORT_KEYS))
        # a measured spindle's file as it is now: a side computed from another state of it is not used
        identity = _identity(store, common.spindle.measurement_id) if measured else ()  # type: ignore[union-attr]
        with self._lock:
            kept = self._items.peek(key)
        hit = kept[1] if kept is not None and identity is not None and kept[0] == identity else None
        if hit is None:  # new, or deleted, replaced or damaged since: resolve again (as a fresh request would)
            hit = SpindleSide(common, resolver(store))
        with self._lock:
            if len(hit.cache) > PREFIXES_PER_SIDE or identity is None:
                self._items.pop(key)
                return hit
            self._items.put(key, (identity, hit))
        return hit


def _identity(store: Any, measurement_id: str) -> Any:
    """What identifies a stored measurement's file now (one ``stat``), None when it is gone or unknown."""
    identity = getattr(store, "file_identity", None)
    if identity is not None:
        return identity(measurement_id)
    if hasattr(type(store), "__contains__"):
        return measurement_id if measurement_id in store else None
    return None  # a source that cannot say: never keep its sides


#: The process's kept spindle sides (``SIDES.size = 0`` keeps none: every prediction cold).
SIDES = SpindleSides()


def predict(assembly: Mapping[str, Any] | AssemblySpec, *, store: MeasurementSource | None = None,
            max_lines: int = MAX_FREQUENCY_LINES) -> Prediction:
    """Tool-point prediction of one assembly (``docs/contract.md`` "Python API").

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

    Notes
    -----
    The spindle side (its condensations and a measured base on the grid) is kept across
    calls with the same spindle, grid and materials (:class:`SpindleSides`): the next tool on
    that spindle and holder skips the condensation.

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
    side = SpindleSide(common, resolver(store)) if isinstance(assembly, AssemblySpec) else \
        SIDES.side(assembly, common, store)
    return side.predict(spec, uncertainty=uncertainty)


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


def predict_draws(assembly: Mapping[str, Any], uncertainty: object, *, store: MeasurementSource | None = None,
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
    prediction = side.predict(spec)
    return prediction, side.tool_point_draws(spec, options, prediction), options


def predict_batch(request: Mapping[str, Any], *, store: MeasurementSource | None = None,
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
