"""Effect analysis on a measured spindle: how joints and tool move the modes of a hybrid model.

On a measured spindle (``docs/contract.md`` "Additions in v1.1") there are no exact natural
frequencies: the modes are those of the modal fit of the predicted tool-point ``h``
(:func:`rcsa.model.modal_fit.modal_fit`, as the hybrid prediction reports them). Each
parameter is perturbed by ``p·e^{±δ}`` and every nominal mode is fitted again on **its own
band** (:func:`rcsa.model.modal_fit.refit_mode`): the band never moves, so a mode is
tracked by construction and its fitted features are smooth functions of the parameters even
on a noisy measured spindle (its noise is the same in both runs). The sensitivities are
``S = [ln q(p·e^{+δ}) − ln q(p·e^{−δ})]/(2δ)`` of the fitted natural frequency, damping
ratio, peak height and peak frequency.

What a measured spindle cannot have is reported as not applicable, never silently dropped:
bearings (the spindle is measured, not modelled) and, on a ``holder_tip`` measurement, the
spindle–holder joint (it is inside the measurement). Asking for one of them by name is an
:class:`~rcsa.errors.InputError`.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from rcsa.analysis.effects.mode_features import ModeFeatures
from rcsa.analysis.effects.report import FEATURES, EffectReport
from rcsa.analysis.progress import Progress, report
from rcsa.analysis.tool_point_model import ToolPointModel
from rcsa.errors import InputError
from rcsa.model.contract import AssemblySpec
from rcsa.model.modal_fit import FittedMode, modal_fit, refit_mode
from rcsa.model.parameters import chosen_parameters, get_parameter, parameter_names

__all__ = ["BEARINGS_REASON", "HOLDER_TIP_REASON", "hybrid_effect_analysis", "split_parameters"]

BEARINGS_REASON = "not applicable: the spindle is measured, so its bearings are inside the measurement"
HOLDER_TIP_REASON = ("not applicable: the measured spindle's plane is holder_tip, so the spindle–holder joint "
                     "is inside the measurement")


def split_parameters(spec: AssemblySpec, plane: str, requested: Sequence[str] | None
                     ) -> tuple[tuple[str, ...], dict[str, str]]:
    """The parameters to analyse on a measured spindle, and those not applicable (with why).

    Raises
    ------
    InputError
        A requested parameter that cannot exist on this spindle, or is unknown, zero or rigid.
    """
    not_applicable = {"bearings": BEARINGS_REASON}
    if plane == "holder_tip":
        not_applicable["spindle_holder"] = HOLDER_TIP_REASON
    available = tuple(n for n in parameter_names(spec) if not (plane == "holder_tip"
                                                                 and n.startswith("spindle_holder.")))
    for n in requested or ():
        if n.startswith("bearings["):
            raise InputError("parameters", f"{n}: {BEARINGS_REASON}")
        if plane == "holder_tip" and n.startswith("spindle_holder."):
            raise InputError("parameters", f"{n}: {HOLDER_TIP_REASON}")
    return chosen_parameters(spec, requested, available), not_applicable


def _features(modes: Sequence[FittedMode | None], window_rel: np.ndarray) -> ModeFeatures:
    def col(attr: str) -> np.ndarray:
        return np.array([math.nan if m is None else getattr(m, attr) for m in modes], dtype=float)

    return ModeFeatures(col("frequency_hz"), col("residue_1_kg"), col("peak_frequency_hz"),
                        col("peak_magnitude_m_n"), col("damping_ratio"), window_rel)


def hybrid_effect_analysis(model: ToolPointModel, names: Sequence[str], not_applicable: dict[str, str],
                           relative_step: float, band_hz: tuple[float, float],
                           progress: Progress | None = None) -> EffectReport:
    """Sensitivities of the modal-fit modes of a hybrid model (see the module docstring).

    Parameters
    ----------
    model : ToolPointModel
        The assembly on its measured spindle.
    names : sequence of str
        Parameters (checked by :func:`split_parameters`).
    not_applicable : dict of str to str
        Reported as is.
    relative_step : float
        δ in ln(parameter).
    band_hz : (float, float)
        Modes whose fitted natural frequency lies here.
    progress : callable, optional
        ``progress(done, total)`` after the nominal fit and after each parameter.

    Returns
    -------
    EffectReport
        ``modes_method == "modal_fit"``, with each mode's ``frequency_sd_hz``.
    """
    spec = model.spec
    f = spec.frequency_hz
    fit = modal_fit(f, model.h(f))
    nominal = [m for m in fit.modes if band_hz[0] <= m.frequency_hz <= band_hz[1]]
    window = np.array([[1 - m.band_hz[0] / m.frequency_hz, m.band_hz[1] / m.frequency_hz - 1] for m in nominal]
                      ).reshape(-1, 2)
    base = _features(nominal, window)
    values = np.array([get_parameter(spec, n) for n in names], dtype=float)
    sens = {q: np.full((len(nominal), len(names)), np.nan) for q in FEATURES}
    notes = [f"modes from the modal fit of the hybrid model's tool-point h (as natural_frequencies_hz of its "
             f"prediction); each is refitted on its own band ({len(nominal)} modes in the band)"]
    lines = np.unique(np.concatenate([np.flatnonzero((f >= m.band_hz[0]) & (f <= m.band_hz[1]))
                                      for m in nominal])) if nominal else np.empty(0, dtype=int)
    report(progress, 1, len(names) + 1)
    for j, name in enumerate(names):
        if not nominal:
            break
        sets = [{name: values[j] * math.exp(sign * relative_step)} for sign in (1.0, -1.0)]
        h = model.h_sets(f[lines], sets)
        runs = [_features([refit_mode(f[lines], h[k], m) for m in nominal], window) for k in (0, 1)]
        if any(not np.all(np.isfinite(r.frequency_hz)) for r in runs):
            notes.append(f"{name}: some modes lost their pole in a perturbed run")
        for q in FEATURES:
            with np.errstate(invalid="ignore", divide="ignore"):
                sens[q][:, j] = (np.log(runs[0].feature(q)) - np.log(runs[1].feature(q))) / (2 * relative_step)
        report(progress, j + 2, len(names) + 1)
    report(progress, len(names) + 1, len(names) + 1)
    if not nominal:
        notes.append(f"the modal fit finds no mode in the band {band_hz[0]:g}–{band_hz[1]:g} Hz: nothing to analyse")
    notes.extend(f"{k}: {v}" for k, v in not_applicable.items())
    base_report = None if model.base is None else dict(model.base.report)
    return EffectReport(band_hz, relative_step, base, tuple(names), values, sens, tuple(dict.fromkeys(notes)),
                        "modal_fit", np.array([m.sd_hz for m in nominal], dtype=float), dict(not_applicable),
                        base_report)
