"""CSV/TSV tables as other tools write them: columns and units from the header, refusals that
name what was seen, truncated files, decimal commas. Each file is read right (against the
known receptance) or refused with a reason; none is silently wrong.

Tolerances (relative): 17-digit values through one unit scaling, 1e-14; through degrees or a
kHz axis, 1e-13; through dB (20·log10 then 10^(x/20): ~|x|·eps·ln10/20 plus the log), 1e-13;
numpy.savetxt's default %.18e is exact; 7-digit values (decimal-comma export), 1e-6.
"""

from __future__ import annotations

import csv
import io

import numpy as np
import pytest

from rcsa.errors import InputError
from rcsa.measured.importers import read_csv

from ._synth import ARTIFACT_META, META, two_mode_receptance

F = np.arange(50.0, 2050.0, 10.0)
H = two_mode_receptance(F)  # m/N, peak 1.2e-6 m/N at 700 Hz
W = 2 * np.pi * F
G = 9.80665


def _text(header, columns, sep=",", fmt="{:.17g}", newline="\n", end=True) -> str:
    rows = [sep.join(fmt.format(float(v)) for v in row) for row in zip(*columns, strict=True)]
    head = [header] if isinstance(header, str) else list(header)
    return newline.join(head + rows) + (newline if end else "")


def _read(tmp_path, text, name="t.csv", **kw):
    path = tmp_path / name
    path.write_bytes(text.encode("utf-8") if isinstance(text, str) else text)
    return read_csv(path, META, **kw)


def _refused(tmp_path, text, field, *needles, **kw):
    with pytest.raises(InputError) as err:
        _read(tmp_path, text, **kw)
    assert err.value.field == field, str(err.value)
    for needle in needles:
        assert needle in err.value.rule, (needle, err.value.rule)
    return err.value


# --- the defect: a magnitude/phase table read as f,re,im --------------------------------


def test_magnitude_phase_header_is_read_as_magnitude_and_phase(tmp_path):
    text = _text(
        "Frequency (Hz),Magnitude (um/N),Phase (deg)", (F, np.abs(H) * 1e6, np.degrees(np.angle(H)))
    )
    m = _read(tmp_path, text)  # no columns, no units: the header says both
    np.testing.assert_allclose(m.frfs["h"], H, rtol=1e-13, atol=0)
    assert m.provenance.original_units == "um/N"
    assert m.provenance.conversions[0].startswith("columns from the header (line 1)")
    # the old silent default (f,re,im) is now a conflict with the header, not a pick
    _refused(
        tmp_path,
        text,
        "columns",
        "column 2 is declared 'h.re'",
        "'Magnitude (um/N)'",
        columns="f,re,im",
        units="um/N",
    )


# --- header styles from other tools -----------------------------------------------------

STYLES = {
    "comma, (unit), kHz": (
        "Freq (kHz),Real (m/N),Imag (m/N)", ",", lambda: (F / 1e3, H.real, H.imag), 1e-13),
    "semicolon, [unit], um/N": (
        "Frequency [Hz];Re [µm/N];Im [µm/N]", ";", lambda: (F, H.real * 1e6, H.imag * 1e6), 1e-14),
    "tab, dB re 1 m/N, rad": (
        "Frequency (Hz)\tMagnitude (dB re 1 m/N)\tPhase (rad)", "\t",
        lambda: (F, 20 * np.log10(np.abs(H)), np.angle(H)), 1e-13),
    "comma, |H| dB re 1 um/N, deg": (
        "f [Hz],|H| [dB re 1 µm/N],phase [°]", ",",
        lambda: (F, 20 * np.log10(np.abs(H) / 1e-6), np.degrees(np.angle(H))), 1e-13),
    "accelerance (m/s²)/N": (
        "Frequency (Hz),Real ((m/s²)/N),Imag ((m/s²)/N)", ",",
        lambda: (F, (-(W**2) * H).real, (-(W**2) * H).imag), 1e-14),
    "mobility, trailing unit words": (
        "Frequency Hz,Mobility real (m/s)/N,Mobility imag (m/s)/N", ",",
        lambda: (F, (1j * W * H).real, (1j * W * H).imag), 1e-14),
    "accelerance g/N": (
        "freq;Re(H) [g/N];Im(H) [g/N]", ";", lambda: (F, (-(W**2) * H / G).real, (-(W**2) * H / G).imag), 1e-14),
    "inch units, Re(H11)": (
        "Frequency (Hz),Re(H11) [in/lbf],Im(H11) [in/lbf]", ",",
        lambda: (F, H.real / 0.0254 * 4.4482216152605, H.imag / 0.0254 * 4.4482216152605), 1e-14),
    "whitespace, two-space header": (
        "Frequency (Hz)  Real (m/N)  Imag (m/N)", "  ", lambda: (F, H.real, H.imag), 0.0),
    "coherence and a pandas index": (
        ",frequency_hz,H real [m/N],H imag [m/N],Coherence", ",",
        lambda: (np.arange(F.size), F, H.real, H.imag, np.linspace(0.5, 1, F.size)), 0.0),
}  # fmt: skip


