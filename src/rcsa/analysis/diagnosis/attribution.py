"""Which effect: exact evidence per candidate, Occam penalty included, and the decision rules.

For every candidate M_k with parameters φ (uniform prior on the box [lo, hi], volume V)::

    lnZ_k = ln ∫ L(φ) dφ / V,      L(φ) = p(f_meas | f(φ) + μ, Σ)
    lnZ_0 = ln L(null)             (the base model has no free parameter)
    ln BF_k = lnZ_k − lnZ_0

``f(φ)`` are the model features with the effect added, ``μ`` and ``Σ`` the discrepancy
(:mod:`.discrepancy`). The likelihood is Gaussian or, by default, Student-t (ν = 5) on the
symmetrically whitened residuals ``z = Σ^{-1/2} r`` — robust to a single feature that jumps
when a mode crosses a window edge (``docs/diagnosis.md`` §6.5).

**Understated tolerances.** The stated tolerances may be too small: Σ is taken as ``s² Σ``
with the scatter scale ``s`` a nuisance hyperparameter, marginalised in every likelihood —
half the prior mass at ``s = 1`` (the tolerances as stated), half log-uniform on
``(1, MAX_SCATTER_SCALE]``. With the tolerances right the marginal is within ``ln 2`` of
the likelihood at ``s = 1`` for every model alike (Bayes factors unchanged); with a truth
that scatters more than stated (``diagnosis.md`` §6.4: false claims 13–20 % at 1.5×) a gap
spread over every feature is explained by ``s`` — no effect can claim it — while an effect
that concentrates the gap in its own signature still wins, the remainder then being at
``s ≈ 1``. The χ² of the held-out and remainder tests stay at ``s = 1`` (they report the gap
against the stated tolerances).

A structured deviation — one nuisance parameter drawn beyond its stated tolerance — still
looks like an effect under the marginal. So the verdict is then re-weighed at the scatter the
data show once the best effect is in (``ŝ``: the remainder's χ² over the Monte-Carlo null's
median, :meth:`rcsa.analysis.diagnosis.state.Analysis.remainder_scale`): its evidence again with Σ·ŝ²
(``Likelihood(scale=ŝ)``) decides whether the best effect is claimed at all (and weighs a
second effect); the ranking and the ambiguity between candidates stay at the stated Σ. A
right effect leaves ``ŝ ≈ 1`` and loses nothing; on data that scatter twice as stated,
``ŝ ≈ 1.5–2`` and a claim must clear τ with Σ that much wider.

The integral is a trapezoid sum on a grid (25 points in 1-D, 11 × 11 in 2-D). When the
posterior is narrower than the grid step it is redone on a fine grid over MAP ± 6 sd in 1-D
and by the Laplace approximation (with the prior box's truncation) in 2-D; the MAP is refined
by a bounded Nelder–Mead search and the sd comes from a finite-difference Hessian.

Decision (Kass & Raftery 1995 scale, ``docs/diagnosis.md`` §4.5): ``none`` unless the best
ln BF > τ (3, "strong"); ``ambiguous`` when other candidates lie within ``amb`` (2.3, a
Bayes factor of 10) of the best; otherwise ``identified``.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from rcsa.analysis.diagnosis.candidates import Candidate
from rcsa.analysis.diagnosis.discrepancy import Discrepancy
from rcsa.analysis.diagnosis.simplex import nelder_mead

__all__ = ["Decision", "Fit", "Likelihood", "decide", "evidence", "fit_candidate"]

NU = 5.0
#: Largest factor by which the stated tolerances (and noise) may understate the scatter.
MAX_SCATTER_SCALE = 4.0
_SCALES = np.geomspace(1.0, MAX_SCATTER_SCALE, 25)


#: Prior mass of ``s = 1`` exactly (the tolerances as stated); the rest is log-uniform.
SCATTER_MASS_AT_ONE = 0.5


def _scale_log_prior(at_one: float = SCATTER_MASS_AT_ONE) -> np.ndarray:
    """ln prior weights of the scatter-scale grid: ``at_one`` at s = 1, the rest log-uniform (trapezoid in ln s)."""
    w = np.full(_SCALES.size, 1.0 / (_SCALES.size - 1))
    w[[0, -1]] *= 0.5
    w *= 1.0 - at_one
    w[0] += at_one
    out: np.ndarray = np.log(w)
    return out


_SCALE_LOG_PRIOR = _scale_log_prior()
GRID_1D = 25
GRID_2D = 11
FINE_1D = 41


class Likelihood:
    """ln p(f_meas | f_model) on a subset of the features.

    Parameters
    ----------
    measured : numpy.ndarray, shape (nfeat,)
    disc : Discrepancy
    rows : numpy.ndarray of int
        Features that enter (e.g. the training measurements).
    kind : {"student_t", "gaussian"}
    scatter : bool
        Marginalise the scatter scale ``s`` (module docstring); False: ``s = 1``.
    scale : float
        Σ taken as ``scale² Σ`` before anything else (the scatter the data showed; 1: as stated).
    """

    def __init__(self, measured: np.ndarray, disc: Discrepancy, rows: np.ndarray, kind: str = "student_t",
                 scatter: bool = True, scale: float = 1.0) -> None:
        self.rows = np.asarray(rows)
        self.w = disc.whitener(self.rows) / scale
        self.target = measured[self.rows] - disc.mu[self.rows]
        self.kind = kind
        self.scatter = scatter
        n = self.rows.size
        log_det_w = float(np.linalg.slogdet(self.w)[1])
        if kind == "gaussian":
            self.const = log_det_w - 0.5 * n * np.log(2 * np.pi)
        else:
            self.const = log_det_w + n * (math.lgamma((NU + 1) / 2) - math.lgamma(NU / 2) - 0.5 * np.log(NU * np.pi))

    def whitened(self, model_features: np.ndarray) -> np.ndarray:
        """``z = Σ^{-1/2} (f_meas − μ − f_model)`` on the rows, shape (..., nrows)."""
        z: np.ndarray = (self.target - model_features[..., self.rows]) @ self.w.T
        return z

    def chi2(self, model_features: np.ndarray) -> np.ndarray:
        """Mahalanobis χ² of the residual."""
        chi2: np.ndarray = np.sum(self.whitened(model_features) ** 2, axis=-1)
        return chi2

    def log_likelihood_by_scale(self, model_features: np.ndarray) -> np.ndarray:
        """ln L at every scatter scale of the grid, shape (..., nscales)."""
        z2 = self.whitened(model_features) ** 2
        s2 = _SCALES**2
        n = self.rows.size
        if self.kind == "gaussian":
            fit = -0.5 * np.sum(z2, axis=-1)[..., None] / s2
        else:
            fit = -0.5 * (NU + 1) * np.sum(np.log1p(z2[..., None, :] / (NU * s2[:, None])), axis=-1)
        out: np.ndarray = self.const - n * np.log(_SCALES) + fit
        return out

    def scatter_scale(self, model_features: np.ndarray) -> float:
        """The scatter the residual shows: the maximum-likelihood ``s`` on the grid [1, MAX_SCATTER_SCALE].

        1 when the residual scatters as stated (or less); parabolic refinement in ln s between
        grid points.
        """
        ll = self.log_likelihood_by_scale(model_features)
        i = int(np.argmax(ll))
        if 0 < i < _SCALES.size - 1:
            y0, y1, y2 = ll[i - 1], ll[i], ll[i + 1]
            den = y0 - 2 * y1 + y2
            step = float(np.log(_SCALES[1] / _SCALES[0]))
            if den < 0:
                return float(_SCALES[i] * np.exp(0.5 * (y0 - y2) / den * step))
        return float(_SCALES[i])

    def __call__(self, model_features: np.ndarray) -> np.ndarray:
        if self.scatter:
            lp = self.log_likelihood_by_scale(model_features) + _SCALE_LOG_PRIOR
            top = lp.max(axis=-1)
            marginal: np.ndarray = top + np.log(np.sum(np.exp(lp - top[..., None]), axis=-1))
            return marginal
        z = self.whitened(model_features)
        out: np.ndarray = (self.const - 0.5 * np.sum(z * z, axis=-1) if self.kind == "gaussian" else
                           self.const - 0.5 * (NU + 1) * np.sum(np.log1p(z * z / NU), axis=-1))
        return out


@dataclass
class Fit:
    """Posterior summary of one candidate on one set of measurements."""

    candidate: Candidate
    log_evidence: float
    log_bayes_factor: float
    map: np.ndarray
    sd: np.ndarray
    log_lik_map: float
    at_bound: list[bool]
    method: str


def _hessian(f: Callable[[np.ndarray], np.ndarray], x: np.ndarray, step: np.ndarray, lo: np.ndarray,
             hi: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Finite-difference gradient and Hessian of ``f`` (batched) at ``c`` (``x`` moved inside the box)."""
    d = x.size
    c = np.clip(x, lo + step, hi - step)
    e = np.diag(step)
    pts = [c] + [c + e[i] for i in range(d)] + [c - e[i] for i in range(d)]
    pairs = [(i, j) for i in range(d) for j in range(i)]
    for i, j in pairs:
        pts += [c + e[i] + e[j], c + e[i] - e[j], c - e[i] + e[j], c - e[i] - e[j]]
    v = f(np.array(pts))
    h = np.zeros((d, d))
    for i in range(d):
        h[i, i] = (v[1 + i] - 2 * v[0] + v[1 + d + i]) / step[i] ** 2
    for k, (i, j) in enumerate(pairs):
        a, b, c_, d_ = v[1 + 2 * d + 4 * k: 5 + 2 * d + 4 * k]
        h[i, j] = h[j, i] = (a - b - c_ + d_) / (4 * step[i] * step[j])
    grad = (v[1:1 + d] - v[1 + d:1 + 2 * d]) / (2 * step)
    return grad, h, c


