"""How far the gap shrinks on measurements the fit did not see (``docs/diagnosis.md`` §4.6).

Folds: the request's ``options.held_out`` (one fold); otherwise, with four or more
measurements, every second one in order of stickout is held out; with two or three,
leave-one-configuration-out (one fold per measurement); a single measurement cannot be held
out (the report says so). In each fold the effect is refitted on the training measurements
only (MAP of the training likelihood, started from the all-data MAP) and the held-out
measurements are predicted:

* feature gap: Mahalanobis χ² of the held-out features before (base) and after (effect);
  ``gap_ratio = sqrt(χ²_after / χ²_before)`` pooled over the folds;
* dB gap: RMS over the held-out analysis lines of 20 log10 |H_meas / H_model|;
* ``confirmed``: χ²_after < χ²_before.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from rcsa.analysis.diagnosis.attribution import Likelihood
from rcsa.analysis.diagnosis.discrepancy import Discrepancy
from rcsa.analysis.diagnosis.simplex import nelder_mead

__all__ = ["HeldOut", "folds", "held_out"]


def folds(stickouts_m: Sequence[float], requested: Sequence[int] | None) -> list[tuple[list[int], list[int]]]:
    """(train, test) index lists.

    Parameters
    ----------
    stickouts_m : sequence of float
        Per measurement (orders the alternating split).
    requested : sequence of int, optional
        Explicit held-out measurements.
    """
    n = len(stickouts_m)
    every = list(range(n))
    if requested is not None:
        test = sorted(requested)
        return [([i for i in every if i not in test], test)] if test else []
    if n >= 4:
        order = list(np.argsort(stickouts_m, kind="stable"))
        test = sorted(int(i) for i in order[1::2])
        return [([i for i in every if i not in test], test)]
    if n >= 2:
        return [([j for j in every if j != i], [i]) for i in every]
    return []


@dataclass
class HeldOut:
    """Held-out scores of one effect (``None`` when nothing could be held out)."""

    chi2_before: float
    chi2_after: float
    n_features: int
    db_before: float
    db_after: float
    maps: list[np.ndarray]

    @property
    def gap_ratio(self) -> float:
        """√(χ²_after / χ²_before)."""
        return float(np.sqrt(self.chi2_after / self.chi2_before)) if self.chi2_before > 0 else float("nan")

    @property
    def confirmed(self) -> bool:
        """Held-out χ² improved."""
        return self.chi2_after < self.chi2_before


def held_out(fold_list: Sequence[tuple[list[int], list[int]]], rows_of: Callable[[Sequence[int]], np.ndarray],
             measured: np.ndarray, disc: Discrepancy, kind: str, base_features: np.ndarray,
             features_at: Callable[[int, np.ndarray], np.ndarray], x_all: np.ndarray, lo: np.ndarray,
             hi: np.ndarray, db_of: Callable[[int, np.ndarray, Sequence[int]], tuple[float, float, int]]
             ) -> HeldOut | None:
    """Refit on each fold's training set and score its held-out measurements.

    Parameters
    ----------
    fold_list : list of (train, test)
    rows_of : callable
        Measurement indices → feature indices.
    measured, base_features : numpy.ndarray, shape (nfeat,)
        Measured features, and the base model's ("before").
    disc : Discrepancy
    kind : str
        Likelihood kind.
    features_at : callable
        ``(fold, params)`` → model features (all measurements); the fold index lets effects
        fixed before this one take their own training-only values.
    x_all : numpy.ndarray
        All-data MAP (start of each refit).
    lo, hi : numpy.ndarray
        Parameter bounds.
    db_of : callable
        ``(fold, params, test) → (sum of squared dB errors before, after, number of lines)``.

    Returns
    -------
    HeldOut or None
    """
    if not fold_list:
        return None
    c2b = c2a = 0.0
    nf = 0
    sb = sa = 0.0
    nl = 0
    maps = []
    for k, (train, test) in enumerate(fold_list):
        like = Likelihood(measured, disc, rows_of(train), kind)
        x0 = np.clip(x_all, lo, hi)
        if x0.size:
            def objective(p: np.ndarray, like: Likelihood = like, k: int = k) -> float:
                return -float(like(features_at(k, np.clip(p, lo, hi))))

            res_x, _ = nelder_mead(objective, x0, lo, hi, xatol=1e-4 * float(np.min(hi - lo)), fatol=1e-3,
                                   maxfev=30 * x0.size)
            x = np.clip(res_x, lo, hi)
        else:
            x = x0
        maps.append(x)
        test_like = Likelihood(measured, disc, rows_of(test), kind)
        c2b += float(test_like.chi2(base_features))
        c2a += float(test_like.chi2(features_at(k, x)))
        nf += test_like.rows.size
        b, a, n = db_of(k, x, test)
        sb, sa, nl = sb + b, sa + a, nl + n
    return HeldOut(c2b, c2a, nf, float(np.sqrt(sb / max(nl, 1))), float(np.sqrt(sa / max(nl, 1))), maps)
