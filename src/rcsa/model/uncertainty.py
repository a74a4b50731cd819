"""Uncertainty on predictions: the request option, a measured spindle's own draws, the result.

A prediction request may carry ``"uncertainty": {"draws": 200, "seed": 1, "tolerances":
{...}, "solver": "reduced"}`` (``docs/contract.md`` "Additions in v1.1"; ``solver`` is ours). The
assembly is then drawn ``draws`` times under the nuisance tolerances of
:mod:`rcsa.model.tolerances` (the diagnosis's names and defaults) and — on a measured spindle
— under the measurement's own uncertainty (:class:`rcsa.model.spindle_side.BaseUncertainty`,
:func:`rcsa.model.spindle_side.measured_base_draws`). With ``"solver": "reduced"`` (the
default) the draws are solved by a reduced model whose error is checked draw by draw
(:mod:`rcsa.model.reduced_draws`); with ``"exact"``
every draw is solved exactly on every line (:mod:`rcsa.model.draws`, all draws at once). The
result gains::

    "uncertainty": {"draws": 200, "seed": 1, "tolerances": {...}, "solver": "reduced",
                    "h_magnitude_m_n": {"p05": [...], "p50": [...], "p95": [...]},
                    "natural_frequencies_hz": {"mean": [...], "sd": [...], "in_band_fraction": [...]},
                    "modes_entering_band": [...], "natural_frequencies_matching": "...",
                    "reduced_model": {...}, "notes": [...]}

The percentiles are numpy's (linear interpolation between order statistics) over the draws
at every line; ``sd`` is the sample standard deviation (``ddof = 1``). The draws' random
numbers come from ``numpy.random.default_rng(seed)`` in a fixed order: the nuisance knobs of
every draw (:func:`rcsa.model.tolerances.draw_nuisance`), then the measured spindle's noise,
then its rotation-estimate lengths — so a seed reproduces a band exactly.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any, Literal

import numpy as np

from rcsa.errors import InputError
from rcsa.model.bounds import (
    MAX_FREQUENCY_LINES,
    MAX_UNCERTAINTY_DRAW_LINES,
    MAX_UNCERTAINTY_DRAWS,
    MAX_UNCERTAINTY_SEED,
    MIN_UNCERTAINTY_DRAWS,
    UNCERTAINTY_SOLVERS,
)
from rcsa.model.contract import AssemblySpec, MeasuredSpindleSpec, parse_assembly
from rcsa.model.fields import Fields, json_object
from rcsa.model.tolerances import parse_tolerances
from rcsa.physics.arrays import FloatArray

__all__ = [
    "DEFAULT_DRAWS",
    "DEFAULT_SEED",
    "PERCENTILES",
    "UNCERTAINTY_FIELDS",
    "UncertaintyBand",
    "UncertaintyOptions",
    "parse_prediction_request",
    "parse_uncertainty",
]

#: Fields of the ``uncertainty`` option.
UNCERTAINTY_FIELDS = ("draws", "seed", "tolerances", "solver")
#: Draws and seed when the request leaves them out (a fixed seed: a request without one is
#: still reproducible, and its results can be cached by content).
DEFAULT_DRAWS = 200
DEFAULT_SEED = 0
#: The band's percentiles of |h|, by their names in the result.
PERCENTILES: Mapping[str, float] = {"p05": 5.0, "p50": 50.0, "p95": 95.0}


@dataclass(frozen=True)
class UncertaintyOptions:
    """A validated ``uncertainty`` option.

    Attributes
    ----------
    draws : int
        Number of Monte-Carlo draws.
    seed : int
        Seed of ``numpy.random.default_rng``.
    tolerances : mapping of str to float
        Every tolerance (defaults filled in), one standard deviation
        (:mod:`rcsa.model.tolerances`).
    solver : {"reduced", "exact"}
        How the draws are solved (module docstring).
    """

    draws: int
    seed: int
    tolerances: Mapping[str, float]
    solver: str = "reduced"

    def to_dict(self) -> dict[str, Any]:
        """The option as a request carries it (every default filled in)."""
        return {"draws": self.draws, "seed": self.seed, "tolerances": dict(self.tolerances), "solver": self.solver}


def parse_uncertainty(value: object, path: str = "uncertainty", *, measured_spindle: bool = False,
                      lines: int | None = None) -> UncertaintyOptions | None:
    """The ``uncertainty`` option of a request; None when it is absent (or null).

    Parameters
    ----------
    value : dict or None
        ``{"draws", "seed", "tolerances", "solver"}``, each optional.
    path : str
        Where the option sits in the request, for error messages.
    measured_spindle : bool
        The assembly's spindle is a stored measurement (its tolerances are accepted too).
    lines : int, optional
        Frequency lines of the prediction: ``draws × lines`` must stay within
        :data:`~rcsa.model.bounds.MAX_UNCERTAINTY_DRAW_LINES`.

    Returns
    -------
    UncertaintyOptions or None

    Raises
    ------
    InputError
        Naming the field: an unknown member, ``draws`` outside
        [``MIN_UNCERTAINTY_DRAWS``, ``MAX_UNCERTAINTY_DRAWS``] or over the compute budget,
        a ``seed`` that is not an integer in [0, ``MAX_UNCERTAINTY_SEED``], a tolerance
        unknown or out of bounds.

    Examples
    --------
    >>> u = parse_uncertainty({"draws": 50, "tolerances": {"stickout_m": 0.0}})
    >>> u.draws, u.seed, u.tolerances["stickout_m"], u.tolerances["loss_factor_log"]
    (50, 0, 0.0, 0.25)
    """
    if value is None:
        return None
    o = Fields(value, path, UNCERTAINTY_FIELDS)
    draws = o.integer("draws", default=DEFAULT_DRAWS, ge=MIN_UNCERTAINTY_DRAWS, le=MAX_UNCERTAINTY_DRAWS)
    if lines is not None and draws * lines > MAX_UNCERTAINTY_DRAW_LINES:
        raise InputError(o.at("draws"), f"draws × frequency lines must be at most {MAX_UNCERTAINTY_DRAW_LINES} "
                                        f"(the compute budget of one uncertain assembly): {draws} × {lines}; "
                                        f"use at most {MAX_UNCERTAINTY_DRAW_LINES // lines} draws or fewer lines")
    seed = o.integer("seed", default=DEFAULT_SEED, ge=0, le=MAX_UNCERTAINTY_SEED)
    tolerances = parse_tolerances(o.value.get("tolerances"), o.at("tolerances"), measured_spindle=measured_spindle)
    solver = o.string("solver", UNCERTAINTY_SOLVERS[0], choices=UNCERTAINTY_SOLVERS)
    return UncertaintyOptions(draws, seed, tolerances, solver)


def parse_prediction_request(document: object, max_lines: int = MAX_FREQUENCY_LINES
                             ) -> tuple[AssemblySpec, UncertaintyOptions | None]:
    """A prediction request: the assembly document, optionally with ``uncertainty``.

    Parameters
    ----------
    document : dict
        The assembly (``docs/contract.md`` "Assembly") and, optionally, ``"uncertainty"``.
    max_lines : int
        Largest accepted number of frequency lines.

    Returns
    -------
    spec : AssemblySpec
    uncertainty : UncertaintyOptions or None

    Raises
    ------
    InputError
        Naming the offending field.
    """
    body = json_object(document, "")
    spec = parse_assembly({k: v for k, v in body.items() if k != "uncertainty"}, max_lines)
    return spec, parse_uncertainty(body.get("uncertainty"), measured_spindle=isinstance(spec.spindle,
                                                                                         MeasuredSpindleSpec),
                                   lines=int(spec.frequency_hz.size))


@dataclass(frozen=True)
class UncertaintyBand:
    """What the draws say about a prediction (the result's ``uncertainty``).

    Attributes
    ----------
    options : UncertaintyOptions
        Draws, seed and every tolerance used.
    h_magnitude_m_n : numpy.ndarray, shape (3, nfreq)
        Percentiles p05, p50, p95 of ``|h|`` over the draws at every line, m/N.
    natural_frequencies_mean_hz, natural_frequencies_sd_hz : numpy.ndarray, shape (nmodes,)
        Mean and sample sd (Hz) over the draws of each natural frequency of the nominal
        prediction (in its order; see ``matching``).
    in_band_fraction : numpy.ndarray, shape (nmodes,)
        Fraction of the draws in which that mode lies in the requested band.
    matching : str
        How each draw's modes were matched to the nominal ones.
    modes_entering_band : tuple of dict
        Modes outside the band nominally but inside it in some draws:
        ``{"mean_hz", "sd_hz", "in_band_fraction"}``.
    measured_spindle : dict or None
        What the measured spindle's draws assumed (:func:`rcsa.model.spindle_side.measured_base_draws`).
    notes : tuple of str
    reduced_model : dict or None
        What the reduced model did and how well it held (``"solver": "reduced"``), JSON-ready.
    """

    options: UncertaintyOptions
    h_magnitude_m_n: FloatArray
    natural_frequencies_mean_hz: FloatArray
    natural_frequencies_sd_hz: FloatArray
    in_band_fraction: FloatArray
    matching: str
    modes_entering_band: tuple[dict[str, float], ...] = ()
    measured_spindle: Mapping[str, Any] | None = None
    notes: tuple[str, ...] = field(default=())
    reduced_model: Mapping[str, Any] | None = None

    def to_dict(self, arrays: Literal["list", "numpy"] = "list") -> dict[str, Any]:
        """The result's ``uncertainty`` object.

        Parameters
        ----------
        arrays : {"list", "numpy"}
            The percentile arrays as lists or numpy arrays, as for the prediction's own
            (:meth:`rcsa.model.prediction.Prediction.to_dict`).
        """
        def out(a: FloatArray) -> Any:
            return a.tolist() if arrays == "list" else np.ascontiguousarray(a)

        doc: dict[str, Any] = {
            **self.options.to_dict(),
            "h_magnitude_m_n": {name: out(row) for name, row in zip(PERCENTILES, self.h_magnitude_m_n, strict=True)},
            "natural_frequencies_hz": {"mean": self.natural_frequencies_mean_hz.tolist(),
                                       "sd": self.natural_frequencies_sd_hz.tolist(),
                                       "in_band_fraction": self.in_band_fraction.tolist()},
            "natural_frequencies_matching": self.matching,
            "modes_entering_band": [dict(m) for m in self.modes_entering_band],
            "notes": list(self.notes),
        }
        if self.measured_spindle is not None:
            doc["measured_spindle"] = dict(self.measured_spindle)
        if self.reduced_model is not None:
            doc["reduced_model"] = dict(self.reduced_model)
        return doc