def _parabola_sd(x: np.ndarray, ll: np.ndarray, i: int) -> tuple[float, float]:
    """Vertex and sd of a Gaussian through the grid maximum ``i`` and its neighbours.

    At a bound (or with a flat/convex triple) the sd comes from the drop to the one
    neighbour: ``sd = step / sqrt(2 Δ)``.
    """
    step = x[1] - x[0]
    if 0 < i < x.size - 1:
        c2 = (ll[i + 1] - 2 * ll[i] + ll[i - 1]) / (2 * step**2)
        if c2 < 0:
            b = (ll[i + 1] - ll[i - 1]) / (2 * step)
            return float(np.clip(x[i] - b / (2 * c2), x[i - 1], x[i + 1])), float(1.0 / np.sqrt(-2 * c2))
    j = i + 1 if i < x.size - 1 else i - 1
    drop = ll[i] - ll[j]
    return float(x[i]), float(step / np.sqrt(2 * drop)) if drop > 0 else float("inf")


def _evidence_1d(loglik: Callable[[np.ndarray], np.ndarray], lo: float, hi: float
                 ) -> tuple[float, np.ndarray, np.ndarray, float, str]:
    x = np.linspace(lo, hi, GRID_1D)
    ll = loglik(x[:, None])
    i = int(np.argmax(ll))
    step = x[1] - x[0]
    x_map, sd = _parabola_sd(x, ll, i)
    if sd >= step:  # the coarse grid resolves the posterior
        w = np.exp(ll - ll.max())
        mean = float(w @ x / w.sum())
        return (_trapz_log(ll, [x]) - np.log(hi - lo), np.array([x_map]),
                np.array([np.sqrt(float(w @ (x - mean) ** 2 / w.sum()))]), float(ll.max()), "grid")
    half = max(6 * sd, step)
    xf = np.linspace(max(lo, x_map - half), min(hi, x_map + half), FINE_1D)
    llf = loglik(xf[:, None])
    top = max(float(llf.max()), float(ll.max()))
    outside = (x < xf[0]) | (x > xf[-1])
    z = np.exp(_trapz_log(llf, [xf]) - top) + step * float(np.exp(ll[outside] - top).sum())
    k = int(np.argmax(llf))
    x_map, _ = _parabola_sd(xf, llf, k)
    w = np.exp(llf - llf.max())
    mean = float(w @ xf / w.sum())
    sd_f = np.sqrt(float(w @ (xf - mean) ** 2 / w.sum()))
    return float(top + np.log(z) - np.log(hi - lo)), np.array([x_map]), np.array([sd_f]), top, "fine-grid"


