"""The compute budget of every operation: what a request will cost, known before it runs.

A request that passes validation may still ask for hours of work or gigabytes of memory
(a 5 Hz–10 MHz grid, 40 000 holder segments, 5 000 Monte-Carlo draws). Each operation has a
*cost model* here that reads the request's sizes — frequency lines, beam elements (and how
finely a beam must be cut at the band's top for exact natural frequencies), modes,
parameters, measurements, draws, combinations, speeds — and estimates the compute seconds
and the peak memory the work will take on the reference machine (2 cores, Python 3.11;
constants below, calibrated by ``benchmarks/bench_budget.py``). :func:`check` compares the
estimate with the limits of how the work is asked for, **before any work starts**:

* :data:`SYNC` — a request answered at once (every anonymous HTTP request unless it asks
  for a job): ≤ 20 s estimated, ≤ 1 GiB estimated. Whatever fits, runs; nothing that fits
  can take more than the stated bound :data:`STATED_SYNC_BOUND` (60 s CPU, 1.5 GiB peak
  RSS: the estimate's margin, checked by ``tests/service/test_budget.py``).
* :data:`JOB` — the same work queued as a job (``Prefer: respond-async``): ≤ 1 h, ≤ 4 GiB.

Above the limit, :class:`BudgetExceeded` (an :class:`~rcsa.errors.InputError`, a 422 in the
service) names the limit, the request's cost and its terms, the fields that shrink it, and
how to run it as a job instead.

Extending: an operation (or a new option of one, e.g. another lobes method) registers its
cost model with :func:`cost_model`; the model receives the request document and returns a
:class:`Cost`. Options a model does not know cost nothing, so **a new option that adds work
must add its term here** (a lobes method: :data:`LOBE_METHOD_S`), and every option has a
bound in its parser.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any, Literal

import numpy as np

from rcsa.analysis.progress import time_limit
from rcsa.errors import InputError
from rcsa.model.assembly import build_model
from rcsa.model.contract import AssemblySpec, SpindleSpec, parse_assembly, parse_frequency
from rcsa.model.parameters import parameter_names
from rcsa.model.uncertainty import DEFAULT_DRAWS
from rcsa.physics.chain import Beam, Chain

__all__ = [
    "BODY_LIMITS",
    "JOB",
    "OPERATIONS",
    "SDM_COST",
    "STATED_SYNC_BOUND",
    "SYNC",
    "BudgetExceeded",
    "Cost",
    "Limits",
    "Mode",
    "SdmCostModel",
    "auto_lobes_fallback",
    "body_limit",
    "check",
    "check_work",
    "cost_model",
    "estimate",
    "held_result_bytes",
    "natural_frequency_seconds",
    "sdm_terms",
    "time_limited",
]

MiB = 1024 * 1024
GiB = 1024 * MiB

Mode = Literal["sync", "job"]


@dataclass(frozen=True)
class Limits:
    """What one request may cost: estimated compute seconds and peak memory, bytes."""

    seconds: float
    memory_bytes: float


#: A request answered at once.
SYNC = Limits(seconds=20.0, memory_bytes=1.0 * GiB)
#: The same work run as a job (its runtime is also bounded by the job queue).
JOB = Limits(seconds=3600.0, memory_bytes=4.0 * GiB)
#: What no synchronous request inside :data:`SYNC` can exceed, measured: CPU seconds and
#: peak resident memory of the process (the estimate's margin covers load and error).
STATED_SYNC_BOUND = Limits(seconds=60.0, memory_bytes=1.5 * GiB)

#: Largest request body of each operation's endpoint, bytes (the service states them in the
#: OpenAPI as ``x-max-body-bytes``). An assembly with the most segments is ~0.2 MB and a
#: 200 000-line grid given as values ~4 MB; analyses carry up to 20 measured FRFs.
BODY_LIMITS: dict[str, int] = {
    "prediction": 8 * MiB,
    "lobes": 16 * MiB,
    "effects": 8 * MiB,
    "identification": 32 * MiB,
    "diagnosis": 32 * MiB,
    "plot": 16 * MiB,
    "batch": 64 * MiB,
    "library": 64 * MiB,
    "measurement": 64 * MiB,
}

# ---------------------------------------------------------------------------- calibration
# Seconds on the reference machine (benchmarks/bench_budget.py prints the fit):
#: Exact receptance of one beam element on one frequency line (a 4×4 condensation step).
K_LINE_S = 2.0e-7
#: Natural frequencies (Wittrick–Williams bisection): per element of the chain cut for the
#: band's top frequency, and per such element and mode (modes ≈ those elements).
K_NF_ELEMENT_S = 1.8e-3
K_NF_MODE_S = 4.2e-6
#: Memory per frequency line of a prediction (result and condensation workspaces), bytes.
MEM_LINE_BYTES = 3072.0
#: Memory of the process that is not the request's (libraries, caches), bytes.
MEM_BASE_BYTES = 64.0 * MiB
#: Batches, fitted to the peaks ``benchmarks/bench_memory.py`` measures (10–2 000 tools,
#: 1 000–20 000 lines, as jobs and answered at once) and raised ~10 % so that none is above
#: its estimate: a chunk of tools is computed at a time (:func:`rcsa.libraries.chunks.chunk_size`),
#: bytes per line (the spindle side's condensation, the grid), per tool and line of the
#: chunk in flight (its receptances, the stacked march's workspaces, the results being
#: written), per tool of the batch (its parsed combination and result summary), and, for an
#: answer given at once, per tool and line of the whole result held (four complex
#: receptances as arrays, then as JSON text while it is serialised).
MEM_BATCH_FIXED_BYTES = 4.0 * MiB
MEM_BATCH_LINE_BYTES = 2100.0
MEM_CHUNK_TOOL_LINE_BYTES = 225.0
MEM_TOOL_BYTES = 17_600.0
MEM_RESULT_TOOL_LINE_BYTES = 240.0


@dataclass(frozen=True)
class Cost:
    """The estimated cost of one request.

    Attributes
    ----------
    operation : str
    seconds : float
        Estimated compute seconds on the reference machine.
    memory_bytes : float
        Estimated peak memory of the work, bytes.
    terms : dict
        The sizes the estimate is made of (``lines``, ``elements``, ``draws`` …).
    shrink : tuple of str
        What to reduce (request fields, in words) to make it cheaper.
    """

    operation: str
    seconds: float
    memory_bytes: float
    terms: Mapping[str, float] = field(default_factory=dict)
    shrink: tuple[str, ...] = ()

    def to_dict(self) -> dict[str, Any]:
        """JSON form (in problem documents)."""
        return {"operation": self.operation, "estimated_seconds": round(self.seconds, 3),
                "estimated_memory_bytes": int(self.memory_bytes),
                "terms": {k: (int(v) if float(v).is_integer() else round(float(v), 6)) for k, v in self.terms.items()}}


class BudgetExceeded(InputError):
    """A request whose estimated cost exceeds the limits of how it was asked for.

    Attributes
    ----------
    cost : Cost
    limits : Limits
    mode : {"sync", "job"}
    """

    def __init__(self, cost: Cost, limits: Limits, mode: Mode, field_name: str = "") -> None:
        self.cost = cost
        self.limits = limits
        self.mode = mode
        over = []
        if cost.seconds > limits.seconds:
            over.append(f"about {cost.seconds:.3g} s of computation, above the {limits.seconds:g} s")
        if cost.memory_bytes > limits.memory_bytes:
            over.append(f"about {cost.memory_bytes / MiB:.0f} MiB of memory, above the "
                        f"{limits.memory_bytes / MiB:.0f} MiB")
        terms = ", ".join(f"{k} {v:g}" for k, v in cost.terms.items())
        where = "a request answered at once" if mode == "sync" else "a job"
        advice = (f"Send it with the header Prefer: respond-async to run it as a job (up to {JOB.seconds:g} s and "
                  f"{JOB.memory_bytes / GiB:g} GiB), or make it smaller"
                  if mode == "sync" and cost.seconds <= JOB.seconds and cost.memory_bytes <= JOB.memory_bytes
                  else "Make it smaller")
        shrink = f": {'; '.join(cost.shrink)}" if cost.shrink else ""
        super().__init__(field_name, f"this {cost.operation} needs {' and '.join(over)} that {where} may use "
                                     f"(estimated from {terms}). {advice}{shrink}")


CostModel = Callable[[Mapping[str, Any]], Cost]
OPERATIONS: dict[str, CostModel] = {}


def cost_model(operation: str) -> Callable[[CostModel], CostModel]:
    """Register the cost model of ``operation`` (decorator); the last registration wins."""
    def register(fn: CostModel) -> CostModel:
        OPERATIONS[operation] = fn
        return fn
    return register


def estimate(operation: str, request: Mapping[str, Any]) -> Cost:
    """The estimated cost of ``request`` for ``operation``.

    Raises
    ------
    InputError
        The request is invalid where the estimate needs it (the same error the operation
        would raise), or the operation has no cost model.
    """
    model = OPERATIONS.get(operation)
    if model is None:
        raise InputError("", f"no cost model for operation {operation!r}")
    if not isinstance(request, Mapping):
        raise InputError("", "the request must be a JSON object")
    return model(request)


def check(operation: str, request: Mapping[str, Any], *, mode: Mode = "sync",
          limits: Limits | None = None) -> Cost:
    """Estimate ``request`` and refuse it when it exceeds the limits of ``mode``.

    Parameters
    ----------
    operation : str
        A key of :data:`OPERATIONS` (``prediction``, ``batch``, ``library``, ``lobes``,
        ``effects``, ``identification``, ``diagnosis``).
    request : mapping
        The request document.
    mode : {"sync", "job"}
    limits : Limits, optional
        Default :data:`SYNC` or :data:`JOB`.

    Returns
    -------
    Cost

    Raises
    ------
    BudgetExceeded
    """
    lim = limits if limits is not None else (SYNC if mode == "sync" else JOB)
    cost = estimate(operation, request)
    if operation == "lobes" and not _within(cost, lim) and auto_lobes_fallback(request, lim) is not None:
        cost = estimate(operation, {**request, "method": "zoa"})  # what "auto" will run within them
    if not _within(cost, lim):
        raise BudgetExceeded(cost, lim, mode)
    return cost


def _within(cost: Cost, limits: Limits) -> bool:
    return cost.seconds <= limits.seconds and cost.memory_bytes <= limits.memory_bytes


def auto_lobes_fallback(request: Mapping[str, Any], limits: Limits) -> str | None:
    """Why ``"method": "auto"`` answers zero-order lobes within ``limits`` (None: it does not).

    ``auto`` picks the resolved semi-discretization wherever zero-order averaging is not exact
    (:func:`rcsa.analysis.lobes.options.auto_method`). Where that costs more than ``limits`` (a
    synchronous answer's, :data:`SYNC`) and the zero-order lobes do not, the answer is zero-order,
    says so, and marks every speed unresolved: a caller who needs resolved limits sends the
    request as a job (``Prefer: respond-async``) or with fewer speeds. A request that names its
    method is never changed.

    Parameters
    ----------
    request : mapping
        A stability-lobes request.
    limits : Limits

    Returns
    -------
    str or None
    """
    if request.get("method", "auto") != "auto":
        return None
    try:
        from rcsa.analysis.lobes.options import auto_method, teeth_in_cut

        teeth, immersion = int(request.get("teeth", 1)), float(request.get("radial_immersion", 1.0))
        if auto_method(teeth, immersion)[0] != "semi_discretization":
            return None
        sdm = estimate("lobes", {**request, "method": "semi_discretization"})
        zoa = estimate("lobes", {**request, "method": "zoa"})
    except (InputError, TypeError, ValueError, ArithmeticError):
        return None  # the parser says why
    if _within(sdm, limits) or not _within(zoa, limits):
        return None
    return (f"auto: the resolved semi-discretization of these {sdm.terms.get('speeds', 0):.0f} speeds is estimated "
            f"at {sdm.seconds:.0f} s and {sdm.memory_bytes / GiB:.1f} GiB, beyond the {limits.seconds:g} s and "
            f"{limits.memory_bytes / GiB:g} GiB of an answer given at once: zero-order limits instead, not checked "
            f"against it, every speed marked unresolved (with {teeth_in_cut(teeth, immersion):.2f} teeth in the cut "
            "zero-order limits may lie tens of percent from the resolved ones at single speeds: docs/presets.md 'Which "
            "method'); for resolved limits send the request as a job (Prefer: respond-async) or with fewer speeds")


def time_limited(seconds: float | None) -> Any:
    """A context manager: what runs inside stops at its next step boundary once ``seconds``
    have passed, raising :class:`~rcsa.errors.TimeLimitExceeded` (None: no limit). The
    service runs every answer given at once inside it (``RCSA_SYNC_TIME_LIMIT_S``).

    Returns
    -------
    contextlib.AbstractContextManager
    """
    return time_limit(seconds)


def body_limit(operation: str) -> int:
    """Largest request body of ``operation``'s endpoint, bytes (:data:`BODY_LIMITS`)."""
    return BODY_LIMITS[operation]


# ---------------------------------------------------------------------------- sizes


def natural_frequency_seconds(effective_elements: float) -> float:
    """Estimated seconds of one exact natural-frequency search over a chain cut into
    ``effective_elements`` pieces for its band (modes ≈ pieces)."""
    return effective_elements * (K_NF_ELEMENT_S + K_NF_MODE_S * effective_elements)


def _effective_elements(chain: Chain, top_hz: float) -> float:
    """Elements of ``chain`` once its beams are cut for exact counting up to ``top_hz``
    (as :func:`rcsa.physics.elimination.subdivide` would, without building the pieces)."""
    omega = 2.0 * math.pi * top_hz
    n = 0.0
    for item in chain:
        if isinstance(item, Beam):
            n += max(1.0, math.ceil(float(np.max(item.length_m)) / item.max_piece_length_m(omega)))
        else:
            n += 1.0
    return n


def _chain(spec: AssemblySpec) -> Chain:
    # a measured spindle without a holder is a holder_tip measurement (its holder is inside it)
    return build_model(spec, base_plane="holder_tip" if spec.holder is None else None).chain()


def _assembly_cost(spec: AssemblySpec, *, natural_frequencies: bool = True) -> tuple[float, float, dict[str, float]]:
    """Seconds and bytes of one prediction, and its terms."""
    chain = _chain(spec)
    lines = float(spec.frequency_hz.size)
    top = float(spec.frequency_hz[-1])
    elements = float(len(chain))
    effective = _effective_elements(chain, top) if natural_frequencies and isinstance(spec.spindle, SpindleSpec) \
        else elements
    seconds = K_LINE_S * elements * lines + (natural_frequency_seconds(effective) if natural_frequencies else 0.0)
    return seconds, MEM_BASE_BYTES + MEM_LINE_BYTES * lines, {
        "lines": lines, "elements": elements, "elements_cut_for_modes": effective}


def _draws(request: Mapping[str, Any]) -> float:
    """Monte-Carlo draws an ``uncertainty`` option asks for (0 without one; its default when unset)."""
    option = request.get("uncertainty")
    if not isinstance(option, Mapping):
        return 0.0
    draws = option.get("draws", DEFAULT_DRAWS)
    return float(draws) if isinstance(draws, int | float) and not isinstance(draws, bool) else float(DEFAULT_DRAWS)


def _with_draws(seconds: float, memory: float, terms: dict[str, float], draws: float
                ) -> tuple[float, float, dict[str, float]]:
    """A prediction's cost with ``draws`` drawn assemblies: each costs one march of the chain over
    the grid (the stacked march is vectorised as the plain one is, not cheaper per line), plus
    the draws' tool-point ``h`` kept (16 bytes per draw and line) and their modes. Priced for
    ``"solver": "exact"``: an upper bound for the reduced model of the draws (the default,
    :mod:`rcsa.model.reduced_draws`), which solves each draw on a few percent of the lines."""
    if not draws:
        return seconds, memory, terms
    per_draw = K_LINE_S * terms["elements"] * terms["lines"]
    return (seconds + draws * (per_draw + K_NF_MODE_S * terms["elements"]),
            memory + 16.0 * draws * terms["lines"] * 4.0, {**terms, "draws": draws})


_DRAWS_SHRINK = ("fewer draws (uncertainty.draws)",)

_ASSEMBLY_SHRINK = ("fewer frequency lines (frequency)", "a lower top frequency (natural frequencies are found "
                    "exactly up to it)", "fewer holder or spindle segments")


def _parse(document: object, prefix: str = "") -> AssemblySpec:
    try:
        return parse_assembly(document)
    except InputError as exc:
        if not prefix:
            raise
        raise InputError(f"{prefix}.{exc.field}".rstrip("."), exc.rule) from None


# ---------------------------------------------------------------------------- operations


@cost_model("prediction")
def _prediction(request: Mapping[str, Any]) -> Cost:
    spec = _parse({k: v for k, v in request.items() if k != "uncertainty"})
    seconds, memory, terms = _with_draws(*_assembly_cost(spec), _draws(request))
    return Cost("prediction", seconds, memory, terms, (*_DRAWS_SHRINK, *_ASSEMBLY_SHRINK) if _draws(request)
                else _ASSEMBLY_SHRINK)


def _count(value: object) -> int:
    return len(value) if isinstance(value, list) else 0


def _holder_segments(combo: object) -> int:
    holder = combo.get("holder") if isinstance(combo, Mapping) else None
    return _count(holder.get("segments")) if isinstance(holder, Mapping) else 0


@cost_model("batch")
def _batch(request: Mapping[str, Any]) -> Cost:
    """Every combination costs a prediction; the one with the most holder segments stands
    for all (they share the spindle and the band)."""
    combos = request.get("combinations")
    combos = combos if isinstance(combos, list) else []
    if not combos:
        return Cost("batch", 0.0, MEM_BASE_BYTES, {"combinations": 0.0})
    # memory: one chunk of tools in flight (the result is streamed; an answer given at once
    # adds the whole result held, in check_work), plus one prediction's workspaces
    worst = max(range(len(combos)), key=lambda i: _holder_segments(combos[i]))
    base = {k: v for k, v in request.items() if k not in ("combinations", "options", "natural_frequencies",
                                                           "uncertainty")}
    combo = combos[worst]
    n = float(len(combos))
    shrink: tuple[str, ...] = ("fewer combinations (split the batch)", *_ASSEMBLY_SHRINK)
    try:
        spec = parse_assembly({**base, **{k: v for k, v in combo.items() if k not in ("id", "name")}})
    except (InputError, TypeError, AttributeError):  # that combination is refused by the batch itself
        lines = float(parse_frequency(request.get("frequency")).size)
        elements = 30.0 + _holder_segments(combo)
        seconds = n * (K_LINE_S * elements * lines + natural_frequency_seconds(elements))
        return Cost("batch", seconds, MEM_BASE_BYTES + _chunk_bytes(n, lines),
                    {"combinations": n, "lines": lines, "elements": elements}, shrink)
    seconds, memory, terms = _with_draws(*_assembly_cost(spec, natural_frequencies=request.get(
        "natural_frequencies", True) is not False), _draws(request))
    if _draws(request):
        shrink = (*_DRAWS_SHRINK, *shrink)
    from rcsa.libraries.chunks import chunk_size

    draws_bytes = memory - MEM_BASE_BYTES - MEM_LINE_BYTES * terms["lines"]  # each tool's drawn FRFs, if any
    in_flight = min(n, float(chunk_size(int(terms["lines"]))))
    return Cost("batch", seconds * n, MEM_BASE_BYTES + _chunk_bytes(n, terms["lines"]) + draws_bytes * in_flight,
                {"combinations": n, **terms}, shrink)


def _chunk_bytes(tools: float, lines: float) -> float:
    """Memory of a batch computed chunk by chunk (:func:`rcsa.libraries.chunks.chunk_size`),
    its result streamed: the grid, the chunk of tools in flight and every tool's summary."""
    from rcsa.libraries.chunks import chunk_size

    in_flight = min(tools, float(chunk_size(int(lines))))
    return (MEM_BATCH_FIXED_BYTES + lines * MEM_BATCH_LINE_BYTES + in_flight * lines * MEM_CHUNK_TOOL_LINE_BYTES
            + tools * MEM_TOOL_BYTES)


def held_result_bytes(tools: float, lines: float) -> float:
    """Memory of a batch result held whole (an answer given at once), bytes."""
    return tools * lines * MEM_RESULT_TOOL_LINE_BYTES


@cost_model("library")
def _library(request: Mapping[str, Any]) -> Cost:
    """Like a batch whose tools each have a holder of up to ~60 cylinders (cones cut into
    ``holder_segments_per_cone``)."""
    library = request.get("library")
    items = library.get("data") if isinstance(library, Mapping) else None
    n = float(len(items)) if isinstance(items, list) else 1.0
    lines = float(parse_frequency(request.get("frequency")).size) if isinstance(request.get("frequency"), Mapping) \
        else 1.0
    elements = 80.0
    seconds = n * (K_LINE_S * elements * lines + natural_frequency_seconds(elements))
    return Cost("library", seconds, MEM_BASE_BYTES + _chunk_bytes(n, lines),
                {"tools": n, "lines": lines, "elements": elements}, ("fewer tools", "fewer frequency lines"))


#: Estimated seconds per speed and frequency line of each lobes method (``method``); the
#: semi-discretization is priced by :data:`SDM_COST` on top of its line term.
LOBE_METHOD_S: dict[str, float] = {"zoa": 1.0e-9, "semi_discretization": 1.0e-9}


@dataclass(frozen=True)
class SdmTerms:
    """What a semi-discretization request will solve, known before it runs.

    Attributes
    ----------
    speeds : float
    step_sum : float
        ``Σ_s k_s``: the steps of every speed (the steps that resolve the cut,
        :func:`rcsa.analysis.lobes.semi_discretization.resolving_steps`, or ``steps_per_period``).
    step_max : float
        The largest ``k_s``.
    states : float
        ``n``: twice the modes in x and y (an upper bound: every mode of the band, at most
        ``modes_per_direction`` per direction).
    """

    speeds: float
    step_sum: float
    step_max: float
    states: float


@dataclass(frozen=True)
class SdmCostModel:
    """What semi-discretization lobes cost, from :class:`SdmTerms`.

    The search evaluates the period map ``E`` times per speed on average (the scan, the bracket,
    the check at a second resolution and the refinements it may ask for); an evaluation of a speed
    with ``k`` steps builds ``k`` step exponentials of the ``n``-state system (``n³`` each), a
    blocked period map (``n²·k``) and runs Arnoldi on it; every round of evaluations also passes over
    the steps in Python. Hence::

        seconds = (1 + draws) · (E · Σ_s k_s · (per_square_s · n² + per_cube_s · n³)
                                 + rounds · per_round_step_s · k_max)
        memory  = min(speeds · mem_pair_step_bytes · k_max · n (n + 8), chunk_bytes) + speeds · mem_speed_bytes

    (the evaluations run in chunks of at most ``chunk_bytes`` of period maps).

    The constants are fitted by ``.venv/bin/python benchmarks/bench_budget.py --fit-sdm`` (CPU
    seconds and peak RSS measured over a grid of cuts, speeds and modes, each in a fresh process;
    the fit is scaled so that no measured point exceeds its estimate), which prints the line to
    paste here; refit after any change of the solver (``--check-sdm`` compares).
    """

    evaluations: float
    per_square_s: float
    per_cube_s: float
    rounds: float
    per_round_step_s: float
    mem_pair_step_bytes: float
    mem_speed_bytes: float
    chunk_bytes: float = 3.0 * 96 * 2**20

    def seconds(self, t: SdmTerms, draws: float = 0.0) -> float:
        """Estimated CPU seconds on the reference machine."""
        n = t.states
        work = self.evaluations * t.step_sum * (self.per_square_s * n * n + self.per_cube_s * n**3)
        return (1.0 + draws) * (work + self.rounds * self.per_round_step_s * t.step_max)

    def memory_bytes(self, t: SdmTerms) -> float:
        """Estimated peak memory of the search, bytes (beyond the process's base)."""
        chunk = t.speeds * self.mem_pair_step_bytes * t.step_max * t.states * (t.states + 8.0)
        return min(chunk, self.chunk_bytes) + t.speeds * self.mem_speed_bytes


#: The semi-discretization's constants, fitted by ``benchmarks/bench_budget.py --fit-sdm`` on 12 grid points
#: (RA-1, 20–500 speeds from 1 000–8 000 rpm to 30 000, 1–4 teeth, a/D 0.05–0.5, 1–8 modes a direction, the
#: default steps; load 4.2–4.5 on the 2-core VM, ``benchmarks/results/budget_sdm.json``): estimates 1.0–3.5×
#: the measured CPU seconds, 1.0–2.5× the measured peak RSS (none below it).
SDM_COST = SdmCostModel(evaluations=14.0, per_square_s=1.0e-7, per_cube_s=0.0, rounds=1.0, per_round_step_s=0.0031,
                        mem_pair_step_bytes=1.8, mem_speed_bytes=7.6e5)


def _speeds_of(request: Mapping[str, Any]) -> Any:
    """The request's speed grid as an array (empty when it cannot be read: the parser says why)."""
    import numpy as np

    value = request.get("spindle_speed_rpm")
    try:
        if isinstance(value, list):
            grid = np.asarray(value, dtype=float)
        elif isinstance(value, Mapping):
            grid = np.linspace(float(value["start"]), float(value["stop"]), int(value["count"]))
        else:
            return np.empty(0)
    except (KeyError, TypeError, ValueError, OverflowError, MemoryError):
        return np.empty(0)
    return grid[np.isfinite(grid) & (grid > 0)] if grid.ndim == 1 and grid.size <= 10**6 else np.empty(0)


def _modal_extent(request: Mapping[str, Any], modes_cap: int) -> tuple[float, float]:
    """``(f_top, modes per direction)`` bounds of a lobes request before anything is solved: a
    modal table's own; an inline FRF's highest frequency line; an assembly's band top and the
    number of its natural frequencies in the band (an analytical spindle), at most ``modes_cap``."""
    table = request.get("modal_x")
    if isinstance(table, list):
        freqs = [float(m.get("frequency_hz", 0.0)) for m in table if isinstance(m, Mapping)
                 and isinstance(m.get("frequency_hz"), int | float)]
        y = request.get("modal_y")
        freqs += [float(m.get("frequency_hz", 0.0)) for m in (y if isinstance(y, list) else [])
                  if isinstance(m, Mapping) and isinstance(m.get("frequency_hz"), int | float)]
        count = max(len(table), len(y) if isinstance(y, list) else 0)
        return (max(freqs) if freqs else 1.0), float(min(count, modes_cap))
    frf = request.get("frf_x")
    if isinstance(frf, Mapping):
        peaks = [_frf_peaks_hz(frf, modes_cap)] + ([_frf_peaks_hz(request["frf_y"], modes_cap)]
                                                   if isinstance(request.get("frf_y"), Mapping) else [])
        if all(p is not None for p in peaks):
            found = [p for p in peaks if p]
            return (max(max(p) for p in found) if found else 1.0), float(max((len(p) for p in found), default=1))
        f = frf.get("frequency_hz")
        top = max((float(v) for v in f if isinstance(v, int | float)), default=1.0) if isinstance(f, list) else 1.0
        return top, float(modes_cap)
    assembly = request.get("assembly")
    if isinstance(assembly, Mapping):
        try:
            spec = _parse(assembly, "assembly")
        except InputError:
            return 1.0, float(modes_cap)
        top = float(spec.frequency_hz[-1])
        if isinstance(spec.spindle, SpindleSpec):
            from rcsa.physics.natural_frequencies import natural_frequencies_hz

            count = natural_frequencies_hz(_chain(spec), float(spec.frequency_hz[0]), top).size
            return top, float(min(max(count, 1), modes_cap))
        return top, float(modes_cap)
    return 1.0, float(modes_cap)


def _frf_peaks_hz(frf: Mapping[str, Any], modes_cap: int) -> list[float] | None:
    """The peaks an inline FRF's modal fit will keep (None where the FRF cannot be read: the
    estimate then assumes the most modes up to the highest line, and the parser says why)."""
    import numpy as np

    from rcsa.analysis.lobes.modal_model import kept_peaks_hz

    try:
        h = frf["h"]
        f = np.asarray(frf["frequency_hz"], dtype=float)
        values = np.asarray(h["real"], dtype=float) + 1j * np.asarray(h["imag"], dtype=float)
        if f.ndim != 1 or f.shape != values.shape or f.size < 3 or not np.all(np.isfinite(f)) \
                or not np.all(np.isfinite(values)) or not np.all(np.diff(f) > 0):
            return None
        return kept_peaks_hz(f, values, modes_cap)
    except (KeyError, TypeError, ValueError, OverflowError, MemoryError):
        return None


def sdm_terms(request: Mapping[str, Any]) -> SdmTerms:
    """:class:`SdmTerms` of a lobes request (its parsers say why, where it cannot be read)."""
    import numpy as np

    from rcsa.analysis.lobes.modal_model import ModalModel
    from rcsa.analysis.lobes.options import parse_method
    from rcsa.analysis.lobes.semi_discretization import cut_scheme, resolving_steps

    try:
        teeth, immersion = int(request.get("teeth", 1)), float(request.get("radial_immersion", 1.0))
        milling = str(request.get("milling", "down"))
        method = parse_method({**request, "method": "semi_discretization"}, teeth=teeth, radial_immersion=immersion)
        cut_scheme(teeth, immersion, milling)  # type: ignore[arg-type]
    except (InputError, TypeError, ValueError):  # the request's parser says why
        return SdmTerms(0.0, 0.0, 0.0, 0.0)
    speeds = _speeds_of(request)
    f_top, modes = _modal_extent(request, method.modes_per_direction)
    if method.steps_per_period is not None:
        steps = np.full(speeds.size, float(method.steps_per_period))
    elif speeds.size:
        probe = ModalModel.of([f_top], [0.02], [1.0], [0])
        steps = resolving_steps(probe, teeth, speeds, radial_immersion=immersion, milling=milling)  # type: ignore[arg-type]
    else:
        steps = np.zeros(0)
    return SdmTerms(float(speeds.size), float(steps.sum()), float(steps.max()) if steps.size else 0.0, 4.0 * modes)


@cost_model("lobes")
def _lobes(request: Mapping[str, Any]) -> Cost:
    seconds = 0.0
    memory = MEM_BASE_BYTES
    terms: dict[str, float] = {}
    if request.get("assembly") is not None:
        spec = _parse(request["assembly"], "assembly")
        seconds, memory, terms = _with_draws(*_assembly_cost(spec), _draws(request))
        lines = terms["lines"]
    else:
        frf = request.get("frf_x")
        lines = float(_count(frf.get("frequency_hz"))) if isinstance(frf, Mapping) else 0.0
        terms["lines"] = lines
    count = float(_speeds_of(request).size)
    method = request.get("method")
    name = "auto" if method is None else method
    if name == "auto":  # the method the request's parser will pick
        from rcsa.analysis.lobes.options import auto_method

        try:
            name = auto_method(int(request.get("teeth", 1)), float(request.get("radial_immersion", 1.0)))[0]
        except (TypeError, ValueError, ArithmeticError):
            name = "semi_discretization"  # the dearer one
    per = LOBE_METHOD_S.get(str(name), LOBE_METHOD_S["zoa"])
    seconds += per * count * max(lines, 1.0) * (1.0 + _draws(request))
    memory += 64.0 * count * (1.0 + _draws(request))
    shrink: tuple[str, ...] = ("fewer speeds (spindle_speed_rpm.count)", "fewer frequency lines")
    if name == "semi_discretization":
        from rcsa.analysis.lobes.robust_sdm import REDUCED_COST_DIAGRAMS

        t = sdm_terms(request)
        # robust: the reduced model of the draws solves a few diagrams more, whatever the draws
        extra = REDUCED_COST_DIAGRAMS if _draws(request) > 0 else 0.0
        seconds += SDM_COST.seconds(t, extra)
        memory += SDM_COST.memory_bytes(t)
        terms = {**terms, "steps_total": t.step_sum, "steps_max": t.step_max, "modal_states": t.states}
        shrink = ("fewer speeds (spindle_speed_rpm.count), or higher ones (fewer vibration cycles in a cut need "
                  "fewer steps)", "a lower top of the frequency band (the highest mode sets the steps)",
                  "fewer modes_per_direction")
    return Cost("lobes", seconds, memory, {**terms, "speeds": count}, shrink)


@cost_model("effects")
def _effects(request: Mapping[str, Any]) -> Cost:
    """Two perturbed natural-frequency searches per parameter, plus the nominal one, over
    the band (widened by 12 %)."""
    document = request.get("assembly", request)
    spec = _parse(document, "assembly" if "assembly" in request else "")
    params = request.get("parameters") if "assembly" in request else None
    n_params = float(len(params)) if isinstance(params, list) else float(len(parameter_names(spec)))
    band = request.get("band_hz") if "assembly" in request else None
    top = float(spec.frequency_hz[-1])
    if isinstance(band, list) and len(band) == 2 and all(isinstance(b, int | float) and not isinstance(b, bool)
                                                          for b in band):
        top = max(float(band[1]), 1.0e-3)
    top *= 1.12
    chain = _chain(spec)
    effective = _effective_elements(chain, top)
    runs = 1.0 + 2.0 * n_params
    seconds = runs * (natural_frequency_seconds(effective) + K_LINE_S * len(chain) * 400.0)
    return Cost("effects", seconds, MEM_BASE_BYTES + 4096.0 * effective * runs / 8.0,
                {"parameters": n_params, "band_top_hz": top, "elements_cut_for_modes": effective, "runs": runs},
                ("a narrower band (band_hz, or the assembly's frequency range): every mode in it is tracked",
                 "fewer parameters"))


def _taps(request: Mapping[str, Any]) -> list[Mapping[str, Any]]:
    taps = request.get("measurements")
    return [t for t in taps if isinstance(t, Mapping)] if isinstance(taps, list) else []


def _tap_lines(tap: Mapping[str, Any]) -> float:
    return float(_count(tap.get("frequency_hz")))


def _analysis_spec(request: Mapping[str, Any]) -> AssemblySpec:
    assembly = request.get("assembly")
    if not isinstance(assembly, Mapping):
        raise InputError("assembly", "is required (an object)")
    return _parse({"frequency": {"values_hz": [1.0]}, **assembly}, "assembly")


#: Estimated seconds of an identification per measurement and beam element.
K_IDENT_S = 0.05


@cost_model("identification")
def _identification(request: Mapping[str, Any]) -> Cost:
    spec = _analysis_spec(request)
    taps = _taps(request)
    elements = float(len(_chain(spec)))
    lines = sum(_tap_lines(t) for t in taps)
    n = float(len(taps))
    seconds = n * K_IDENT_S * elements + K_LINE_S * elements * lines * 20.0
    return Cost("identification", seconds, MEM_BASE_BYTES + 2048.0 * lines,
                {"measurements": n, "lines": lines, "elements": elements},
                ("fewer measurements", "fewer segments"))


#: Diagnosis, per beam element, configuration and (draw + fit equivalent): seconds per line
#: of the union grid, and seconds that do not grow with the grid; plus a fixed part.
K_DIAG_LINE_S = 2.5e-8
K_DIAG_CONFIG_S = 4.0e-5
K_DIAG_FIXED_S = 0.5
#: The candidate fits cost about as much as this many Monte-Carlo draws.
DIAG_FIT_DRAWS = 300.0
#: Memory per draw, configuration and line of the union grid, bytes (draws and features kept).
MEM_DIAG_BYTES = 100.0


def _union_lines(taps: list[Mapping[str, Any]], max_lines: float) -> float:
    """Lines of the grid a diagnosis solves on: the union of the lines picked from each
    measurement (at most ``max_lines`` each), bounded by the distinct frequencies given."""
    picked = sum(min(_tap_lines(t), max_lines) for t in taps)
    values = [t.get("frequency_hz") for t in taps]
    try:
        distinct = float(np.unique(np.concatenate([np.asarray(v, dtype=float) for v in values
                                                   if isinstance(v, list) and v])).size)
    except (ValueError, TypeError):  # not numbers: the parser says so
        return picked
    return min(picked, distinct)


@cost_model("diagnosis")
def _diagnosis(request: Mapping[str, Any]) -> Cost:
    """Every Monte-Carlo draw and every candidate fit solves each configuration (one per
    measurement) on the union of the lines picked from the measurements."""
    spec = _analysis_spec(request)
    taps = _taps(request)
    options = request.get("options") if isinstance(request.get("options"), Mapping) else {}
    assert isinstance(options, Mapping)
    draws = options.get("monte_carlo_draws", 200)
    draws = float(draws) if isinstance(draws, int | float) and not isinstance(draws, bool) else 200.0
    max_lines = options.get("max_lines", 1200)
    max_lines = float(max_lines) if isinstance(max_lines, int | float) and not isinstance(max_lines, bool) else 1200.0
    configs = float(len(taps))
    grid = _union_lines(taps, max_lines)
    elements = float(len(_chain(spec)))
    seconds = K_DIAG_FIXED_S + elements * configs * (draws + DIAG_FIT_DRAWS) * (K_DIAG_LINE_S * grid + K_DIAG_CONFIG_S)
    memory = MEM_BASE_BYTES + MEM_DIAG_BYTES * draws * configs * grid
    return Cost("diagnosis", seconds, memory,
                {"measurements": configs, "grid_lines": grid, "draws": draws, "elements": elements},
                ("fewer Monte-Carlo draws (options.monte_carlo_draws)", "fewer lines (options.max_lines)",
                 "fewer measurements"))


def check_work(kind: str, request: Mapping[str, Any], size: int, *, mode: Mode,
               limits: Limits | None = None) -> Cost:
    """:func:`check` for prepared batch, library and sync work (:class:`rcsa.app.jobs.Work`):
    its combinations form a batch (``request["batch"]``), of which ``size`` are computed (a
    sync computes only tools not in its cache). A job streams its result (one chunk of tools
    in memory); an answer given at once also holds the whole result (:func:`held_result_bytes`).

    Parameters
    ----------
    kind : {"batch", "library", "library-sync"}
    request : mapping
        The prepared work's request.
    size : int
        Combinations computed.
    mode : {"sync", "job"}
    limits : Limits, optional
        Default :data:`SYNC` or :data:`JOB`.

    Returns
    -------
    Cost

    Raises
    ------
    BudgetExceeded
    """
    inner = request.get("batch")
    batch = inner if isinstance(inner, Mapping) else request  # prepared work: {"entries", "batch"}
    if not isinstance(batch, Mapping):
        return Cost(kind, 0.0, MEM_BASE_BYTES)
    cost = estimate("batch", batch)
    combos = batch.get("combinations")
    n = len(combos) if isinstance(combos, list) else 0
    lines = float(cost.terms.get("lines", 0.0))
    if n and size != n:  # only ``size`` of them are computed
        cost = Cost(kind, cost.seconds * size / n,
                    cost.memory_bytes - _chunk_bytes(n, lines) + _chunk_bytes(size, lines),
                    {**cost.terms, "combinations": float(size)}, cost.shrink)
    if mode == "sync" and kind != "library-sync":  # a sync's answer is its report, not the results
        cost = Cost(kind, cost.seconds, cost.memory_bytes + held_result_bytes(size, lines), cost.terms, cost.shrink)
    lim = limits if limits is not None else (SYNC if mode == "sync" else JOB)
    if cost.seconds > lim.seconds or cost.memory_bytes > lim.memory_bytes:
        raise BudgetExceeded(cost, lim, mode)
    return cost
