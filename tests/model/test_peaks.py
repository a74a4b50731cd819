"""The one peak picker: its rule, the callers' rules, and its lazy import of scipy.signal."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest

from rcsa.model.peaks import find_frf_peaks, peak_lines


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
