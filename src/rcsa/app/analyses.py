"""Analyses as the CLI and the REST service ask for them: lobes, effects, identification, diagnosis."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING, Any

import numpy as np

from rcsa.analysis.progress import Progress, check_time
from rcsa.app.stores import library_store, open_store, resolver
from rcsa.errors import InputError, NotFoundError
from rcsa.model.bounds import MAX_FREQUENCY_LINES

# Each analysis loads its own modules when it runs (lobes, effects, predictions and the stores
# are a third of a second to import): a diagnosis in a fresh process pays only for its own.
if TYPE_CHECKING:
    from rcsa.analysis.lobes.modal_model import ModalModel
    from rcsa.analysis.lobes.request import LobesRequest, SdmSolver
    from rcsa.analysis.lobes.robust import RobustLobes, RobustRequest
    from rcsa.analysis.lobes.semi_discretization import DiagramsSolver, SemiDiscretizationResult
    from rcsa.analysis.lobes.zoa import LobeResult
    from rcsa.app.budget import Limits
    from rcsa.infra.compute_backends import Backend
    from rcsa.libraries.sync import LibraryStore
    from rcsa.measured.hybrid import MeasurementSource

__all__ = ["ANALYSIS_KINDS", "LobesAnswer", "cutting_conditions", "diagnose", "effects", "identify",
           "resolve_lobes_references", "run_analysis", "spread_sdm_diagrams", "spread_sdm_solver", "stability_lobes",
           "stability_lobes_answer", "stability_lobes_result", "stability_lobes_results", "validate"]

#: Single computations that may also run as jobs (``Prefer: respond-async``), by the name of
#: their cost model in :mod:`rcsa.app.budget`.
ANALYSIS_KINDS = ("prediction", "lobes", "effects", "identification", "diagnosis")


def _parse_lobes(request: Mapping[str, Any], within: Limits | None = None
                 ) -> tuple[LobesRequest, RobustRequest | None, str | None]:
    """A stability-lobes request, its robust part and, where ``"auto"`` falls back to zero-order
    lobes within ``within`` (:func:`rcsa.app.budget.auto_lobes_fallback`), why."""
    from rcsa.analysis.lobes.request import parse_lobes_request
    from rcsa.analysis.lobes.robust import split_robust_request
    from rcsa.app.budget import auto_lobes_fallback

    fallback = None if within is None else auto_lobes_fallback(request, within)
    body, robust = split_robust_request({**request, "method": "zoa"} if fallback else request)
    parsed = parse_lobes_request(body)
    if parsed.assembly is not None and "uncertainty" in parsed.assembly:
        raise InputError("assembly.uncertainty", "give uncertainty at the top of a stability-lobes request "
                                                 "(it asks for robust lobes there)")
    return parsed, robust, fallback


@dataclass(frozen=True)
class LobesAnswer:
    """Stability lobes with what the response says beside them.

    Attributes
    ----------
    nominal : rcsa.analysis.lobes.zoa.LobeResult
    robust : rcsa.analysis.lobes.robust.RobustLobes or None
    notes : tuple of str
        Caveats found here (a zero-order diagram on an FRF grid too coarse for it); a
        semi-discretization's own notes (under-resolved speeds) come with ``nominal``.
    flute_length_m : float or None
        The assembly tool's flute length: no stepdown can exceed it (pictures and the web
        page cap the depth axis and the pockets there).
    method_reason : str
        Why ``"method": "auto"`` chose the method (empty otherwise).
    conditions : dict or None
        How the diagram was made (:func:`cutting_conditions`): written as the response's
        ``conditions`` and on its pictures.
    """

    nominal: LobeResult
    robust: RobustLobes | None = None
    notes: tuple[str, ...] = ()
    flute_length_m: float | None = None
    method_reason: str = ""
    conditions: dict[str, Any] | None = None
    unchecked: bool = False

    def extras(self) -> dict[str, Any]:
        """The response's fields beside the nominal diagram: ``notes`` (all of them),
        ``flute_length_m`` (with an assembly), ``conditions``, the robust fields, and the method used
        and why (``method``, ``method_reason``)."""
        from rcsa.analysis.lobes.semi_discretization import SemiDiscretizationResult

        own = self.nominal.to_dict().get("notes", [])
        out: dict[str, Any] = {"notes": [*own, *self.notes]}
        out["method"] = "semi_discretization" if isinstance(self.nominal, SemiDiscretizationResult) else "zoa"
        out["method_reason"] = self.method_reason or f"{out['method']}: chosen by the request"
        if self.unchecked:  # "auto" answered zero-order within a budget: no speed checked
            out["resolved"] = [False] * len(self.nominal.spindle_speed_rpm)
            out["notes"].append(self.method_reason)
        if self.flute_length_m is not None:
            out["flute_length_m"] = self.flute_length_m
        if self.conditions is not None:
            out["conditions"] = dict(self.conditions)
        if self.robust is not None:
            out.update(self.robust.to_dict())
        return out

    def to_dict(self) -> dict[str, Any]:
        """The contract's stability-lobes response with the extras."""
        return {**self.nominal.to_dict(), **self.extras()}


