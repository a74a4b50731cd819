"""Chatter-safe presets: per tool, the best stable pocket, written into the Fusion library.

For every milling tool of a Fusion library whose tool-point FRF is known (a stored sync, or
predicted on the fly), :func:`recommend_presets`

1. takes the cut: the workpiece material's cutting coefficients (the sourced table of
   :mod:`rcsa.analysis.lobes.workpiece_materials`, or the caller's), the teeth ``NOF``, the
   radial immersion and up/down milling;
2. takes the speed range: from ``min_rpm`` to the least of the machine's ``max_rpm``, the
   surface-speed limit ``v_c,max / (π DC)`` (the table's, for carbide tools, or the
   caller's ``max_surface_speed_m_min``) and the speed ``n`` of the tool's own presets for
   this material (a vendor's preset named e.g. "Aluminum": the tool's own limit);
3. computes the stability lobes (the same FRF in x and y) by the method asked for — zero-order,
   semi-discretization, or ``"auto"``: zero-order only where it is exact (even-toothed slotting),
   else the semi-discretization — and picks the best pocket
   (:func:`rcsa.analysis.lobes.tool_pockets.tool_pockets`, the rule of
   :mod:`rcsa.analysis.lobes.pockets`: the speed maximising ``n · a_p`` whose ± tolerance
   window stays stable at the stepdown times the safety factor; the stepdown at most the flute
   length ``LCF``, and a window stable deeper than that gets the flute length, said so);
4. writes it as a Fusion preset (:mod:`rcsa.libraries.fusion_presets`) named
   ``"rcsa chatter-safe: <material>"`` with a guid fixed by the tool id and the material, so
   that running again replaces rcsa's preset and touches no other.

The preset (in the tool's unit: mm and m/min, or inches and ft/min): ``name``, ``guid``,
``description`` (how it was chosen), ``material`` (``{"category": "all", "query": <material>,
"use-hardness": false}``), ``n`` and ``n_ramp`` (rpm, whole), ``v_c`` (from that ``n``: Fusion
recomputes it from ``n``), ``stepdown`` (rounded down) with ``use-stepdown``, ``stepover``
(``a_e = radial_immersion · DC``) with ``use-stepover``; and, when a feed per tooth is known
(``feed_per_tooth_m``, else the ``f_z`` of the tool's first own preset), ``f_z``, ``v_f = n f_z
NOF`` and the lead-in, lead-out and transition feeds equal to it (plunge and ramp feeds keep
their ratio to ``v_f`` from that preset when it has them); ``tool-coolant`` from that preset.
Without a feed per tooth no feed is written (the report says so).

Each tool's report says what was chosen — speed, depth limit, safety factor, robust limit,
pocket width, lobe method — or why the tool was skipped or failed.
"""

from __future__ import annotations

import math
import re
import uuid
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from rcsa._version import __version__
from rcsa.analysis.lobes.pockets import (
    DEFAULT_SAFETY_FACTOR,
    DEFAULT_SPEED_TOLERANCE,
    Pocket,
    PocketRule,
)
from rcsa.analysis.lobes.robust import DEFAULT_CONFIDENCE
from rcsa.analysis.lobes.tool_pockets import (
    PRESET_METHODS,
    CutSettings,
    ToolCut,
    ToolPocket,
    tool_pockets,
)
from rcsa.analysis.lobes.workpiece_materials import (
    COEFFICIENT_MODEL,
    SPEED_SOURCE,
    WorkpieceMaterial,
    material_key,
    workpiece_material,
)
from rcsa.analysis.lobes.zoa import Milling, check_cut
from rcsa.analysis.progress import check_time
from rcsa.errors import InputError
from rcsa.infra.compute_backends import Backend, LocalBackend
from rcsa.libraries.fusion_geometry import tool_geometry
from rcsa.libraries.fusion_presets import FusionFile, is_replaced, write_presets
from rcsa.libraries.tool_materials import tool_material
from rcsa.model import fields
from rcsa.model.bounds import MAX_CONFIDENCE, MAX_SPEED_RPM, MIN_CONFIDENCE

__all__ = [
    "DEFAULT_MIN_RPM",
    "POCKET_CHUNK_TOOLS",
    "LOBE_METHODS",
    "MILLING_TOOL_TYPES",
    "OPTION_FIELDS",
    "PRESET_PREFIX",
    "Frf",
    "FrfFailure",
    "Recommendation",
    "RecommendOptions",
    "parse_recommend_options",
    "pocket_chunk",
    "pocket_chunks",
    "pockets_on",
    "preset_guid",
    "preset_name",
    "recommend_presets",
]

