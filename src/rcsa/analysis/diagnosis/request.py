"""The diagnosis request (``docs/contract.md`` "Diagnosis"), validated once at the edge.

Request::

    {"assembly": {...base model, contract "Assembly"; its frequency grid is not used...},
     "measurements": [{"tool": {"stickout_m": 0.050},          # overrides of assembly.tool
                       "frequency_hz": [...], "h": {"real": [...], "imag": [...]},
                       "coherence": [...],                      # γ² per line, optional
                       "n_averages": 5,                         # impacts averaged, optional
                       "sensor_mass_kg": 0.004,                 # bounds sensor_mass, optional
                       "label": "50 mm"}],                      # optional
     "tolerances": {"tool_youngs_modulus_rel": 0.05, ...},      # optional, 1σ, see discrepancy
     "options": {"effects": [...], "held_out": [1, 3], "seed": 0, "monte_carlo_draws": 200,
                 "likelihood": "student_t", "claim_threshold": 3.0, "ambiguity_window": 2.3,
                 "max_effects": 2, "max_lines": 1200}}          # optional

``assembly.spindle`` may be a stored measured spindle (``{"measurement_id": ...}``, the hybrid
case); it is looked up through the ``resolve_base`` the caller passes
(:data:`rcsa.model.spindle_side.BaseResolver`, e.g. the application layer's store), never by
this module. Every violation raises :class:`~rcsa.errors.InputError` naming the field and the
rule.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from rcsa.analysis.diagnosis.candidates import CANDIDATE_NAMES
from rcsa.analysis.diagnosis.discrepancy import DEFAULT_TOLERANCES
from rcsa.analysis.measured_tool_point import MAX_TAP_TESTS, TapTest, parse_tap_tests
from rcsa.errors import InputError
from rcsa.model import fields
from rcsa.model.bounds import MAX_SENSOR_MASS_KG
from rcsa.model.contract import AssemblySpec, MeasuredSpindleSpec, ToolSpec, parse_assembly

if TYPE_CHECKING:  # types only: the measured spindle's module loads with a measured spindle
    from rcsa.model.spindle_side import BaseResolver

__all__ = ["MAX_MEASUREMENTS", "MIN_VALID_LINES", "Measurement", "Options", "Request", "parse_request"]

MAX_MEASUREMENTS = MAX_TAP_TESTS
MAX_LINES_PER_MEASUREMENT = 200_000
# Below ~100 lines in the valid band a mode window holds only a handful of lines and the
# five-line peak parabola has nothing to average over.
MIN_VALID_LINES = 100
DEFAULT_N_AVERAGES = 5.0
#: Largest number of averaged impacts a measurement may claim, and the largest seed (64 bits).
MAX_N_AVERAGES = 1.0e6
MAX_SEED = 2**63 - 1
# Relative |H| noise assumed when a measurement carries no coherence (1 %, the benchmark level).
DEFAULT_NOISE_REL = 0.01

_FIELDS = ("assembly", "measurements", "tolerances", "options")


@dataclass(frozen=True)
class Measurement:
    """One tap test: the configuration's tool and its FRF on the measured lines."""

    tool: ToolSpec
    overrides: Mapping[str, Any]
    frequency_hz: np.ndarray
    h: np.ndarray
    coherence: np.ndarray | None
    n_averages: float
    sensor_mass_kg: float | None
    label: str


@dataclass(frozen=True)
class Options:
    """Decision and effort settings (``docs/diagnosis.md`` §7 defaults)."""

    effects: tuple[str, ...] = CANDIDATE_NAMES
    effects_requested: bool = False
    held_out: tuple[int, ...] | None = None
    seed: int = 0
    monte_carlo_draws: int = 200
    likelihood: str = "student_t"
    claim_threshold: float = 3.0
    ambiguity_window: float = 2.3
    max_effects: int = 2
    max_lines: int = 1200


@dataclass(frozen=True)
class Request:
    """A validated diagnosis request."""

    assembly: Mapping[str, Any]
    spec: AssemblySpec
    measurements: tuple[Measurement, ...]
    tolerances: Mapping[str, float]
    options: Options = field(default_factory=Options)
    resolve_base: BaseResolver | None = None

    @property
    def measured_spindle(self) -> MeasuredSpindleSpec | None:
        """The stored spindle of a hybrid request, else None."""
        sp = self.spec.spindle
        return sp if isinstance(sp, MeasuredSpindleSpec) else None


