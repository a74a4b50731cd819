"""Fixtures of the diagnosis tests: small requests built from the model itself (fast)."""

from __future__ import annotations

import copy

import numpy as np
import pytest

from rcsa.analysis.diagnosis.perturbed_model import Knobs, Solver, config_parts
from rcsa.model.contract import parse_assembly
from tests.analysis.diagnosis.truth import base_document

STICKOUTS_M = (0.055, 0.066, 0.077)
FREQUENCY_HZ = np.arange(50.0, 6000.0 + 1e-9, 4.0)


def model_request(knobs: Knobs = Knobs(), seed: int = 0, stickouts_m=STICKOUTS_M,  # noqa: B008
                  frequency_hz: np.ndarray = FREQUENCY_HZ, noise_rel: float = 0.01) -> dict:
    """A request whose "measurements" are the rcsa model with ``knobs``, plus 1 % noise.

    Only for tests of the plumbing (shape, validation, CLI); the benchmark's truth is the FE
    oracle (``tests/analysis/diagnosis/truth.py``).
    """
    base = base_document()
    spec = parse_assembly({**base, "frequency": {"values_hz": frequency_hz.tolist()}})
    solver = Solver(frequency_hz)
    rng = np.random.default_rng(seed)
    measurements = []
    for stickout in stickouts_m:
        tool = spec.tool.__class__(**{**{f: getattr(spec.tool, f) for f in spec.tool.__slots__},
                                      "stickout_m": stickout})
        h = solver.tip_h(config_parts(spec, tool, knobs))
        sigma = np.sqrt((noise_rel * np.abs(h)) ** 2 + (10 ** (-50 / 20) * np.abs(h).max()) ** 2)
        noisy = h + sigma * (rng.standard_normal(h.size) + 1j * rng.standard_normal(h.size))
        coherence = 1.0 / (1.0 + 10.0 * (sigma / np.abs(h)) ** 2)
        measurements.append({"tool": {"stickout_m": stickout}, "frequency_hz": frequency_hz.tolist(),
                             "h": {"real": noisy.real.tolist(), "imag": noisy.imag.tolist()},
                             "coherence": coherence.tolist(), "n_averages": 5,
                             "label": f"{stickout * 1e3:.0f} mm"})
    return {"assembly": base, "measurements": measurements}


@pytest.fixture(scope="session")
def mass_request() -> dict:
    """Three stickouts measured with a 5 g sensor on the tip (model-generated)."""
    return model_request(Knobs(tip_mass_kg=0.005))


@pytest.fixture
def small_request(mass_request) -> dict:
    """A fresh deep copy the test may edit."""
    return copy.deepcopy(mass_request)
