"""File uploads the importers now read from the file itself: CSV columns from the header, the
UFF response direction, scalar UFF FRFs (form field scalar_direction), tap stamps of 7 digits;
and the refusals that say what was wrong (422, nothing stored)."""

from __future__ import annotations

import numpy as np

from rcsa.measured.store import MeasurementStore
from tests.measured.importers._synth import frf58, two_mode_receptance, write_uff

from .conftest import WRITE, assert_problem

F = np.arange(50.0, 2050.0, 10.0)
H = two_mode_receptance(F)
META = {"spindle_id": "mc1", "plane": "spindle_nose"}


def _upload(client, name, content, **fields):
    return client.post("/v1/measurements", files={"file": (name, content)}, data=fields, headers=WRITE)


def test_csv_columns_from_the_header(client):
    rows = "".join(f"{f:.17g},{abs(z) * 1e6:.17g},{np.degrees(np.angle(z)):.17g}\n" for f, z in zip(F, H, strict=True))
    r = _upload(client, "tip.csv", ("Frequency (Hz),Magnitude (um/N),Phase (deg)\n" + rows).encode(), **META,
                direction="x")  # fmt: skip
    assert r.status_code == 201, r.text
    doc = client.get(f"/v1/measurements/{r.json()['id']}").json()
    got = np.array(doc["h"]["real"]) + 1j * np.array(doc["h"]["imag"])
    np.testing.assert_allclose(got, H, rtol=1e-13, atol=0)
    assert doc["summary"]["h"]["max_magnitude"] == float(np.abs(got).max())
    assert doc["source"]["original_units"] == "um/N"


def test_csv_without_header_or_with_a_conflict_is_422(client, store_path):
    rows = "".join(f"{f:.17g},{z.real:.17g},{z.imag:.17g}\n" for f, z in zip(F, H, strict=True))
    body = assert_problem(_upload(client, "tip.csv", rows.encode(), **META, direction="x", units="m/N"), 422, "columns")
    assert "columns='f,re,im'" in body["errors"][0]["detail"]
    headed = ("Frequency (Hz),Real (um/N),Imag (um/N)\n" + rows).encode()
    assert_problem(_upload(client, "tip.csv", headed, **META, direction="x", units="m/N"), 422, "units")
    assert_problem(_upload(client, "tip.csv", headed, **META, direction="x", columns="f,mag,phase"), 422, "columns")
    assert MeasurementStore(store_path).list() == []
    ok = _upload(client, "tip.csv", rows.encode(), **META, direction="x", units="m/N", columns="f,re,im")
    assert ok.status_code == 201, ok.text


def test_uff_direction_from_the_file_and_scalar_direction(client, tmp_path, store_path):
    y = write_uff(tmp_path / "y.uff", [frf58(F, H, binary=1, rsp=(1, 2), ref=(1, 2))], (1, 1.0, 1.0)).read_bytes()
    r = _upload(client, "y.uff", y, **META)
    assert r.status_code == 201, r.text
    assert r.json()["direction"] == "y"
    body = assert_problem(_upload(client, "y.uff", y, **META, direction="x"), 422, "direction")
    assert "along Y" in body["errors"][0]["detail"]
    s = write_uff(tmp_path / "s.uff", [frf58(F, H, binary=1, rsp=(1, 0), ref=(1, 0))], (1, 1.0, 1.0)).read_bytes()
    assert_problem(_upload(client, "s.uff", s, **META), 422, "scalar_direction")
    r = _upload(client, "s.uff", s, **META, scalar_direction="x")
    assert r.status_code == 201 and r.json()["direction"] == "x", r.text
    assert_problem(_upload(client, "tip.csv", b"f,re,im\n", **META, direction="x", scalar_direction="x"), 422,
                   "scalar_direction")  # fmt: skip
    assert len(MeasurementStore(store_path).list()) == 2


def test_tap_with_seven_digit_stamps_has_an_exact_grid(client):
    fs, n = 51200.0, 5120
    t = np.arange(n) / fs
    force = np.where(t <= 1e-3, 200.0 * np.sin(np.pi * t / 1e-3), 0.0).clip(0.0)
    f = np.fft.rfftfreq(n, 1 / fs)
    acc = np.fft.irfft(np.fft.rfft(force) * -((2 * np.pi * f) ** 2) * two_mode_receptance(f), n=n)
    text = "".join(f"{a:.6e}\t{b:.17g}\t{c:.17g}\n" for a, b, c in zip(t, force, acc, strict=True)).encode()
    fields = {**META, "direction": "x", "format": "tap", "force_unit": "N", "response_unit": "m/s^2",
              "max_frequency_hz": "5000"}  # fmt: skip
    auto = _upload(client, "tap.txt", text, **fields)
    assert auto.status_code == 201, auto.text
    assert auto.json()["frequency_max_hz"] == 5000.0 and auto.json()["n_frequencies"] == 500
    declared = _upload(client, "tap.txt", text, **fields, sample_rate_hz="51200")
    assert declared.status_code == 201
    assert_problem(_upload(client, "tap.txt", text, **fields, sample_rate_hz="50000"), 422, "sample_rate_hz")