def _modes(parsed: LobesRequest, spec: Any, frequency_hz: np.ndarray, h: np.ndarray) -> ModalModel | None:
    """The SDM's modes of an assembly: its exact modes when analytical (None: fitted to ``h`` by solve)."""
    from rcsa.analysis.lobes.modal_model import modal_model_from_assembly
    from rcsa.model.contract import SpindleSpec

    if parsed.method.name != "semi_discretization" or not isinstance(spec.spindle, SpindleSpec):
        return None
    return modal_model_from_assembly(spec, modes_per_direction=parsed.method.modes_per_direction,
                                     frequency_hz=frequency_hz, h=h)


def cutting_conditions(parsed: LobesRequest) -> dict[str, Any]:
    """How a diagram was made, as its pictures and its response say it.

    Parameters
    ----------
    parsed : LobesRequest

    Returns
    -------
    dict
        ``teeth``, ``tangential_coefficient_n_m2``, ``radial_ratio``, ``radial_immersion``,
        ``milling``, ``method`` (``zoa`` or ``semi_discretization``, with its
        ``steps_per_period`` — null: the steps that resolve the cut — and ``modes_per_direction``)
        and ``frf``: ``"assembly"`` (the predicted tool point, used in x and y: a rotationally
        symmetric tool), ``"x_only"`` (an inline x FRF, used in y too), ``"x_and_y"``,
        ``"modal_table_x_only"`` (a modal table of x, used in y too) or ``"modal_table_x_and_y"``.
    """
    if parsed.assembly is not None:
        frf = "assembly"
    elif parsed.modal_model is not None:
        frf = "modal_table_x_only" if parsed.modal_model.same_in_y else "modal_table_x_and_y"
    else:
        frf = "x_only" if parsed.frf_yy is None else "x_and_y"
    out: dict[str, Any] = {"teeth": parsed.teeth, "tangential_coefficient_n_m2": parsed.tangential_coefficient_n_m2,
                           "radial_ratio": parsed.radial_ratio, "radial_immersion": parsed.radial_immersion,
                           "milling": parsed.milling, "method": parsed.method.name, "frf": frf}
    if parsed.method.name == "semi_discretization":
        out.update(steps_per_period=parsed.method.steps_per_period,
                   modes_per_direction=parsed.method.modes_per_direction)
    return out


def _described(parsed: LobesRequest, frequency_hz: np.ndarray, h: np.ndarray) -> dict[str, Any]:
    """The :class:`LobesAnswer` fields that say how a diagram was made: its conditions and, for
    zero-order lobes, the FRF grid's notes."""
    from rcsa.analysis.lobes.zoa import frf_grid_notes

    zoa = parsed.method.name == "zoa"
    return {"notes": tuple(frf_grid_notes(frequency_hz, h)) if zoa else (), "conditions": cutting_conditions(parsed)}


