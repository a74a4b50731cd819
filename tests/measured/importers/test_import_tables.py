"""CSV/TSV tables and CutPro .frf files: declared columns and units, tolerated headers,
refusals that name the field.

Tolerances: values written with 17 significant digits parse exactly; each unit scaling or
quantity conversion adds at most a couple of roundings, so 1e-14 relative is generous.
Magnitude/phase adds cos/sin of a rounded angle (≈ 1e-16 rad), also within 1e-14.
"""

from __future__ import annotations

import numpy as np
import pytest

from rcsa.errors import InputError
from rcsa.measured.importers import read_csv, read_cutpro
from rcsa.measured.importers.csv_table import parse_columns
from rcsa.measured.importers.units import FORCE_N, LENGTH_M, parse_frf_unit

from ._synth import ARTIFACT_META, META, two_mode_receptance

F = np.arange(50.0, 2050.0, 10.0)
H = two_mode_receptance(F)
RTOL = 1e-14


def _table(rows, sep=",") -> str:
    return "".join(sep.join(f"{float(x):.17g}" for x in row) + "\n" for row in rows)


def test_csv_real_imag_with_header_and_comments(tmp_path):
    text = "% exported by an analyser\nFrequency [Hz], Real [m/N], Imag [m/N]\n" + _table(
        zip(F, H.real, H.imag, strict=True)
    )
    text = text.replace("\n2050", "\n# a comment in the data\n2050")
    path = tmp_path / "h.csv"
    path.write_text(text)
    m = read_csv(path, META, units="m/N")
    assert m.frfs["h"].tobytes() == H.tobytes()  # no scaling: bit-exact
    assert m.provenance.source_format == "csv" and len(m.provenance.source_sha256) == 64


@pytest.mark.parametrize("sep", ["\t", ";", " "])
def test_tsv_semicolon_and_space_delimiters(tmp_path, sep):
    (tmp_path / "h.txt").write_text(_table(zip(F, H.real * 1e3, H.imag * 1e3, strict=True), sep))
    m = read_csv(tmp_path / "h.txt", META, units="mm/N", columns="f,re,im")
    np.testing.assert_allclose(m.frfs["h"], H, rtol=RTOL, atol=0)


def test_magnitude_phase_in_degrees_and_khz(tmp_path):
    rows = zip(F / 1e3, np.abs(H) * 1e6, np.degrees(np.angle(H)), strict=True)
    (tmp_path / "mp.csv").write_text(_table(rows))
    m = read_csv(
        tmp_path / "mp.csv",
        META,
        units="um/N",
        columns="f,mag,phase",
        phase_unit="deg",
        frequency_unit="kHz",
    )
    np.testing.assert_allclose(m.frequency_hz, F, rtol=RTOL, atol=0)
    np.testing.assert_allclose(m.frfs["h"], H, rtol=RTOL, atol=0)


@pytest.mark.parametrize(
    ("unit", "to_file"),
    [
        ("in/lbf", lambda f, h: h * FORCE_N["lbf"] / LENGTH_M["in"]),
        ("m/s/N", lambda f, h: 1j * 2 * np.pi * f * h),
        ("(m/s²)/N", lambda f, h: -((2 * np.pi * f) ** 2) * h),
        ("g/lbf", lambda f, h: -((2 * np.pi * f) ** 2) * h / 9.80665 * FORCE_N["lbf"]),
    ],
)
def test_declared_units_and_quantities(tmp_path, unit, to_file):
    v = to_file(F, H)
    (tmp_path / "u.csv").write_text(_table(zip(F, v.real, v.imag, strict=True)))
    m = read_csv(tmp_path / "u.csv", META, units=unit, columns="f,re,im")
    np.testing.assert_allclose(m.frfs["h"], H, rtol=RTOL, atol=0)
    assert m.provenance.original_quantity == parse_frf_unit(unit).quantity


def test_artifact_columns_with_coherence(tmp_path):
    coh = np.linspace(0.2, 1.0, F.size)
    rows = zip(
        F,
        H.real,
        H.imag,
        coh,
        (0.5 * H).real,
        (0.5 * H).imag,
        (0.8 * H).real,
        (0.8 * H).imag,
        F,
        strict=True,
    )
    (tmp_path / "a.csv").write_text(_table(rows))
    cols = "f,h11.re,h11.im,h11.coh,h21.re,h21.im,h22.re,h22.im,_"
    m = read_csv(tmp_path / "a.csv", ARTIFACT_META, units="m/N", columns=cols)
    assert set(m.frfs) == {"h11", "h21", "h22"}
    assert m.coherence["h11"].tobytes() == coh.tobytes()
    assert m.meta.points_m == (0.0, 0.025)


def _bad(tmp_path, text, **kw):
    (tmp_path / "bad.csv").write_text(text)
    with pytest.raises(InputError) as err:
        read_csv(tmp_path / "bad.csv", META, **{"units": "m/N", "columns": "f,re,im", **kw})
    return err.value


