"""Reference: Altintas' half-immersion down-milling example (zero-order stability lobes).

Source
------
Y. Altintas, *Manufacturing Automation: Metal Cutting Mechanics, Machine Tool Vibrations,
and CNC Design*, 2nd ed., Cambridge University Press, 2012, §4.4 "Chatter stability of
milling" (zero-order solution, eigenvalue equation ``a0 Λ² + a1 Λ + 1 = 0``,
``a_lim = −2π ΛR (1 + κ²)/(N Kt)``, ``ε = π − 2ψ``, ``ψ = atan κ``, ``n = 60/(N T)``,
``ωc T = ε + 2kπ``), with the Altintas & Budak, CIRP Annals 44(1):357–362 (1995) method.

Inputs, as transcribed in the public MATLAB scripts of the UBC Manufacturing Automation
Laboratory example (repository leekunhwee/Dynamics, ``Cutting/Stability/FrequencyDomain/
Milling/FRFs.m`` at commit 9a1c904 citing the book's p. 162 for the modal data, and
``LobeZOAAltintas.m`` at commit 385e185 citing p. 156 for the solution):

* x: fn = 452.77, 1448.53 Hz; ζ = 0.123718, 0.01651;
  residues 9.202966e-5 − 1.862195e-4 i, −4.181562e-5 − 3.043618e-4 i (m/N);
* y: fn = 516.17, 1407.64 Hz; ζ = 0.0243, 0.0324;
  residues −2.3929e-6 − 1.721539e-4 i, 4.055052e-5 − 3.618808e-4 i (m/N);
* FRF per mode ``(α + iβω)/(ωn² − ω² + 2iζωnω)``, ``α = 2(ζωnσ − ωd ν)``, ``β = 2σ``
  for residue ``σ + iν``; grid 1 Hz, 1–7999 Hz (the script's 0 Hz point dropped);
* Kt = 1319.4 MPa, Kr = Krc/Ktc = 788.8/1319.4 = 0.598, N = 2 teeth, D = 31.75 mm,
  a_e = D/2 (radial immersion 0.5), down-milling (φst = π/2, φex = π).

Expected values — honest status
-------------------------------
No printed table of numbers for this example was found: the book shows the lobes as a
figure. The expected numbers below were therefore computed by a literal Python
transcription of ``LobeZOAAltintas.m`` (one ``np.roots`` per frequency, kept below as
:func:`_script_transcription`) and rounded to five significant digits; the figure's axes
(0–16 000 rpm, 0–6 mm) are consistent with them. Two independent checks back them:

* the modal synthesis reproduces the script's own output file ``FRFX.frf`` (CSV sample
  ``data/altintas2012_frfx_rows.csv``) to its 13 printed digits;
* the analytic oracle of one flexible direction in slotting,
  ``b_lim = −2/(N Kr Kt Re Φxx)`` (Tlusty's ``−1/(2 K Re G)`` with the revolution-averaged
  ``K = N Kr Kt/4``), applied to this example's Φxx, is matched to 1e-9.

The script computes ``ε = 3π − 2 atan2(ΛI, ΛR)``; that equals the book's ``π − 2 atan κ``
when ``ΛI >= 0`` and is 4π larger otherwise (it renumbers lobes by two). The governing
eigenvalue here has ``ΛI > 0``, so the lobe speeds agree; the transcription keeps the
script's form and the test asserts the sign.
"""

from __future__ import annotations

import csv
import math
from pathlib import Path

import numpy as np
import pytest

from rcsa.analysis.lobes.zoa import (
    directional_factors,
    engagement_angles_rad,
    stability_lobes,
    zoa_depth_limit,
)

pytestmark = pytest.mark.reference

DATA = Path(__file__).parent / "data"
SOURCE = "Altintas (2012) §4.4 example via LobeZOAAltintas.m transcription"

MODES_X = (
    (452.77, 1448.53),
    (0.123718, 0.01651),
    (9.202966e-05 - 1.862195e-04j, -4.181562e-05 - 3.043618e-04j),
)
MODES_Y = (
    (516.17, 1407.64),
    (0.0243, 0.0324),
    (-2.3929e-06 - 1.721539e-04j, 4.055052e-05 - 3.618808e-04j),
)
KT_N_M2 = 1319.4e6
KR = 788.8 / 1319.4
TEETH = 2
IMMERSION = 0.5  # a_e = D/2 with D = 31.75 mm