@pytest.mark.parametrize("style", list(STYLES))
def test_header_styles_are_read_right(tmp_path, style):
    header, sep, cols, rtol = STYLES[style]
    m = _read(tmp_path, _text(header, cols(), sep=sep))
    np.testing.assert_allclose(m.frequency_hz, F, rtol=1e-15, atol=0)
    np.testing.assert_allclose(m.frfs["h"], H, rtol=rtol, atol=0)
    if "Coherence" in header:
        assert m.coherence["h"].tobytes() == np.linspace(0.5, 1, F.size).tobytes()


def test_names_line_over_units_line_with_decimal_commas(tmp_path):
    """A German-locale spreadsheet export: semicolons, decimal commas, units on their own line."""
    rows = [
        f"{f:.0f};{z.real * 1e6:.6E};{z.imag * 1e6:.6E}".replace(".", ",")
        for f, z in zip(F, H, strict=True)
    ]
    text = "Frequenz;Realteil;Imaginärteil\nHz;µm/N;µm/N\n" + "\r\n".join(rows) + "\r\n"
    text = text.replace("Realteil", "Real").replace("Imaginärteil", "Imag")
    m = _read(tmp_path, text.encode("latin-1"), name="de.csv")
    np.testing.assert_allclose(m.frfs["h"], H, rtol=1e-6, atol=0)  # 7 significant digits
    assert "decimal commas read as decimal points" in m.provenance.conversions


@pytest.mark.parametrize("sep", ["\t", " "])
def test_decimal_commas_with_tab_or_space(tmp_path, sep):
    text = _text(sep.join(["f[Hz]", "re[m/N]", "im[m/N]"]), (F, H.real, H.imag), sep=sep).replace(
        ".", ","
    )
    np.testing.assert_allclose(_read(tmp_path, text).frfs["h"], H, rtol=1e-15, atol=0)


def test_numpy_savetxt_commented_header(tmp_path):
    path = tmp_path / "np.csv"
    np.savetxt(
        path, np.column_stack([F, H.real, H.imag]), delimiter=",", header="f [Hz],re [m/N],im [m/N]"
    )
    m = read_csv(path, META)
    assert m.frfs["h"].tobytes() == H.tobytes()  # %.18e round-trips


def test_python_csv_writer_crlf_with_quoted_header(tmp_path):
    buf = io.StringIO()
    w = csv.writer(buf)
    w.writerow(["Frequency, Hz", "Real (um/N)", "Imag (um/N)"])  # a comma inside the name: quoted
    w.writerows(
        [
            [repr(float(f)), repr(float(z.real * 1e6)), repr(float(z.imag * 1e6))]
            for f, z in zip(F, H, strict=True)
        ]
    )
    # a quoted comma splits into 4 header cells for 3 columns: refused, never shifted
    e = _refused(tmp_path, buf.getvalue(), "columns", "does not split into 3", "columns='f,re,im'")
    assert "Frequency, Hz" in e.rule
    buf2 = buf.getvalue().replace('"Frequency, Hz"', "Frequency (Hz)")
    np.testing.assert_allclose(_read(tmp_path, buf2).frfs["h"], H, rtol=1e-14, atol=0)


def test_quoted_numbers_and_trailing_delimiters(tmp_path):
    buf = io.StringIO()
    w = csv.writer(buf, quoting=csv.QUOTE_ALL, lineterminator="\n")
    w.writerow(["Frequency (Hz)", "Real (m/N)", "Imag (m/N)", ""])
    w.writerows(
        [
            [repr(float(f)), repr(float(z.real)), repr(float(z.imag)), ""]
            for f, z in zip(F, H, strict=True)
        ]
    )
    assert _read(tmp_path, buf.getvalue().replace(',""', ",")).frfs["h"].tobytes() == H.tobytes()


