"""The synthetic fixtures in tests/data/measurements import to one and the same receptance.

Tolerances follow the digits each file carries: 17 (CSV, JSON: exact up to one scaling,
1e-14), 17 through degrees → radians (1e-13), UFF ASCII 12 (1e-11), CutPro 7 (1e-6 of the
peak), tap 11-digit signals through an FFT ratio (1e-6 below the force spectrum's first zero
at 1.5 kHz: at 4 Hz the accelerance is ω²-small, so the signals' rounding, ~5e-11 of their
peak, weighs 2e-7 there).
"""

from __future__ import annotations

import importlib.util

import numpy as np
import pytest

from rcsa.measured.importers import read_contract_json, read_csv, read_cutpro, read_tap, read_uff
from rcsa.measured.store import MeasurementMeta, MeasurementStore
from tests.helpers import REPO

HERE = REPO / "tests" / "data" / "measurements"
_spec = importlib.util.spec_from_file_location("generate_fixtures", HERE / "generate.py")
gen = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(gen)
META = MeasurementMeta("demo-hsk63", "x", "spindle_nose", "direct_frf")


def test_csv_tsv_frf_and_json_agree():
    h = gen.receptance(gen.F)
    csv = read_csv(HERE / "direct_frf_um_per_n.csv", META, units="um/N")
    tsv = read_csv(
        HERE / "direct_frf_mag_phase_deg.tsv",
        META,
        units="um/N",
        columns="f,mag,phase",
        phase_unit="deg",
    )
    frf = read_cutpro(HERE / "direct_frf.frf", META)
    pr = read_contract_json(HERE / "point_receptance.json")
    np.testing.assert_allclose(csv.frfs["h"], h, rtol=1e-14, atol=0)
    np.testing.assert_allclose(tsv.frfs["h"], h, rtol=1e-13, atol=0)
    np.testing.assert_allclose(frf.frfs["h"], h, rtol=1e-6, atol=1e-6 * np.abs(h).max())
    assert pr.frfs["h"].tobytes() == h.tobytes()
    assert pr.receptance().values.shape == (gen.F.size, 2, 2)


def test_artifact_uff_and_tap():
    meta = MeasurementMeta(
        "demo-hsk63",
        "x",
        "spindle_nose",
        "artifact_frfs",
        points_m=(0.0, 0.03),
        artifact={"diameter_m": 0.02, "stickout_m": 0.08, "material": "steel"},
    )
    m = read_uff(
        HERE / "artifact_frfs_accelerance.uff",
        meta,
        roles={"h11": (1, 1), "h21": (2, 1), "h22": (2, 2)},
    )
    for name, scale in (("h11", 1.0), ("h21", 0.6), ("h22", 0.45)):
        np.testing.assert_allclose(m.frfs[name], gen.receptance(gen.F, scale), rtol=1e-11, atol=0)
    assert set(m.coherence) == {"h11"}
    tap = read_tap(
        HERE / "tap_synthetic.txt",
        META,
        force_unit="N",
        response_unit="m/s^2",
        max_frequency_hz=1200,
    )
    np.testing.assert_allclose(tap.frfs["h"], gen.receptance(tap.frequency_hz), rtol=1e-6, atol=0)


@pytest.mark.parametrize(
    "name", ["direct_frf_um_per_n.csv", "point_receptance.json", "artifact_frfs_accelerance.uff"]
)
def test_fixtures_store(tmp_path, name):
    store = MeasurementStore(tmp_path / "s")
    if name.endswith(".json"):
        m = read_contract_json(HERE / name)
    elif name.endswith(".uff"):
        m = read_uff(
            HERE / name,
            MeasurementMeta(
                "d",
                "x",  # the file's FRFs are along +X (was "y": the importer ignored the file)
                "spindle_nose",
                "artifact_frfs",
                points_m=(0.0, 0.03),
                artifact={"diameter_m": 0.02, "stickout_m": 0.08},
            ),
            roles={"h11": (1, 1), "h21": (2, 1), "h22": (2, 2)},
        )
    else:
        m = read_csv(HERE / name, META, units="um/N")
    got = store.get(store.put(m))
    assert m.frfs and set(got.frfs) == set(m.frfs)  # the loop below cannot pass by having nothing to compare
    assert got.frequency_hz.tobytes() == m.frequency_hz.tobytes()
    for k, v in m.frfs.items():
        assert got.frfs[k].tobytes() == v.tobytes()