#: Most tools per chunk of pocket work: a library is cut into ``ceil(n / this)`` chunks of equal size
#: (a chunk's semi-discretization runs as one batch; chunks run on the workbench's backend: this
#: process, its worker processes or a Dask cluster). The cut depends on the library only, so every
#: backend computes the same batches and writes the same presets — the batch a tool is solved in
#: moves rounding, which can move a search's bracket within its tolerance (0.4 % seen between 25-
#: and 13-tool batches). 13: 25 tools run as two chunks, one per core on two cores.
POCKET_CHUNK_TOOLS = 13
#: Name of every preset rcsa writes: ``"rcsa chatter-safe: <material>"``.
PRESET_PREFIX = "rcsa chatter-safe: "
#: Default lowest spindle speed, rpm.
DEFAULT_MIN_RPM = 1000.0
#: Lobe methods of a recommendation (contract v1.2): zero-order, semi-discretization, or the
#: one :func:`rcsa.analysis.lobes.options.auto_method` picks per tool (the default).
LOBE_METHODS = PRESET_METHODS
#: Fusion tool types that mill sideways (stability lobes of peripheral milling apply).
MILLING_TOOL_TYPES = frozenset({
    "flat end mill", "ball end mill", "bull nose end mill", "chamfer mill", "face mill", "slot mill",
    "radius mill", "dovetail mill", "tapered mill", "lollipop mill", "bore mill", "form mill",
})
#: The options of a recommendation, as the CLI and the REST service name them.
OPTION_FIELDS = ("material", "tangential_coefficient_n_m2", "radial_ratio", "radial_immersion", "milling",
                 "min_rpm", "max_rpm", "safety_factor", "speed_tolerance", "max_surface_speed_m_min",
                 "feed_per_tooth_m", "method", "uncertainty", "confidence")

_NAMESPACE = uuid.uuid5(uuid.NAMESPACE_URL, "urn:rcsa:chatter-safe-preset")
_INCH = (254, 10000)


@dataclass(frozen=True, slots=True)
class Frf:
    """A tool-point FRF: frequency grid (Hz) and the direct receptance ``h`` (m/N), and the
    ``h`` of the tool's drawn assemblies, shape (ndraws, nfreq), when robust presets are asked for."""

    frequency_hz: np.ndarray
    h: np.ndarray
    h_draws: np.ndarray | None = None


class FrfFailure(str):
    """Why a tool has no FRF when computing it failed (the tool is reported ``failed``, not skipped)."""

    __slots__ = ()