def test_csv_refusals_name_the_field(tmp_path):
    good = _table([[10, 1e-7, -1e-7], [20, 2e-7, -2e-7]])
    assert _bad(tmp_path, good, units=None).field == "units"
    assert _bad(tmp_path, good, units="furlong/N").field == "units"
    e = _bad(tmp_path, good + "30,1e-7\n")
    assert e.field == "columns" and "line 3 has 2 values" in e.rule
    e = _bad(tmp_path, good + "30,nan,1e-7\n")
    assert e.field == "h" and "line 3" in e.rule
    e = _bad(tmp_path, good + "15,1e-7,1e-7\n")
    assert e.field == "frequency_hz" and "strictly increasing" in e.rule
    e = _bad(tmp_path, "0,1,0\n" + good)
    assert e.field == "frequency_hz" and "0 Hz" in e.rule and "drop_nonpositive" in e.rule
    assert _bad(tmp_path, good, columns="f,mag,phase").field == "phase_unit"
    assert _bad(tmp_path, good, columns="f,re,re").field == "columns"
    assert _bad(tmp_path, good, columns="f,re,imaginary").field == "columns"
    assert _bad(tmp_path, good + "the end\n").field == "file"
    assert _bad(tmp_path, "only words\n").field == "file"


def test_drop_nonpositive_is_explicit_and_recorded(tmp_path):
    (tmp_path / "z.csv").write_text(_table([[0, 0.77, 0], [10, 1e-7, -1e-7], [20, 2e-7, -2e-7]]))
    m = read_csv(tmp_path / "z.csv", META, units="m/N", columns="f,re,im", drop_nonpositive=True)
    np.testing.assert_array_equal(m.frequency_hz, [10.0, 20.0])
    assert "dropped 1 row(s) at f <= 0 Hz" in m.provenance.conversions


def test_point_receptance_table_must_be_si(tmp_path):
    meta = ARTIFACT_META.__class__("s", "x", "spindle_nose", "point_receptance")
    rows = zip(F, H.real, H.imag, H.real, H.imag, H.real, H.imag, H.real, H.imag, strict=True)
    (tmp_path / "p.csv").write_text(_table(rows))
    cols = "f,h.re,h.im,l.re,l.im,n.re,n.im,p.re,p.im"
    assert read_csv(
        tmp_path / "p.csv", meta, units="m/N", columns=cols
    ).receptance().values.shape == (F.size, 2, 2)
    with pytest.raises(InputError) as err:
        read_csv(tmp_path / "p.csv", meta, units="um/N", columns=cols)
    assert err.value.field == "units"


def test_parse_columns_needs_names_beyond_direct_frf():
    assert parse_columns("f,re,im", "direct_frf") == [("", "f"), ("h", "re"), ("h", "im")]
    with pytest.raises(InputError) as err:
        parse_columns("f,re,im", "artifact_frfs")
    assert err.value.field == "columns"


CUTPRO_FIRST = "{f:.6e}\t{re:.6e}\t{im:.6e}\tFreq Hz Real m/N Imag Real\n"


def _cutpro(f, h, first=CUTPRO_FIRST) -> str:
    lines = [first.format(f=f[0], re=h[0].real, im=h[0].imag)]
    lines += [f"{a:.6e}\t{b.real:.6e}\t{b.imag:.6e}\n" for a, b in zip(f[1:], h[1:], strict=True)]
    return "".join(lines)


def test_cutpro_file_as_written_by_matlab2cutpro(tmp_path):
    (tmp_path / "x.frf").write_text(_cutpro(F, H))
    m = read_cutpro(tmp_path / "x.frf", META)
    # the writer prints 7 significant digits: compare at that precision (5e-7 relative)
    np.testing.assert_allclose(m.frfs["h"], H, rtol=1e-6, atol=1e-6 * np.abs(H).max())
    assert m.provenance.original_units == "m/N (CutPro convention, assumed)"


def test_cutpro_units_must_be_declared_when_not_m_per_n(tmp_path):
    (tmp_path / "mm.frf").write_text(
        _cutpro(F, H * 1e3, first="{f:.6e}\t{re:.6e}\t{im:.6e}\tFreq Hz Real mm/N\n")
    )
    with pytest.raises(InputError) as err:
        read_cutpro(tmp_path / "mm.frf", META)
    assert err.value.field == "units"
    m = read_cutpro(tmp_path / "mm.frf", META, units="mm/N")
    np.testing.assert_allclose(m.frfs["h"], H, rtol=1e-6, atol=1e-6 * np.abs(H).max())
    (tmp_path / "m.frf").write_text(_cutpro(F, H))
    with pytest.raises(InputError, match="differs from mm/N"):
        read_cutpro(tmp_path / "m.frf", META, units="mm/N")  # the file itself says m/N
    (tmp_path / "bad.frf").write_text(_cutpro(F, H) + "3000\t1e-7\n")
    with pytest.raises(InputError) as err:
        read_cutpro(tmp_path / "bad.frf", META)
    assert err.value.field == "columns"