# Expected (see module docstring): absolute stability limit, its chatter frequency, and
# the speeds of the bottoms of lobes k = 0..4.
EXPECTED_MIN_DEPTH_M = 1.0147e-3
EXPECTED_CHATTER_HZ = 1441.0
EXPECTED_LOBE_BOTTOM_RPM = (74198.0, 27315.0, 16739.0, 12067.0, 9433.4)
# Brief's acceptance bound for a published example: 2 %. The literal transcription on
# the same grid must agree far tighter (only rounding differs): 1e-9.
RTOL_PUBLISHED = 0.02
RTOL_TRANSCRIPTION = 1e-9


def residue_frf(frequency_hz: np.ndarray, modes) -> np.ndarray:
    """Modal sum in the script's residue form, m/N, shape (nfreq,)."""
    w = 2 * np.pi * np.asarray(frequency_hz, dtype=float)[:, None]
    fn, zeta, res = (np.asarray(m) for m in modes)
    wn = 2 * np.pi * fn
    wd = wn * np.sqrt(1 - zeta**2)
    alpha = 2 * (zeta * wn * res.real - wd * res.imag)
    beta = 2 * res.real
    return ((alpha + 1j * beta * w) / (wn**2 - w**2 + 2j * zeta * wn * w)).sum(axis=1)


@pytest.fixture(scope="module")
def frf():
    f = np.arange(1.0, 8000.0, 1.0)
    return f, residue_frf(f, MODES_X), residue_frf(f, MODES_Y)


@pytest.fixture(scope="module")
def result(frf):
    f, hxx, hyy = frf
    return stability_lobes(
        f,
        hxx,
        hyy,
        teeth=TEETH,
        tangential_coefficient_n_m2=KT_N_M2,
        radial_ratio=KR,
        radial_immersion=IMMERSION,
        milling="down",
        spindle_speed_rpm=np.linspace(2000.0, 16000.0, 2801),
        # automatic lobe count: the script's 20 lobes stop short of 2000 rpm for the
        # 1441 Hz chatter (k ≈ 60·1441/(2·2000) ≈ 21.6 is needed there)
    )


def _script_transcription(f, hxx, hyy):
    """LobeZOAAltintas.m line by line: roots per frequency, b_lim > 0, ε = 3π − 2ψ."""
    d = 31.75
    ae = d / 2
    phis = math.acos((d / 2 - ae) / (d / 2))
    phiex = math.pi
    phist = phiex - phis
    kn = KR

    def prim(p):
        return (
            math.cos(2 * p) - 2 * kn * p + kn * math.sin(2 * p),
            -math.sin(2 * p) - 2 * p + kn * math.cos(2 * p),
            -math.sin(2 * p) + 2 * p + kn * math.cos(2 * p),
            -math.cos(2 * p) - 2 * kn * p - kn * math.sin(2 * p),
        )

    axx, axy, ayx, ayy = (0.5 * (e - s) for e, s in zip(prim(phiex), prim(phist), strict=True))
    best = (math.inf, 0.0, 0.0, 0j)
    for fi, x, y in zip(f, hxx, hyy, strict=True):
        a0 = x * y * (axx * ayy - axy * ayx)
        a1 = axx * x + ayy * y
        for lam in np.roots([a0, a1, 1]):
            blim = -(2 * math.pi / TEETH / KT_N_M2) * (lam.real * (1 + (lam.imag / lam.real) ** 2))
            if 0 < blim < best[0]:
                psi = math.atan2(lam.imag, lam.real)
                best = (blim, fi, 3 * math.pi - 2 * psi, lam)
    blim, fc, eps, lam = best
    speeds = [(60 / TEETH) * 2 * math.pi * fc / (eps + 2 * k * math.pi) for k in range(5)]
    return blim, fc, speeds, lam


def _frfx_rows():
    with open(DATA / "altintas2012_frfx_rows.csv", newline="") as fh:
        rows = [r for r in csv.reader(fh) if r and not r[0].startswith("#")]
    return [tuple(float(v) for v in r) for r in rows[1:]]