@dataclass(frozen=True, slots=True)
class RecommendOptions:
    """Checked options of a recommendation (:func:`parse_recommend_options`).

    Attributes
    ----------
    material : str
        The material as the caller named it.
    workpiece : WorkpieceMaterial or None
        The table row it selects (None: not in the table).
    tangential_coefficient_n_m2, radial_ratio : float
        The cutting coefficients used.
    coefficient_source : str
        ``"table"`` or ``"given"``.
    radial_immersion : float
        ``a_e / D``.
    milling : {"up", "down"}
    min_rpm, max_rpm : float
        The machine's speed range, rpm.
    safety_factor, speed_tolerance : float
        The pocket rule (:class:`~rcsa.analysis.lobes.pockets.PocketRule`).
    max_surface_speed_m_min : float or None
        The caller's surface-speed limit (else the table's, carbide tools only).
    feed_per_tooth_m : float or None
        Feed per tooth for the preset's feeds, m.
    method : {"zoa", "semi_discretization", "auto"}
        Lobe method (:data:`LOBE_METHODS`); ``"auto"`` picks per tool
        (:func:`rcsa.analysis.lobes.tool_pockets.auto_method`).
    uncertainty : mapping or None
        The ``uncertainty`` option (draws, seed, tolerances; :mod:`rcsa.model.uncertainty`):
        each tool's assembly is drawn and the pocket chosen on the robust limit.
    confidence : float or None
        The robust limit's confidence (default 0.95 with ``uncertainty``; None without).
    """

    material: str
    workpiece: WorkpieceMaterial | None
    tangential_coefficient_n_m2: float
    radial_ratio: float
    coefficient_source: str
    radial_immersion: float = 0.5
    milling: Milling = "down"
    min_rpm: float = DEFAULT_MIN_RPM
    max_rpm: float = 20000.0
    safety_factor: float = DEFAULT_SAFETY_FACTOR
    speed_tolerance: float = DEFAULT_SPEED_TOLERANCE
    max_surface_speed_m_min: float | None = None
    feed_per_tooth_m: float | None = None
    method: str = "auto"
    uncertainty: Mapping[str, Any] | None = None
    confidence: float | None = None

    @property
    def display_name(self) -> str:
        """The material's name in presets: the table's, else the caller's."""
        return self.workpiece.name if self.workpiece is not None else self.material.strip()

    @property
    def key(self) -> str:
        """The material's identity in preset guids."""
        return self.workpiece.key if self.workpiece is not None else material_key(self.material)

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready options with the coefficients' sources."""
        w = self.workpiece
        return {"material": self.material, "material_entry": None if w is None else w.key,
                "tangential_coefficient_n_m2": self.tangential_coefficient_n_m2, "radial_ratio": self.radial_ratio,
                "coefficient_source": (w.coefficient_source if self.coefficient_source == "table" and w is not None
                                       else "given by the caller"),
                "coefficient_model": COEFFICIENT_MODEL, "radial_immersion": self.radial_immersion,
                "milling": self.milling, "min_rpm": self.min_rpm, "max_rpm": self.max_rpm,
                "safety_factor": self.safety_factor, "speed_tolerance": self.speed_tolerance,
                "max_surface_speed_m_min": self.max_surface_speed_m_min,
                "surface_speed_source": SPEED_SOURCE if self.max_surface_speed_m_min is None else "given by the caller",
                "feed_per_tooth_m": self.feed_per_tooth_m, "method": self.method,
                "uncertainty": None if self.uncertainty is None else dict(self.uncertainty),
                "confidence": self.confidence}


