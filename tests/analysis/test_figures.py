"""Tests of :mod:`rcsa.analysis.figures`: valid PNG/SVG files whose drawn data are the inputs."""

from __future__ import annotations

import os
import struct
import subprocess
import sys
import xml.etree.ElementTree as ET

import numpy as np
import pytest

import rcsa
from rcsa.analysis.figures import frf_figure, lobes_figure, save_figure
from rcsa.analysis.lobes.zoa import stability_lobes
from rcsa.errors import InputError

PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"
# Unit conversions are one multiplication: exact up to 1 ulp.
RTOL_UNITS = 1e-15


def single_mode(f, fn, zeta, k):
    r = np.asarray(f) / fn
    return 1.0 / (k * (1 - r * r + 2j * zeta * r))


@pytest.fixture(scope="module")
def frf():
    f = np.linspace(50.0, 3000.0, 1200)
    hxx = single_mode(f, 800.0, 0.03, 2e7) + single_mode(f, 2100.0, 0.02, 6e7)
    hyy = single_mode(f, 900.0, 0.025, 2.5e7)
    return f, hxx, hyy


@pytest.fixture(scope="module")
def lobes(frf):
    f, hxx, hyy = frf
    return stability_lobes(
        f, hxx, hyy, teeth=4, tangential_coefficient_n_m2=7e8, radial_ratio=0.3,
        radial_immersion=0.5, milling="down", spindle_speed_rpm=np.linspace(3000, 25000, 800),
    )  # fmt: skip


def png_size(data: bytes) -> tuple[int, int]:
    assert data[:8] == PNG_SIGNATURE
    assert data[12:16] == b"IHDR"
    return struct.unpack(">II", data[16:24])


def test_frf_figure_lines_are_the_input_in_um_per_n(frf):
    f, hxx, hyy = frf
    fig = frf_figure(f, np.stack([hxx, hyy], axis=1), labels=["xx", "yy"])
    axes = {ax.get_gid(): ax for ax in fig.axes}
    real_ax, imag_ax, mag_ax, phase_ax = (axes[g] for g in ("real", "imag", "mag", "phase"))
    for c, h in enumerate((hxx, hyy)):
        np.testing.assert_array_equal(real_ax.lines[c].get_xdata(), f)
        np.testing.assert_allclose(real_ax.lines[c].get_ydata(), h.real * 1e6, rtol=RTOL_UNITS)
        np.testing.assert_allclose(imag_ax.lines[c].get_ydata(), h.imag * 1e6, rtol=RTOL_UNITS)
        np.testing.assert_allclose(mag_ax.lines[c].get_ydata(), np.abs(h) * 1e6, rtol=RTOL_UNITS)
        np.testing.assert_allclose(
            phase_ax.lines[c].get_ydata(), np.degrees(np.angle(h)), rtol=RTOL_UNITS
        )
    assert mag_ax.get_yscale() == "log" and real_ax.get_yscale() == "linear"
    assert "µm/N" in real_ax.get_ylabel() and "deg" in phase_ax.get_ylabel()
    assert [t.get_text() for t in real_ax.get_legend().get_texts()] == ["xx", "yy"]


@pytest.mark.parametrize(("layout", "n_axes"), [("real_imag", 2), ("bode", 2), ("full", 4)])
def test_frf_layouts(frf, layout, n_axes):
    f, hxx, _ = frf
    fig = frf_figure(f, hxx, layout=layout)
    assert len(fig.axes) == n_axes
    assert fig.axes[-1].get_xlabel() == "Frequency (Hz)"


def test_lobes_figure_lines_are_the_result_in_mm(lobes):
    fig = lobes_figure(lobes, operating_point=(12000.0, 0.5 * lobes.min_depth_limit_m))
    (ax,) = fig.axes
    by_gid = {line.get_gid(): line for line in ax.lines}
    env = by_gid["envelope"]
    np.testing.assert_array_equal(env.get_xdata(), lobes.spindle_speed_rpm)
    np.testing.assert_allclose(env.get_ydata(), lobes.depth_limit_m * 1e3, rtol=RTOL_UNITS)
    drawn = [lobe for lobe in lobes.lobes if lobe.spindle_speed_rpm.size]
    assert len(drawn) >= 3
    for lobe in drawn:
        line = by_gid[f"lobe-{lobe.index}"]
        np.testing.assert_array_equal(line.get_xdata(), lobe.spindle_speed_rpm)
        np.testing.assert_allclose(line.get_ydata(), lobe.depth_limit_m * 1e3, rtol=RTOL_UNITS)
    op = by_gid["operating-point"]
    assert op.get_color() == "tab:green"  # half the absolute limit is stable at any speed
    assert "rpm" in ax.get_xlabel() and "mm" in ax.get_ylabel()
    assert "Φyy = Φxx" not in ax.get_title()


def test_lobes_figure_marks_assumed_y_and_unstable_point(frf):
    f, hxx, _ = frf
    r = stability_lobes(
        f, hxx, teeth=4, tangential_coefficient_n_m2=7e8, radial_ratio=0.3, radial_immersion=0.5,
        milling="down", spindle_speed_rpm=np.linspace(3000, 25000, 300),
    )  # fmt: skip
    fig = lobes_figure(r, operating_point=(10000.0, 100 * r.min_depth_limit_m), show_lobes=False,
                       conditions={"frf": "x_only"})
    (ax,) = fig.axes
    assert "Φyy = Φxx assumed" in ax.get_title()
    # without conditions it says what the result itself knows (x used in y), assuming nothing more
    untold = lobes_figure(r, show_lobes=False).axes[0].get_title()
    assert "Φyy = Φxx (the x FRF used in y)" in untold and "assumed" not in untold
    gids = [line.get_gid() for line in ax.lines]
    assert not any(g and g.startswith("lobe-") for g in gids)
    op = next(line for line in ax.lines if line.get_gid() == "operating-point")
    assert op.get_color() == "tab:red"