#: Fewest speeds in a part when a semi-discretization is spread over workers (:func:`spread_sdm_solver`):
#: smaller parts lose more to their own coarse searches than a worker gains (``benchmarks/bench_lobes.py``).
SDM_MIN_SPEEDS_PER_PART = 32
#: Parts per worker slot: cost-balanced parts (:func:`~rcsa.analysis.lobes.semi_discretization.speed_parts`),
#: two a slot so that one part costing more than its estimate does not leave the others idle.
SDM_PARTS_PER_SLOT = 2
#: Least cost (:func:`~rcsa.analysis.lobes.semi_discretization.speed_costs`, in steps) worth spreading:
#: about 2–3 s of one core. Below it one process answers sooner than workers start (a spawned
#: worker imports NumPy, SciPy and rcsa: about a second on a 2-core VM; a 300-speed single-mode
#: diagram of 7 200 took 3.1 s on two workers, 2.6 s in one process).
SDM_MIN_SPREAD_COST = 8000.0


def _sdm_part(part: Sequence[tuple[int, np.ndarray]],
              shared: tuple[Sequence[ModalModel], dict[str, Any]]) -> list[SemiDiscretizationResult]:
    """One part of spread semi-discretizations, where a worker runs it: a slice of speeds of each of
    some models, ``part`` = [(which model, its speeds), …], solved together in one call."""
    from rcsa.analysis.lobes.semi_discretization import semi_discretization_lobes_many

    models, settings = shared
    which = [i for i, _ in part]
    floors = settings.get("min_depth_search_max_m")
    own = settings if floors is None else {**settings, "min_depth_search_max_m": [floors[i] for i in which]}
    return semi_discretization_lobes_many([models[i] for i in which], spindle_speed_rpm=[s for _, s in part], **own)


def _slots(backend: Backend) -> int:
    """Chunks ``backend`` computes at once: its Dask threads, or its worker processes (2 when it does not say)."""
    described = backend.describe()
    return max(1, int(described.get("threads") or described.get("workers") or 2))


