"""What a person reads of a result: short tables of a prediction, a batch, a diagnosis and lobes.

The CLI prints them on a terminal (rich tables, :func:`rcsa.cli._common.emit`) instead of the
result's JSON, which stays for machines (``--json``, a pipe, ``-o OUT.json``). Each builder
reads the contract's result document (a :class:`~rcsa.model.prediction.Prediction` is a mapping
of it) and keeps the few numbers a machinist acts on, in the units of the shop floor (Hz,
N/µm, µm/N, mm, rpm). Plain data (titles, headers, rows of text); nothing is drawn here.

>>> from rcsa.app.predictions import predict
>>> from rcsa.reference import ra1
>>> modes, tool_point = prediction_summary(predict(ra1({"start_hz": 100.0, "stop_hz": 2000.0, "step_hz": 5.0})))
>>> modes.rows[0], tool_point.rows[0]
(('1', '599.9'), ('static stiffness', '2.417 N/µm'))
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:
    from rcsa.analysis.lobes.pockets import PocketRule

__all__ = ["MAX_CHORD", "MAX_ROWS", "POCKETS", "Table", "batch_summary", "diagnosis_summary", "lobes_summary",
           "prediction_summary", "unsettled_speeds"]

#: Rows of a long table shown (the caption says how many more there are).
MAX_ROWS = 12
#: Pockets listed by :func:`lobes_summary`.
POCKETS = 3
#: A lobe drawn straight over more than this fraction of the speed is flagged as coarse: as long
#: as the pocket rule's speed tolerance (``rcsa.analysis.lobes.pockets.DEFAULT_SPEED_TOLERANCE``,
#: checked by the tests), so a lobe minimum hidden under the chord could sit in a recommended window.
MAX_CHORD = 0.03
_UM = 1e6
_MM = 1e3


@dataclass(frozen=True)
class Table:
    """One table: its ``title``, the ``columns``' headers (the first a label, the others values,
    drawn right-aligned), the ``rows`` of text (one entry per column) and a ``caption`` of notes
    under it ("" for none)."""

    title: str
    columns: tuple[str, ...]
    rows: tuple[tuple[str, ...], ...]
    caption: str = ""


def _num(value: object) -> float | None:
    """A finite float, or None (missing, null, NaN)."""
    if isinstance(value, bool) or not isinstance(value, int | float | np.floating | np.integer):
        return None
    x = float(value)
    return x if math.isfinite(x) else None


def _fmt(value: object, digits: int = 4, scale: float = 1.0, unit: str = "") -> str:
    """``value × scale`` to ``digits`` significant digits with its unit, "—" when there is none."""
    x = _num(value)
    if x is None:
        return "—"
    text = f"{x * scale:.{digits}g}"
    return f"{text} {unit}" if unit else text


def _clipped(rows: Sequence[tuple[str, ...]], what: str) -> tuple[tuple[tuple[str, ...], ...], str]:
    """At most :data:`MAX_ROWS` rows, and a caption saying how many were left out."""
    if len(rows) <= MAX_ROWS:
        return tuple(rows), ""
    return tuple(rows[:MAX_ROWS]), f"… and {len(rows) - MAX_ROWS} more {what} in the result"


def _frequency_band(result: Mapping[str, Any]) -> str:
    f = result.get("frequency_hz")
    if f is None or len(f) == 0:
        return "—"
    return f"{float(f[0]):g}–{float(f[-1]):g} Hz, {len(f)} lines"


def _largest_peak(result: Mapping[str, Any]) -> str:
    peaks = [p for p in result.get("peaks") or [] if _num(p.get("magnitude_m_n")) is not None]
    if not peaks:
        return "—"
    top = max(peaks, key=lambda p: float(p["magnitude_m_n"]))
    return f"{_fmt(top['magnitude_m_n'], 4, _UM, 'µm/N')} at {_fmt(top.get('frequency_hz'), 5, unit='Hz')}"


def prediction_summary(result: Mapping[str, Any]) -> list[Table]:
    """Natural frequencies, static stiffness, the most negative real part of ``h`` and its
    largest peak (a prediction result, ``docs/contract.md``).

    Parameters
    ----------
    result : mapping
        The contract's prediction result (or a :class:`~rcsa.model.prediction.Prediction`).

    Returns
    -------
    list of Table
        The natural frequencies (with each estimate's sd on a measured spindle), then the
        tool point's numbers; the result's notes are the second table's caption.
    """
    freqs = [float(f) for f in result.get("natural_frequencies_hz") or []]
    fitted = result.get("natural_frequencies_method") == "modal_fit"
    sd = list(result.get("natural_frequencies_sd_hz") or []) if fitted else []
    columns: tuple[str, ...] = ("mode", "frequency (Hz)")
    if fitted:
        columns += ("± sd (Hz)",)
    mode_rows = [(str(i + 1), _fmt(f, 5), *([_fmt(sd[i], 2)] if fitted and i < len(sd) else
                                            ["—"] if fitted else [])) for i, f in enumerate(freqs)]
    rows, more = _clipped(mode_rows, "natural frequencies")
    how = "modal-fit estimates (measured spindle)" if fitted else "exact, undamped"
    modes = Table(f"Natural frequencies ({how})", columns, rows,
                  more or ("" if freqs else "no natural frequency in the band"))
    static = _num(result.get("static_stiffness_n_m"))
    tool_point = Table("Tool point", ("", ""), (
        ("static stiffness", _fmt(static, 4, 1e-6, "N/µm") if static is not None
         else "not given (measured spindle)"),
        ("most negative real part of h", f"{_fmt(result.get('min_real_m_n'), 4, _UM, 'µm/N')} at "
                                         f"{_fmt(result.get('min_real_frequency_hz'), 5, unit='Hz')}"),
        ("largest peak of |h|", _largest_peak(result)),
        ("band", _frequency_band(result)),
    ), "\n".join(str(n) for n in result.get("notes") or []))
    return [modes, tool_point]


def batch_summary(result: Mapping[str, Any]) -> list[Table]:
    """One row per combination of a batch result: its first natural frequency, static stiffness
    and most negative real part of ``h``, or why it failed.

    Parameters
    ----------
    result : mapping
        ``{"results": [...], "summary": {"ok", "error"}}``.

    Returns
    -------
    list of Table
    """
    rows = []
    for r in result.get("results") or []:
        if r.get("status") != "ok":
            rows.append((str(r.get("id")), "error", str(r.get("error", {}).get("detail", r.get("error", ""))),
                         "", ""))
            continue
        freqs = r.get("natural_frequencies_hz") or []
        rows.append((str(r.get("id")), "ok", _fmt(freqs[0] if len(freqs) else None, 5, unit="Hz"),
                     _fmt(r.get("static_stiffness_n_m"), 4, 1e-6, "N/µm"),
                     f"{_fmt(r.get('min_real_m_n'), 4, _UM)} at {_fmt(r.get('min_real_frequency_hz'), 5)} Hz"))
    shown, more = _clipped(rows, "combinations")
    counts = result.get("summary") or {}
    caption = f"{counts.get('ok', 0)} ok, {counts.get('error', 0)} with an error" + (f"; {more}" if more else "")
    return [Table("Batch", ("id", "status", "first mode", "static stiffness", "min Re h (µm/N)"), shown, caption)]


def _verdict_text(verdict: Mapping[str, Any], named: Mapping[str, Any] | None) -> str:
    """The verdict's effect, or the model form it proposes (``clamping_model → contact``), and its status."""
    effect = verdict.get("effect")
    proposed = (named or {}).get("proposed_model")
    what = f"{effect} → {proposed}" if proposed else str(effect)
    return f"{what} ({verdict.get('status')})"


def _calibrated_text(calibrated: Mapping[str, Any]) -> str:
    """The calibrated model's gap and the nuisance parameter it moved most (in its own σ)."""
    moved = {k: _num(v) for k, v in (calibrated.get("parameters_moved_sd") or {}).items()}
    moved = {k: v for k, v in moved.items() if v is not None}
    with_ = ", ".join(str(e) for e in calibrated.get("effects") or []) or "no effect"
    text = f"{_fmt(calibrated.get('gap_db'), 3, unit='dB')} rms ({with_}; tolerances where the data put them"
    if moved:
        name = max(moved, key=lambda k: abs(moved[k] or 0.0))
        text += f", most moved: {name} {moved[name]:+.2g} σ"
    return text + ")"


def _model_form_table(block: Mapping[str, Any]) -> Table | None:
    """The model-form candidates (``model_form`` of a diagnosis response), None without any."""
    rows = [(f"{c.get('candidate')} → {c.get('proposed_model')}", _fmt(c.get("log_bayes_factor"), 3),
             _fmt(c.get("log_evidence_over_best_effect"), 3))
            for c in block.get("candidates") or []]
    if not rows:
        return None
    return Table(f"Model form (base: {block.get('base_model')})", ("candidate", "ln BF", "ln over best effect"),
                 tuple(rows), str(block.get("sentence") or ""))


def diagnosis_summary(result: Mapping[str, Any]) -> list[Table]:
    """The verdict, how far the gap shrinks with it (all measurements and held-out ones), the
    calibrated model's gap, the fitted values, the ranking of the candidate effects and the
    model-form candidates (a diagnosis response).

    Parameters
    ----------
    result : mapping
        The diagnosis response (``docs/contract.md`` "Diagnosis"; ``model_form`` and
        ``calibrated`` are read when present).

    Returns
    -------
    list of Table
        The verdict (its sentence as the caption), the named effect's fitted values, the
        ranking, then the model-form candidates.
    """
    verdict = result.get("verdict") or {}
    gap = result.get("gap") or {}
    effect = verdict.get("effect")
    named = next((e for e in result.get("effects") or [] if e.get("effect") == effect), None)
    rows = [("verdict", _verdict_text(verdict, named)),
            ("gap to the base model", f"{_fmt(gap.get('db_rms'), 3, unit='dB')} rms; χ²/n "
                                      f"{_fmt(gap.get('chi2_per_feature'), 3)}, p {_fmt(gap.get('p_value'), 2)}")]
    if named is not None:
        rows += [
            ("evidence", f"ln BF {_fmt(named.get('log_bayes_factor'), 3)}, SNR {_fmt(named.get('snr'), 3)}, "
                         f"confirmed on held-out: {'yes' if named.get('confirmed_on_held_out') else 'no'}"),
            ("shrink", f"{_fmt(named.get('gap_before_db'), 3)} → {_fmt(named.get('gap_after_db'), 3)} dB rms"),
            ("shrink on held-out", f"{_fmt(named.get('held_out_gap_before_db'), 3)} → "
                                   f"{_fmt(named.get('held_out_gap_after_db'), 3)} dB rms (ratio "
                                   f"{_fmt(named.get('held_out_gap_ratio'), 2)})"),
        ]
    calibrated = result.get("calibrated")
    if isinstance(calibrated, Mapping):
        rows.append(("calibrated model", _calibrated_text(calibrated)))
    table = Table("Diagnosis", ("", ""), tuple(rows), str(verdict.get("sentence") or gap.get("summary") or ""))
    fitted = Table("Fitted values", ("parameter", "value"),
                   tuple((k, _fmt(v, 4)) for k, v in ((named or {}).get("physical") or {}).items()))
    ranking = [(str(e.get("effect")), _fmt(e.get("log_bayes_factor"), 3), _fmt(e.get("posterior_probability"), 3),
                _fmt(e.get("held_out_gap_ratio"), 2)) for e in result.get("ranking") or []]
    shown, more = _clipped(ranking, "candidates")
    forms = _model_form_table(result["model_form"]) if isinstance(result.get("model_form"), Mapping) else None
    return [table, *([fitted] if fitted.rows else []), Table("Candidates, best first", ("effect", "ln BF", "posterior", "held-out gap ratio"), shown,
                         more), *([forms] if forms is not None else [])]


def _pockets(speed: np.ndarray, depth: np.ndarray, chatter: np.ndarray, rule: PocketRule,
             count: int) -> list[Any]:
    """The ``count`` best pockets: each the best of :func:`~rcsa.analysis.lobes.pockets.best_pocket`
    once the pockets found before are taken out of the diagram."""
    from rcsa.analysis.lobes.pockets import best_pocket

    found = []
    depth = depth.copy()
    for _ in range(count):
        pocket = best_pocket(speed, depth, min_rpm=float(speed[0]), max_rpm=float(speed[-1]), rule=rule,
                             chatter_frequency_hz=chatter)
        if pocket is None:
            break
        found.append(pocket)
        depth[(speed >= pocket.pocket_low_rpm) & (speed <= pocket.pocket_high_rpm)] = np.nan
    return found


def lobes_summary(result: Mapping[str, Any]) -> list[Table]:
    """The absolute limit and the best pockets of a stability-lobes result.

    The pockets follow the rule of :mod:`rcsa.analysis.lobes.pockets` with its defaults (the
    worst limit within ±3 % of the speed, divided by the safety factor 1.25, capped at the
    flute length): the best by removal rate, then the best of what is left once it is taken
    out, and so on. With a robust limit in the result the pockets are those of the robust limit.

    Parameters
    ----------
    result : mapping
        The stability-lobes response (``docs/contract.md`` "Stability lobes").

    Returns
    -------
    list of Table
        The limits, then the pockets.
    """
    # the lobes' modules only when lobes are summarised (``rcsa predict`` does without them)
    from rcsa.analysis.lobes.pockets import (
        DEFAULT_SAFETY_FACTOR,
        DEFAULT_SPEED_TOLERANCE,
        PocketRule,
    )

    speed = np.asarray(result.get("spindle_speed_rpm") or [], dtype=float)
    robust = result.get("depth_limit_robust_m")
    limit = robust if robust is not None else result.get("depth_limit_m")
    depth = np.asarray([np.nan if d is None else d for d in limit or []], dtype=float)
    chatter = np.asarray([np.nan if c is None else c for c in result.get("chatter_frequency_hz") or []], dtype=float)
    method = str(result.get("method") or ("semi_discretization" if "steps_per_period" in result else "zoa"))
    rows = [("method", {"zoa": "zero-order (Altintas–Budak)", "semi_discretization":
                        f"semi-discretization ({result.get('steps_per_period')} steps per period)"}.get(method, method)),
            ("absolute limit", f"{_fmt(result.get('min_depth_limit_m'), 3, _MM, 'mm')} (chatter at "
                               f"{_fmt(result.get('min_depth_chatter_frequency_hz'), 5, unit='Hz')})"),
            ("speeds", f"{speed[0]:g}–{speed[-1]:g} rpm, {speed.size} speeds" if speed.size else "—")]
    if robust is not None:
        about = result.get("robust") or {}
        finite = depth[np.isfinite(depth)]
        rows.append((f"robust absolute limit (p{_fmt(about.get('percentile'), 3)} of draws)",
                     _fmt(float(finite.min()) if finite.size else None, 3, _MM, "mm")))
    flute = _num(result.get("flute_length_m"))
    if flute is not None:
        rows.append(("flute length (deepest stepdown)", _fmt(flute, 3, _MM, "mm")))
    limits = Table("Stability lobes", ("", ""), tuple(rows), "\n".join(str(n) for n in result.get("notes") or []))
    rule = PocketRule(max_depth_m=flute)
    pockets = _pockets(speed, depth, chatter, rule, POCKETS) if speed.size >= 2 and speed.size == depth.size \
        and np.all(np.diff(speed) > 0) else []
    doubtful = unsettled_speeds(result)
    columns: tuple[str, ...] = ("rank", "speed (rpm)", "stepdown (mm)", "limited by", "pocket (rpm)", "chatter (Hz)")
    pocket_rows = []
    for i, p in enumerate(pockets):
        row: tuple[str, ...] = (str(i + 1), f"{p.spindle_speed_rpm:.0f}", _fmt(p.stepdown_m, 3, _MM),
                                p.limited_by.replace("_", " "), f"{p.pocket_low_rpm:.0f}–{p.pocket_high_rpm:.0f}",
                                _fmt(p.chatter_frequency_hz, 4))
        if doubtful:
            inside = (speed >= p.pocket_low_rpm) & (speed <= p.pocket_high_rpm)
            why = [w for w, mask in doubtful.items() if bool(np.any(mask[inside]))]
            row += (", ".join(why) or "—",)
        pocket_rows.append(row)
    if doubtful:
        columns += ("doubtful speeds",)
    which = "robust limit" if robust is not None else "stability limit"
    caption = (f"worst {which} within ±{DEFAULT_SPEED_TOLERANCE:.0%} of the speed, divided by "
               f"{DEFAULT_SAFETY_FACTOR:g}" + (", capped at the flute length" if flute is not None else "")
               + ("" if pockets else "; no speed has a stable window"))
    return [limits, Table("Best pockets", columns, tuple(pocket_rows), caption)]


def unsettled_speeds(result: Mapping[str, Any]) -> dict[str, np.ndarray]:
    """The speeds of a stability-lobes result whose limit is not to be trusted as drawn, by why.

    * ``"unresolved"``: two resolutions of the semi-discretization disagree by more than 1 %
      (``resolved`` false);
    * ``"under-resolved"``: a semi-discretization result without ``resolved`` (from before the
      per-speed check) with fewer than
      :data:`~rcsa.analysis.lobes.semi_discretization.MIN_STEPS_PER_CHATTER_CYCLE` steps per
      chatter cycle there (``steps_per_chatter_cycle``);
    * ``"coarse grid"``: the envelope is a straight chord there, longer than :data:`MAX_CHORD`
      of the speed: zero-order lobes pass through one point per FRF line, so a coarse FRF grid
      draws them as polygons, and a lobe's minimum between two lines is missed.

    Parameters
    ----------
    result : mapping
        A stability-lobes response.

    Returns
    -------
    dict of str to numpy.ndarray
        A boolean mask over ``spindle_speed_rpm`` for each reason that flags any speed.
    """
    from rcsa.analysis.lobes.semi_discretization import MIN_STEPS_PER_CHATTER_CYCLE

    n = len(result.get("spindle_speed_rpm") or [])
    out: dict[str, np.ndarray] = {}
    steps = result.get("steps_per_chatter_cycle")
    resolved = result.get("resolved")
    if isinstance(resolved, list) and len(resolved) == n:
        out["unresolved"] = ~np.asarray([bool(r) for r in resolved])
    elif isinstance(steps, list) and len(steps) == n:
        cycles = np.asarray([np.inf if s is None else s for s in steps], dtype=float)
        out["under-resolved"] = cycles < MIN_STEPS_PER_CHATTER_CYCLE
    chords = _long_chords(result, n)
    if chords is not None:
        out["coarse grid"] = chords
    return {why: mask for why, mask in out.items() if mask.any()}


def _long_chords(result: Mapping[str, Any], n: int) -> np.ndarray | None:
    """Speeds on a straight piece of the envelope longer than :data:`MAX_CHORD` of the speed, or
    None when the result has no envelope to read.

    A lobe drawn through sparse points and resampled onto the speed grid is linear between
    them: three or more grid speeds on one line (equal slopes to rounding, 1e-9 relative) mark
    a chord. A lobe computed at every speed, or through points denser than the speed grid, has
    curvature between any three speeds.
    """
    speed = np.asarray(result.get("spindle_speed_rpm") or [], dtype=float)
    depth = np.asarray([np.nan if d is None else d for d in result.get("depth_limit_m") or []], dtype=float)
    if speed.size < 3 or speed.size != n or depth.size != n:
        return None
    slope = np.diff(depth) / np.diff(speed)
    straight = np.abs(np.diff(slope)) <= 1e-9 * (np.abs(slope[1:]) + np.abs(slope[:-1])) + 1e-300
    out = np.zeros(n, dtype=bool)
    change = np.flatnonzero(np.diff(np.concatenate([[0], straight.astype(np.int8), [0]])))
    for a, b in zip(change[::2], change[1::2], strict=True):  # runs of interior speeds on one line
        lo, hi = a, b + 1  # the chord runs from the speed before the run to the one after it
        if speed[hi] - speed[lo] > MAX_CHORD * speed[lo]:
            out[lo:hi + 1] = True
    return out
