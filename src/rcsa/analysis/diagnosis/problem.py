"""One diagnosis problem: analysis lines, base model, windows and measured features.

The model is solved on a log-spaced subset of the measured lines inside each measurement's
valid band (coherence γ² ≥ 0.8 after a 9-line running median): at most ``max_lines`` lines
per measurement, all of them where the measured grid is sparser than the log grid. The same
lines carry the measured and the modelled FRF through the same extractor. When the
measurements share a frequency grid they share the lines, and the spindle (and holder) are
condensed once for all of them.

A measured spindle (hybrid) is looked up on these lines through the request's resolver; its
plane decides what is modelled (holder and spindle–holder joint at ``spindle_nose``, only
the tool at ``holder_tip``), and its own uncertainty (noise, identification conditioning,
estimated rotations) is drawn with the tolerances in the discrepancy.
"""

from __future__ import annotations

import hashlib
import json
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from rcsa.analysis.diagnosis.discrepancy import (
    Discrepancy,
    build_discrepancy,
    draw_knobs,
    noise_sd_rel,
)
from rcsa.analysis.diagnosis.features import Windows, band_rms_db, design_windows, extract
from rcsa.analysis.diagnosis.perturbed_model import BaseReceptance, Knobs, PartsBuilder, Solver
from rcsa.analysis.diagnosis.request import DEFAULT_NOISE_REL, MIN_VALID_LINES, Request
from rcsa.errors import InputError
from rcsa.model.spindle_side import MeasuredBase
from rcsa.physics.subassembly_cache import LruStore

__all__ = ["Problem", "VALID_COHERENCE"]

VALID_COHERENCE = 0.8
#: Monte-Carlo draws of the last few problems, by content (:meth:`Problem._cache_key`): a
#: repeated diagnosis of the same measurements (e.g. with another claim threshold) reuses them.
_DRAW_CACHE: LruStore[str, list[np.ndarray]] = LruStore(4)


def _median_filter(x: np.ndarray, size: int) -> np.ndarray:
    """Running median over ``size`` samples, the ends extended by their nearest value
    (``scipy.ndimage.median_filter(x, size, mode="nearest")`` for 1-D ``x``, without importing it)."""
    half = size // 2
    padded = np.concatenate([np.full(half, x[0]), x, np.full(size - 1 - half, x[-1])])
    out: np.ndarray = np.median(np.lib.stride_tricks.sliding_window_view(padded, size), axis=-1)
    return out


def _valid_band(coherence: np.ndarray | None, n: int) -> tuple[int, int]:
    if coherence is None:
        return 0, n
    ok = _median_filter(np.asarray(coherence, dtype=float), 9) >= VALID_COHERENCE
    idx = np.flatnonzero(ok)
    if idx.size == 0:
        return 0, 0
    return int(idx[0]), int(idx[-1]) + 1


def _log_subset(f: np.ndarray, lo: int, hi: int, f_lo: float, f_hi: float, n_target: int) -> np.ndarray:
    """Indices (into ``f``) of the lines nearest a log grid of ``n_target`` points, inside [lo, hi)."""
    target = np.geomspace(f_lo, f_hi, n_target)
    band = f[lo:hi]
    j = np.clip(np.searchsorted(band, target), 1, band.size - 1)
    nearer = np.where(np.abs(band[j - 1] - target) <= np.abs(band[j] - target), j - 1, j)
    keep = (target >= band[0] * (1 - 1e-12)) & (target <= band[-1] * (1 + 1e-12))
    return lo + np.unique(nearer[keep])


@dataclass
class Config:
    """One measurement as the diagnosis sees it."""

    index: int
    lines: np.ndarray        # indices into the measurement's own grid
    grid_lines: np.ndarray   # the same lines as indices into the solver grid
    frequency_hz: np.ndarray
    h_meas: np.ndarray
    noise_rel: np.ndarray
    h_base: np.ndarray
    windows: Windows
    bands: list[np.ndarray]  # per window, its lines with coherence >= VALID_COHERENCE
    good: np.ndarray         # lines with coherence >= VALID_COHERENCE (dB gaps are taken there)

    def db_error(self, h_model: np.ndarray) -> np.ndarray:
        """20 log10 |h_meas / h_model| on the good lines, dB."""
        db: np.ndarray = 20.0 * np.log10(np.abs(self.h_meas[self.good] / h_model[self.good]))
        return db


