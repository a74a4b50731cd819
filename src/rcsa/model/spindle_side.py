"""The spindle side of predictions: an analytical spindle chain, or a measured base receptance.

Every tool of a batch sits on one spindle. :class:`SpindleSide` holds what they share — the
condensed spindle (analytical) or the measured spindle-side receptance at its plane
(hybrid), and the cache of spindle + holder condensations — and predicts one assembly
after the other on it. How a measured base is obtained from a store is the measured layer's
business (:func:`rcsa.measured.hybrid.measured_base`); here it is just a
:class:`MeasuredBase`.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from rcsa.errors import InputError
from rcsa.model.assembly import AssemblyModel, assembly_notes, build_model, spindle_chain
from rcsa.model.contract import AssemblySpec, CommonSpec, MeasuredSpindleSpec, SpindleSpec
from rcsa.model.prediction import Prediction, SubassemblyCache, predict_model, tool_point_receptance
from rcsa.model.wire import complex_to_wire
from rcsa.physics.arrays import ComplexArray, FloatArray

__all__ = ["BaseResolver", "MeasuredBase", "SpindleSide", "spread_of_bounds"]


@dataclass(frozen=True)
class MeasuredBase:
    """Spindle-side receptance of a measured spindle on the requested grid.

    Attributes
    ----------
    plane : {"spindle_nose", "holder_tip"}
    receptance : numpy.ndarray, shape (nfreq, 2, 2)
    alternatives : tuple of numpy.ndarray
        Receptances bounding an estimate's uncertainty (``direct_frf``), else empty.
    notes : tuple of str
    report : dict
        What was done (kind, method, conditioning, interpolation), JSON-ready.
    artifact_diameter_m : float or None
        Shank diameter a holder-tip measurement was taken with (to check the tool's shank).
    """

    plane: str
    receptance: ComplexArray
    alternatives: tuple[ComplexArray, ...] = ()
    notes: tuple[str, ...] = ()
    report: dict[str, Any] = field(default_factory=dict)
    artifact_diameter_m: float | None = None


#: Turns a measured spindle of a request into its base receptance on a grid (Hz).
BaseResolver = Callable[[MeasuredSpindleSpec, FloatArray], MeasuredBase]


class SpindleSide:
    """The spindle side shared by all combinations: plane, base receptance and cache.

    Parameters
    ----------
    common : CommonSpec
        Grid, materials, beam theory and spindle of the request.
    resolve_base : callable, optional
        Needed when ``common.spindle`` is measured (:data:`BaseResolver`).
    """

    def __init__(self, common: CommonSpec, resolve_base: BaseResolver | None = None) -> None:
        self.base: MeasuredBase | None = None
        omega = 2 * np.pi * common.frequency_hz
        if isinstance(common.spindle, MeasuredSpindleSpec):
            if resolve_base is None:
                raise InputError("spindle.measurement_id", "a measured spindle needs a measurement store")
            self.base = resolve_base(common.spindle, common.frequency_hz)
        self.cache = SubassemblyCache(omega, None if self.base is None else self.base.receptance)
        self.spindle = (spindle_chain(common.spindle, common.materials, common.shear_coefficient, common.beam_theory)
                        if isinstance(common.spindle, SpindleSpec) else ())
        self.alt_caches = [] if self.base is None else [SubassemblyCache(omega, r) for r in self.base.alternatives]

    def predict(self, spec: AssemblySpec, natural_frequencies: bool = True) -> Prediction:
        """Tool-point prediction of one assembly on this spindle side.

        Parameters
        ----------
        spec : AssemblySpec
            An assembly on this spindle side's grid and spindle.
        natural_frequencies : bool
            Compute the exact natural frequencies (analytical spindles).
        """
        return self.predict_with_model(spec, natural_frequencies)[1]

    def predict_with_model(self, spec: AssemblySpec, natural_frequencies: bool = True
                           ) -> tuple[AssemblyModel, Prediction]:
        """The solved chain model and its prediction.

        Parameters
        ----------
        spec : AssemblySpec
            An assembly on this spindle side's grid and spindle.
        natural_frequencies : bool
            Compute the exact natural frequencies (analytical spindles).
        """
        base = self.base
        if base is None:
            model = build_model(spec, spindle=self.spindle)
            return model, predict_model(model, spec.frequency_hz, cache=self.cache,
                                        natural_frequencies=natural_frequencies, notes=assembly_notes(spec))
        if base.plane == "holder_tip" and base.artifact_diameter_m is not None and \
                abs(spec.tool.shank_diameter_m - base.artifact_diameter_m) > 1e-6 * base.artifact_diameter_m:
            raise InputError("tool.shank_diameter_m",
                             f"must match the shank the holder-tip measurement was taken with "
                             f"({base.artifact_diameter_m:g} m); got {spec.tool.shank_diameter_m:g} m")
        model = build_model(spec, base.plane)
        extra: dict[str, Any] = {"spindle_measurement": base.report}
        if self.alt_caches:
            h = [tool_point_receptance(model, c)[:, 0, 0] for c in self.alt_caches]
            extra["uncertainty"] = spread_of_bounds(spec.frequency_hz, h)
        return model, predict_model(model, spec.frequency_hz, base_receptance=base.receptance, cache=self.cache,
                                    natural_frequencies=natural_frequencies, notes=(*base.notes, *assembly_notes(spec)),
                                    extra=extra)


def spread_of_bounds(frequency_hz: FloatArray, bounds: list[ComplexArray]) -> dict[str, Any]:
    """Envelope of the tool-point h over an estimate's bounds, relative to its peak.

    Parameters
    ----------
    frequency_hz : numpy.ndarray, shape (nfreq,)
    bounds : list of two numpy.ndarray, shape (nfreq,)
        Tool-point ``h`` (m/N) at the low and high end of the estimate.

    Returns
    -------
    dict
        ``h_bounds`` (wire form), ``max_relative_spread_of_peak`` and where it occurs.
    """
    lo, hi = bounds
    ref = max(float(np.max(np.abs(lo))), float(np.max(np.abs(hi))))
    rel = np.abs(hi - lo) / ref
    return {"h_bounds": {"low": complex_to_wire(lo), "high": complex_to_wire(hi)},
            "max_relative_spread_of_peak": float(rel.max()),
            "frequency_of_max_spread_hz": float(frequency_hz[int(np.argmax(rel))])}
