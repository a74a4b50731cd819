"""The one peak picker: its rule, the callers' rules, and that it does without scipy.signal.

Oracle: ``scipy.signal.find_peaks(y, prominence=...)`` (imported here only), whose peaks and
prominences :func:`rcsa.model.peaks.peak_lines` reproduces without importing it.
"""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest

from rcsa.model.peaks import find_frf_peaks, peak_lines
from tests.helpers import REPO


def test_peak_lines_uses_topographic_prominence():
    y = np.array([0.0, 2.0, 1.0, 1.5, 1.0, 3.0, 0.0])
    lines, prominences = peak_lines(y, 0.4)
    assert lines.tolist() == [1, 3, 5]
    assert prominences.tolist() == [1.0, 0.5, 3.0]
    assert peak_lines(y, 0.8)[0].tolist() == [1, 5]


def test_frf_peaks_are_relative_to_the_largest_peak():
    f = np.arange(1.0, 8.0)
    h = np.array([0.0, 2.0, 1.0, 1.01, 1.0, 3.0, 0.0]) + 0j  # a 0.01 bump is below 1 % of max|h|
    assert [p["frequency_hz"] for p in find_frf_peaks(f, h)] == [2.0, 6.0]
    assert [p["frequency_hz"] for p in find_frf_peaks(f, h, rel_prominence=0.001)] == [2.0, 4.0, 6.0]
    assert find_frf_peaks(f[:2], h[:2]) == []


@pytest.mark.slow
def test_import_rcsa_does_not_import_scipy_signal():
    code = "import sys, rcsa, rcsa.analysis.diagnosis; sys.exit('scipy.signal' in sys.modules)"
    assert subprocess.run([sys.executable, "-c", code], check=False).returncode == 0


def test_a_prediction_and_a_diagnosis_import_no_scipy_signal_stats_or_optimize():
    code = ("import sys, json, rcsa; rcsa.predict(json.load(open('examples/ra1.json'))); "
            "rcsa.diagnose(json.load(open('examples/diagnosis.json'))); "
            "sys.exit(any(m in sys.modules for m in ('scipy.signal', 'scipy.stats', 'scipy.optimize')))")
    assert subprocess.run([sys.executable, "-c", code], check=False, cwd=REPO).returncode == 0


@pytest.mark.parametrize("seed", range(6))
def test_peaks_and_prominences_equal_scipy_find_peaks(seed):
    find_peaks = pytest.importorskip("scipy.signal").find_peaks
    rng = np.random.default_rng(seed)
    y = np.cumsum(rng.standard_normal(400))
    y[50:60] = y[50]                                     # a plateau
    y[200:203] = y[199] + 1.0                            # a flat-topped peak (midpoint rule)
    y = np.round(y, 1)                                   # equal neighbours elsewhere too
    for prominence in (0.0, 0.5, 2.0):
        lines, prominences = peak_lines(y, prominence)
        expected, props = find_peaks(y, prominence=prominence)
        np.testing.assert_array_equal(lines, expected)
        np.testing.assert_allclose(prominences, props["prominences"], rtol=0, atol=0)
