"""Golden master: the whole result document of ``rcsa.predict(ra1())`` against a stored file.

The oracle tests (``test_ra1.py``, ``tests/oracles``) bound the model's distance from
independent references (2e-8 of the peak, 1e-5 on modes); this one pins the document as a
whole — every field, every line of h, l, n and p — so that any change of the numbers, the
fields or their shapes is seen and has to be explained. The file is
``tests/data/ra1/golden_prediction.json.gz`` (13 significant digits). After an intended change
of the model, regenerate it and say in the commit why the numbers moved::

    python -m tests.reference.regenerate_golden            # shows what changed, writes nothing
    python -m tests.reference.regenerate_golden --write    # overwrites the file

Tolerances (relative): the same code on another numpy/BLAS build or CPU rounds differently,
and the elimination's rounding error is ~1e-14 of the peak (the independent receptance-coupling
path agrees with it to 1e-14 from 900 Hz on, O13), amplified at most ~1e3 where an entry
passes through zero (antiresonances, sign changes of Re h). So: each receptance entry within
1e-10 of its own value plus 1e-11 of its own peak; natural frequencies (bisected to 1e-11)
within 1e-10; peak heights, the static stiffness and the most negative real part within 1e-10;
the frequency grid, peak and minimum frequencies (grid lines), the method and notes exactly.
"""

from __future__ import annotations

import numpy as np
import pytest

import rcsa
from rcsa.reference import ra1
from tests.helpers import assert_receptance_close

from .regenerate_golden import GOLDEN, differences, load_golden

pytestmark = pytest.mark.reference

RTOL = 1e-10
#: absolute floor of the receptance comparison, as a fraction of each entry's peak
ATOL_OF_PEAK = 1e-11


@pytest.fixture(scope="module")
def golden() -> dict:
    return load_golden()


@pytest.fixture(scope="module")
def result() -> dict:
    return rcsa.predict(ra1()).to_dict()


def test_the_document_has_the_golden_fields_and_shapes(golden, result):
    assert sorted(result) == sorted(golden)
    assert sorted(result["tool_point"]) == sorted(golden["tool_point"]) == ["h", "l", "n", "p"]
    assert result["frequency_hz"] == golden["frequency_hz"]  # 5 … 9999 Hz, 1 Hz lines
    assert len(golden["frequency_hz"]) == 9996
    for key in ("natural_frequencies_method", "notes", "min_real_frequency_hz"):
        assert result[key] == golden[key], key


@pytest.mark.parametrize("entry", ["h", "l", "n", "p"])
def test_tool_point_receptance(golden, result, entry):
    def complex_of(doc: dict) -> np.ndarray:
        part = doc["tool_point"][entry]
        return np.asarray(part["real"]) + 1j * np.asarray(part["imag"])

    assert_receptance_close(complex_of(result), complex_of(golden), rtol=RTOL, atol_scale=ATOL_OF_PEAK,
                            err_msg=f"tool_point.{entry} vs {GOLDEN.name}")


def test_natural_frequencies_peaks_and_static_quantities(golden, result):
    np.testing.assert_allclose(result["natural_frequencies_hz"], golden["natural_frequencies_hz"], rtol=RTOL, atol=0)
    assert [p["frequency_hz"] for p in result["peaks"]] == [p["frequency_hz"] for p in golden["peaks"]]
    np.testing.assert_allclose([p["magnitude_m_n"] for p in result["peaks"]],
                               [p["magnitude_m_n"] for p in golden["peaks"]], rtol=RTOL, atol=0)
    for key in ("static_stiffness_n_m", "min_real_m_n"):
        assert result[key] == pytest.approx(golden[key], rel=RTOL, abs=0), key


def test_the_regenerate_command_names_what_changed(golden):
    moved = {**golden, "static_stiffness_n_m": golden["static_stiffness_n_m"] * (1 + 1e-6),
             "tool_point": {**golden["tool_point"], "h": {"real": [2 * x for x in golden["tool_point"]["h"]["real"]],
                                                          "imag": golden["tool_point"]["h"]["imag"]}}}
    lines = differences(golden, moved)
    assert [line.split(":")[0] for line in lines] == ["static_stiffness_n_m", "tool_point.h"]
    assert "of the peak" in lines[1]
