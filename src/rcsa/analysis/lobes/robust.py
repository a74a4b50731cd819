"""Robust stability lobes: the depth limit per speed that holds with a stated confidence.

A stability-lobes request with an ``assembly`` may add ``"uncertainty": {"draws", "seed",
"tolerances"}`` (as a prediction request, :mod:`rcsa.model.uncertainty`) and ``"robust":
{"confidence": 0.95}``. The assembly is then drawn under its tolerances (and a measured
spindle under its own uncertainty), the draws' FRFs come from the reduced model of the draws
(:meth:`rcsa.model.spindle_side.SpindleSide.tool_point_draws`, :mod:`rcsa.model.reduced_draws`;
``"solver": "exact"`` solves every draw on every line), every draw's lobes are computed (all
draws at once, :func:`rcsa.analysis.lobes.zoa.depth_limit_envelopes`), and beside the nominal
envelope the response gives::

    "depth_limit_robust_m": [...],          # per speed of spindle_speed_rpm
    "robust": {"confidence": 0.95, "draws": 200, "seed": 0, "percentile": 5.0,
               "tolerances": {...}, "method": "zoa", "rule": "..."}

``depth_limit_robust_m`` is the ``(1 − confidence)`` quantile over the draws of the depth
limit at each speed (numpy's linear interpolation between order statistics), **never above
the nominal limit**: where the draws' quantile lies above it — at the cusps between lobes,
where any shift of the lobes raises the limit — the nominal is kept, so a machinist never
reads a robust depth deeper than the model's own. A speed where the nominal or any draw is
unsettled (NaN) is NaN (never an optimistic value). With zero tolerances every draw is the
nominal and the two limits agree. The contract's fields are unchanged.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from rcsa.analysis.lobes.request import LobesRequest
from rcsa.analysis.lobes.zoa import LobeResult, depth_limit_envelopes
from rcsa.errors import InputError
from rcsa.model.bounds import MAX_CONFIDENCE, MIN_CONFIDENCE
from rcsa.model.fields import Fields, json_object
from rcsa.model.uncertainty import UncertaintyOptions

__all__ = ["DEFAULT_CONFIDENCE", "ROBUST_FIELDS", "RobustLobes", "RobustRequest", "robust_depth_limit",
           "robust_lobes", "split_robust_request"]

#: Request fields of robust lobes (beside those of a stability-lobes request).
ROBUST_FIELDS = ("uncertainty", "robust")
#: Confidence when ``robust`` is left out.
DEFAULT_CONFIDENCE = 0.95


@dataclass(frozen=True)
class RobustRequest:
    """The robust part of a stability-lobes request, validated but for the option's draws.

    Attributes
    ----------
    uncertainty : mapping
        The request's ``uncertainty`` object (parsed with the assembly, whose spindle and
        grid it depends on: :func:`rcsa.model.uncertainty.parse_uncertainty`).
    confidence : float
        In [``MIN_CONFIDENCE``, ``MAX_CONFIDENCE``].
    """

    uncertainty: Mapping[str, Any]
    confidence: float


def split_robust_request(body: object) -> tuple[dict[str, Any], RobustRequest | None]:
    """A stability-lobes request without its robust fields, and those fields.

    Parameters
    ----------
    body : dict
        A stability-lobes request, perhaps with ``uncertainty`` and ``robust``.

    Returns
    -------
    request : dict
        The request for :func:`rcsa.analysis.lobes.request.parse_lobes_request`.
    robust : RobustRequest or None
        None when the request has no ``uncertainty``.

    Raises
    ------
    InputError
        ``robust`` without ``uncertainty``, ``uncertainty`` without an ``assembly``, or a
        ``confidence`` out of bounds.
    """
    doc = dict(json_object(body, ""))
    uncertainty, robust = doc.pop("uncertainty", None), doc.pop("robust", None)
    if uncertainty is None:
        if robust is not None:
            raise InputError("robust", "needs uncertainty: robust lobes are the lobes of drawn assemblies")
        return doc, None
    if doc.get("assembly") is None:
        raise InputError("uncertainty", "needs an assembly (robust lobes draw the assembly); inline FRFs have "
                                        "no tolerances to draw")
    json_object(uncertainty, "uncertainty")
    confidence = Fields(robust if robust is not None else {}, "robust", ("confidence",)).number(
        "confidence", default=DEFAULT_CONFIDENCE, ge=MIN_CONFIDENCE, le=MAX_CONFIDENCE)
    return doc, RobustRequest(uncertainty, confidence)


def _percentile(confidence: float) -> float:
    """``100 (1 − confidence)``, rounded to 1e-9 (0.95 gives 5, not 5.000000000000004)."""
    return round(100.0 * (1.0 - confidence), 9)


@dataclass(frozen=True)
class RobustLobes:
    """Robust depth limits beside a nominal lobe diagram.

    Attributes
    ----------
    depth_limit_m : numpy.ndarray, shape (nspeed,)
        The depth limit at each speed of the nominal diagram's grid with the stated
        confidence, never above the nominal one, m; NaN where unsettled.
    draws_depth_limit_m : numpy.ndarray, shape (ndraws, nspeed)
        Every draw's envelope, m.
    confidence : float
    options : UncertaintyOptions
        Draws, seed and tolerances.
    method : {"zoa", "semi_discretization"}
        How the draws' limits were found (semi-discretization: the reduced model of
        :mod:`rcsa.analysis.lobes.robust_sdm`).
    """

    depth_limit_m: np.ndarray
    draws_depth_limit_m: np.ndarray
    confidence: float
    options: UncertaintyOptions
    method: str = "zoa"

    @property
    def percentile(self) -> float:
        """The percentile taken over the draws, ``100 (1 − confidence)``."""
        return _percentile(self.confidence)

    def to_dict(self) -> dict[str, Any]:
        """The response's extra fields: ``depth_limit_robust_m`` and ``robust``."""
        return {"depth_limit_robust_m": [float(x) if np.isfinite(x) else None for x in self.depth_limit_m.tolist()],
                "robust": {"confidence": self.confidence, "percentile": self.percentile, "method": self.method,
                           **self.options.to_dict(),
                           "rule": f"the {self.percentile:g}th percentile over the draws of the depth limit at each "
                                   f"speed, never above the nominal limit; null where the nominal or a draw is "
                                   f"unsettled" + ("" if self.method == "zoa" else
                                                   "; each draw's limit from the reduced model of the draws (the "
                                                   "nominal diagram moved by each mode's frequency, damping and "
                                                   "stiffness changes, rcsa.analysis.lobes.robust_sdm)")}}