def evidence(loglik: Callable[[np.ndarray], np.ndarray], lo: np.ndarray, hi: np.ndarray
             ) -> tuple[float, np.ndarray, np.ndarray, float, str]:
    """ln of the prior-averaged likelihood over the box ``[lo, hi]`` (uniform prior).

    Parameters
    ----------
    loglik : callable
        ln L for a batch of parameter vectors, shape (n, d) → (n,); d = 1 or 2.
    lo, hi : numpy.ndarray, shape (d,)

    Returns
    -------
    log_z : float
    map : numpy.ndarray, shape (d,)
    sd : numpy.ndarray, shape (d,)
        Posterior standard deviations (grid moments, or Laplace in 2-D).
    log_lik_map : float
    method : str
        ``"grid"``, ``"fine-grid"`` (1-D) or ``"laplace"`` (2-D).

    Examples
    --------
    A linear-Gaussian toy: y = φ + noise, σ = 0.1, prior U(−1, 1)::

    >>> def ll(p):
    ...     return -0.5 * ((0.3 - p[:, 0]) / 0.1) ** 2 - np.log(np.sqrt(2 * np.pi) * 0.1)
    >>> round(float(evidence(ll, np.array([-1.0]), np.array([1.0]))[0]), 4)   # = ln(1/2)
    -0.6931
    """
    if lo.size == 1:
        return _evidence_1d(loglik, float(lo[0]), float(hi[0]))
    d = lo.size
    volume = float(np.prod(hi - lo))
    axes = [np.linspace(a, b, GRID_2D) for a, b in zip(lo, hi, strict=True)]
    pts = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, d)
    ll = loglik(pts)
    best = pts[np.argmax(ll)]
    step = (hi - lo) / (GRID_2D - 1)
    res_x, res_fun = nelder_mead(lambda p: -float(loglik(np.clip(p, lo, hi)[None, :])[0]), best, lo, hi,
                                 xatol=1e-4 * float(np.min(hi - lo)), fatol=1e-3, maxfev=40,
                                 initial_simplex=_simplex(best, step / 2, lo, hi))
    x_map, ll_map = (np.clip(res_x, lo, hi), -res_fun) if -res_fun > ll.max() else (best, float(ll.max()))
    h = step / 4
    cov = None
    for _ in range(3):  # shrink the stencil until it is below half a posterior sd
        grad, hess, centre = _hessian(loglik, x_map, h, lo, hi)
        prec = -hess
        if not np.all(np.linalg.eigvalsh(prec) > 0):
            cov = None
            break
        cov = np.linalg.inv(prec)
        newton = np.clip(centre + cov @ grad, lo, hi)  # one Newton step polishes the simplex's MAP
        ll_newton = float(loglik(newton[None, :])[0])
        if ll_newton > ll_map:
            x_map, ll_map = newton, ll_newton
        sd = np.sqrt(np.diag(cov))
        if np.all(h <= sd / 2):
            break
        h = np.minimum(h, sd / 2)
    if cov is None or np.all(np.sqrt(np.diag(cov)) >= step):
        w = np.exp(ll - ll.max())
        mean = (w @ pts) / w.sum()
        sd = np.sqrt(np.maximum((w @ (pts - mean) ** 2) / w.sum(), 0.0))
        return _trapz_log(ll.reshape([GRID_2D] * d), axes) - np.log(volume), x_map, sd, ll_map, "grid"
    sd = np.sqrt(np.diag(cov))
    mass = float(np.prod([_normal_cdf(b) - _normal_cdf(a) for a, b in zip((lo - x_map) / sd, (hi - x_map) / sd,
                                                                           strict=True)]))
    log_z = ll_map + 0.5 * d * np.log(2 * np.pi) + 0.5 * np.linalg.slogdet(cov)[1] + np.log(max(mass, 1e-300)) \
        - np.log(volume)
    return float(log_z), x_map, sd, ll_map, "laplace"