def parse_recommend_options(body: Mapping[str, Any]) -> RecommendOptions:
    """Check the options of a recommendation (:data:`OPTION_FIELDS`).

    Parameters
    ----------
    body : mapping
        ``material`` (required), ``max_rpm`` (required), and optionally
        ``tangential_coefficient_n_m2`` with ``radial_ratio`` (both, or neither: then the
        table's), ``radial_immersion`` (0.5), ``milling`` (``"down"``), ``min_rpm`` (1000),
        ``safety_factor`` (1.25), ``speed_tolerance`` (0.03), ``max_surface_speed_m_min``,
        ``feed_per_tooth_m``, ``method`` (``"auto"``, or ``"zoa"``, ``"semi_discretization"``),
        ``uncertainty`` (robust presets:
        every tool's assembly drawn, :mod:`rcsa.analysis.lobes.robust`) and ``confidence``
        (0.95; only with ``uncertainty``).

    Returns
    -------
    RecommendOptions

    Raises
    ------
    InputError
        Naming the field: unknown fields, a missing or out-of-range value, a material the
        table has no coefficients for without the caller's, a method or confidence this
        version cannot compute.

    Examples
    --------
    >>> o = parse_recommend_options({"material": "Al 7075", "max_rpm": 24000})
    >>> o.workpiece.key, round(o.radial_ratio, 4), o.safety_factor
    ('aluminium-7075', 0.5979, 1.25)
    """
    unknown = sorted(set(body) - set(OPTION_FIELDS))
    if unknown:
        raise InputError(unknown[0], f"unknown option (allowed: {', '.join(OPTION_FIELDS)})")
    if body.get("material") is None:
        raise InputError("material", "is required: the workpiece material (e.g. aluminium-7075)")
    material = fields.string(body["material"], "material")
    row = workpiece_material(material)
    kt, kr = body.get("tangential_coefficient_n_m2"), body.get("radial_ratio")
    if (kt is None) != (kr is None):
        missing = "radial_ratio" if kr is None else "tangential_coefficient_n_m2"
        raise InputError(missing, "give both tangential_coefficient_n_m2 and radial_ratio, or neither")
    source = "given"
    if kt is None:
        if row is None or row.tangential_coefficient_n_m2 is None or row.radial_ratio is None:
            what = f"{material!r} is not in the table" if row is None else \
                f"the table has no citable cutting coefficients for {row.name}"
            raise InputError("tangential_coefficient_n_m2", f"{what}: give tangential_coefficient_n_m2 and "
                                                            "radial_ratio (the linear edge-force model's K_tc and "
                                                            "K_rc/K_tc)")
        kt, kr, source = row.tangential_coefficient_n_m2, row.radial_ratio, "table"
    if body.get("max_rpm") is None:
        raise InputError("max_rpm", "is required: the machine's highest spindle speed, rpm")
    immersion = body.get("radial_immersion", 0.5)
    milling = body.get("milling", "down")
    cut = check_cut(1, kt, kr, immersion, milling)
    min_rpm = fields.number(body.get("min_rpm", DEFAULT_MIN_RPM), "min_rpm", gt=0.0, le=MAX_SPEED_RPM)
    max_rpm = fields.number(body["max_rpm"], "max_rpm", gt=0.0, le=MAX_SPEED_RPM)
    if not min_rpm < max_rpm:
        raise InputError("max_rpm", f"must be greater than min_rpm ({min_rpm:g}), got {max_rpm:g}")
    rule = PocketRule(fields.number(body.get("safety_factor", DEFAULT_SAFETY_FACTOR), "safety_factor"),
                      fields.number(body.get("speed_tolerance", DEFAULT_SPEED_TOLERANCE), "speed_tolerance"))
    vc = body.get("max_surface_speed_m_min")
    vc = None if vc is None else fields.number(vc, "max_surface_speed_m_min", gt=0.0, le=1e5)
    fz = body.get("feed_per_tooth_m")
    fz = None if fz is None else fields.number(fz, "feed_per_tooth_m", gt=0.0, le=0.1)
    method = body.get("method", "auto")
    if method not in LOBE_METHODS:
        raise InputError("method", f"must be one of {', '.join(LOBE_METHODS)}, got {method!r}")
    uncertainty, confidence = body.get("uncertainty"), body.get("confidence")
    if uncertainty is None and confidence is not None:
        raise InputError("confidence", "needs uncertainty: the robust limit is taken over drawn assemblies")
    if uncertainty is not None:
        uncertainty = fields.json_object(uncertainty, "uncertainty")
        confidence = fields.number(DEFAULT_CONFIDENCE if confidence is None else confidence, "confidence",
                                   ge=MIN_CONFIDENCE, le=MAX_CONFIDENCE)
    return RecommendOptions(material=material, workpiece=row, tangential_coefficient_n_m2=cut.tangential_coefficient_n_m2,
                            radial_ratio=cut.radial_ratio, coefficient_source=source,
                            radial_immersion=cut.radial_immersion, milling=cut.milling, min_rpm=min_rpm,
                            max_rpm=max_rpm, safety_factor=rule.safety_factor, speed_tolerance=rule.speed_tolerance,
                            max_surface_speed_m_min=vc, feed_per_tooth_m=fz, method=str(method),
                            uncertainty=uncertainty, confidence=confidence)


def preset_name(options: RecommendOptions) -> str:
    """The name of rcsa's preset for this material: ``"rcsa chatter-safe: aluminium 7075"``."""
    return PRESET_PREFIX + options.display_name


def preset_guid(tool_id: str, options: RecommendOptions) -> str:
    """The guid of rcsa's preset on one tool for one material (stable across runs).

    Examples
    --------
    >>> o = parse_recommend_options({"material": "aluminium-7075", "max_rpm": 20000})
    >>> preset_guid("T1", o) == preset_guid("T1", o) != preset_guid("T2", o)
    True
    """
    return str(uuid.uuid5(_NAMESPACE, f"{tool_id}\n{options.key}"))


@dataclass(frozen=True, slots=True)
class Recommendation:
    """The library with the presets written, and the report.

    Attributes
    ----------
    data : bytes
        The new ``.json`` or ``.tools`` file.
    report : dict
        JSON-ready: ``options``, ``rule``, ``summary`` (``written``, ``skipped``, ``failed``)
        and ``tools`` (one entry per library item, in library order).
    """

    data: bytes
    report: dict[str, Any] = field(default_factory=dict)


class _Skip(Exception):
    """Internal: the tool gets no preset (status ``skipped``)."""


def pocket_chunk(chunk: list[ToolCut], settings: CutSettings) -> list[ToolPocket]:
    """The pockets of one chunk of tools (:func:`~rcsa.analysis.lobes.tool_pockets.tool_pockets`): a
    module-level function, so that a cluster's workers can run it by name."""
    return tool_pockets(chunk, settings)


