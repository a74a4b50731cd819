"""``rcsa store import`` with what the file says: CSV header columns and units (no --columns,
no --units, no --frequency-unit), the UFF's direction (no --direction), --scalar-direction,
--sample-rate-hz; conflicts fail with one line on stderr and nothing stored."""

from __future__ import annotations

import json

import numpy as np
from typer.testing import CliRunner

from rcsa.cli.store_cmd import store_app
from rcsa.measured.store import MeasurementStore
from tests.measured.importers._synth import frf58, two_mode_receptance, write_uff

F = np.arange(50.0, 2050.0, 10.0)
H = two_mode_receptance(F)


def _run(tmp_path, path, *args):
    base = ["import", str(path), "--store", str(tmp_path / "s"), "--spindle-id", "mc1", "--plane", "spindle_nose"]
    return CliRunner().invoke(store_app, [*base, *args])


def _fails(result, needle):
    assert result.exit_code == 1 and result.stdout == ""
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and needle in lines[0], result.stderr


def test_csv_header_says_columns_units_and_khz(tmp_path):
    path = tmp_path / "tip.csv"
    path.write_text("Freq (kHz);|H| (dB re 1 m/N);Phase (rad)\n" + "".join(
        f"{f / 1e3:.17g};{20 * np.log10(abs(z)):.17g};{np.angle(z):.17g}\n" for f, z in zip(F, H, strict=True)))  # fmt: skip
    result = _run(tmp_path, path, "--direction", "x")
    assert result.exit_code == 0, result.stderr
    out = json.loads(result.stdout)
    assert out["frequency_min_hz"] == 50.0 and out["source"]["original_units"] == "dB re 1 m/N"
    np.testing.assert_allclose(MeasurementStore(tmp_path / "s").get(out["id"]).frfs["h"], H, rtol=1e-13, atol=0)
    _fails(_run(tmp_path, path, "--direction", "x", "--frequency-unit", "Hz"), "frequency_unit: 'Hz' was declared")


def test_uff_direction_from_the_file_or_a_conflict(tmp_path):
    path = write_uff(tmp_path / "y.uff", [frf58(F, -H, binary=1, rsp=(1, -2), ref=(1, 2))], (1, 1.0, 1.0))
    result = _run(tmp_path, path)
    assert result.exit_code == 0, result.stderr
    assert json.loads(result.stdout)["direction"] == "y"
    _fails(_run(tmp_path, path, "--direction", "x"), "direction: the file's FRFs are along Y")
    assert len(MeasurementStore(tmp_path / "s").list()) == 1
    _fails(_run(tmp_path, tmp_path / "x.csv"), "--direction is required for --format csv")


def test_tap_sample_rate_flag(tmp_path):
    fs, n = 1024.0, 1024
    t = np.arange(n) / fs
    force = np.where(t <= 0.004, 100.0 * np.sin(np.pi * t / 0.004), 0.0).clip(0.0)
    acc = np.fft.irfft(np.fft.rfft(force) * -((2 * np.pi * np.fft.rfftfreq(n, 1 / fs)) ** 2) * 1e-7, n=n)
    path = tmp_path / "tap.txt"
    path.write_text("".join(f"{b:.17g}\t{c:.17g}\n" for b, c in zip(force, acc, strict=True)))
    args = ["--direction", "x", "--format", "tap", "--force-unit", "N", "--response-unit", "m/s^2",
            "--columns", "force,response", "--max-frequency-hz", "100"]  # fmt: skip
    _fails(_run(tmp_path, path, *args), "sample_rate_hz: is required when there is no time column")
    result = _run(tmp_path, path, *args, "--sample-rate-hz", "1024")
    assert result.exit_code == 0, result.stderr
    out = json.loads(result.stdout)
    assert out["n_frequencies"] == 100 and out["frequency_max_hz"] == 100.0
