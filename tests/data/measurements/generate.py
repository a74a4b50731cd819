"""Regenerate the synthetic measurement fixtures in this folder (invented numbers, no source).

    .venv/bin/python tests/data/measurements/generate.py

The same two-mode receptance underlies every file (modes at 700 Hz, ζ 3 %, and 1900 Hz,
ζ 4 %; static compliance 1/3e7 + 1/8e7 m/N), so the importers must agree on it.
"""

from __future__ import annotations

import json
import warnings
from pathlib import Path

import numpy as np
import pyuff

HERE = Path(__file__).resolve().parent
F = np.arange(20.0, 2420.0, 40.0)  # 60 points, Hz


def receptance(f: np.ndarray, scale: float = 1.0) -> np.ndarray:
    """Two-mode driving-point receptance, m/N (e^{iwt}: Im <= 0)."""
    w = 2 * np.pi * np.asarray(f, dtype=float)
    h = np.zeros(w.shape, dtype=complex)
    for fn, zeta, k in ((700.0, 0.03, 3e7), (1900.0, 0.04, 8e7)):
        wn = 2 * np.pi * fn
        h += (wn**2 / k) / (wn**2 - w**2 + 2j * zeta * wn * w)
    return scale * h


def main() -> None:
    h = receptance(F)
    rows = "".join(
        f"{f:.17g},{z.real * 1e6:.17g},{z.imag * 1e6:.17g}\n" for f, z in zip(F, h, strict=True)
    )
    (HERE / "direct_frf_um_per_n.csv").write_text(
        "# synthetic tool-tip FRF, receptance in um/N (declare --units um/N)\nfrequency_hz,real_um_n,imag_um_n\n"
        + rows
    )
    rows = "".join(
        f"{f:.17g}\t{abs(z) * 1e6:.17g}\t{np.degrees(np.angle(z)):.17g}\n"
        for f, z in zip(F, h, strict=True)
    )
    (HERE / "direct_frf_mag_phase_deg.tsv").write_text("Hz\t|H| um/N\tphase deg\n" + rows)
    first = f"{F[0]:.6e}\t{h[0].real:.6e}\t{h[0].imag:.6e}\tFreq Hz Real m/N Imag Real\n"
    rest = "".join(
        f"{f:.6e}\t{z.real:.6e}\t{z.imag:.6e}\n" for f, z in zip(F[1:], h[1:], strict=True)
    )
    (HERE / "direct_frf.frf").write_text(first + rest)

    def c(z: np.ndarray) -> dict:
        return {"real": z.real.tolist(), "imag": z.imag.tolist()}

    doc = {
        "spindle_id": "demo-hsk63",
        "machine": "demo-mill",
        "direction": "x",
        "plane": "spindle_nose",
        "kind": "point_receptance",
        "frequency_hz": F.tolist(),
        "h": c(h),
        "l": c(-40.0 * h),
        "n": c(-40.0 * h),
        "p": c(2000.0 * h),
    }
    (HERE / "point_receptance.json").write_text(json.dumps(doc, indent=1) + "\n")

    w2 = (2 * np.pi * F) ** 2
    sets = [
        pyuff.prepare_164(
            units_code=1,
            units_description="SI",
            temp_mode=1,
            length=1.0,
            force=1.0,
            temp=1.0,
            temp_offset=273.15,
        )
    ]
    for (rsp, ref), scale in {(1, 1): 1.0, (2, 1): 0.6, (2, 2): 0.45}.items():
        sets.append(
            pyuff.prepare_58(
                binary=0,
                func_type=4,
                rsp_node=rsp,
                rsp_dir=1,
                ref_node=ref,
                ref_dir=1,
                data=-w2 * receptance(F, scale),
                x=F,
                id1=f"artifact H{rsp}{ref} accelerance",
                rsp_ent_name="blank",
                ref_ent_name="blank",
                abscissa_spacing=1,
                abscissa_spec_data_type=18,
                ordinate_spec_data_type=12,
                orddenom_spec_data_type=13,
            )
        )
    sets.append(
        pyuff.prepare_58(
            binary=0,
            func_type=6,
            rsp_node=1,
            rsp_dir=1,
            ref_node=1,
            ref_dir=1,
            data=np.linspace(0.9, 1.0, F.size),
            x=F,
            id1="coherence H11",
            rsp_ent_name="blank",
            ref_ent_name="blank",
            abscissa_spacing=1,
            abscissa_spec_data_type=18,
            ordinate_spec_data_type=0,
            orddenom_spec_data_type=0,
        )
    )
    out = HERE / "artifact_frfs_accelerance.uff"
    out.unlink(missing_ok=True)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        pyuff.UFF(str(out)).write_sets(sets, mode="add")

    fs, n = 4096.0, 1024  # 0.25 s: 4 Hz bins
    t = np.arange(n) / fs
    width = 1e-3
    force = np.where(t <= width, 150.0 * np.sin(np.pi * t / width), 0.0)
    force = np.roll(np.clip(force, 0, None), 20)
    fb = np.fft.rfftfreq(n, 1 / fs)
    acc = np.fft.irfft(np.fft.rfft(force) * (-((2 * np.pi * fb) ** 2)) * receptance(fb), n=n)
    (HERE / "tap_synthetic.txt").write_text(
        "".join(f"{a:.10e}\t{b:.10e}\t{c_:.10e}\n" for a, b, c_ in zip(t, force, acc, strict=True))
    )


if __name__ == "__main__":
    main()