PocketFinder = Callable[[list[ToolCut], CutSettings, Callable[[int, int], None] | None], list[ToolPocket]]


def pocket_chunks(order: list[int], most: int = POCKET_CHUNK_TOOLS) -> list[list[int]]:
    """``order`` cut into the fewest chunks of at most ``most`` items, of equal size (± 1).

    >>> [len(c) for c in pocket_chunks(list(range(25)))], [len(c) for c in pocket_chunks(list(range(27)))]
    ([12, 13], [9, 9, 9])
    """
    n = len(order)
    count = max(1, -(-n // int(most)))
    bounds = [n * k // count for k in range(count + 1)]
    return [order[a:b] for a, b in zip(bounds[:-1], bounds[1:], strict=True) if b > a]


def pockets_on(backend: Backend | None = None, tools_per_chunk: int = POCKET_CHUNK_TOOLS) -> PocketFinder:
    """Find pockets in chunks of tools on a compute backend (default: this process), with progress.

    Tools are ordered by tooth count (a chunk of one count is one semi-discretization batch)
    and cut into equal chunks of at most ``tools_per_chunk`` (:func:`pocket_chunks`; the cut
    depends on the library only); each chunk is :func:`pocket_chunk`, sent to ``backend``
    (:mod:`rcsa.infra.compute_backends`), which is stopped at the caller's time limit
    (:func:`~rcsa.analysis.progress.check_time`, checked while it waits: also where chunks run in other
    processes).
    ``progress(done, total)`` is called as chunks finish. The pockets are the same whichever
    backend computes them.
    """
    def run(cuts: list[ToolCut], settings: CutSettings,
            progress: Callable[[int, int], None] | None = None) -> list[ToolPocket]:
        chunks = pocket_chunks(sorted(range(len(cuts)), key=lambda i: cuts[i].teeth), tools_per_chunk)
        out: list[ToolPocket | None] = [None] * len(cuts)
        done = 0
        if progress is not None:
            progress(0, len(cuts))
        for i, found in (backend or LocalBackend()).map(pocket_chunk, [[cuts[j] for j in c] for c in chunks],
                                                        shared=settings, ordered=False, on_wait=check_time):
            for j, pocket in zip(chunks[i], found, strict=True):
                out[j] = pocket
            done += len(chunks[i])
            if progress is not None:
                progress(done, len(cuts))
        return [p for p in out if p is not None]

    return run


def recommend_presets(file: FusionFile, entries: list[Mapping[str, Any]], frfs: Mapping[str, Frf | str],
                      options: RecommendOptions, progress: Callable[[int, int], None] | None = None,
                      pockets: PocketFinder | None = None) -> Recommendation:
    """Write a chatter-safe preset into every tool that has a stable pocket (module docstring).

    The tools are prepared one by one (import status, tool type, teeth, speed range, FRF),
    then all their pockets are found together (:func:`rcsa.analysis.lobes.tool_pockets.
    tool_pockets`: the semi-discretization of all tools of a tooth count is one batch), then
    the presets are written.

    Parameters
    ----------
    file : FusionFile
        The library as uploaded (:func:`rcsa.libraries.fusion_presets.read_fusion_file`).
    entries : list of mapping
        The library's import entries (``id``, ``index``, ``status``, ``reason`` or ``error``,
        ``teeth``, ``tool_type``, ``description``, ``number``), one per ``data`` item.
    frfs : mapping of str to Frf or str
        Tool id → its tool-point FRF, or why there is none (a :class:`FrfFailure` when
        computing it failed: the tool is then ``failed``; else ``skipped``).
    options : RecommendOptions
    progress : callable, optional
        ``progress(done, total)`` over the tools whose pockets are computed.
    pockets : callable, optional
        How the pockets are found (:func:`pockets_on` a backend; default: in this process).

    Returns
    -------
    Recommendation
    """
    doc = file.document
    edits: dict[int, dict[str, Any]] = {}
    tools: list[dict[str, Any]] = []
    prepared: list[tuple[int, _Prepared]] = []
    for entry in entries:
        head = {k: entry.get(k) for k in ("id", "index", "description", "number", "tool_type")}
        try:
            ready = _prepare(doc["data"][int(entry["index"])], entry, frfs.get(str(entry["id"])), options)
        except _Skip as skip:
            tools.append({**head, "status": "skipped", "reason": str(skip)})
            continue
        except InputError as err:
            tools.append({**head, "status": "failed", "reason": str(err)})
            continue
        prepared.append((len(tools), ready))
        tools.append(head)
    settings = CutSettings(options.tangential_coefficient_n_m2, options.radial_ratio, options.radial_immersion,
                           options.milling, PocketRule(options.safety_factor, options.speed_tolerance),
                           method=options.method, confidence=options.confidence)  # type: ignore[arg-type]
    found_all = (pockets or pockets_on())([r.cut for _, r in prepared], settings, progress)
    for (slot, ready), found in zip(prepared, found_all, strict=True):
        head = tools[slot]
        if found.pocket is None:
            tools[slot] = {**head, "status": "skipped", "reason": found.refusal or "no stable pocket",
                           "lobe_method": found.method, "method_reason": found.method_reason}
            continue
        try:
            preset, report = _written(ready, found, options)
        except _Skip as skip:
            tools[slot] = {**head, "status": "skipped", "reason": str(skip)}
            continue
        except InputError as err:
            tools[slot] = {**head, "status": "failed", "reason": str(err)}
            continue
        edits[int(ready.entry["index"])] = preset
        tools[slot] = {**head, "status": "written", **report}
    data = write_presets(file, edits)
    summary = {s: sum(t["status"] == s for t in tools) for s in ("written", "skipped", "failed")}
    rule = PocketRule(options.safety_factor, options.speed_tolerance)
    return Recommendation(data, {
        "options": options.to_dict(),
        "rule": {**rule.to_dict(), "max_depth_m": "the tool's flute length LCF",
                 "objective": "maximise n * stepdown (material removal rate at a fixed a_e and f_z)",
                 "window": "the depth limit is the smallest within n * (1 +/- speed_tolerance)",
                 "stepdown": "window depth limit / safety_factor, at most LCF",
                 "method": "auto: zoa only where it is exact (slotting with an even number of teeth, 4 or "
                           "more), else semi_discretization with the steps that resolve the cut, checked at "
                           "two resolutions"},
        "preset_name": preset_name(options), "summary": summary, "tools": tools})


# --------------------------------------------------------------------------- one tool


@dataclass(frozen=True)
class _Prepared:
    """A tool ready for its pocket: the library item, its entry, geometry, speed range and FRF."""

    item: Any
    entry: Mapping[str, Any]
    geo: Mapping[str, Any]
    teeth: int
    limits: list[str]
    warnings: list[str]
    cut: ToolCut


def _prepare(item: Any, entry: Mapping[str, Any], frf: Frf | str | None, options: RecommendOptions) -> _Prepared:
    status = entry.get("status")
    if status == "skipped":
        raise _Skip(str(entry.get("reason") or "skipped by the import"))
    if status == "error":
        error = entry.get("error") or {}
        raise InputError(str(error.get("field", "")), str(error.get("detail", entry.get("reason", ""))))
    kind = str(entry.get("tool_type") or "").strip().lower()
    if kind not in MILLING_TOOL_TYPES:
        raise _Skip(f"{kind or 'this tool type'} is not a milling cutter: chatter-safe presets are for "
                    "milling (end mills, face mills, ...)")
    teeth = entry.get("teeth")
    if not isinstance(teeth, int) or teeth < 1:
        raise _Skip("geometry.NOF (number of flutes) is missing: the stability lobes need it")
    geo = tool_geometry(item)
    diameter_m, flute_m = float(geo["DC"]), float(geo["LCF"])
    lo, hi, limits, warnings = _speed_range(item, diameter_m, options)
    if frf is None:
        raise _Skip("no tool-point FRF for this tool")
    if isinstance(frf, FrfFailure):
        raise InputError("tool_point", str(frf))
    if isinstance(frf, str):
        raise _Skip(frf)
    if options.confidence is not None and frf.h_draws is None:
        raise InputError("uncertainty", "no drawn FRFs for this tool: robust presets need them")
    return _Prepared(item, entry, geo, teeth, limits, warnings,
                     ToolCut(str(entry["id"]), frf.frequency_hz, frf.h, teeth, flute_m, lo, hi, frf.h_draws))


def _written(ready: _Prepared, found: ToolPocket, options: RecommendOptions) -> tuple[dict[str, Any], dict[str, Any]]:
    pocket = found.pocket
    assert pocket is not None
    item, entry, teeth = ready.item, ready.entry, ready.teeth
    warnings = list(ready.warnings)
    preset, unit_report, feed_note = _preset(item, entry, ready.geo, pocket, teeth, options, found)
    if feed_note:
        warnings.append(feed_note)
    report = {
        "spindle_speed_rpm": preset["n"], "stepdown_m": pocket.stepdown_m, "stepdown": unit_report,
        "depth_limit_m": _num(found.depth_limit_m), "safety_factor": options.safety_factor,
        "robust_depth_limit_m": None if found.robust_depth_limit_m is None else _num(found.robust_depth_limit_m),
        "confidence": options.confidence,
        "limited_by": pocket.limited_by, "stable_to_flute_length": found.stable_to_flute_length,
        "flute_length_m": ready.cut.flute_length_m,
        "pocket": pocket.pocket_dict(),
        "speed_tolerance": options.speed_tolerance,
        "speed_range": {"min_rpm": ready.cut.min_rpm, "max_rpm": ready.cut.max_rpm, "limited_by": ready.limits},
        "lobe_method": found.method, "method_reason": found.method_reason,
        "chatter_frequency_hz": _num(pocket.chatter_frequency_hz),
        "governing_lobe": pocket.governing_lobe, "absolute_depth_limit_m": _num(found.absolute_depth_limit_m),
        "teeth": teeth, "frf_y_source": "same_as_x",
        "preset": {"name": preset["name"], "guid": preset["guid"],
                   "replaced": _had_preset(item, preset["guid"], preset["name"])},
        "notes": list(found.notes), "warnings": warnings,
    }
    return preset, report


def _num(x: float) -> float | None:
    return float(x) if math.isfinite(x) else None


def _presets(item: Any) -> list[Any]:
    start = item.get("start-values") if isinstance(item, dict) else None
    presets = start.get("presets") if isinstance(start, dict) else None
    return presets if isinstance(presets, list) else []


def _had_preset(item: Any, guid: str, name: str) -> bool:
    return any(is_replaced(p, guid, name) for p in _presets(item))


def _own_presets(item: Any) -> list[dict[str, Any]]:
    """The tool's presets that rcsa did not write."""
    return [p for p in _presets(item) if isinstance(p, dict)
            and not (isinstance(p.get("name"), str) and p["name"].startswith(PRESET_PREFIX))]


def _names_material(text: object, options: RecommendOptions) -> bool:
    """Whether a preset's name or material query names the workpiece material (whole words)."""
    if not isinstance(text, str) or not text.strip():
        return False
    w = options.workpiece
    spellings = {material_key(s) for s in ((w.key, w.name, *w.aliases) if w is not None else (options.material,))}
    words = [t for t in re.split(r"[^a-z0-9]+", text.lower()) if t]
    candidates = {*words, *(a + b for a, b in zip(words, words[1:], strict=False)), material_key(text)}
    return bool(candidates & spellings)


def _positive(value: object) -> float | None:
    if isinstance(value, bool) or not isinstance(value, int | float):
        return None
    return float(value) if math.isfinite(value) and value > 0 else None


def _speed_range(item: Any, diameter_m: float, options: RecommendOptions
                 ) -> tuple[float, float, list[str], list[str]]:
    """Lowest and highest speed for this tool, what limits the highest, and notes."""
    warnings: list[str] = []
    hi, limits = options.max_rpm, ["machine max_rpm"]
    vc = options.max_surface_speed_m_min
    if vc is None:
        material, _ = tool_material(item.get("BMC"))
        if material != "carbide":
            raise _Skip(f"tool material {item.get('BMC')!r} is not carbide: the table's surface-speed limits are "
                        "for solid carbide end mills; give max_surface_speed_m_min for this tool")
        if options.workpiece is None:
            raise _Skip(f"no surface-speed limit for {options.material!r} (not in the table): give "
                        "max_surface_speed_m_min")
        vc = options.workpiece.max_surface_speed_m_min(options.radial_immersion)
    n_vc = vc / (math.pi * diameter_m)
    if n_vc < hi:
        hi, limits = n_vc, [f"surface speed {vc:g} m/min"]
    own = [n for p in _own_presets(item)
           if (_names_material(p.get("name"), options)
               or _names_material((p.get("material") or {}).get("query") if isinstance(p.get("material"), dict)
                                  else None, options))
           and (n := _positive(p.get("n"))) is not None]
    if own and max(own) < hi:
        hi, limits = max(own), [f"the tool's own {options.display_name} preset (n = {max(own):g} rpm)"]
    if not options.min_rpm < hi:
        raise _Skip(f"no speed range: the highest speed ({hi:.0f} rpm, {limits[0]}) is not above min_rpm "
                    f"({options.min_rpm:g} rpm)")
    return options.min_rpm, hi, limits, warnings


def _round_down(x: float, step: float) -> float:
    return round(math.floor(x / step * (1 + 1e-12)) * step, 10)


def _preset(item: Any, entry: Mapping[str, Any], geo: Mapping[str, Any], pocket: Pocket, teeth: int,
            options: RecommendOptions, found: ToolPocket) -> tuple[dict[str, Any], dict[str, Any], str | None]:
    unit = tuple(geo["unit"])
    inch = unit == _INCH
    per_unit_m = unit[0] / unit[1]
    unit_name, speed_unit = ("inches", "ft/min") if inch else ("millimeters", "m/min")
    if unit not in (_INCH, (1, 1000)):
        raise InputError("unit", "presets are written for tools in millimeters or inches")
    n = int(round(pocket.spindle_speed_rpm))
    dc = geo["DC"] / per_unit_m
    stepdown = _round_down(pocket.stepdown_m / per_unit_m, 0.0001 if inch else 0.001)
    if stepdown <= 0:
        raise _Skip(f"the allowed stepdown ({pocket.stepdown_m * 1e3:.4f} mm) rounds to zero")
    v_c = round(math.pi * dc * n / (12.0 if inch else 1000.0), 6)
    stepover = _round_down(options.radial_immersion * dc, 0.0001 if inch else 0.001)
    guid = preset_guid(str(entry["id"]), options)
    name = preset_name(options)
    description = (f"rcsa {__version__}: {found.method} stability lobes"
                   + (" (auto)" if options.method == "auto" else "") + "; "
                   + ("stepdown = the flute length (the window is stable deeper than "
                      f"{options.safety_factor:g} x the flute length); " if pocket.limited_by == "flute_length" else
                      f"stepdown = depth limit within +/-{options.speed_tolerance:.0%} of n / {options.safety_factor:g}; ")
                   + f"{options.display_name}, "
                   f"Kt {options.tangential_coefficient_n_m2 / 1e6:g} N/mm2, Kr {options.radial_ratio:.4g}, "
                   f"ae/D {options.radial_immersion:g}, {options.milling} milling"
                   + ("" if options.confidence is None else
                      f"; robust: the {100 * (1 - options.confidence):g}th percentile over "
                      f"{(options.uncertainty or {}).get('draws', 'the')} drawn assemblies"))
    preset: dict[str, Any] = {
        "name": name, "guid": guid, "description": description,
        "material": {"category": "all", "query": options.display_name, "use-hardness": False},
        "n": n, "n_ramp": n, "v_c": v_c,
        "stepdown": stepdown, "use-stepdown": True, "stepover": stepover, "use-stepover": True,
    }
    template = next(iter(_own_presets(item)), None)
    fz_u = options.feed_per_tooth_m / per_unit_m if options.feed_per_tooth_m is not None else \
        (_positive(template.get("f_z")) if template is not None else None)
    note = None
    if fz_u is None:
        note = "no feed per tooth (feed_per_tooth_m, or f_z of the tool's own preset): the preset has no feeds"
    else:
        v_f = round(n * fz_u * teeth, 6)
        preset.update({"f_z": round(fz_u, 8), "v_f": v_f, "v_f_leadIn": v_f, "v_f_leadOut": v_f,
                       "v_f_transition": v_f})
        t_vf = _positive(template.get("v_f")) if template is not None else None
        for key in ("v_f_plunge", "v_f_ramp"):
            t_val = _positive(template.get(key)) if template is not None else None
            if t_val is not None and t_vf is not None:
                preset[key] = round(v_f * t_val / t_vf, 6)
        if "v_f_plunge" in preset:
            preset["f_n"] = round(preset["v_f_plunge"] / n, 8)
    if template is not None and isinstance(template.get("tool-coolant"), str):
        preset["tool-coolant"] = template["tool-coolant"]
    unit_report = {"value": stepdown, "unit": unit_name, "v_c": v_c, "v_c_unit": speed_unit}
    return preset, unit_report, note
