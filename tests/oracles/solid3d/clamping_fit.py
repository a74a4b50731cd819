"""The clamping model's coefficients fitted to the 3-D data set (least squares over every peak).

Shared by ``benchmarks/calibrate_clamping.py`` (the committed fit, its starts and the
leave-one-family-out folds) and ``tests/model/test_clamping_calibration.py`` (a reduced fit in
the suite).

The residuals of one case and base (:class:`Row`), every one dimensionless:

* each 3-D peak in the band (:func:`tests.oracles.solid3d.clamping_scores.truth_peaks`): rcsa's
  nearest peak's frequency against the 3-D one, ``(f/f₃ − 1) / σ_f``, and its height,
  ``ln(|h|/|h₃|) / σ_h`` (both refined on fine grids around the peak);
* the static compliance at the grid's first line, ``ln(|h|/|h₃|) / σ_s``.

The coefficients are fitted in their logarithms (all are positive) by a trust-region least
squares (``scipy.optimize.least_squares``) within :data:`BOUNDS`; a coefficient left out of the
fit keeps the value it is given.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import asdict, dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np
from scipy.optimize import least_squares

import rcsa.model.clamping as clamping
from rcsa.physics.elimination import tip_receptance
from tests.oracles.solid3d import clamping_scores, dataset

__all__ = ["BOUNDS", "SIGMA", "START_BOX", "FitResult", "Row", "fit", "prepare", "residuals"]

#: Scales of the residuals: 0.5 % in frequency, 5 % in peak height, 2 % in static compliance
#: (about the 3-D reference's own discretisation error, ×1, ×5, ×3).
SIGMA = {"frequency": 0.005, "height": 0.05, "static": 0.02}
#: Where each coefficient may go (the search's box), as (lowest, highest).
BOUNDS = {"interface": (0.5, 200.0), "step_cone": (0.05, 4.0), "holder_shear": (0.3, 5.0)}
#: Where the random starts are drawn (log-uniform): a factor of 4 either side of plausible values.
START_BOX = {"interface": (2.0, 32.0), "step_cone": (0.25, 3.0), "holder_shear": (0.5, 2.5)}
_LOSS = 0.002


@dataclass(frozen=True, slots=True)
class Row:
    """One case and base of the data set, its truth prepared for the fit.

    Attributes
    ----------
    name, base : str
    peak_hz : numpy.ndarray
        The 3-D peaks' undamped natural frequencies, Hz.
    peak_m_n : numpy.ndarray
        Their heights, m/N.
    static_hz, static_m_n : float
        The grid's first line, Hz, and |h| there, m/N.
    band_hz : (float, float)
        The data set's band.
    """

    name: str
    base: str
    peak_hz: np.ndarray
    peak_m_n: np.ndarray
    static_hz: float
    static_m_n: float
    band_hz: tuple[float, float]


def prepare(names: Sequence[str], bases: Sequence[str] = dataset.BASES, directory: Path = dataset.DATA_DIR
            ) -> list[Row]:
    """The rows of ``names`` × ``bases`` with their 3-D peaks and static compliance."""
    rows = []
    for name in names:
        data = clamping_scores.load(name, directory)
        f = data["frequency_hz"]
        for base in bases:
            peaks, heights = clamping_scores.refine_peaks(
                clamping_scores.truth_peaks(name, base, directory),
                lambda x, n=name, b=base: clamping_scores.truth_h(n, b, x, directory), _LOSS)
            rows.append(Row(name, base, peaks, heights, float(f[0]), float(abs(data[f"h_{base}"][0])),
                            (float(f[0]), float(f[-1]))))
    return rows


def coefficients(x: np.ndarray, names: Sequence[str], fixed: clamping.BulkCoefficients
                 ) -> clamping.BulkCoefficients:
    """``fixed`` with the coefficients ``names`` set to ``exp(x)``."""
    return replace(fixed, **{n: float(math.exp(v)) for n, v in zip(names, x, strict=True)})


def row_residuals(row: Row, directory: Path = dataset.DATA_DIR) -> np.ndarray:
    """The residuals of one row under the current :data:`rcsa.model.clamping.BULK_COEFFICIENTS`."""
    chain = clamping_scores.model_chain(row.name, "clamping", row.base, directory)
    grid = clamping_scores.load(row.name, directory)["frequency_hz"]
    model_f, heights = clamping_scores.model_peaks(chain, grid, row.peak_hz, _LOSS)
    static = abs(tip_receptance(chain, np.array([2 * np.pi * row.static_hz]))[0, 0, 0])
    return np.concatenate([(model_f / row.peak_hz - 1.0) / SIGMA["frequency"],
                           np.log(heights / row.peak_m_n) / SIGMA["height"],
                           [math.log(static / row.static_m_n) / SIGMA["static"]]])


def residuals(x: np.ndarray, names: Sequence[str], rows: Sequence[Row], fixed: clamping.BulkCoefficients,
              directory: Path = dataset.DATA_DIR) -> np.ndarray:
    """Every row's residuals with the coefficients ``names`` at ``exp(x)`` (the others as ``fixed``)."""
    saved = clamping.BULK_COEFFICIENTS
    clamping.BULK_COEFFICIENTS = coefficients(x, names, fixed)
    try:
        return np.concatenate([row_residuals(r, directory) for r in rows])
    finally:
        clamping.BULK_COEFFICIENTS = saved


