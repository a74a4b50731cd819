"""What the base model already expects: the discrepancy covariance Σ by Monte Carlo.

The known imperfections of the base model — material grade, bearing and joint stiffness,
damping, re-clamping and the stickout setting — and the measurement noise are pushed through
the model and the feature extractor (``docs/diagnosis.md`` §4.3)::

    for i in 1..n_mc:
        knobs_i = draw(tolerances)               # shared by all measurements + per measurement
        f_i     = features(noise(h(knobs_i), coherence))
    mu    = mean(f_i) − features(base)           # bias (nonlinearity, noise), added to every prediction
    Sigma = (1 − a) cov(f_i) + a diag(cov(f_i))  # a = 0.1: shrinkage keeps Σ invertible

This is a structured Kennedy–O'Hagan discrepancy: a gap the base model already expects is
never blamed on an effect. Noise is complex Gaussian with the Bendat & Piersol random error of
|H| (and of its phase, rad) ``σ = √(1−γ²) / (|γ| √(2 n_avg))`` from the measured coherence γ².

Default tolerances (one standard deviation; overridable per request, ``tolerances``) follow
``docs/diagnosis.md`` §2 and §5.1: those of the model (the table of :mod:`rcsa.model.tolerances`,
where they and their draws are defined once — predictions with uncertainty bands use the
same), and those of a measured spindle:

==================================  =======  =============================================
key                                 default  meaning
==================================  =======  =============================================
spindle_effective_length_log        0.35     measured ``direct_frf`` spindle: ln-scale of the
                                             equivalent-cantilever length of its estimated
                                             rotations (L/2 and 2L at 2σ)
spindle_rotation_shape_log          0.35     measured ``direct_frf`` spindle: ln-scale of the
                                             estimate's shape PH/N² (4/3 for a cantilever;
                                             a real spindle's differs: RA-1's is 1.55)
spindle_noise_rel                   0.005    measured spindle: relative noise of its stored FRFs
                                             where no coherence is stored
==================================  =======  =============================================

For a measured spindle the bearing tolerances do not apply (the bearings are inside the
measurement), and at a ``holder_tip`` plane neither do the spindle–holder ones; the
measurement's own uncertainty enters instead (:meth:`rcsa.analysis.diagnosis.problem.Problem.discrepancy`).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, replace

import numpy as np

from rcsa.analysis.diagnosis.perturbed_model import Knobs
from rcsa.model.tolerances import DEFAULT_TOLERANCES as MODEL_TOLERANCES
from rcsa.model.tolerances import apply_nuisance, draw_nuisance

__all__ = ["DEFAULT_TOLERANCES", "Discrepancy", "build_discrepancy", "draw_knobs", "noise_sd_rel",
           "shrink"]

#: The diagnosis's tolerances: the model's (:data:`rcsa.model.tolerances.DEFAULT_TOLERANCES`)
#: and a measured spindle's own (see the table above).
DEFAULT_TOLERANCES: dict[str, float] = {
    **MODEL_TOLERANCES,
    "spindle_effective_length_log": 0.35,
    "spindle_rotation_shape_log": 0.35,
    "spindle_noise_rel": 0.005,
}
# Shrinkage towards the diagonal (Ledoit–Wolf style, fixed weight as in the prototype): with
# ~40-60 features and a few hundred draws the sample covariance is invertible but noisy.
SHRINKAGE = 0.1
# Floor on the relative noise (1e-4 = 0.01 %): coherence of exactly 1 must not make a
# feature infinitely precise.
MIN_NOISE_REL = 1e-4


def noise_sd_rel(coherence: np.ndarray, n_averages: float) -> np.ndarray:
    """Random error of |H| (relative) from the coherence (Bendat & Piersol 2010, Table 9.6).

    Parameters
    ----------
    coherence : numpy.ndarray, shape (nlines,)
        γ² in [0, 1].
    n_averages : float
        Number of averaged impacts n_d.

    Returns
    -------
    numpy.ndarray, shape (nlines,)
        ``√(1−γ²) / (|γ| √(2 n_d))``; also the phase error in rad.
    """
    g2 = np.clip(np.asarray(coherence, dtype=float), 1e-3, 1.0)
    out: np.ndarray = np.maximum(np.sqrt(1.0 - g2) / (np.sqrt(g2) * np.sqrt(2.0 * n_averages)), MIN_NOISE_REL)
    return out


def draw_knobs(rng: np.random.Generator, tol: Mapping[str, float], n_configs: int,
               base: Knobs | None = None, estimated_rotations: bool = False) -> list[Knobs]:
    """One nuisance draw: the shared part once, the per-measurement part per configuration.

    The draw itself is the one every model user shares (:func:`rcsa.model.tolerances.draw_nuisance`).
    ``estimated_rotations``: the spindle's rotations are an equivalent-cantilever estimate
    (a measured ``direct_frf`` spindle); its length is drawn too (``base_rotation_scale``
    = L/L' with ln L' ~ N(ln L, ``spindle_effective_length_log``²)) and its shape, after
    everything else.
    """
    draw = draw_nuisance(rng, tol, 1, n_configs)
    base = Knobs() if base is None else base
    out = [apply_nuisance(base, draw.fields(0, c)) for c in range(n_configs)]
    if estimated_rotations:
        scale = float(np.exp(-tol["spindle_effective_length_log"] * rng.standard_normal()))
        shape = float(np.exp(tol["spindle_rotation_shape_log"] * rng.standard_normal()))
        out = [replace(k, base_rotation_scale=k.base_rotation_scale * scale,
                       base_rotation_shape=k.base_rotation_shape * shape) for k in out]
    return out


def shrink(cov: np.ndarray, weight: float = SHRINKAGE) -> np.ndarray:
    """``(1 − a) C + a diag(C)``: positive definite whenever diag(C) > 0 and a > 0."""
    return (1.0 - weight) * cov + weight * np.diag(np.diag(cov))


@dataclass(frozen=True)
class Discrepancy:
    """Bias, covariance and whitening of the features under tolerances and noise.

    Attributes
    ----------
    mu : numpy.ndarray, shape (nfeat,)
        Mean feature offset of the nuisance draws from the base features.
    sigma : numpy.ndarray, shape (nfeat, nfeat)
        Shrunk covariance.
    samples : numpy.ndarray, shape (n_mc, nfeat)
        Feature deviations of the draws from ``base + mu`` (for empirical nulls).
    band_db : numpy.ndarray, shape (n_mc, nbands)
        Band RMS dB error of each draw against the base model.
    """

    mu: np.ndarray
    sigma: np.ndarray
    samples: np.ndarray
    band_db: np.ndarray

    def whitener(self, rows: np.ndarray | slice = slice(None)) -> np.ndarray:
        """``Σ_rows^{-1/2}`` (symmetric), shape (nrows, nrows)."""
        s = self.sigma[rows, rows] if isinstance(rows, slice) else self.sigma[np.ix_(rows, rows)]
        vals, vecs = np.linalg.eigh(s)
        w: np.ndarray = (vecs / np.sqrt(vals)) @ vecs.T
        return w

    @property
    def sd(self) -> np.ndarray:
        """Feature standard deviations, shape (nfeat,)."""
        return np.sqrt(np.diag(self.sigma))


def build_discrepancy(base_features: np.ndarray, draws_h: Callable[[int], list[np.ndarray]],
                      features: Callable[[list[np.ndarray]], np.ndarray],
                      band_db: Callable[[list[np.ndarray]], np.ndarray],
                      noise_rel: list[np.ndarray], n_mc: int, rng: np.random.Generator) -> Discrepancy:
    """Monte-Carlo Σ from tolerance draws plus coherence noise.

    Parameters
    ----------
    base_features : numpy.ndarray, shape (nfeat,)
    draws_h : callable
        ``draws_h(n)`` → per measurement an array (n, nlines) of noise-free model FRFs under
        ``n`` nuisance draws (cached by the caller).
    features : callable
        Per-measurement FRF stacks → features, shape (n, nfeat).
    band_db : callable
        Per-measurement FRF stacks → band RMS dB against the base, shape (n, nbands).
    noise_rel : list of numpy.ndarray
        Per measurement, relative noise sd per analysis line.
    n_mc : int
    rng : numpy.random.Generator
        For the noise (the tolerance draws are the caller's).

    Returns
    -------
    Discrepancy
    """
    clean = draws_h(n_mc)
    noisy = []
    for h, s in zip(clean, noise_rel, strict=True):
        e = rng.standard_normal((2,) + h.shape)
        noisy.append(h * (1.0 + s * (e[0] + 1j * e[1])))
    f = features(noisy)
    mu = f.mean(axis=0) - base_features
    cov = np.cov(f, rowvar=False)
    # Floor: the feature extractor resolves ~1e-4 in ln f / ln|h| on the analysis lines.
    cov = cov + np.eye(cov.shape[0]) * 1e-8
    return Discrepancy(mu, shrink(cov), f - (base_features + mu), band_db(noisy))