class Problem:
    """Analysis setup shared by the gap map, the discrepancy and the attribution.

    Parameters
    ----------
    request : Request
    """

    def __init__(self, request: Request) -> None:
        self.request = request
        self.spec = request.spec
        self.tools = [m.tool for m in request.measurements]
        n_lines = request.options.max_lines
        bands = []
        for i, m in enumerate(request.measurements):
            lo, hi = _valid_band(m.coherence, m.frequency_hz.size)
            if hi - lo < MIN_VALID_LINES:
                raise InputError(f"measurements[{i}].coherence" if m.coherence is not None
                                 else f"measurements[{i}].frequency_hz",
                                 f"needs at least {MIN_VALID_LINES} lines with coherence >= {VALID_COHERENCE}, "
                                 f"has {max(hi - lo, 0)}")
            bands.append((lo, hi))
        f_lo = min(m.frequency_hz[lo] for m, (lo, _) in zip(request.measurements, bands, strict=True))
        f_hi = max(m.frequency_hz[hi - 1] for m, (_, hi) in zip(request.measurements, bands, strict=True))
        picks = [_log_subset(m.frequency_hz, lo, hi, f_lo, f_hi, n_lines)
                 for m, (lo, hi) in zip(request.measurements, bands, strict=True)]
        grid = np.unique(np.concatenate([m.frequency_hz[p] for m, p in zip(request.measurements, picks, strict=True)]))
        self.solver = Solver(grid)
        self.measured: MeasuredBase | None = None
        if request.measured_spindle is not None:
            self.measured = self._resolve(grid)
            self.builder = PartsBuilder(self.spec, self.measured.plane, BaseReceptance(self.measured.receptance))
        else:
            self.builder = PartsBuilder(self.spec)
        self.configs: list[Config] = []
        for i, (m, p) in enumerate(zip(request.measurements, picks, strict=True)):
            f = m.frequency_hz[p]
            grid_lines = np.searchsorted(grid, f)
            h_base = self.solver.tip_h(self.builder.parts(m.tool, Knobs()), grid_lines)
            noise = (noise_sd_rel(m.coherence[p], m.n_averages) if m.coherence is not None
                     else np.full(p.size, DEFAULT_NOISE_REL))
            try:
                windows = design_windows(f, h_base)
            except ValueError:
                raise InputError(f"measurements[{i}].frequency_hz",
                                 "the base model has no resonance inside the valid band of this measurement; "
                                 "measure over a band that contains at least one mode") from None
            good = (m.coherence[p] >= VALID_COHERENCE) if m.coherence is not None else np.ones(p.size, bool)
            good_idx = np.flatnonzero(good)
            edges = windows.edges
            bands_i = []
            for j in range(edges.size - 1):
                band = good_idx[(good_idx >= edges[j]) & (good_idx < edges[j + 1])]
                bands_i.append(band if band.size else np.arange(edges[j], edges[j + 1]))
            self.configs.append(Config(i, p, grid_lines, f, m.h[p], noise, h_base, windows, bands_i, good_idx))
        self.offsets = np.cumsum([0] + [c.windows.size for c in self.configs])
        self.base_features = self.features([c.h_base for c in self.configs])
        self.measured_features = self.features([c.h_meas for c in self.configs])
        self.feature_config = np.concatenate([np.full(c.windows.size, c.index) for c in self.configs])

    # ------------------------------------------------------------------ measured spindle
    @property
    def plane(self) -> str | None:
        """Plane of a measured spindle (``spindle_nose`` or ``holder_tip``); None when analytical."""
        return None if self.measured is None else self.measured.plane

    def _resolve(self, grid: np.ndarray) -> MeasuredBase:
        """The measured spindle on the analysis grid, checked against the assembly and the tools.

        Also resolves it on every measurement's own lines (:attr:`full_bases`, for the corrected
        FRFs on those lines): a measurement whose band leaves the spindle's measured band is
        refused, naming it.
        """
        req = self.request
        resolve, spindle = req.resolve_base, req.measured_spindle
        assert resolve is not None and spindle is not None

        def field_of(exc: InputError) -> str:
            return f"assembly.{exc.field}" if exc.field.startswith("spindle") else exc.field

        self.full_bases: dict[bytes, MeasuredBase] = {}
        for i, m in enumerate(req.measurements):
            key = m.frequency_hz.tobytes()
            if key in self.full_bases:
                continue
            try:
                self.full_bases[key] = resolve(spindle, m.frequency_hz)
            except InputError as exc:
                if exc.field != "frequency":
                    raise InputError(field_of(exc), exc.rule) from None
                raise InputError(f"measurements[{i}].frequency_hz",
                                 f"this measurement's band lies outside the measured spindle's: {exc.rule}") from None
        try:
            base = resolve(spindle, grid)
        except InputError as exc:
            raise InputError(field_of(exc), exc.rule) from None
        spec = self.spec
        if base.plane == "holder_tip" and spec.holder is not None:
            raise InputError("assembly.holder", f"must be left out: the measured spindle "
                                                f"{spindle.measurement_id!r} (plane holder_tip) already "
                                                "contains its holder")
        if base.plane != "holder_tip" and spec.holder is None:
            raise InputError("assembly.holder", "is required: the measured spindle's plane is spindle_nose, so the "
                                                "holder is modelled")
        if base.plane == "holder_tip" and base.artifact_diameter_m is not None:
            d = base.artifact_diameter_m
            for i, m in enumerate(req.measurements):
                if abs(m.tool.shank_diameter_m - d) > 1e-6 * d:
                    where = (f"measurements[{i}].tool.shank_diameter_m" if "shank_diameter_m" in m.overrides
                             else "assembly.tool.shank_diameter_m")
                    raise InputError(where, f"must match the shank the holder-tip measurement was taken with "
                                            f"({d:g} m); got {m.tool.shank_diameter_m:g} m")
        return base

    # ------------------------------------------------------------------ evaluation
    def h(self, knobs: Knobs | Sequence[Knobs], base: BaseReceptance | None = None) -> list[np.ndarray]:
        """Model ``h`` of every configuration on its analysis lines (one knobs, or one per config).

        ``base``: another draw of the measured spindle's receptance (default: as measured).
        """
        ks = [knobs] * len(self.configs) if isinstance(knobs, Knobs) else list(knobs)
        return [self.solver.tip_h(self.builder.parts(self.tools[c.index], k, base), c.grid_lines)
                for c, k in zip(self.configs, ks, strict=True)]

    def h_many(self, knobs: Sequence[Knobs]) -> list[np.ndarray]:
        """Model ``h`` of every configuration for many knobs, per configuration shape (n, nlines)."""
        return [self.solver.tip_h_many([self.builder.parts(self.tools[c.index], k) for k in knobs], c.grid_lines)
                for c in self.configs]

    def features(self, hs: Sequence[np.ndarray]) -> np.ndarray:
        """Concatenated features of per-configuration FRFs (each (nlines,) or (n, nlines))."""
        return np.concatenate([extract(c.frequency_hz, h, c.windows) for c, h in zip(self.configs, hs, strict=True)],
                              axis=-1)

    def band_db(self, hs: Sequence[np.ndarray], ref: Sequence[np.ndarray] | None = None) -> np.ndarray:
        """Band RMS dB of ``hs`` against ``ref`` (default: the base), concatenated over configurations."""
        ref = [c.h_base for c in self.configs] if ref is None else ref
        return np.concatenate([band_rms_db(h, r, c.bands) for c, h, r in zip(self.configs, hs, ref, strict=True)],
                              axis=-1)

    def rows(self, configs: Sequence[int]) -> np.ndarray:
        """Feature indices belonging to the given configurations."""
        return np.flatnonzero(np.isin(self.feature_config, list(configs)))

    # ------------------------------------------------------------------ discrepancy
    def _cache_key(self, n_mc: int) -> str:
        req = self.request
        payload = json.dumps({"assembly": req.assembly, "tools": [m.overrides for m in req.measurements],
                              "tolerances": req.tolerances, "n": n_mc, "seed": req.options.seed},
                             sort_keys=True, default=str).encode()
        digest = hashlib.sha256(payload)
        for c in self.configs:
            digest.update(c.frequency_hz.tobytes())
        if self.measured is not None:
            digest.update(self.measured.receptance.tobytes())
            digest.update(json.dumps(self.spindle_uncertainty(), sort_keys=True, default=str).encode())
        return digest.hexdigest()

    def _draws(self, n_mc: int) -> list[np.ndarray]:
        """Model ``h`` of every configuration under ``n_mc`` nuisance draws, each (n_mc, nlines),
        kept by content for a repeated diagnosis (:data:`_DRAW_CACHE`)."""
        return _DRAW_CACHE.get(self._cache_key(n_mc), lambda: self._draw(n_mc))

    def _draw(self, n_mc: int) -> list[np.ndarray]:
        """Model ``h`` of every configuration under ``n_mc`` nuisance draws, each (n_mc, nlines).

        Each draw turns every tolerance (shared and per measurement) and, for a measured
        spindle, draws its receptance (noise through its identification) and — for estimated
        rotations — its equivalent-cantilever length.
        """
        rng = np.random.default_rng([self.request.options.seed, 1])
        out = [np.empty((n_mc, c.frequency_hz.size), dtype=complex) for c in self.configs]
        bases: list[BaseReceptance | None] = [None] * n_mc
        m = self.measured
        if m is not None and m.uncertainty is not None:
            drawn = m.uncertainty.draw(np.random.default_rng([self.request.options.seed, 3]), n_mc,
                                       self.request.tolerances["spindle_noise_rel"])
            bases = [BaseReceptance(b) for b in drawn]
        estimated = m is not None and m.effective_length_m is not None
        for d in range(n_mc):
            knobs = draw_knobs(rng, self.request.tolerances, len(self.configs), estimated_rotations=estimated)
            for c, h in zip(out, self.h(knobs, bases[d]), strict=True):
                c[d] = h
        return out

    def spindle_feature_covariance(self, n_draws: int = 60) -> np.ndarray | None:
        """Covariance of the features under the measured spindle's own uncertainty alone.

        The model at its base values on ``n_draws`` draws of the measured receptance (noise
        through its identification) and, for estimated rotations, of the cantilever length and
        shape — the part of Σ the spindle measurement is responsible for. None for an
        analytical spindle; zeros when the measurement states no uncertainty.

        Parameters
        ----------
        n_draws : int

        Returns
        -------
        numpy.ndarray, shape (nfeat, nfeat), or None
        """
        m = self.measured
        if m is None:
            return None
        opts, tol = self.request.options, self.request.tolerances
        bases: list[BaseReceptance | None] = [None] * n_draws
        if m.uncertainty is not None:
            drawn = m.uncertainty.draw(np.random.default_rng([opts.seed, 5]), n_draws, tol["spindle_noise_rel"])
            bases = [BaseReceptance(b) for b in drawn]
        rng = np.random.default_rng([opts.seed, 6])
        feats = []
        for b in bases:
            k = Knobs()
            if m.effective_length_m is not None:
                k = Knobs(base_rotation_scale=float(np.exp(-tol["spindle_effective_length_log"]
                                                           * rng.standard_normal())),
                          base_rotation_shape=float(np.exp(tol["spindle_rotation_shape_log"] * rng.standard_normal())))
            feats.append(self.features(self.h(k, b)))
        return np.cov(np.array(feats), rowvar=False)

    def spindle_uncertainty(self) -> dict[str, object] | None:
        """What the discrepancy assumes about the measured spindle's own uncertainty (None: analytical)."""
        m = self.measured
        if m is None:
            return None
        tol = self.request.tolerances
        out: dict[str, object] = {"kind": m.report.get("kind"), "plane": m.plane}
        if m.uncertainty is None:
            out["noise"] = "not propagated (finite-difference identification: its bias is not a random error)"
        else:
            out["noise"] = m.uncertainty.summary(tol["spindle_noise_rel"])
        if m.effective_length_m is not None:
            sd = tol["spindle_effective_length_log"]
            out["estimated_rotations"] = {
                "effective_length_m": m.effective_length_m, "log_sd": sd,
                "two_sigma_range_m": [m.effective_length_m * float(np.exp(-2 * sd)),
                                      m.effective_length_m * float(np.exp(2 * sd))]}
        return out

    def discrepancy(self) -> Discrepancy:
        """Σ and μ of the features under the stated tolerances, the measured coherence and the spindle's uncertainty."""
        n_mc = self.request.options.monte_carlo_draws
        return build_discrepancy(self.base_features, self._draws, self.features, self.band_db,
                                 [c.noise_rel for c in self.configs], n_mc,
                                 np.random.default_rng([self.request.options.seed, 2]))
