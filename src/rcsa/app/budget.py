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
    cost = estimate(operation, request)
    lim = limits if limits is not None else (SYNC if mode == "sync" else JOB)
    if cost.seconds > lim.seconds or cost.memory_bytes > lim.memory_bytes:
        raise BudgetExceeded(cost, lim, mode)
    return cost


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
class SdmCostModel:
    """What semi-discretization lobes cost, from the request's speeds, steps and modes.

    The depth search evaluates the period map ~20 times per speed, all open speeds of a
    chunk at once; each evaluation loops over the ``k`` steps of a tooth period (a Python
    loop whose numpy calls cost about the same whatever the chunk), updates the modal state
    ``n = 4 m`` (``m`` modes per direction, x and y, position and velocity) on every step,
    couples the ``k_cut`` steps in cut to their delayed samples, and takes the eigenvalues of
    the period map of dimension ``D = n + 2 k_cut``. Hence, for ``S`` speeds (and ``draws``
    more diagrams: robust lobes add :data:`rcsa.analysis.lobes.robust_sdm.REDUCED_COST_DIAGRAMS`,
    whatever the number of drawn assemblies)::

        seconds = (1 + draws) · (per_step_s · k
                                 + S · (per_state_s · k·n + k_cut · (per_cut_s + per_cut_state_s · n)
                                        + per_eig_s · D³))
        memory  = min(S, chunk) · (mem_state_bytes · k·n + mem_cut_bytes · k_cut·n + mem_map_bytes · D²)
                  + S · mem_speed_bytes · k·n

    (the chunk in flight, and what every speed keeps for the whole search).

    The constants are fitted by ``.venv/bin/python benchmarks/bench_budget.py --fit-sdm``
    (non-negative least squares on the relative error of measured CPU seconds and peak RSS
    over a grid of speeds, ``steps_per_period``, ``modes_per_direction`` and immersions, then
    scaled up so that no measured point exceeds its estimate), which prints the line to
    paste here; refit after any change of the SDM solver (``--check-sdm`` compares the
    constants in force with new measurements).
    """

    per_step_s: float
    per_state_s: float
    per_cut_s: float
    per_cut_state_s: float
    per_eig_s: float
    mem_state_bytes: float
    mem_cut_bytes: float
    mem_map_bytes: float
    mem_speed_bytes: float
    chunk: int = 256

    def sizes(self, steps: float, modes: float, cut_fraction: float) -> tuple[float, float, float]:
        """``(n, k_cut, D)``: the modal state, the steps in cut and the period map's dimension."""
        n = 4.0 * modes
        k_cut = float(math.ceil(steps * min(1.0, max(cut_fraction, 1.0 / steps))))
        return n, k_cut, n + 2.0 * k_cut

    def seconds(self, speeds: float, steps: float, modes: float, cut_fraction: float, draws: float = 0.0) -> float:
        """Estimated CPU seconds on the reference machine."""
        n, k_cut, d = self.sizes(steps, modes, cut_fraction)
        per_speed = (self.per_state_s * steps * n + k_cut * (self.per_cut_s + self.per_cut_state_s * n)
                     + self.per_eig_s * d**3)
        return (1.0 + draws) * (self.per_step_s * steps + speeds * per_speed)

    def memory_bytes(self, speeds: float, steps: float, modes: float, cut_fraction: float) -> float:
        """Estimated peak memory of the search, bytes (beyond the process's base)."""
        n, k_cut, d = self.sizes(steps, modes, cut_fraction)
        return (min(speeds, self.chunk) * (self.mem_state_bytes * steps * n + self.mem_cut_bytes * k_cut * n
                                           + self.mem_map_bytes * d * d)
                + speeds * self.mem_speed_bytes * steps * n)


#: The semi-discretization's constants, fitted by ``benchmarks/bench_budget.py --fit-sdm`` on 18
#: grid points (20–1 000 speeds, k = 10–200, 1–8 modes per direction, a/D = 0.05–1; refitted after
#: the SDM was batched over speeds and tools, load 0.9–1.2 on the 2-core VM): estimates 1.0–2.2×
#: the measured CPU seconds, 1.00–1.27× the measured peak RSS (none below it).
SDM_COST = SdmCostModel(per_step_s=0.0012, per_state_s=0.0, per_cut_s=2.8e-05, per_cut_state_s=5.5e-06,
                        per_eig_s=9.5e-11, mem_state_bytes=0.0, mem_cut_bytes=5.7e+02, mem_map_bytes=1.0,
                        mem_speed_bytes=1.5e+02)


def sdm_terms(request: Mapping[str, Any]) -> tuple[float, float, float]:
    """``(steps_per_period, modes_per_direction, fraction of a tooth period in cut)`` of a lobes request."""
    from rcsa.analysis.lobes.options import parse_method
    from rcsa.analysis.lobes.zoa import engagement_angles_rad

    try:
        method = parse_method(request, teeth=int(request.get("teeth", 1)),
                              radial_immersion=float(request.get("radial_immersion", 1.0)))
    except (InputError, TypeError, ValueError):  # the request's parser says why
        method = parse_method({})
    try:
        phi_st, phi_ex = engagement_angles_rad(float(request.get("radial_immersion", 1.0)),
                                               str(request.get("milling", "down")))  # type: ignore[arg-type]
        teeth = float(request.get("teeth", 1))
        fraction = (phi_ex - phi_st) * teeth / (2.0 * math.pi)
    except (InputError, TypeError, ValueError):  # the request's parser says why
        fraction = 1.0
    return float(method.steps_per_period), float(method.modes_per_direction), fraction


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
    speeds = request.get("spindle_speed_rpm")
    count = speeds.get("count", 0) if isinstance(speeds, Mapping) else 0
    count = float(count) if isinstance(count, int | float) and not isinstance(count, bool) else 0.0
    method = request.get("method")
    name = method if isinstance(method, str) else (method.get("name", "zoa") if isinstance(method, Mapping) else "zoa")
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

        steps, modes, fraction = sdm_terms(request)
        # robust: the reduced model of the draws solves a few diagrams more, whatever the draws
        extra = REDUCED_COST_DIAGRAMS if _draws(request) > 0 else 0.0
        seconds += SDM_COST.seconds(count, steps, modes, fraction, extra)
        memory += SDM_COST.memory_bytes(count, steps, modes, fraction)
        terms = {**terms, "steps_per_period": steps, "modes_per_direction": modes,
                 "period_map_dimension": SDM_COST.sizes(steps, modes, fraction)[2]}
        shrink = ("fewer speeds (spindle_speed_rpm.count)", "fewer steps_per_period",
                  "fewer modes_per_direction", "fewer frequency lines")
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