def test_png_bytes_and_file(tmp_path, lobes):
    fig = lobes_figure(lobes)
    data = save_figure(fig, "png", dpi=100)
    assert isinstance(data, bytes)
    width, height = png_size(data)
    assert (width, height) == (800, 480)  # 8 x 4.8 in at 100 dpi
    assert len(data) > 20_000  # lines, fill and text, not a blank canvas
    path = save_figure(fig, tmp_path / "lobes.png", dpi=100)
    assert path.read_bytes() == data  # deterministic output


def test_svg_bytes_and_file(tmp_path, frf):
    f, hxx, hyy = frf
    fig = frf_figure(f, np.stack([hxx, hyy], axis=1))
    data = save_figure(fig, "SVG")
    root = ET.fromstring(data)
    assert root.tag == "{http://www.w3.org/2000/svg}svg"
    assert len(root.findall(".//{http://www.w3.org/2000/svg}path")) > 20
    path = save_figure(fig, str(tmp_path / "frf.svg"))
    assert path.read_bytes() == data


def test_bad_output_and_inputs(tmp_path, frf):
    f, hxx, _ = frf
    fig = frf_figure(f, hxx)
    with pytest.raises(InputError):
        save_figure(fig, tmp_path / "frf.jpg")
    with pytest.raises(InputError):
        frf_figure(f, hxx[:-1])
    with pytest.raises(InputError):
        frf_figure(f, hxx, labels=["a", "b"])
    with pytest.raises(InputError):
        frf_figure(f, hxx, layout="nyquist")


def test_no_pyplot_and_no_global_state():
    """Importing and drawing never loads pyplot nor changes rcParams (reading
    ``rcParams['backend']`` would itself import pyplot, hence the snapshot without it)."""
    code = (
        "import sys, matplotlib, numpy as np\n"
        "snap = lambda: {k: matplotlib.rcParams[k] for k in matplotlib.rcParams if k != 'backend'}\n"
        "before = snap()\n"
        "from rcsa.analysis.figures import frf_figure, save_figure\n"
        "f = np.linspace(10, 100, 50); save_figure(frf_figure(f, 1e-7/(1-(f/50)**2+0.1j)), 'svg')\n"
        "assert 'matplotlib.pyplot' not in sys.modules, 'pyplot imported'\n"
        "assert snap() == before, 'rcParams changed'\n"
    )
    src = os.path.dirname(os.path.dirname(rcsa.__file__))  # works installed or not
    env = {
        **os.environ,
        "PYTHONPATH": os.pathsep.join(filter(None, [src, os.environ.get("PYTHONPATH")])),
    }
    subprocess.run([sys.executable, "-c", code], check=True, env=env)


CONDITIONS = {"teeth": 4, "tangential_coefficient_n_m2": 7e8, "radial_ratio": 0.3, "radial_immersion": 0.5,
              "milling": "down", "method": "zoa", "frf": "assembly"}


def test_lobes_figure_states_its_conditions_and_no_false_assumption(lobes):
    """An assembly's diagram names its cutting conditions and method, and says the predicted tool
    point is used in x and y — not that only an x FRF was given."""
    fig = lobes_figure(lobes, conditions=CONDITIONS)
    text = fig.axes[0].get_title()
    for words in ("4 teeth", "a_e/D = 0.5", "down milling", "K_t = 700 N/mm²", "K_r/K_t = 0.3",
                  "zero-order (Altintas–Budak)", "predicted tool point, in x and y"):
        assert words in text, (words, text)
    assert "assumed" not in text and "only x" not in text
    assert fig._suptitle.get_text() == "Stability lobes"


def test_lobes_figure_legend_stands_outside_the_data(lobes):
    fig = lobes_figure(lobes, conditions=CONDITIONS)
    (ax,) = fig.axes
    renderer = fig.canvas.get_renderer()
    legend = ax.get_legend().get_window_extent(renderer)
    data = ax.get_window_extent(renderer)
    assert legend.y1 <= data.y0  # wholly under the axes: no lobe is hidden behind it


def test_lobes_figure_hatches_doubtful_speeds(lobes):
    """Each reason's flagged speeds become hatched spans named once in the legend; contiguous
    runs are one span each, reaching halfway to their unflagged neighbours."""
    speed = lobes.spindle_speed_rpm
    mask = (speed > 5000.0) & (speed < 6000.0) | (speed > 20000.0)
    fig = lobes_figure(lobes, doubtful_speeds={"unresolved": mask})
    (ax,) = fig.axes
    spans = [p for p in ax.patches if p.get_gid() == "doubtful-unresolved"]
    assert len(spans) == 2
    lows = sorted(p.get_x() for p in spans)
    first = np.flatnonzero(mask)[0]
    assert lows[0] == pytest.approx(0.5 * (speed[first] + speed[first - 1]), rel=1e-12)
    labels = ax.get_legend_handles_labels()[1]
    assert sum("unresolved" in label for label in labels) == 1


def test_frf_figure_marks_and_titles_the_natural_frequencies(frf):
    f, hxx, _ = frf
    fig = frf_figure(f, hxx, title="Tool point", natural_frequencies_hz=[800.0, 2100.0, 9000.0])
    for ax in fig.axes:
        marks = [line for line in ax.lines if line.get_gid() == "natural-frequency"]
        assert [line.get_xdata()[0] for line in marks] == [800.0, 2100.0]  # 9 kHz is outside the band
    title = fig._suptitle.get_text()
    assert title.startswith("Tool point") and "800, 2100 Hz" in title
