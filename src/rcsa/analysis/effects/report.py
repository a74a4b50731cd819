"""The result of an effect analysis: modes, parameters and the sensitivity table.

Shared by the analysis on analytical spindles (:mod:`rcsa.analysis.effects.sensitivities`, exact
modes) and on measured ones (:mod:`rcsa.analysis.effects.measured_spindle`, modal-fit modes).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from rcsa.analysis.effects.mode_features import ModeFeatures
from rcsa.model.parameters import is_damping

__all__ = ["FEATURES", "EffectReport"]

#: Mode features whose sensitivities are reported, in table order.
FEATURES = ("frequency_hz", "peak_magnitude_m_n", "damping_ratio", "peak_frequency_hz")


@dataclass(frozen=True)
class EffectReport:
    """Normalised sensitivities of the modes of an assembly to its parameters.

    Attributes
    ----------
    band_hz : tuple of float
        Band whose modes are analysed, Hz.
    relative_step : float
        Finite-difference step δ in ln(parameter).
    modes : ModeFeatures
        Features of the nominal model, arrays (nmodes,).
    parameters : tuple of str
        Parameter names, in column order.
    values : numpy.ndarray, shape (nparams,)
        Their nominal values, SI.
    sensitivity : dict of str to numpy.ndarray, shape (nmodes, nparams)
        ``d ln(feature)/d ln(parameter)`` per feature of :data:`FEATURES`; NaN where the
        feature is undefined (no peak) or the mode could not be tracked.
    notes : tuple of str
    modes_method : {"wittrick_williams", "modal_fit"}
        Exact natural frequencies (analytical spindle), or a modal fit of the predicted
        tool-point ``h`` (measured spindle, :mod:`rcsa.analysis.effects.measured_spindle`).
    frequency_sd_hz : numpy.ndarray, shape (nmodes,), or None
        Standard uncertainty of each modal-fit natural frequency, Hz.
    not_applicable : dict of str to str
        Parameters that cannot exist on this spindle (bearings of a measured one, the
        spindle–holder joint inside a holder-tip measurement), and why.
    spindle_measurement : dict or None
        What the measured spindle is (kind, plane, method), when hybrid.
    """

    band_hz: tuple[float, float]
    relative_step: float
    modes: ModeFeatures
    parameters: tuple[str, ...]
    values: np.ndarray
    sensitivity: Mapping[str, np.ndarray]
    notes: tuple[str, ...] = ()
    modes_method: str = "wittrick_williams"
    frequency_sd_hz: np.ndarray | None = None
    not_applicable: Mapping[str, str] = field(default_factory=dict)
    spindle_measurement: Mapping[str, Any] | None = None

    @property
    def frequency_hz(self) -> np.ndarray:
        """Natural frequencies of the analysed modes, Hz, shape (nmodes,)."""
        return self.modes.frequency_hz

    @property
    def tip_participation(self) -> np.ndarray:
        """Tip residue relative to the largest in the band, shape (nmodes,), in [0, 1]."""
        r = np.abs(self.modes.tip_residue_1_kg)
        out: np.ndarray = r / r.max() if r.size and r.max() > 0 else r
        return out

    def column(self, parameter: str, feature: str = "frequency_hz") -> np.ndarray:
        """Sensitivities of all modes to one parameter, shape (nmodes,)."""
        return self.sensitivity[feature][:, self.parameters.index(parameter)]

    def controls(self, parameter: str, feature: str | None = None) -> float | None:
        """Natural frequency (Hz) of the mode a parameter moves most.

        By default a stiffness or geometry parameter is judged on ``frequency_hz`` and a
        damping on ``peak_magnitude_m_n`` (stiffness moves frequencies, damping peaks).
        Returns ``None`` when no mode responds.
        """
        i = self.controlled_mode(parameter, feature)
        return None if i is None else float(self.frequency_hz[i])

    def controlled_mode(self, parameter: str, feature: str | None = None,
                        min_participation: float = 0.0) -> int | None:
        """Index of the mode with the largest ``|S|`` for ``parameter`` (see :meth:`controls`).

        Parameters
        ----------
        parameter : str
            A named parameter (:mod:`rcsa.model.parameters`).
        feature : str, optional
            Default: ``peak_magnitude_m_n`` for a damping, else ``frequency_hz``.
        min_participation : float
            Consider only modes whose :attr:`tip_participation` reaches this.
        """
        feature = feature or ("peak_magnitude_m_n" if is_damping(parameter) else "frequency_hz")
        s = np.abs(self.column(parameter, feature))
        s = np.where(self.tip_participation >= min_participation, s, np.nan)
        if not np.any(np.isfinite(s)) or np.nanmax(s) == 0:
            return None
        return int(np.nanargmax(s))

    def controlled_by(self, mode: int, feature: str = "frequency_hz",
                      among: Sequence[str] | None = None) -> str | None:
        """The parameter with the largest ``|S|`` for one mode (``among`` a subset of names)."""
        names = list(among) if among is not None else list(self.parameters)
        cols = [self.parameters.index(n) for n in names if n in self.parameters]
        s = np.abs(self.sensitivity[feature][mode, cols])
        if not np.any(np.isfinite(s)) or np.nanmax(s) == 0:
            return None
        return self.parameters[cols[int(np.nanargmax(s))]]

    def to_dict(self) -> dict[str, Any]:
        """JSON form: modes, parameters and the sensitivity table (NaN → null)."""
        interface = [p for p in self.parameters if not p.startswith("tool.")]
        part = self.tip_participation
        modes = []
        for i in range(self.frequency_hz.size):
            modes.append({
                "index": i,
                "frequency_hz": float(self.frequency_hz[i]),
                **({} if self.frequency_sd_hz is None else {"frequency_sd_hz": _num(self.frequency_sd_hz[i])}),
                "tip_residue_1_kg": _num(self.modes.tip_residue_1_kg[i]),
                "tip_participation": _num(part[i]),
                "peak_frequency_hz": _num(self.modes.peak_frequency_hz[i]),
                "peak_magnitude_m_n": _num(self.modes.peak_magnitude_m_n[i]),
                "damping_ratio": _num(self.modes.damping_ratio[i]),
                "controlled_by": {q: self.controlled_by(i, q) for q in FEATURES},
                "controlled_by_interface": {q: self.controlled_by(i, q, interface) for q in FEATURES},
            })
        table = []
        for j, name in enumerate(self.parameters):
            row: dict[str, Any] = {"parameter": name, "value": float(self.values[j])}
            for q in FEATURES:
                row[q] = [_num(x) for x in self.sensitivity[q][:, j]]
            mode = self.controlled_mode(name)
            row["controls_mode"] = mode
            row["controls_frequency_hz"] = None if mode is None else float(self.frequency_hz[mode])
            table.append(row)
        exact = self.modes_method == "wittrick_williams"
        out: dict[str, Any] = {
            "band_hz": list(self.band_hz),
            "relative_step": self.relative_step,
            "sensitivity": ("d ln(feature) / d ln(parameter), central finite differences of the exact model"
                            if exact else "d ln(feature) / d ln(parameter), central finite differences of the "
                            "modal-fit features of the hybrid model, each mode refitted on its own band"),
            "modes_method": self.modes_method,
            "features": list(FEATURES),
            "modes": modes,
            "parameters": table,
            "notes": list(self.notes),
        }
        if self.not_applicable:
            out["not_applicable"] = [{"parameter": k, "reason": v} for k, v in self.not_applicable.items()]
        if self.spindle_measurement is not None:
            out["spindle_measurement"] = dict(self.spindle_measurement)
        return out


def _num(x: float) -> float | None:
    x = float(x)
    return x if math.isfinite(x) else None