@pytest.mark.parametrize("row", _frfx_rows(), ids=lambda r: f"{r[0]:g}Hz")
def test_modal_synthesis_matches_published_frf_file(row):
    f_hz, re, im = row
    got = residue_frf(np.array([f_hz]), MODES_X)[0]
    # The file prints 13 significant digits; 1e-10 relative covers that rounding.
    np.testing.assert_allclose(
        [got.real, got.imag],
        [re, im],
        rtol=1e-10,
        err_msg=f"Phi_xx at {f_hz} Hz vs FRFX.frf ({SOURCE})",
    )


def test_absolute_stability_limit(result):
    np.testing.assert_allclose(
        result.min_depth_limit_m,
        EXPECTED_MIN_DEPTH_M,
        rtol=RTOL_PUBLISHED,
        err_msg=f"minimum stable axial depth, m ({SOURCE})",
    )
    np.testing.assert_allclose(
        result.min_depth_chatter_frequency_hz,
        EXPECTED_CHATTER_HZ,
        rtol=RTOL_PUBLISHED,
        err_msg=f"chatter frequency at the minimum, Hz ({SOURCE})",
    )


@pytest.mark.parametrize("k", range(5), ids=lambda k: f"lobe{k}")
def test_lobe_bottom_speeds(result, k):
    np.testing.assert_allclose(
        result.min_depth_spindle_speed_rpm[k],
        EXPECTED_LOBE_BOTTOM_RPM[k],
        rtol=RTOL_PUBLISHED,
        err_msg=f"speed of the bottom of lobe {k}, rpm ({SOURCE})",
    )


def test_envelope_in_plotted_range(result):
    """Inside the figure's 2 000–16 000 rpm window the envelope is covered and bounded by
    the absolute limit; it touches it (within 0.1 %) at the lobe-3 and lobe-4 bottoms."""
    r = result
    assert np.all(np.isfinite(r.depth_limit_m))
    assert np.all(r.depth_limit_m >= r.min_depth_limit_m * (1 - 1e-12))
    for n in EXPECTED_LOBE_BOTTOM_RPM[3:5]:
        j = int(np.argmin(np.abs(r.spindle_speed_rpm - n)))
        # grid step 5 rpm: the envelope 2.5 rpm off a lobe bottom is within 0.1 %.
        np.testing.assert_allclose(r.depth_limit_m[j], r.min_depth_limit_m, rtol=1e-3)


def test_against_literal_script_transcription(frf, result):
    f, hxx, hyy = frf
    blim, fc, speeds, lam = _script_transcription(f, hxx, hyy)
    assert lam.imag > 0  # the script's ε branch equals the book's here (module docstring)
    np.testing.assert_allclose(result.min_depth_limit_m, blim, rtol=RTOL_TRANSCRIPTION)
    assert result.min_depth_chatter_frequency_hz == fc
    np.testing.assert_allclose(
        result.min_depth_spindle_speed_rpm[:5], speeds, rtol=RTOL_TRANSCRIPTION
    )
    # and the tabulated expectations are that transcription, rounded to 5 digits
    np.testing.assert_allclose(blim, EXPECTED_MIN_DEPTH_M, rtol=1e-4)
    np.testing.assert_allclose(speeds, EXPECTED_LOBE_BOTTOM_RPM, rtol=1e-4)


def test_one_direction_analytic_oracle_on_this_frf(frf):
    """Φyy = 0, slotting: ``b_lim(ω) = −2/(N Kr Kt Re Φxx(ω))`` exactly, on every grid point."""
    f, hxx, _ = frf
    depth, _ = zoa_depth_limit(
        hxx,
        np.zeros_like(hxx),
        teeth=TEETH,
        tangential_coefficient_n_m2=KT_N_M2,
        alpha=directional_factors(*engagement_angles_rad(1.0, "up"), KR),
    )
    b = np.fmin(depth[:, 0], depth[:, 1])
    expected = -2.0 / (TEETH * KR * KT_N_M2 * hxx.real)
    expected[expected <= 0] = np.nan
    np.testing.assert_allclose(
        b, expected, rtol=1e-9, equal_nan=True, err_msg="one-direction closed form"
    )
    np.testing.assert_allclose(
        np.nanmin(b), 2.0 / (TEETH * KR * KT_N_M2 * -hxx.real.min()), rtol=1e-9
    )
