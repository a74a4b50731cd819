"""The best stable pocket of every tool of a library, by zero-order or semi-discretization lobes.

:func:`tool_pockets` takes many tools (each: its tool-point FRF, teeth, flute length and
speed range; optionally the FRFs of drawn assemblies for a robust pocket) and one cut
(cutting coefficients, radial immersion, milling direction, the pocket rule), and gives each
tool its pocket (:func:`rcsa.analysis.lobes.pockets.best_pocket`'s rule) or a refusal whose
reason is true. The method is chosen per tool:

* ``"zoa"`` — Altintas–Budak zero-order lobes on the pocket grid (relative spacing
  ``τ/10``). A cut in which zero-order averaging finds no positive depth limit is refused with
  that reason (the average force cannot judge it), never called "cannot chatter".
* ``"semi_discretization"`` — the tool's modes are fitted to its FRF
  (:func:`~rcsa.analysis.lobes.modal_model.fit_modal_model`) and all tools of one tooth
  count are solved together (:func:`~rcsa.analysis.lobes.semi_discretization.
  semi_discretization_lobes_many`) on a geometric grid of ``sdm_speed_count`` speeds. The
  pocket rule is applied on that grid (a screening pass: fewer steps, no check), then the best
  candidates' ``±τ`` windows are solved densely (``_VERIFY_POINTS`` speeds each, plus the grid
  speeds bracketing them) with the steps that resolve the cut, every speed checked at a second
  resolution (an unresolved speed counts as unstable), and a candidate is kept only with the
  depth its dense window allows; candidates are verified
  best-first until the best verified one beats every unverified candidate's grid score
  (:func:`_verify`). The grid is screened by branch and bound (:func:`_screen_pruned`): its
  top band first, verified; then only the slower windows that can still beat the best
  verified one — not those whose speed times the flute length falls short, nor those holding a
  speed found unstable (one evaluation) at the depth they would need — so the slow speeds,
  whose cut holds the most steps, are mostly never searched, and the pocket is the one the
  whole grid gives (their limits unknown, the absolute depth limit is then NaN; robust pockets
  screen the whole grid). The search reaches at least
  ``safety_factor × flute length`` deep, so a speed without an SDM limit below it is stable to
  the flute length: the stepdown is then capped there (``limited_by: "flute_length"``, said in
  the tool's notes), never refused.
* ``"auto"`` — zero-order only where it is exact
  (:func:`rcsa.analysis.lobes.options.auto_method`: even-toothed slotting), else
  semi-discretization.

Robust pockets (a confidence and drawn FRFs) use the robust limit of
:mod:`rcsa.analysis.lobes.robust` (zero-order: every draw's envelope; semi-discretization:
the reduced model of the draws of :mod:`rcsa.analysis.lobes.robust_sdm`).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, replace
from typing import Any, Literal

import numpy as np

from rcsa.analysis.lobes.modal_model import DEFAULT_MODES_PER_DIRECTION, ModalModel, fit_modal_model
from rcsa.analysis.lobes.options import auto_method
from rcsa.analysis.lobes.pockets import (
    Pocket,
    PocketRule,
    best_pocket,
    pocket_speed_grid,
    window_minimum,
)
from rcsa.analysis.lobes.robust import robust_depth_limit
from rcsa.analysis.lobes.robust_sdm import (
    VERIFY_DRAWS,
    drawn_models,
    modal_ratios,
    robust_sdm_limits,
)
from rcsa.analysis.lobes.semi_discretization import (
    SemiDiscretizationResult,
    merged_result,
    semi_discretization_lobes_many,
    stable_at_depth_many,
)
from rcsa.analysis.lobes.zoa import LobeResult, Milling, depth_limit_envelopes, stability_lobes
from rcsa.errors import InputError

__all__ = [
    "DEFAULT_SDM_SPEED_COUNT",
    "POCKET_FOLLOWED_SPAN",
    "PRESET_METHODS",
    "CutSettings",
    "PresetMethod",
    "ToolCut",
    "ToolPocket",
    "tool_pockets",
]

PresetMethod = Literal["zoa", "semi_discretization", "auto"]
#: Lobe methods of a recommendation (contract v1.2).
PRESET_METHODS: tuple[PresetMethod, ...] = ("zoa", "semi_discretization", "auto")
#: Speeds of the semi-discretization grid of each tool (geometric over the speed range).
DEFAULT_SDM_SPEED_COUNT = 400
#: Speeds solved densely across each verified ``±τ`` window.
_VERIFY_POINTS = 31
#: Windows verified per tool and round (the first round: the best candidate alone — a tool
#: stable to its flute length at its best speed is then done), and rounds at most.
_VERIFY_PER_ROUND = 3
_VERIFY_FIRST_ROUND = 1
_VERIFY_ROUNDS = 3
#: A tool is done when its best verified ``n · stepdown`` is within this fraction of every
#: unverified candidate's coarse score (the search's productivity slack).
_VERIFY_SLACK = 0.05
#: The search reaches this much deeper than ``safety_factor × flute length``.
_CAP_MARGIN = 1.02
#: The coarse grid screens candidates: its limits are bracketed to this relative width (the
#: verified windows to ``_VERIFY_RTOL``), with this many steps per cycle of the highest mode over
#: the cut and no check (first-order semi-discretization then over-estimates by about 6 %, never
#: by a multiple: candidates are ranked, not trusted; every verified window is solved with the
#: resolving steps, checked at a second resolution and refined where the two differ).
_SCREEN_RTOL = 0.05
_SCREEN_STEPS_PER_CYCLE = 8.0
#: Relative width of the verified windows' brackets: the limit kept is the bracket's stable
#: end, so a preset can only lose this fraction of its depth, never exceed the limit.
_VERIFY_RTOL = 0.005
#: The first screening pass takes the speeds from this fraction of the grid's top speed up
#: (:func:`_screen_pruned`), and counts for this share of the progress.
_TOP_BAND = 0.5
_TOP_SHARE = 0.2
#: Speeds below a pruned grid checked at once while a pocket is followed down (:func:`_pocket_extent`).
_EXTENT_CHUNK = 16
#: A semi-discretization pocket is followed at most this factor slower and faster than its speed
#: (the report says where it is open): below the screened speeds every speed costs one evaluation
#: at the screening's steps, and those grow as 1/n: one three-flute tool whose pocket reaches the
#: bottom of the range costs 4-5x more followed all the way (benchmarks/bench_pocket_extent.py).
POCKET_FOLLOWED_SPAN = 2.0
#: The first round of refutation probes takes every this-many grid speed: a window with its two
#: bracketing speeds holds about 20 speeds of the pocket grid (spacing τ/10) and 9–10 of the
#: default 400-speed grid over 1 000–24 000 rpm, so each holds a probe (the stride is only a cost:
#: the second round probes the other speeds of every window still open).
_PROBE_STRIDE = 8



@dataclass(frozen=True)
class ToolCut:
    """One tool to find a pocket for.

    Attributes
    ----------
    key : str
        The caller's name for it (a tool id).
    frequency_hz : numpy.ndarray, shape (nfreq,)
    h : numpy.ndarray, shape (nfreq,), complex
        Tool-point receptance, m/N (used in x and y).
    teeth : int
    flute_length_m : float
        Largest stepdown, m.
    min_rpm, max_rpm : float
        The speeds that may be chosen, rpm.
    h_draws : numpy.ndarray, shape (ndraws, nfreq), complex, optional
        The drawn assemblies' ``h`` (robust pockets).
    """

    key: str
    frequency_hz: np.ndarray
    h: np.ndarray
    teeth: int
    flute_length_m: float
    min_rpm: float
    max_rpm: float
    h_draws: np.ndarray | None = None


@dataclass(frozen=True)
class CutSettings:
    """The cut and the rule shared by every tool.

    Attributes
    ----------
    tangential_coefficient_n_m2, radial_ratio, radial_immersion : float
    milling : {"up", "down"}
    rule : PocketRule
        Safety factor and speed tolerance (its ``max_depth_m`` is ignored: each tool's flute length).
    method : {"zoa", "semi_discretization", "auto"}
    confidence : float or None
        Choose the pocket on the robust limit at this confidence (needs ``h_draws``).
    sdm_speed_count : int
        Speeds of each tool's semi-discretization grid.
    modes_per_direction : int
        Modes fitted per tool for the semi-discretization, at most (default: the maximum,
        ``DEFAULT_MODES_PER_DIRECTION``; every peak above the fit's threshold is kept up to it,
        and any mode left out is named in the tool's notes).
    """

    tangential_coefficient_n_m2: float
    radial_ratio: float
    radial_immersion: float
    milling: Milling
    rule: PocketRule = field(default_factory=PocketRule)
    method: PresetMethod = "auto"
    confidence: float | None = None
    sdm_speed_count: int = DEFAULT_SDM_SPEED_COUNT
    modes_per_direction: int = DEFAULT_MODES_PER_DIRECTION


@dataclass(frozen=True)
class ToolPocket:
    """What a tool gets: a pocket, or the reason for none.

    Attributes
    ----------
    key : str
    method : str
        The method used (``"zoa"`` or ``"semi_discretization"``).
    method_reason : str
        Why (the caller's choice, or :func:`auto_method`'s rule).
    pocket : Pocket or None
        None when refused.
    refusal : str or None
        Why there is no pocket (a true reason).
    depth_limit_m : float
        Nominal depth limit within the chosen speed's window, m (NaN when refused; inf when
        stable to the search depth).
    robust_depth_limit_m : float or None
        The robust one, when asked for.
    absolute_depth_limit_m : float
        The smallest limit of the diagram, m (NaN when it has none, or when slow speeds that
        cannot win were not screened: :func:`_screen_pruned`).
    stable_to_flute_length : bool
        The stepdown is the flute length and the window is stable at least to
        ``safety_factor × flute length``.
    notes : tuple of str
        Plain-language caveats (under-resolved speeds in the window, the flute-length cap, …).
    lobes : LobeResult or None
        The lobe diagram the pocket was chosen on (coarse grid for SDM).
    """

    key: str
    method: str
    method_reason: str
    pocket: Pocket | None = None
    refusal: str | None = None
    depth_limit_m: float = math.nan
    robust_depth_limit_m: float | None = None
    absolute_depth_limit_m: float = math.nan
    stable_to_flute_length: bool = False
    notes: tuple[str, ...] = ()
    lobes: LobeResult | None = None

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready summary (NaN and inf as None)."""
        def num(x: float | None) -> float | None:
            return float(x) if x is not None and math.isfinite(x) else None
        return {"key": self.key, "method": self.method, "method_reason": self.method_reason,
                "pocket": None if self.pocket is None else self.pocket.to_dict(), "refusal": self.refusal,
                "depth_limit_m": num(self.depth_limit_m), "robust_depth_limit_m": num(self.robust_depth_limit_m),
                "absolute_depth_limit_m": num(self.absolute_depth_limit_m),
                "stable_to_flute_length": self.stable_to_flute_length, "notes": list(self.notes)}


def _method(cut: ToolCut, settings: CutSettings) -> tuple[str, str]:
    if settings.method == "auto":
        return auto_method(cut.teeth, settings.radial_immersion)
    return settings.method, f"{settings.method}: chosen by the caller"


def tool_pockets(tools: Sequence[ToolCut], settings: CutSettings,
                 progress: Callable[[int, int], None] | None = None,
                 robust_sdm: Callable[..., np.ndarray] | None = None) -> list[ToolPocket]:
    """Each tool's best stable pocket (module docstring), in the order given.

    Parameters
    ----------
    tools : sequence of ToolCut
    settings : CutSettings
    progress : callable, optional
        ``progress(done, total)`` over the tools.
    robust_sdm : callable, optional
        The robust semi-discretization limit (default
        :func:`rcsa.analysis.lobes.robust_sdm.robust_sdm_limits`); a seam for reduced draws.

    Returns
    -------
    list of ToolPocket
    """
    methods = [_method(t, settings) for t in tools]
    out: list[ToolPocket | None] = [None] * len(tools)
    done = 0
    for i, (cut, (method, reason)) in enumerate(zip(tools, methods, strict=True)):  # a loop over tools (ZOA)
        if method == "zoa":
            out[i] = _zoa_pocket(cut, settings, reason)
            done += 1
            if progress is not None:
                progress(done, len(tools))
    sdm = [i for i, (m, _) in enumerate(methods) if m == "semi_discretization"]
    for teeth in sorted({tools[i].teeth for i in sdm}):  # one batch per tooth count
        group = [i for i in sdm if tools[i].teeth == teeth]
        base = done

        def group_progress(part: int, total: int, base: int = base, n: int = len(group)) -> None:
            if progress is not None:
                progress(base + int(n * part / max(total, 1)), len(tools))

        for i, result in zip(group, _sdm_pockets([tools[i] for i in group], settings, [methods[i][1] for i in group],
                                                 group_progress, robust_sdm), strict=True):
            out[i] = result
        done += len(group)
    return [o for o in out if o is not None]


# --------------------------------------------------------------------------- zero-order


def _zoa_pocket(cut: ToolCut, settings: CutSettings, reason: str) -> ToolPocket:
    grid = pocket_speed_grid(cut.min_rpm, cut.max_rpm, settings.rule.speed_tolerance)
    common = {"teeth": cut.teeth, "tangential_coefficient_n_m2": settings.tangential_coefficient_n_m2,
              "radial_ratio": settings.radial_ratio, "radial_immersion": settings.radial_immersion,
              "milling": settings.milling, "spindle_speed_rpm": grid}
    try:
        lobes = stability_lobes(cut.frequency_hz, cut.h, None, **common)
    except InputError as err:
        if err.field == "frf_x" and "no frequency gives a positive depth limit" in err.rule:
            return ToolPocket(cut.key, "zoa", reason, refusal=(
                f"zero-order averaging finds no positive depth limit in this cut ({cut.teeth} teeth, a_e/D = "
                f"{settings.radial_immersion:g}: the average cutting force has no direction that excites the "
                "tool): it cannot judge the cut; use method semi_discretization (or auto)"))
        raise InputError(f"stability lobes: {err.field}", err.rule) from None
    limit = lobes.depth_limit_m
    if settings.confidence is not None:
        if cut.h_draws is None:
            raise InputError("uncertainty", "no drawn FRFs for this tool: robust presets need them")
        envelopes = depth_limit_envelopes(cut.frequency_hz, cut.h_draws, **common)
        limit = robust_depth_limit(envelopes, lobes.depth_limit_m, settings.confidence)
    return _finish(cut, settings, "zoa", reason, grid, limit, lobes.depth_limit_m, lobes,
                   search_max_m=math.inf, robust=settings.confidence is not None)


def _finish(cut: ToolCut, settings: CutSettings, method: str, reason: str, grid: np.ndarray, limit: np.ndarray,
            nominal: np.ndarray, lobes: LobeResult, *, search_max_m: float, robust: bool,
            notes: Sequence[str] = ()) -> ToolPocket:
    rule = replace(settings.rule, max_depth_m=cut.flute_length_m)
    pocket = best_pocket(grid, limit, min_rpm=cut.min_rpm, max_rpm=cut.max_rpm, rule=rule,
                         chatter_frequency_hz=lobes.chatter_frequency_hz, governing_lobe=lobes.governing_lobe)
    absolute = float(np.nanmin(nominal)) if np.any(np.isfinite(nominal)) else math.nan
    if pocket is None:
        return ToolPocket(cut.key, method, reason, refusal=(
            f"no speed between {cut.min_rpm:.0f} and {cut.max_rpm:.0f} rpm keeps a ±{settings.rule.speed_tolerance:.0%} "
            "window stable" + (" at the robust limit" if robust else "") + f" ({method} lobes)"),
            absolute_depth_limit_m=absolute, lobes=lobes, notes=tuple(notes))
    at = int(np.argmin(np.abs(grid - pocket.spindle_speed_rpm)))
    nominal_window = float(window_minimum(grid, nominal, settings.rule.speed_tolerance)[at])
    capped = pocket.limited_by == "flute_length"
    out_notes = list(notes)
    if capped:
        deep = ("every speed of the window is stable" + (" (no limit found below "
                f"{search_max_m * 1e3:.4g} mm)" if math.isfinite(search_max_m) else "")
                if not math.isfinite(pocket.depth_limit_m) else
                f"the window's limit is {pocket.depth_limit_m * 1e3:.4g} mm")
        out_notes.append(f"stepdown capped at the flute length {cut.flute_length_m * 1e3:.4g} mm: {deep}, deeper "
                         f"than safety factor {settings.rule.safety_factor:g} x the flute length")
    return ToolPocket(cut.key, method, reason, pocket=pocket, depth_limit_m=nominal_window,
                      robust_depth_limit_m=pocket.depth_limit_m if robust else None, absolute_depth_limit_m=absolute,
                      stable_to_flute_length=capped, notes=tuple(out_notes), lobes=lobes)


# --------------------------------------------------------------------------- semi-discretization


def _sdm_grid(cut: ToolCut, settings: CutSettings) -> np.ndarray:
    tol = settings.rule.speed_tolerance
    fine = pocket_speed_grid(cut.min_rpm, cut.max_rpm, tol)
    return np.geomspace(fine[0], fine[-1], min(settings.sdm_speed_count, fine.size))


def _pocket_limit(depth: np.ndarray, ceiling_m: float, needed_m: float) -> np.ndarray:
    """SDM limits for the pocket rule: no limit below a ceiling that reaches ``needed_m`` is
    stable to the flute length (inf); below a shallower ceiling only the ceiling is known."""
    return np.where(np.isfinite(depth), depth, np.inf if ceiling_m >= needed_m else ceiling_m)


def _fit(cut: ToolCut, settings: CutSettings) -> ModalModel | str:
    try:
        return fit_modal_model(np.asarray(cut.frequency_hz, dtype=float), np.asarray(cut.h),
                               modes_per_direction=settings.modes_per_direction)
    except InputError as err:
        return f"the tool-point FRF has no mode to build the semi-discretization on ({err.rule})"


def _sdm_pockets(tools: Sequence[ToolCut], settings: CutSettings, reasons: Sequence[str],
                 progress: Callable[[int, int], None] | None,
                 robust_sdm: Callable[..., np.ndarray] | None) -> list[ToolPocket]:
    method = "semi_discretization"
    fits = [_fit(t, settings) for t in tools]
    ok = [i for i, f in enumerate(fits) if isinstance(f, ModalModel)]
    out: list[ToolPocket] = [ToolPocket(t.key, method, r, refusal=f if isinstance(f, str) else None)
                             for t, f, r in zip(tools, fits, reasons, strict=True)]
    if not ok:
        return out
    models = [fits[i] for i in ok]
    assert all(isinstance(m, ModalModel) for m in models)
    cuts = [tools[i] for i in ok]
    full = [_sdm_grid(t, settings) for t in cuts]
    needed = [settings.rule.safety_factor * t.flute_length_m * _CAP_MARGIN for t in cuts]
    kw = {"teeth": cuts[0].teeth, "tangential_coefficient_n_m2": settings.tangential_coefficient_n_m2,
          "radial_ratio": settings.radial_ratio, "radial_immersion": settings.radial_immersion,
          "milling": settings.milling}
    robust: list[np.ndarray | None] = [None] * len(cuts)
    drawn: list[list[ModalModel] | None] = [None] * len(cuts)
    if settings.confidence is None:
        coarse, state = _screen_pruned(models, cuts, full, needed, settings, kw, progress)
    else:  # robust limits are drawn on the whole coarse diagram: nothing pruned
        coarse = _screen(models, full, needed, kw, progress)
        solve = robust_sdm or robust_sdm_limits
        for j, (cut, model, lobes) in enumerate(zip(cuts, models, coarse, strict=True)):  # a loop over tools
            if cut.h_draws is None:
                raise InputError("uncertainty", "no drawn FRFs for this tool: robust presets need them")
            robust[j] = solve(model, cut.frequency_hz, cut.h, cut.h_draws, lobes, settings.confidence, **kw)
            drawn[j] = drawn_models(model, modal_ratios(model, cut.frequency_hz, cut.h, cut.h_draws), VERIFY_DRAWS)
        state = _verify(models, cuts, coarse, robust, needed, settings, kw, drawn)
    for j, i in enumerate(ok):
        best = state.best(j)
        extent = _pocket_extent(models[j], full[j], coarse[j], state.limits[j], best, settings, kw, state, j)
        out[i] = _make(cuts[j], full[j], coarse[j], state, j, best, extent, settings, needed[j],
                       robust[j] is not None)(reasons[i])
    return out


def _screen(models: Sequence[ModalModel], grids: Sequence[np.ndarray], needed: Sequence[float], kw: dict[str, Any],
            progress: Callable[[int, int], None] | None) -> list[SemiDiscretizationResult]:
    """The screening pass (:data:`_SCREEN_STEPS_PER_CYCLE`, ``_SCREEN_RTOL``, no check) of each tool's speeds."""
    return semi_discretization_lobes_many(models, **kw, spindle_speed_rpm=grids,  # type: ignore[arg-type]
                                          progress=progress, min_depth_search_max_m=needed, depth_rtol=_SCREEN_RTOL,
                                          scan_from_neighbours=True, steps_per_cycle=_SCREEN_STEPS_PER_CYCLE,
                                          check=False)


def _screen_pruned(models: Sequence[ModalModel], cuts: Sequence[ToolCut], grids: Sequence[np.ndarray],
                   needed: Sequence[float], settings: CutSettings, kw: dict[str, Any],
                   progress: Callable[[int, int], None] | None) -> tuple[list[SemiDiscretizationResult], _Verified]:
    """Screen and verify each tool's top speeds first, then only the slower windows that can still win.

    Branch and bound on the pocket's score ``S = n × stepdown`` (rpm·m). The grid's top band
    (from ``_TOP_BAND × max``) is screened and verified; its best verified score ``S₁`` is a
    score the final pocket reaches. A slower window centred on ``n`` can beat it only when

    * ``n × flute length > S₁`` (the stepdown is capped at the flute length), and
    * every speed ``m`` of its window (the grid speeds in it and the two bracketing it, as the
      rule takes them) is stable at ``D(m) = safety_factor × S₁ × (1 − τ) / (m r²)`` (``r``: the
      grid's ratio; ``D(m)`` is at most the depth any window holding ``m`` needs to beat
      ``S₁``, so one unstable ``m`` refutes all of them).

    Speeds outside every window of the first kind are not looked at; the others are probed
    with one evaluation each at ``D(m)`` (:func:`stable_at_depth_many`, the screening's steps,
    so a refuted speed's screened limit would have been below ``D(m)`` too) — every
    ``_PROBE_STRIDE``-th speed first, then the other speeds of the windows still open — and
    only the windows no probe refutes are screened. The verification then runs on every screened speed,
    a window being a candidate only when all its speeds were screened, sharing the first pass's
    densely solved windows. The pocket chosen is the one screening the whole grid gives. A
    tool with no verified window in the top band is screened whole.
    """
    tol, sf = settings.rule.speed_tolerance, settings.rule.safety_factor
    split = [int(np.searchsorted(g, max(g[0], _TOP_BAND * g[-1]))) for g in grids]
    first = _screen(models, [g[s:] for g, s in zip(grids, split, strict=True)], needed, kw,
                    _share(progress, 0.0, _TOP_SHARE))
    none: list[Any] = [None] * len(cuts)
    state = _verify(models, cuts, first, none, needed, settings, kw, none)
    ranges = [_window_ranges(g, tol) for g in grids]
    alive, depth = [], []
    for j, (cut, g, s) in enumerate(zip(cuts, grids, split, strict=True)):  # a loop over tools
        best = state.best_score(j)
        alive.append((np.arange(g.size) < s) & (g * cut.flute_length_m >= best * (1 - 1e-12)))
        ratio = g[1] / g[0] if g.size > 1 else 1.0
        depth.append(np.minimum(sf * best * (1 - tol) / (g * ratio**2), needed[j]) if best > 0 else None)
    refuted = [np.zeros(g.size, dtype=bool) for g in grids]
    probed = [np.zeros(g.size, dtype=bool) for g in grids]
    for stride in (_PROBE_STRIDE, 1):  # every few speeds first: one unstable speed refutes every window holding it
        probes = []
        for j, (g, s) in enumerate(zip(grids, split, strict=True)):  # a loop over tools
            lo, hi = ranges[j]
            open_ = alive[j] & (_count(refuted[j], lo, hi) == 0)
            touched = _covered(lo[open_], hi[open_], g.size) & ~probed[j]
            touched[s:] = False
            touched[np.arange(g.size) % stride != 0] = False
            probes.append(np.flatnonzero(touched) if depth[j] is not None else np.empty(0, dtype=np.int64))
        asked = [j for j, pr in enumerate(probes) if pr.size]
        if not asked:
            continue
        answers = stable_at_depth_many([models[j] for j in asked], **kw,
                                       spindle_speed_rpm=[grids[j][probes[j]] for j in asked],
                                       depth_m=[depth[j][probes[j]] for j in asked],  # type: ignore[index]
                                       steps_per_cycle=_SCREEN_STEPS_PER_CYCLE)
        for j, stable in zip(asked, answers, strict=True):  # a loop over tools
            probed[j][probes[j]] = True
            refuted[j][probes[j][~stable]] = True
    screened, lower = [], []
    for j, (g, s) in enumerate(zip(grids, split, strict=True)):  # a loop over tools
        lo, hi = ranges[j]
        survive = alive[j] & (_count(refuted[j], lo, hi) == 0)
        wanted = _covered(lo[survive], hi[survive], g.size)
        wanted[s:] = False
        lower.append(np.flatnonzero(wanted))
        wanted[s:] = True
        screened.append(wanted)
    todo = [j for j, low in enumerate(lower) if low.size]
    second = _screen([models[j] for j in todo], [grids[j][lower[j]] for j in todo], [needed[j] for j in todo], kw,
                     _share(progress, _TOP_SHARE, 1.0)) if todo else []
    coarse = list(first)
    for j, part in zip(todo, second, strict=True):  # a loop over tools
        coarse[j] = merged_result([part, first[j]])
    eligible = []
    for j, (g, s) in enumerate(zip(grids, split, strict=True)):  # a loop over tools
        lo, hi = ranges[j]
        whole = _count(~screened[j], lo, hi) == 0
        eligible.append((whole & (alive[j] | (np.arange(g.size) >= s)))[screened[j]])
    state = _verify(models, cuts, coarse, none, needed, settings, kw, none, dense=state.dense,
                    dense_nominal=state.dense_nominal, eligible=eligible)
    return coarse, state


def _window_ranges(grid: np.ndarray, tol: float) -> tuple[np.ndarray, np.ndarray]:
    """Per grid speed, the first and last grid index of its window with the two bracketing speeds
    (as :func:`~rcsa.analysis.lobes.pockets.window_minimum` takes them)."""
    lo = np.maximum(np.searchsorted(grid, grid * (1.0 - tol) * (1.0 + 1e-12), side="right") - 1, 0)
    hi = np.minimum(np.searchsorted(grid, grid * (1.0 + tol) * (1.0 - 1e-12), side="left"), grid.size - 1)
    return lo, hi


def _covered(lo: np.ndarray, hi: np.ndarray, n: int) -> np.ndarray:
    """Mask of the ``n`` indices inside any of the ranges ``lo[i] … hi[i]``."""
    edges = np.zeros(n + 1, dtype=np.int64)
    np.add.at(edges, lo, 1)
    np.add.at(edges, hi + 1, -1)
    return np.cumsum(edges)[:n] > 0


def _count(mask: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """How many of ``mask`` are true in each range ``lo … hi``."""
    total = np.concatenate([[0], np.cumsum(mask)])
    return total[hi + 1] - total[lo]


def _share(progress: Callable[[int, int], None] | None, lo: float, hi: float) -> Callable[[int, int], None] | None:
    """``progress`` of a pass that is the fraction ``lo … hi`` of the screening."""
    if progress is None:
        return None

    def part(done: int, total: int) -> None:
        progress(int(1000 * (lo + (hi - lo) * done / max(total, 1))), 1000)

    return part


def _pocket_extent(model: ModalModel, full: np.ndarray, lobes: SemiDiscretizationResult, limit: np.ndarray,
                   best: int, settings: CutSettings, kw: dict[str, Any], state: _Verified,
                   j: int) -> tuple[float, float, bool, bool]:
    """The chosen speed's pocket: the speeds of the full grid around it, contiguous, whose limit
    reaches the stepdown times the safety factor — a screened speed by its coarse limit, a speed
    not screened (:func:`_screen_pruned`) checked at that depth (one evaluation at the
    screening's steps: :func:`stable_at_depth_many`), a run of them at a time — followed at most
    :data:`POCKET_FOLLOWED_SPAN` times slower or faster than the chosen speed.

    Returns the pocket's lowest and highest speed, rpm, and whether it is open there (stable as far
    as it was followed, the grid going on beyond)."""
    if best < 0:
        return math.nan, math.nan, False, False
    need = state.stepdown(j, best, settings) * settings.rule.safety_factor * (1 - 1e-12)
    at = np.searchsorted(full, lobes.spindle_speed_rpm * (1 - 1e-12))
    known = np.zeros(full.size, dtype=bool)
    known[at] = True
    ok = np.zeros(full.size, dtype=bool)
    ok[at] = limit >= need  # inf (stable to the flute length) counts; NaN does not
    centre = int(at[best])
    lowest = int(np.searchsorted(full, full[centre] / POCKET_FOLLOWED_SPAN * (1 - 1e-12)))
    highest = int(np.searchsorted(full, full[centre] * POCKET_FOLLOWED_SPAN * (1 + 1e-12), side="right")) - 1

    def walk(i: int, step: int, end: int) -> int:
        """The last index of the pocket from ``i`` (inside it) towards ``end`` in direction ``step``."""
        while i != end:
            nxt = i + step
            if known[nxt]:
                if not ok[nxt]:
                    return i
                i = nxt
                continue
            run = [nxt]
            while len(run) < _EXTENT_CHUNK and run[-1] != end and not known[run[-1] + step]:
                run.append(run[-1] + step)
            stable = stable_at_depth_many([model], **kw, spindle_speed_rpm=[full[run]], depth_m=[need],
                                          steps_per_cycle=_SCREEN_STEPS_PER_CYCLE)[0]
            if not stable.all():
                return run[int(np.argmin(stable))] - step
            i = run[-1]
        return i

    low, high = walk(centre, -1, lowest), walk(centre, 1, highest)
    return float(full[low]), float(full[high]), low == lowest > 0, high == highest < full.size - 1


@dataclass
class _Dense:
    """Densely solved speeds of one tool and their limits (pocket form), merged as they come."""

    speed: np.ndarray = field(default_factory=lambda: np.empty(0))
    limit: np.ndarray = field(default_factory=lambda: np.empty(0))
    resolved: np.ndarray = field(default_factory=lambda: np.empty(0, dtype=bool))

    def add(self, speed: np.ndarray, limit: np.ndarray, resolved: np.ndarray) -> None:
        """Merge densely solved speeds; an unresolved one counts as unstable (its limit is not known)."""
        order = np.argsort(np.concatenate([self.speed, speed]))
        self.speed = np.concatenate([self.speed, speed])[order]
        self.limit = np.concatenate([self.limit, np.where(resolved, limit, np.nan)])[order]
        self.resolved = np.concatenate([self.resolved, resolved])[order]

    def unresolved(self, n: float, tol: float) -> int:
        """Dense speeds of the window whose limit two resolutions did not agree on."""
        inside = (self.speed >= n * (1 - tol)) & (self.speed <= n * (1 + tol))
        return int(np.count_nonzero(~self.resolved[inside]))

    def covers(self, n: float, tol: float) -> bool:
        """Dense speeds span the window ``n (1 ± tol)`` with no gap wider than the verification step."""
        inside = self.speed[(self.speed >= n * (1 - tol)) & (self.speed <= n * (1 + tol))]
        if inside.size < 2:
            return False
        edges = np.concatenate([[n * (1 - tol)], inside, [n * (1 + tol)]])
        return bool(np.max(np.diff(np.log(edges))) <= 1.5 * 2 * tol / (_VERIFY_POINTS - 1))

    def window_min(self, n: float, tol: float) -> float:
        """Smallest limit at the dense speeds inside the window and those just beyond its ends
        (within one verification step: as the rule takes the grid's; NaN counts as unstable)."""
        inside = np.flatnonzero((self.speed >= n * (1 - tol) * (1 - 1e-12)) & (self.speed <= n * (1 + tol) * (1 + 1e-12)))
        if not inside.size:
            return math.inf
        gap = math.exp(1.5 * 2 * tol / (_VERIFY_POINTS - 1))  # a neighbour within one verification step
        pick = list(inside)
        if inside[0] > 0 and self.speed[inside[0] - 1] >= n * (1 - tol) / gap:
            pick.append(inside[0] - 1)
        if inside[-1] + 1 < self.speed.size and self.speed[inside[-1] + 1] <= n * (1 + tol) * gap:
            pick.append(inside[-1] + 1)
        values = self.limit[np.array(pick)]
        return float(np.min(np.where(np.isnan(values), -np.inf, values)))


@dataclass
class _Verified:
    """The verification's state over each tool's coarse grid: pocket-form limits, verified
    scores (``n · stepdown``; NaN: not verified) and the densely solved speeds."""

    grids: list[np.ndarray]
    limits: list[np.ndarray]
    nominal: list[np.ndarray]
    verified: list[np.ndarray]
    dense: list[_Dense]
    dense_nominal: list[_Dense]
    flute_m: list[float]

    def best(self, j: int) -> int:
        """Index of tool ``j``'s best verified grid speed (-1: none positive)."""
        v = np.where(np.isnan(self.verified[j]), -np.inf, self.verified[j])
        return int(np.argmax(v)) if np.any(np.isfinite(v) & (v > 0)) else -1

    def best_score(self, j: int) -> float:
        """Tool ``j``'s best verified ``n · stepdown`` (rpm·m; 0 when none)."""
        i = self.best(j)
        return float(self.verified[j][i]) if i >= 0 else 0.0

    def window(self, j: int, i: int, tol: float) -> float:
        """The limit of grid speed ``i``'s window: its coarse window's and the dense speeds' smallest."""
        n = float(self.grids[j][i])
        return min(float(window_minimum(self.grids[j], self.limits[j], tol)[i]), self.dense[j].window_min(n, tol))

    def stepdown(self, j: int, i: int, settings: CutSettings) -> float:
        """The stepdown the rule allows at grid speed ``i``, m."""
        return min(self.window(j, i, settings.rule.speed_tolerance) / settings.rule.safety_factor, self.flute_m[j])


def _verify(models: Sequence[ModalModel], cuts: Sequence[ToolCut], coarse: Sequence[SemiDiscretizationResult],
            robust: Sequence[np.ndarray | None], needed: Sequence[float], settings: CutSettings, kw: dict[str, Any],
            drawn: Sequence[list[ModalModel] | None], *, dense: list[_Dense] | None = None,
            dense_nominal: list[_Dense] | None = None, eligible: Sequence[np.ndarray] | None = None) -> _Verified:
    """Choose each tool's pocket on its coarse grid, then verify the best windows densely.

    A speed's verified window limit is the smallest of its coarse window limit (the grid
    speeds in the window and the two bracketing it, as the rule takes them) and of every
    densely solved speed inside the window, so a verified score never exceeds the coarse
    one. Per round and tool the best unverified candidates (up to ``_VERIFY_PER_ROUND``
    distinct windows, ``_VERIFY_FIRST_ROUND`` in the first round) are solved at ``_VERIFY_POINTS`` speeds across their window; every
    candidate whose window the dense speeds then cover (or already covered: ``dense`` from an
    earlier pass) is verified too. Only ``eligible`` grid speeds are candidates (default all). A tool is done when
    its best verified score is at least ``1 − _VERIFY_SLACK`` of every unverified candidate's
    coarse score (or after ``_VERIFY_ROUNDS`` rounds). A robust
    tool's dense speeds are also solved for its drawn modal models (``drawn``: every draw's own
    modes), and their ``(1 − confidence)`` quantile, never above the nominal, is its limit there.
    """
    tol, sf = settings.rule.speed_tolerance, settings.rule.safety_factor
    grids = [r.spindle_speed_rpm for r in coarse]
    nominal = [_pocket_limit(r.depth_limit_m, r.depth_search_max_m, need) for r, need in zip(coarse, needed,
                                                                                             strict=True)]
    limits = [nom if rob is None else np.fmin(_pocket_limit(rob, r.depth_search_max_m, need), nom)
              for nom, rob, r, need in zip(nominal, robust, coarse, needed, strict=True)]
    coarse_window = [window_minimum(g, lim, tol) for g, lim in zip(grids, limits, strict=True)]
    score, verified = [], []
    for j, (cut, g, w) in enumerate(zip(cuts, grids, coarse_window, strict=True)):  # a loop over tools
        allowed = np.minimum(w / sf, cut.flute_length_m)
        ok = (g >= cut.min_rpm * (1 - 1e-12)) & (g <= cut.max_rpm * (1 + 1e-12)) & np.isfinite(allowed) & (allowed > 0)
        if eligible is not None:
            ok &= eligible[j]
        score.append(np.where(ok, g * np.where(ok, allowed, 0.0), -np.inf))
        verified.append(np.full(g.size, np.nan))
    dense = [_Dense() for _ in cuts] if dense is None else dense
    dense_nominal = [_Dense() for _ in cuts] if dense_nominal is None else dense_nominal

    def mark_covered(j: int) -> None:
        g = grids[j]
        for i in np.flatnonzero(np.isfinite(score[j]) & np.isnan(verified[j])):  # candidates now covered
            n = float(g[i])
            if not dense[j].covers(n, tol):
                continue
            allowed = min(min(coarse_window[j][i], dense[j].window_min(n, tol)) / sf, cuts[j].flute_length_m)
            verified[j][i] = n * allowed if allowed > 0 else -np.inf

    for j in range(len(cuts)):  # a loop over tools: windows an earlier pass solved
        if dense[j].speed.size:
            mark_covered(j)
    open_ = [j for j in range(len(cuts)) if np.any(np.isfinite(score[j]))]
    for round_ in range(_VERIFY_ROUNDS):
        per_round = _VERIFY_FIRST_ROUND if round_ == 0 else _VERIFY_PER_ROUND
        todo: dict[int, list[float]] = {}
        for j in open_:  # a loop over tools
            unverified = np.where(np.isnan(verified[j]), score[j], -np.inf)
            best = np.nanmax(np.where(np.isnan(verified[j]), -np.inf, verified[j]))
            if not np.isfinite(np.max(unverified)) or best >= (1.0 - _VERIFY_SLACK) * np.max(unverified):
                continue
            chosen: list[float] = []
            for i in np.argsort(-unverified):
                if len(chosen) >= per_round or not np.isfinite(unverified[i]):
                    break
                n = float(grids[j][i])
                if all(abs(n / c - 1) >= tol for c in chosen):
                    chosen.append(n)
            todo[j] = chosen
        if not todo:
            break
        solved = _solve_windows(models, todo, needed, kw, tol, [(g, lim) for g, lim in zip(grids, nominal, strict=True)])
        robust_dense = _robust_windows(drawn, solved, needed, kw, settings.confidence)
        for j, r in solved:  # a loop over tools
            nom = _pocket_limit(r.depth_limit_m, r.depth_search_max_m, needed[j])
            dense_nominal[j].add(r.spindle_speed_rpm, nom, r.resolved)
            if j in robust_dense:
                nom = np.fmin(robust_dense[j], nom)
            dense[j].add(r.spindle_speed_rpm, nom, r.resolved)
            mark_covered(j)
    return _Verified(grids, limits, nominal, verified, dense, dense_nominal, [c.flute_length_m for c in cuts])


def _solve_windows(models: Sequence[ModalModel], todo: dict[int, list[float]], needed: Sequence[float],
                   kw: dict[str, Any], tol: float, coarse: Sequence[tuple[np.ndarray, np.ndarray]]
                   ) -> list[tuple[int, SemiDiscretizationResult]]:
    """The windows ``n (1 ± tol)`` of ``todo`` (tool → centre speeds) solved densely, each speed
    with the steps that resolve its cut, checked at a second resolution and refined where the two
    differ (:func:`semi_discretization_lobes_many`); a speed solved from scratch starts its depth
    scan at half the coarse limit there (``coarse``: each tool's grid and pocket-form limits; the
    smaller of the two grid speeds around it)."""
    order = sorted(todo)
    speeds = []
    for j in order:  # a loop over tools
        windows = [np.geomspace(n * (1 - tol), n * (1 + tol), _VERIFY_POINTS) for n in todo[j]]
        speeds.append(np.unique(np.concatenate(windows)))
    starts = [_coarse_start(*coarse[j], sp, needed[j]) for j, sp in zip(order, speeds, strict=True)]
    solved = semi_discretization_lobes_many([models[j] for j in order], **kw, spindle_speed_rpm=speeds,
                                            min_depth_search_max_m=[needed[j] for j in order],
                                            depth_rtol=_VERIFY_RTOL, scan_start_m=starts)
    return list(zip(order, solved, strict=True))


def _coarse_start(grid: np.ndarray, limit: np.ndarray, speeds: np.ndarray, needed: float) -> np.ndarray:
    """Half the smaller coarse limit of the two grid speeds around each speed (pocket form: inf is
    "stable to ``needed``"); NaN where either is unsettled."""
    i = np.clip(np.searchsorted(grid, speeds), 1, grid.size - 1)
    around = np.minimum(np.minimum(limit[i - 1], limit[i]), needed)
    return 0.5 * around


def _robust_windows(drawn: Sequence[list[ModalModel] | None], solved: list[tuple[int, SemiDiscretizationResult]],
                    needed: Sequence[float], kw: dict[str, Any], confidence: float | None) -> dict[int, np.ndarray]:
    """For robust tools, the ``(1 − confidence)`` quantile over their drawn models at the dense speeds just solved
    (pocket form: inf where a draw is stable to the flute length)."""
    if confidence is None:
        return {}
    jobs = [(j, r) for j, r in solved if drawn[j]]
    if not jobs:
        return {}
    models, speeds, depth, owner = [], [], [], []
    for j, r in jobs:  # a loop over robust tools
        for m in drawn[j] or []:
            models.append(m)
            speeds.append(r.spindle_speed_rpm)
            depth.append(needed[j])
            owner.append(j)
    results = semi_discretization_lobes_many(models, **kw, spindle_speed_rpm=speeds,
                                             min_depth_search_max_m=depth, depth_rtol=_VERIFY_RTOL)
    out = {}
    for j, _ in jobs:  # a loop over robust tools
        rows = [np.where(res.resolved, _pocket_limit(res.depth_limit_m, res.depth_search_max_m, needed[j]), np.nan)
                for res, o in zip(results, owner, strict=True) if o == j]
        table = np.where(np.isinf(np.array(rows)), 1e3, np.array(rows))
        q = np.percentile(np.where(np.isnan(table), -np.inf, table), 100.0 * (1.0 - confidence), axis=0,
                          method="lower")
        out[j] = np.where(q >= 1e2, np.inf, q)
    return out


def _make(cut: ToolCut, full: np.ndarray, lobes: SemiDiscretizationResult, state: _Verified, j: int, best: int,
          extent: tuple[float, float, bool, bool], settings: CutSettings, needed: float, robust: bool) -> Callable[[str], ToolPocket]:
    def build(reason: str) -> ToolPocket:
        method = "semi_discretization"
        tol, sf = settings.rule.speed_tolerance, settings.rule.safety_factor
        grid = lobes.spindle_speed_rpm
        notes: list[str] = list(lobes.modal_model.notes())  # every mode left out, with its share of the peak
        absolute = lobes.min_depth_limit_m
        if grid.size < full.size:  # pruned: some slow speeds' limits are not known
            absolute = math.nan
            notes.append(f"{full.size - grid.size} of {full.size} grid speeds (below {grid[-1]:.0f} rpm) were not "
                         "screened: no window holding them can beat this tool's best verified window (n x flute "
                         "length is below its n x stepdown, or one speed of the window is unstable at the depth it "
                         "would need), so the absolute depth limit (the smallest over all speeds) is not known")
        if best < 0:
            return ToolPocket(cut.key, method, reason, refusal=(
                f"no speed between {cut.min_rpm:.0f} and {cut.max_rpm:.0f} rpm keeps a ±{tol:.0%} window stable"
                + (" at the robust limit" if robust else "") + " (semi_discretization lobes)"),
                absolute_depth_limit_m=absolute, lobes=lobes, notes=tuple(notes))
        n = float(grid[best])
        window = state.window(j, best, tol)
        nominal_window = min(float(window_minimum(grid, state.nominal[j], tol)[best]),
                             state.dense_nominal[j].window_min(n, tol))
        stepdown = min(window / sf, cut.flute_length_m)
        capped = stepdown >= cut.flute_length_m
        w_lo = max(int(np.searchsorted(grid, n * (1 - tol) * (1 + 1e-12), side="right")) - 1, 0)
        w_hi = min(int(np.searchsorted(grid, n * (1 + tol) * (1 - 1e-12), side="left")), grid.size - 1)
        part = lobes.depth_limit_m[w_lo : w_hi + 1]
        weakest = w_lo + int(np.argmin(np.where(np.isfinite(part), part, np.inf)))
        pocket = Pocket(spindle_speed_rpm=n, depth_limit_m=window, stepdown_m=stepdown,
                        limited_by="flute_length" if capped else "stability", pocket_low_rpm=extent[0],
                        pocket_high_rpm=extent[1], pocket_low_open=extent[2], pocket_high_open=extent[3],
                        chatter_frequency_hz=float(lobes.chatter_frequency_hz[weakest]),
                        governing_lobe=int(lobes.governing_lobe[weakest]), removal_index_rpm_m=n * stepdown)
        if extent[2] or extent[3]:
            ends = " and ".join(e for e, o in (("below", extent[2]), ("above", extent[3])) if o)
            notes.append(f"pocket followed from {extent[0]:.0f} to {extent[1]:.0f} rpm (at most {POCKET_FOLLOWED_SPAN:g} "
                         f"times slower or faster than its speed) and stable that far: it may extend further {ends}")
        unresolved = state.dense_nominal[j].unresolved(n, tol)
        if unresolved:  # never the chosen window (unresolved speeds count as unstable); said for the record
            notes.append(f"{unresolved} speed(s) of this window are not resolved (two resolutions differ by more "
                         "than 1 %)")
        if capped:
            deep = (f"no semi-discretization limit below {needed * 1e3:.4g} mm in the window"
                    if not math.isfinite(window) else f"the window's limit is {window * 1e3:.4g} mm")
            notes.append(f"stepdown capped at the flute length {cut.flute_length_m * 1e3:.4g} mm: {deep}, at least "
                         f"safety factor {sf:g} x the flute length")
        return ToolPocket(cut.key, method, reason, pocket=pocket, depth_limit_m=nominal_window,
                          robust_depth_limit_m=window if robust else None, absolute_depth_limit_m=absolute,
                          stable_to_flute_length=capped, notes=tuple(notes), lobes=lobes)

    return build