def test_re_im_and_magnitude_phase_together_must_agree(tmp_path):
    header = "Frequency (Hz),Real (m/N),Imag (m/N),Magnitude (m/N),Phase (deg)"
    cols = (F, H.real, H.imag, np.abs(H), np.degrees(np.angle(H)))
    m = _read(tmp_path, _text(header, cols))
    assert m.frfs["h"].tobytes() == H.tobytes()  # re/im read, the polar columns checked
    swapped = (F, H.imag, H.real, np.abs(H), np.degrees(np.angle(H)))  # mislabelled columns
    _refused(tmp_path, _text(header, swapped), "columns", "disagree")


def test_artifact_frfs_named_in_the_header(tmp_path):
    header = "Frequency (Hz),Re(H11) [m/N],Im(H11) [m/N],Re(H21) [m/N],Im(H21) [m/N],Re(H22) [m/N],Im(H22) [m/N]"
    cols = (F, H.real, H.imag, 0.5 * H.real, 0.5 * H.imag, 0.8 * H.real, 0.8 * H.imag)
    m = read_csv_text(tmp_path, _text(header, cols), ARTIFACT_META)
    assert m.frfs["h21"].tobytes() == (0.5 * H).tobytes()
    unnamed = "Frequency (Hz),Real (m/N),Imag (m/N),Real (m/N),Imag (m/N),Real (m/N),Imag (m/N)"
    with pytest.raises(InputError, match="does not name the FRF"):
        read_csv_text(tmp_path, _text(unnamed, cols), ARTIFACT_META)


def read_csv_text(tmp_path, text, meta, **kw):
    (tmp_path / "a.csv").write_text(text)
    return read_csv(tmp_path / "a.csv", meta, **kw)


def test_snake_case_unit_names_must_be_confirmed(tmp_path):
    text = _text("frequency_hz,real_um_n,imag_um_n", (F, H.real * 1e6, H.imag * 1e6))
    _refused(tmp_path, text, "units", "suggests um/n", "units='um/n'")
    np.testing.assert_allclose(_read(tmp_path, text, units="um/N").frfs["h"], H, rtol=1e-14, atol=0)
    _refused(tmp_path, text, "units", "'m/N' was declared", "real_um_n", units="m/N")


# --- refusals ----------------------------------------------------------------------------


def test_no_header_is_refused_with_the_columns_seen(tmp_path):
    e = _refused(
        tmp_path,
        _text([], (F, H.real, H.imag)),
        "columns",
        "no header line",
        "3 comma-delimited columns",
        "'2040'",
        "--columns f,re,im",
    )
    assert "form field columns" in e.rule
    m = _read(tmp_path, _text([], (F, H.real, H.imag)), columns="f,re,im", units="m/N")
    assert m.frfs["h"].tobytes() == H.tobytes()


@pytest.mark.parametrize(
    ("header", "needle"),
    [
        ("Frequency (Hz),Channel 2,Channel 3", "'channel', '2' is not a word"),
        ("Frequency (Hz),X,Y", "column 2 'X'"),
        ("Frequency (Hz),Real (Hz),Imag (m/N)", "a re column cannot be in 'Hz'"),
        ("Frequency (Hz),Receptance real (m/s^2)/N,Imag (m/N)", "says receptance but its unit"),
        ("Frequency (Hz),Frequency (kHz),Real (m/N)", "'f' appears twice"),
        ("Frequency (Hz),Real (m/N),Phase (deg)", "'h' needs either re and im"),
    ],
)
def test_headers_that_are_not_understood_are_refused(tmp_path, header, needle):
    _refused(tmp_path, _text(header, (F, H.real, H.imag)), "columns", needle)


def test_db_without_reference_is_refused_unless_declared(tmp_path):
    text = _text(
        "Frequency (Hz),Magnitude (dB),Phase (deg)",
        (F, 20 * np.log10(np.abs(H)), np.degrees(np.angle(H))),
    )
    _refused(tmp_path, text, "units", "needs its reference")
    _refused(
        tmp_path, text, "units", "needs its reference", units="m/N"
    )  # m/N is not a dB reference
    _refused(tmp_path, text, "units", "has no reference", units="dB")
    m = _read(tmp_path, text, units="dB re 1 m/N")
    np.testing.assert_allclose(m.frfs["h"], H, rtol=1e-13, atol=0)
    m6 = _read(tmp_path, text.replace("\n", "\n", 1), units="dB re 1e-6 m/N")  # 0 dB = 1 um/N
    np.testing.assert_allclose(m6.frfs["h"], H * 1e-6, rtol=1e-13, atol=0)