@dataclass(frozen=True, slots=True)
class FitResult:
    """A fit's answer.

    Attributes
    ----------
    start, coefficients : BulkCoefficients
        Where it started and where it ended.
    cost : float
        ½ Σ r² at the end.
    evaluations : int
        Residual evaluations.
    rms : float
        Root mean square residual at the end.
    singular_values : numpy.ndarray
        Of the final Jacobian (in the log coefficients): how well each direction is identified.
    """

    start: clamping.BulkCoefficients
    coefficients: clamping.BulkCoefficients
    cost: float
    evaluations: int
    rms: float
    singular_values: np.ndarray

    def to_dict(self, names: Sequence[str]) -> dict[str, Any]:
        """A JSON-ready record (the fitted names' start and end values)."""
        return {"start": {n: getattr(self.start, n) for n in names},
                "coefficients": {n: getattr(self.coefficients, n) for n in names},
                "all_coefficients": asdict(self.coefficients), "cost": self.cost, "rms": self.rms,
                "evaluations": self.evaluations, "singular_values": self.singular_values.tolist()}


def fit(rows: Sequence[Row], names: Sequence[str], start: clamping.BulkCoefficients,
        directory: Path = dataset.DATA_DIR, *, tolerance: float = 1e-8, max_evaluations: int = 200) -> FitResult:
    """Least squares of :func:`residuals` over the coefficients ``names``, from ``start``.

    Parameters
    ----------
    rows : sequence of Row
    names : sequence of str
        The coefficients fitted (fields of :class:`rcsa.model.clamping.BulkCoefficients`).
    start : BulkCoefficients
        The start (and the value of every coefficient not fitted).
    directory : pathlib.Path
    tolerance : float
        ``xtol`` and ``ftol`` of the solver.
    max_evaluations : int

    Returns
    -------
    FitResult
    """
    x0 = np.log([getattr(start, n) for n in names])
    lo = np.log([BOUNDS[n][0] for n in names])
    hi = np.log([BOUNDS[n][1] for n in names])
    res = least_squares(residuals, np.clip(x0, lo + 1e-9, hi - 1e-9), args=(names, rows, start, directory),
                        bounds=(lo, hi), x_scale=1.0, diff_step=1e-4, xtol=tolerance, ftol=tolerance,
                        gtol=tolerance, max_nfev=max_evaluations)
    return FitResult(start, coefficients(res.x, names, start), float(res.cost), int(res.nfev),
                     float(np.sqrt(np.mean(res.fun**2))), np.linalg.svd(res.jac, compute_uv=False))