def _measurement(tap: TapTest, i: int) -> Measurement:
    extra = fields.Fields(tap.extra, tap.path)
    n_avg = extra.number("n_averages", ge=1.0, le=MAX_N_AVERAGES, default=DEFAULT_N_AVERAGES)
    mass = extra.optional_number("sensor_mass_kg", ge=0.0, le=MAX_SENSOR_MASS_KG)
    label = tap.extra.get("label", f"#{i}")
    if not isinstance(label, str):
        raise InputError(extra.at("label"), "must be a string")
    return Measurement(tap.tool, dict(tap.overrides), tap.frequency_hz, tap.h, tap.coherence, n_avg, mass, label)


_OPTIONS = ("effects", "held_out", "seed", "monte_carlo_draws", "likelihood", "claim_threshold",
            "ambiguity_window", "max_effects", "max_lines")


def _options(raw: object, n_meas: int) -> Options:
    opts = fields.Fields(raw or {}, "options", _OPTIONS)
    o = opts.value
    effects = o.get("effects", list(CANDIDATE_NAMES))
    if not isinstance(effects, list) or not effects or any(e not in CANDIDATE_NAMES for e in effects):
        raise InputError("options.effects", f"must be a non-empty list of: {', '.join(CANDIDATE_NAMES)}")
    held = o.get("held_out")
    if held is not None:
        if (not isinstance(held, list) or any(isinstance(k, bool) or not isinstance(k, int) for k in held)
                or len(set(held)) != len(held) or any(not 0 <= k < n_meas for k in held)):
            raise InputError("options.held_out", f"must be a list of distinct measurement indices in [0, {n_meas - 1}]")
        if len(held) >= n_meas:
            raise InputError("options.held_out", "must leave at least one measurement for fitting")
    # counts may come as JSON numbers with a fraction (e.g. 200.0): read as numbers, then truncated
    return Options(
        effects=tuple(dict.fromkeys(effects)), effects_requested="effects" in o,
        held_out=None if held is None else tuple(held),
        seed=opts.integer("seed", ge=0, le=MAX_SEED, default=0),
        monte_carlo_draws=int(opts.number("monte_carlo_draws", ge=50, le=5000, default=200)),
        likelihood=opts.string("likelihood", "student_t", ("student_t", "gaussian")),
        claim_threshold=opts.number("claim_threshold", ge=0.0, le=50.0, default=3.0),
        ambiguity_window=opts.number("ambiguity_window", ge=0.0, le=50.0, default=2.3),
        max_effects=int(opts.number("max_effects", ge=1, le=2, default=2)),
        max_lines=int(opts.number("max_lines", ge=200, le=20000, default=1200)))


def parse_request(request: object, resolve_base: BaseResolver | None = None) -> Request:
    """Validate a diagnosis request.

    Parameters
    ----------
    request : dict
        See the module docstring.
    resolve_base : callable, optional
        Looks a measured spindle up (needed when ``assembly.spindle`` is one).

    Returns
    -------
    Request

    Raises
    ------
    InputError
        Naming the offending field and the rule.
    """
    o = fields.json_object(request, "", _FIELDS)
    if "assembly" not in o:
        raise InputError("assembly", "is required")
    assembly = dict(fields.json_object(o["assembly"], "assembly"))
    assembly.setdefault("frequency", {"values_hz": [1.0]})  # replaced by each measurement's lines
    try:
        spec = parse_assembly(assembly)
    except InputError as exc:
        raise InputError(f"assembly.{exc.field}" if exc.field else "assembly", exc.rule) from None
    if isinstance(spec.spindle, MeasuredSpindleSpec) and resolve_base is None:
        raise InputError("assembly.spindle", "a measured spindle is looked up in a measurement store, and none was "
                                             "given: call rcsa.diagnose (or the CLI or the service), or pass "
                                             "resolve_base")
    taps = parse_tap_tests(o.get("measurements"), fields.json_object(assembly.get("tool") or {}, "assembly.tool"),
                           spec.materials,
                           extra_fields=("n_averages", "sensor_mass_kg", "label"), max_tests=MAX_MEASUREMENTS,
                           max_lines=MAX_LINES_PER_MEASUREMENT)
    measurements = tuple(_measurement(t, i) for i, t in enumerate(taps))
    tol = fields.Fields(o.get("tolerances") or {}, "tolerances", tuple(DEFAULT_TOLERANCES))
    tolerances = dict(DEFAULT_TOLERANCES)
    for key in tol.value:
        tolerances[key] = tol.number(key, ge=0.0, le=0.05 if key == "stickout_m" else 2.0)
    return Request(assembly, spec, measurements, tolerances, _options(o.get("options"), len(measurements)),
                   resolve_base)