def _normal_cdf(z: float) -> float:
    """Φ(z), the standard normal CDF."""
    return 0.5 * math.erfc(-float(z) / math.sqrt(2.0))


def _simplex(x: np.ndarray, step: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    pts = [x.copy()]
    for i in range(x.size):
        p = x.copy()
        p[i] = p[i] + step[i] if p[i] + step[i] <= hi[i] else p[i] - step[i]
        pts.append(np.clip(p, lo, hi))
    return np.array(pts)


def _trapz_log(ll: np.ndarray, axes: Sequence[np.ndarray]) -> float:
    """ln of the trapezoid integral of exp(ll) over a tensor grid, without overflow."""
    top = float(ll.max())
    v = np.exp(ll - top)
    for ax in reversed(axes):
        if ax.size < 2:
            v = v[..., 0]
            continue
        v = np.trapezoid(v, ax, axis=-1)
    return top + float(np.log(max(float(v), 1e-300)))


def fit_candidate(candidate: Candidate, features_many: Callable[[Candidate, np.ndarray], np.ndarray],
                  like: Likelihood, log_z0: float) -> Fit:
    """Evidence, MAP and sd of one candidate under one likelihood.

    ``features_many(candidate, values)`` maps parameter vectors (n, d) to model features
    (n, nfeat).
    """
    lo, hi = candidate.lo, candidate.hi
    log_z, x_map, sd, ll_map, method = evidence(lambda v: like(features_many(candidate, v)), lo, hi)
    tol = 0.01 * (hi - lo)
    at_bound = [bool((x - a) < t or (b - x) < t) for x, a, b, t in zip(x_map, lo, hi, tol, strict=True)]
    return Fit(candidate, log_z, log_z - log_z0, x_map, sd, ll_map, at_bound, method)


@dataclass
class Decision:
    """The verdict: ``status`` in {identified, ambiguous, none}."""

    status: str
    effect: str
    ambiguous_with: list[str]
    ranking: list[Fit]


def decide(fits: Sequence[Fit], tau: float, amb: float) -> Decision:
    """Apply the claim threshold τ and the ambiguity window to ranked fits."""
    ranking = sorted(fits, key=lambda f: -f.log_bayes_factor)
    if not ranking or ranking[0].log_bayes_factor <= tau:
        return Decision("none", "none", [], ranking)
    best = ranking[0]
    rivals = [f.candidate.name for f in ranking[1:] if best.log_evidence - f.log_evidence < amb]
    if rivals:
        return Decision("ambiguous", best.candidate.name, rivals, ranking)
    return Decision("identified", best.candidate.name, [], ranking)