def test_declared_and_header_units_must_agree(tmp_path):
    text = _text(
        "Freq (kHz),Mag (um/N),Phase (deg)", (F / 1e3, np.abs(H) * 1e6, np.degrees(np.angle(H)))
    )
    _refused(tmp_path, text, "units", "'m/N' was declared", "'Mag (um/N)'", units="m/N")
    _refused(
        tmp_path, text, "frequency_unit", "'Hz' was declared", "'Freq (kHz)'", frequency_unit="Hz"
    )
    _refused(tmp_path, text, "phase_unit", "'rad' was declared", "'Phase (deg)'", phase_unit="rad")
    m = _read(
        tmp_path, text, units="µm/N", frequency_unit="kHz", phase_unit="deg", columns="f,mag,phase"
    )
    np.testing.assert_allclose(m.frfs["h"], H, rtol=1e-13, atol=0)
    db = _text(
        "f (Hz),Mag (dB re 1 um/N),Phase (deg)",
        (F, 20 * np.log10(np.abs(H) / 1e-6), np.degrees(np.angle(H))),
    )
    _refused(
        tmp_path, db, "units", "'dB re 1 m/N' was declared but the header says", units="dB re 1 m/N"
    )


def test_quantity_words_must_agree_with_the_declared_unit(tmp_path):
    a = -(W**2) * H
    text = _text("Frequency (Hz),Accelerance real,Accelerance imag", (F, a.real, a.imag))
    _refused(
        tmp_path, text, "units", "'Accelerance real' (accelerance) but the unit is m/N", units="m/N"
    )
    np.testing.assert_allclose(
        _read(tmp_path, text, units="m/s^2/N").frfs["h"], H, rtol=1e-14, atol=0
    )


def test_phase_in_degrees_declared_as_radians_is_refused(tmp_path):
    text = _text([], (F, np.abs(H), np.degrees(np.angle(H))))
    _refused(
        tmp_path,
        text,
        "phase_unit",
        "looks like degrees",
        columns="f,mag,phase",
        units="m/N",
        phase_unit="rad",
    )


def test_header_names_of_the_wrong_direction_or_several_frfs(tmp_path):
    yy = _text("f (Hz),Re Hyy (m/N),Im Hyy (m/N)", (F, H.real, H.imag))
    _refused(tmp_path, yy, "direction", "HYY (direction y) but direction x was given")
    xx = _text("f (Hz),Re Hxx (m/N),Im Hxx (m/N)", (F, H.real, H.imag))
    assert _read(tmp_path, xx).frfs["h"].tobytes() == H.tobytes()
    two = _text(
        "f (Hz),Re H11 (m/N),Im H11 (m/N),Re H21 (m/N),Im H21 (m/N)",
        (F, H.real, H.imag, H.real, H.imag),
    )
    _refused(tmp_path, two, "columns", "several FRFs (h11, h21)")
    m = _read(
        tmp_path, two, columns="f,re,im,_,_"
    )  # declared: the first FRF, units from the header
    assert m.frfs["h"].tobytes() == H.tobytes()


def test_mixed_decimal_separators_are_refused(tmp_path):
    rows = [
        f"{f:.1f};{z.real:.6e};{z.imag:.6e}".replace(".", ",", 1) for f, z in zip(F, H, strict=True)
    ]
    _refused(
        tmp_path,
        "f [Hz];re [m/N];im [m/N]\n" + "\n".join(rows) + "\n",
        "file",
        "decimal commas and with decimal points",
    )


# --- truncation --------------------------------------------------------------------------


def _savetxt(fmt="%.18e") -> str:
    buf = io.StringIO()
    np.savetxt(buf, np.column_stack([F, H.real * 1e6, H.imag * 1e6]), delimiter=",", fmt=fmt,
               header="Frequency (Hz),Real (um/N),Imag (um/N)", comments="")  # fmt: skip
    return buf.getvalue()