def robust_lobes(request: LobesRequest, nominal: LobeResult, frequency_hz: np.ndarray, h_draws: np.ndarray,
                 options: UncertaintyOptions, confidence: float) -> RobustLobes:
    """Robust depth limits from the tool-point FRFs of drawn assemblies.

    Parameters
    ----------
    request : LobesRequest
        The cut and the speed grid (``method`` ZOA).
    nominal : LobeResult
        The nominal assembly's diagram (:meth:`LobesRequest.solve`).
    frequency_hz : numpy.ndarray, shape (nfreq,)
        Grid of the FRFs, Hz.
    h_draws : numpy.ndarray, shape (ndraws, nfreq), complex
        Tool-point ``h`` of every draw, m/N (used in x and y, as the nominal's).
    options : UncertaintyOptions
        The draws' option (reported).
    confidence : float
        In (0.5, 1): the limit holds in this fraction of the draws.

    Returns
    -------
    RobustLobes
    """
    envelopes = depth_limit_envelopes(frequency_hz, h_draws, teeth=request.teeth,
                                      tangential_coefficient_n_m2=request.tangential_coefficient_n_m2,
                                      radial_ratio=request.radial_ratio, radial_immersion=request.radial_immersion,
                                      milling=request.milling, spindle_speed_rpm=request.spindle_speed_rpm)
    robust = robust_depth_limit(envelopes, nominal.depth_limit_m, confidence)
    envelopes.flags.writeable = False
    return RobustLobes(robust, envelopes, confidence, options)


def robust_depth_limit(envelopes: np.ndarray, nominal_m: np.ndarray, confidence: float) -> np.ndarray:
    """The robust depth limit per speed from every draw's limit (the rule of the module docstring).

    Parameters
    ----------
    envelopes : numpy.ndarray, shape (ndraws, nspeed)
        Every draw's depth limit at each speed, m (NaN: unsettled).
    nominal_m : numpy.ndarray, shape (nspeed,)
        The nominal assembly's depth limit, m.
    confidence : float
        In (0.5, 1): the limit holds in this fraction of the draws.

    Returns
    -------
    numpy.ndarray, shape (nspeed,)
        The ``100 (1 − confidence)`` percentile over the draws, never above the nominal
        limit, m; NaN where the nominal or any draw is NaN. Read-only.
    """
    quantile = np.percentile(envelopes, _percentile(confidence), axis=0)  # NaN wherever a draw is NaN
    robust = np.fmin(quantile, nominal_m)
    robust[np.isnan(quantile) | np.isnan(nominal_m)] = np.nan
    robust.flags.writeable = False
    return robust
