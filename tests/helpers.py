"""Shared test helpers: relative tolerances and the receptance comparison.

Receptances span 1e-9 … 1e-3 in their units, so every comparison is relative, with an
absolute floor scaled to the magnitude of the expected data (never numpy's default atol).
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
#: The shared data beside the repository (CI's layout); ``RCSA_SHARED_DATA`` points elsewhere
#: (e.g. a work tree whose shared directory is not its sibling). Never copied into the repo.
SHARED_DATA = Path(os.environ.get("RCSA_SHARED_DATA") or REPO.parent / "shared" / "data")

#: algebraic identities evaluated in double precision (a few hundred flops per entry)
RTOL_ALGEBRA = 1e-10
#: golden values regenerated from this implementation
RTOL_GOLDEN = 1e-8


def assert_receptance_close(actual: np.ndarray, expected: np.ndarray, rtol: float,
                            atol_scale: float = 1e-12, err_msg: str = "") -> None:
    """``|actual − expected| <= rtol·|expected| + atol_scale·max|expected|`` elementwise."""
    expected = np.asarray(expected)
    atol = atol_scale * float(np.max(np.abs(expected)))
    np.testing.assert_allclose(actual, expected, rtol=rtol, atol=atol, err_msg=err_msg)


def max_error_of_peak(actual: np.ndarray, expected: np.ndarray) -> float:
    """``max|actual − expected| / max|expected|`` — the error measure of ``docs/physics.md`` §4.6."""
    return float(np.max(np.abs(np.asarray(actual) - expected)) / np.max(np.abs(expected)))