@pytest.mark.parametrize(
    ("fmt", "cut", "field", "needle"),
    [
        ("%.18e", 30, "columns", "has 2 of 3 values and no newline"),  # mid-row
        ("%.18e", 1, "file", "cut mid-number"),  # '...e-0': the exponent lost a digit
        ("%.18e", 3, "file", "the file ends there without a newline"),  # '...e': not a number
        ("%.18e", 4, "file", "cut mid-number"),  # '...8947': the exponent is gone
        ("%.6e", 9, "file", "cut mid-number"),  # '-3.5': decimals lost
        ("%.17g", 5, "file", "cut mid-number"),  # fewer significant digits than any other row
        ("%.8g", 3, "file", "cut mid-number"),
        ("%.8g", 10, "file", "cut mid-number"),  # '-0': would read 0 instead of -0.035
    ],
)
def test_truncated_tables_are_refused(tmp_path, fmt, cut, field, needle):
    whole = _savetxt(fmt)
    np.testing.assert_allclose(_read(tmp_path, whole).frfs["h"], H, rtol=1e-6, atol=0)
    e = _refused(tmp_path, whole.rstrip("\n")[:-cut], field, needle)
    assert "line 201" in e.rule and "truncated" in e.rule


def test_a_complete_file_without_final_newline_is_read(tmp_path):
    for fmt in ("%.6e", "%.17g", "%.8g"):
        text = _savetxt(fmt).rstrip("\n")
        np.testing.assert_allclose(_read(tmp_path, text).frfs["h"], H, rtol=1e-6, atol=0)


def test_absurd_and_non_finite_values_in_a_table_are_refused(tmp_path):
    re_ = H.real.copy()
    re_[10] = 1.7e308
    text = _text("f (Hz),re (m/N),im (m/N)", (F, re_, H.imag))
    _refused(tmp_path, text, "h", "row 11 (line 12), column 2", "out of range")  # the number policy (1e30)
    re_[10] = 1.7e3
    plausible = _text("f (Hz),re (m/N),im (m/N)", (F, re_, H.imag))
    _refused(tmp_path, plausible, "h", "row 11 (line 12) at 150 Hz", "above 1 m/N")  # the FRF's plausibility bound
    big = f"{1.7e308:.17g}"
    for bad in ("inf", "nan", "-Infinity"):
        _refused(
            tmp_path,
            text.replace(big, bad),
            "h",
            "row 11 (line 12), column 2",
            "not a finite number",
        )
    zero = H.copy()
    zero[10] = 0.0  # an empty line of an analyser export
    _refused(
        tmp_path,
        _text("f (Hz),re (m/N),im (m/N)", (F, zero.real, zero.imag)),
        "h",
        "below 1e-15 m/N",
    )
    _refused(tmp_path, plausible.replace("\n2040,", "\n1e300,"), "frequency_hz", "line 201", "out of range")
    _refused(tmp_path, plausible.replace("\n2040,", "\n2e6,"), "frequency_hz", "above 1e+06 Hz")


def test_truncated_cutpro_and_tap_files_are_refused(tmp_path):
    from rcsa.measured.importers import read_cutpro, read_tap

    frf = "".join(f"{a:.6e}\t{b.real:.6e}\t{b.imag:.6e}\n" for a, b in zip(F, H, strict=True))
    (tmp_path / "x.frf").write_text(frf.rstrip("\n")[:-6])  # '-3.5048' of '-3.504865e-08'
    with pytest.raises(InputError, match="cut mid-number") as err:
        read_cutpro(tmp_path / "x.frf", META)
    assert err.value.field == "file"
    (tmp_path / "y.frf").write_text(frf.rstrip("\n"))  # whole, only the final newline missing
    np.testing.assert_allclose(read_cutpro(tmp_path / "y.frf", META).frfs["h"], H, rtol=1e-6)
    t = np.arange(64) / 1024.0
    tap = "".join(f"{a:.6e}\t{np.exp(-a):.6e}\t{np.sin(a):.6e}\n" for a in t).rstrip("\n")
    (tmp_path / "tap.txt").write_text(tap[:-14])  # the last row lost its response value
    with pytest.raises(InputError, match="cut mid-row") as err:
        read_tap(tmp_path / "tap.txt", META, force_unit="N", response_unit="m/s^2")
    assert err.value.field == "columns"
    (tmp_path / "tap.txt").write_text(tap[:-1])  # "...e-0": the exponent lost a digit
    with pytest.raises(InputError, match="cut mid-number") as err:
        read_tap(tmp_path / "tap.txt", META, force_unit="N", response_unit="m/s^2")