def spread_sdm_diagrams(backend: Backend) -> DiagramsSolver | None:
    """A solver of several semi-discretizations (:data:`~rcsa.analysis.lobes.semi_discretization.
    DiagramsSolver`) that shares their speeds among ``backend``'s workers and joins each model's
    answers again (:func:`~rcsa.analysis.lobes.semi_discretization.merged_result`).

    Each model's speed grid is cut into the same number of consecutive slices of about equal cost
    (:func:`~rcsa.analysis.lobes.semi_discretization.speed_parts`); part ``j`` is the ``j``-th slice
    of every model, solved in one call (the models stay batched together, as in one call over all).
    There are :data:`SDM_PARTS_PER_SLOT` parts per worker slot, fewer where the largest grid's slices
    would hold less than :data:`SDM_MIN_SPEEDS_PER_PART` speeds; work that costs less than
    :data:`SDM_MIN_SPREAD_COST` in all is solved here in one call. None for a backend that computes
    here (one call over every model and speed is then the fastest).

    Each speed's limit is searched, bracketed and checked on its own, so the parts give the
    answers of one call over every speed; only where each search starts differs (its guess comes
    from other neighbours). A speed whose two resolutions agree just at the edge of
    ``RESOLVED_RTOL`` may be refined in one and not in the other: the two answers then differ by
    less than that, never in kind (``tests/app/test_lobes_spread.py``).

    Parameters
    ----------
    backend : Backend
        Worker processes of this machine or a Dask cluster (:mod:`rcsa.infra.compute_backends`).

    Returns
    -------
    DiagramsSolver or None
    """
    if backend.name == "local":
        return None

    def solve(models: Sequence[ModalModel], speeds_rpm: Sequence[np.ndarray],
              settings: dict[str, Any]) -> list[SemiDiscretizationResult]:
        from rcsa.analysis.lobes.semi_discretization import (
            merged_result,
            solve_diagrams_here,
            speed_costs,
            speed_parts,
        )

        steps = settings.get("steps_per_period")
        per_speed = (steps is not None and not isinstance(steps, (int, np.integer))) or \
            settings.get("scan_start_m") is not None
        if per_speed:  # settings given speed by speed are not cut apart
            return solve_diagrams_here(models, speeds_rpm, settings)
        costs = [speed_costs(m, s, teeth=settings["teeth"], radial_immersion=settings["radial_immersion"],
                             milling=settings["milling"], steps_per_period=None if steps is None else int(steps))
                 for m, s in zip(models, speeds_rpm, strict=True)]
        n_parts = min(SDM_PARTS_PER_SLOT * _slots(backend), max(s.size for s in speeds_rpm) // SDM_MIN_SPEEDS_PER_PART)
        if n_parts <= 1 or float(sum(c.sum() for c in costs)) < SDM_MIN_SPREAD_COST:
            return solve_diagrams_here(models, speeds_rpm, settings)
        slices = [speed_parts(s, c, n_parts) for s, c in zip(speeds_rpm, costs, strict=True)]
        parts = [part for j in range(n_parts)  # a grid of few speeds (or one costly speed) has fewer slices
                 if (part := [(i, own[j]) for i, own in enumerate(slices) if j < len(own)])]
        solved = [r for _, r in backend.map(_sdm_part, parts, shared=(list(models), settings), on_wait=check_time)]
        mine: list[list[SemiDiscretizationResult]] = [[] for _ in models]
        for part, results in zip(parts, solved, strict=True):
            for (i, _), r in zip(part, results, strict=True):
                # a part computed elsewhere carries a copy of its model: the joined result names the caller's
                mine[i].append(replace(r, modal_model=models[i]))
        return [merged_result(m) for m in mine]

    return solve


def spread_sdm_solver(backend: Backend) -> SdmSolver | None:
    """A semi-discretization solver (:data:`~rcsa.analysis.lobes.request.SdmSolver`) of one model
    that shares its speeds among ``backend``'s workers as :func:`spread_sdm_diagrams` does; None
    for a backend that computes here.

    Parameters
    ----------
    backend : Backend
        Worker processes of this machine or a Dask cluster (:mod:`rcsa.infra.compute_backends`).

    Returns
    -------
    SdmSolver or None
    """
    many = spread_sdm_diagrams(backend)
    return None if many is None else _one_model(many)


def _one_model(many: DiagramsSolver) -> SdmSolver:
    """``many`` as a solver of one model's diagram."""
    def solve(model: ModalModel, speeds_rpm: np.ndarray, settings: dict[str, Any]) -> SemiDiscretizationResult:
        return many([model], [speeds_rpm], settings)[0]

    return solve


def stability_lobes_answer(request: Mapping[str, Any], *, store: MeasurementSource | None = None,
                           max_lines: int = MAX_FREQUENCY_LINES, within: Limits | None = None,
                           backend: Backend | None = None) -> LobesAnswer:
    """Stability lobes (``docs/contract.md`` "Stability lobes"), robust ones when asked for, and notes.

    With an ``assembly``, its tool-point ``h`` is predicted first and used in x and y (the
    result says so: ``same_frf_in_y``). With ``"method": "semi_discretization"`` an
    analytical assembly gives its exact modes (:func:`~rcsa.analysis.lobes.modal_model.
    modal_model_from_assembly`); a measured spindle's predicted ``h`` is fitted instead.
    With ``uncertainty`` (and optionally ``robust``: ``{"confidence"}``) the assembly is also
    drawn: zero-order, every draw's lobes are computed (:mod:`rcsa.analysis.lobes.robust`);
    semi-discretization, the reduced model of the draws gives every draw's limit
    (:mod:`rcsa.analysis.lobes.robust_sdm`). A zero-order diagram on an FRF grid too coarse for
    it gets a note (:func:`~rcsa.analysis.lobes.zoa.frf_grid_notes`). With ``within`` (the
    service's limits of an answer given at once), ``"auto"`` answers zero-order lobes, marked
    unresolved, where the resolved semi-discretization would exceed them
    (:func:`rcsa.app.budget.auto_lobes_fallback`). With ``backend`` (worker processes or a Dask
    cluster) the semi-discretizations' speeds are shared among its workers: the nominal diagram's
    (:func:`spread_sdm_solver`) and those of the robust limits' reduced model
    (:func:`spread_sdm_diagrams`).

    Returns
    -------
    LobesAnswer
    """
    parsed, robust, fallback = _parse_lobes(request, within)
    diagrams = None if backend is None else spread_sdm_diagrams(backend)
    solver = None if diagrams is None else _one_model(diagrams)  # spread_sdm_solver, from the same closure
    if fallback is not None:
        return replace(_answer(parsed, robust, store, max_lines, solver, diagrams), method_reason=fallback,
                       unchecked=True)
    return _answer(parsed, robust, store, max_lines, solver, diagrams)


def _answer(parsed: LobesRequest, robust: RobustRequest | None, store: MeasurementSource | None,
            max_lines: int, solver: SdmSolver | None = None, diagrams: DiagramsSolver | None = None) -> LobesAnswer:
    from rcsa.analysis.lobes.robust import RobustLobes, robust_lobes
    from rcsa.analysis.lobes.robust_sdm import robust_sdm_limits
    from rcsa.analysis.lobes.semi_discretization import SemiDiscretizationResult
    from rcsa.app.predictions import predict, predict_draws
    from rcsa.model.contract import parse_assembly

    zoa = parsed.method.name == "zoa"
    if parsed.assembly is None:  # inline FRFs or a modal table
        if parsed.frequency_hz is not None and parsed.frf_xx is not None:
            described = _described(parsed, parsed.frequency_hz, parsed.frf_xx)
        else:  # a modal table: no FRF grid to be too coarse
            described = {"notes": (), "conditions": cutting_conditions(parsed)}
        return LobesAnswer(parsed.solve(sdm_solver=solver), None, method_reason=parsed.method.reason, **described)
    spec = parse_assembly(parsed.assembly, max_lines)
    flute = float(spec.tool.flute_length_m)
    if robust is not None:
        prediction, draws, options = predict_draws(parsed.assembly, robust.uncertainty, store=store,
                                                   max_lines=max_lines)
        f, h = prediction.frequency_hz, prediction.tool_point.h
        modes = _modes(parsed, spec, f, h)
        nominal = parsed.solve(f, h, modal_model=modes, sdm_solver=solver)
        described = _described(parsed, f, h)
        if zoa:
            return LobesAnswer(nominal, robust_lobes(parsed, nominal, f, draws.h, options, robust.confidence),
                               flute_length_m=flute, method_reason=parsed.method.reason, **described)
        assert isinstance(nominal, SemiDiscretizationResult)
        per_draw: list[np.ndarray] = []
        limit = robust_sdm_limits(nominal.modal_model, f, h, draws.h, nominal, robust.confidence,
                                  teeth=parsed.teeth, tangential_coefficient_n_m2=parsed.tangential_coefficient_n_m2,
                                  radial_ratio=parsed.radial_ratio, radial_immersion=parsed.radial_immersion,
                                  milling=parsed.milling, draws_out=per_draw, diagrams=diagrams)
        limit.flags.writeable = False
        return LobesAnswer(nominal, RobustLobes(limit, per_draw[0], robust.confidence, options,
                                                method="semi_discretization"), flute_length_m=flute,
                           method_reason=parsed.method.reason, **described)
    prediction = predict(spec, store=store, max_lines=max_lines)
    f, h = prediction.frequency_hz, prediction.tool_point.h
    return LobesAnswer(parsed.solve(f, h, modal_model=_modes(parsed, spec, f, h), sdm_solver=solver), None,
                       flute_length_m=flute,
                       method_reason=parsed.method.reason, **_described(parsed, f, h))


def stability_lobes_results(request: Mapping[str, Any], *, store: MeasurementSource | None = None,
                            max_lines: int = MAX_FREQUENCY_LINES) -> tuple[LobeResult, RobustLobes | None]:
    """The nominal and robust stability lobes of a request (:func:`stability_lobes_answer` without its notes).

    Returns
    -------
    nominal : rcsa.analysis.lobes.zoa.LobeResult
    robust : rcsa.analysis.lobes.robust.RobustLobes or None
    """
    answer = stability_lobes_answer(request, store=store, max_lines=max_lines)
    return answer.nominal, answer.robust


def stability_lobes_result(request: Mapping[str, Any], *, store: MeasurementSource | None = None,
                           max_lines: int = MAX_FREQUENCY_LINES) -> LobeResult:
    """The nominal stability lobes of a request (:func:`stability_lobes_results`, robust ones left out).

    Returns
    -------
    rcsa.analysis.lobes.zoa.LobeResult
    """
    return stability_lobes_results(request, store=store, max_lines=max_lines)[0]


def resolve_lobes_references(request: Mapping[str, Any], *, store: MeasurementSource | None = None,
                             libraries: LibraryStore | None = None) -> dict[str, Any]:
    """A stability-lobes request whose references to stored things are replaced by what they name.

    Resolved before the request is parsed (:mod:`rcsa.analysis.lobes.request` never sees them),
    so that everything after — budget, validation, a job — works on an ordinary request:

    * ``"library_tool": {"library_id": ..., "tool_id": ...}`` — a tool of a stored library's last
      sync: becomes the ``assembly`` (the sync's spindle, grid, materials with the tool's holder,
      tool and joints; :meth:`rcsa.libraries.sync.LibraryStore.tool_assembly`), and ``teeth``
      defaults to the tool's flute count;
    * ``"frf_x": {"measurement_id": ...}`` (and ``frf_y``) — a stored measurement's driving-point
      receptance ``h``, taken as the tool-point FRF as it is (e.g. a tap test kept in the store).

    Parameters
    ----------
    request : mapping
        The lobes request (contract "Stability lobes", with the references above).
    store : MeasurementSource, optional
        Where measurements are read.
    libraries : LibraryStore, optional
        Where stored libraries are read (default: those of ``store``, or of the default store).

    Returns
    -------
    dict
        The request with the references replaced (the same object's keys otherwise).

    Raises
    ------
    InputError
        A reference beside what it replaces (``library_tool`` with ``assembly`` or an FRF), a
        measurement without ``h``, a tool without an assembly; a library, tool or measurement
        that does not exist (naming the reference, as an unknown spindle measurement is).
    """
    out = dict(request)
    ref = out.pop("library_tool", None)
    if ref is not None:
        clash = [k for k in ("assembly", "frf_x", "frf_y") if out.get(k) is not None]
        if clash:
            raise InputError("library_tool", f"give either library_tool or {clash[0]}, not both")
        if not isinstance(ref, Mapping) or set(ref) != {"library_id", "tool_id"}:
            raise InputError("library_tool", 'must be {"library_id": ..., "tool_id": ...}')
        if libraries is None:
            libraries = library_store(getattr(store, "path", None))
        try:
            assembly, tool = libraries.tool_assembly(str(ref["library_id"]), str(ref["tool_id"]))
        except NotFoundError as exc:  # a reference to nothing is invalid input, as an unknown spindle is
            field = "library_tool.library_id" if exc.what == "library" else "library_tool.tool_id"
            raise InputError(field, f"{exc}: list them with GET /v1/libraries/{{library_id}}") from None
        out["assembly"] = assembly
        if out.get("teeth") is None and tool.get("teeth"):
            out["teeth"] = tool["teeth"]
    for key in ("frf_x", "frf_y"):
        frf = out.get(key)
        if isinstance(frf, Mapping) and "measurement_id" in frf:
            if set(frf) != {"measurement_id"}:
                raise InputError(key, "a stored FRF is given by measurement_id alone")
            out[key] = _stored_frf(store, str(frf["measurement_id"]), key)
    return out


def _stored_frf(store: MeasurementSource | None, measurement_id: str, field: str) -> dict[str, Any]:
    """A stored measurement's ``h`` as an inline FRF ``{"frequency_hz", "h": {"real", "imag"}}``."""
    from rcsa.model.wire import complex_to_wire as _complex_to_wire

    try:
        measurement = (store if store is not None else open_store(None)).get(measurement_id)
    except NotFoundError as exc:  # as an unknown spindle measurement is
        raise InputError(f"{field}.measurement_id", f"{exc}: list them with GET /v1/measurements") from None
    h = measurement.frfs.get("h")
    if h is None:
        raise InputError(f"{field}.measurement_id", f"measurement {measurement_id} holds no driving-point receptance "
                                                   f"h (it holds {', '.join(sorted(measurement.frfs))})")
    return {"frequency_hz": np.asarray(measurement.frequency_hz, dtype=float).tolist(),
            "h": _complex_to_wire(h)}


def stability_lobes(request: Mapping[str, Any], *, store: MeasurementSource | None = None,
                    max_lines: int = MAX_FREQUENCY_LINES, within: Limits | None = None,
                    backend: Backend | None = None) -> dict[str, Any]:
    """The contract's stability-lobes response (see :func:`stability_lobes_result`).

    Parameters
    ----------
    request : dict
        Inline FRFs or an ``assembly``, with the cutting parameters (contract "Stability lobes").
    store : MeasurementStore, optional
        Where a measured spindle of the assembly is looked up (the default store when omitted).
    max_lines : int
        Largest accepted number of frequency lines.
    within : Limits, optional
        The limits of the answer (:func:`stability_lobes_answer`).
    backend : Backend, optional
        Worker processes or a Dask cluster that share a semi-discretization's speeds
        (:func:`spread_sdm_solver`; default: this process).

    Returns
    -------
    dict
        ``spindle_speed_rpm``, ``depth_limit_m``, ``chatter_frequency_hz``, ``lobes`` and
        the extras of :class:`rcsa.analysis.lobes.zoa.LobeResult` (``frf_y_source``, minimum depth, …),
        ``notes`` and, with an assembly, ``flute_length_m`` (:class:`LobesAnswer`); with
        ``uncertainty``, also ``depth_limit_robust_m`` and ``robust``
        (:class:`rcsa.analysis.lobes.robust.RobustLobes`).
    """
    return stability_lobes_answer(request, store=store, max_lines=max_lines, within=within, backend=backend).to_dict()


def effects(request: Mapping[str, Any], *, store: MeasurementSource | None = None,
            progress: Progress | None = None) -> dict[str, Any]:
    """Effect analysis: sensitivity of each mode to every bearing and joint parameter.

    See :func:`rcsa.analysis.effects.sensitivities.effects` (request: an assembly, or ``{"assembly",
    "parameters", "relative_step", "band_hz"}``). ``store`` is where a measured spindle
    (``"spindle": {"measurement_id": ...}``) is looked up (the default store when omitted);
    ``progress(done, total)`` is called at each step (:mod:`rcsa.analysis.progress`).
    """
    from rcsa.analysis.effects.sensitivities import effects as run

    return run(request, resolver(store), progress)


def identify(request: Mapping[str, Any], *, store: MeasurementSource | None = None,
             progress: Progress | None = None) -> dict[str, Any]:
    """Joint identification from measured tool-point FRFs (``docs/contract.md`` "Joint identification").

    See :func:`rcsa.analysis.joint_identification.identify.identify`; ``store`` is where a
    measured spindle is looked up (the default store when omitted); ``progress(done, total)``
    is called at each step (:mod:`rcsa.analysis.progress`).
    """
    # scipy.optimize (~0.4 s to import): only when an identification is asked for
    from rcsa.analysis.joint_identification.identify import identify as run

    return run(request, resolver(store), progress)


def diagnose(request: Mapping[str, Any], *, store: MeasurementSource | None = None,
             progress: Progress | None = None) -> dict[str, Any]:
    """Sim-to-real gap diagnosis (``docs/contract.md`` "Diagnosis").

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
    # the diagnosis's modules only when a diagnosis is asked for (they no longer load SciPy)
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
        from rcsa.model.uncertainty import parse_prediction_request

        parse_prediction_request(request)  # the option is checked against the spindle and the grid
    # prediction and effects: the budget's estimate already parsed the assembly


def run_analysis(kind: str, request: Mapping[str, Any], *, store: MeasurementSource | None = None,
                 max_lines: int = MAX_FREQUENCY_LINES, backend: Backend | None = None) -> dict[str, Any]:
    """Run one of :data:`ANALYSIS_KINDS` and return its result document (a job's result).

    ``backend`` (a job's: the service's Dask cluster when it has one) shares a lobes request's
    semi-discretization among its workers (:func:`spread_sdm_solver`); the other kinds run here.

    Raises
    ------
    InputError
        An unknown kind, or an invalid request.
    """
    if kind == "prediction":
        from rcsa.app.predictions import predict

        return predict(request, store=store, max_lines=max_lines).to_dict()
    if kind == "lobes":
        from rcsa.app.budget import JOB

        return stability_lobes(request, store=store, max_lines=max_lines, within=JOB, backend=backend)
    if kind == "effects":
        return effects(request, store=store)
    if kind == "identification":
        return identify(request, store=store)
    if kind == "diagnosis":
        return diagnose(request, store=store)
    raise InputError("kind", f"no analysis {kind!r} (known: {', '.join(ANALYSIS_KINDS)})")
