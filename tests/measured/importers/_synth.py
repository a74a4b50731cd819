"""Synthetic FRFs and file writers for the importer tests (pyuff writes the UFF files)."""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pyuff

from rcsa.measured.store import MeasurementMeta

#: 164 factors of the inch system: "to convert from file units to SI divide by" these.
IN_LENGTH, IN_FORCE = 1.0 / 0.0254, 1.0 / (0.45359237 * 9.80665)

META = MeasurementMeta("mc1-hsk63", "x", "spindle_nose", "direct_frf")
ARTIFACT = {"diameter_m": 0.0127, "stickout_m": 0.08, "material": "steel"}
ARTIFACT_META = MeasurementMeta(
    "mc1-hsk63", "y", "spindle_nose", "artifact_frfs", points_m=(0.0, 0.025), artifact=ARTIFACT
)


def two_mode_receptance(frequency_hz: np.ndarray, scale: float = 1.0) -> np.ndarray:
    """A damped two-mode driving-point receptance, m/N (Im <= 0, e^{iwt})."""
    w = 2 * np.pi * np.asarray(frequency_hz, dtype=float)
    h = np.zeros(w.shape, dtype=complex)
    for fn, zeta, k in ((700.0, 0.03, 3e7), (1900.0, 0.04, 8e7)):
        wn = 2 * np.pi * fn
        h += (wn**2 / k) / (wn**2 - w**2 + 2j * zeta * wn * w)
    return scale * h


def write_uff(
    path: Path, datasets: list[dict], units164: tuple[int, float, float] | None = None
) -> Path:
    """Write dataset 164 (code, length factor, force factor) and the prepared 58 sets."""
    sets = []
    if units164 is not None:
        code, length, force = units164
        sets.append(
            pyuff.prepare_164(
                units_code=code,
                units_description="test",
                temp_mode=1,
                length=length,
                force=force,
                temp=1.0,
                temp_offset=0.0,
            )
        )
    sets.extend(datasets)
    path.unlink(missing_ok=True)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ResourceWarning)  # pyuff's binary writer leaks a handle
        # mode="add" on a fresh file: pyuff 2.5.8 truncates the header of a binary 58 written
        # first in mode="overwrite" (it reopens the file with "wb" for the binary block)
        pyuff.UFF(str(path)).write_sets(sets, mode="add")
    return path


def frf58(
    frequency_hz,
    data,
    *,
    binary=0,
    numerator=8,
    denominator=13,
    func_type=4,
    rsp=(1, 1),
    ref=(1, 1),
    spacing=0,
    num_label="NONE",
    den_label="NONE",
) -> dict:
    """A dataset 58 dict (pyuff.prepare_58) for an FRF at (rsp node, dir) / (ref node, dir)."""
    return pyuff.prepare_58(
        binary=binary,
        func_type=func_type,
        rsp_node=rsp[0],
        rsp_dir=rsp[1],
        ref_node=ref[0],
        ref_dir=ref[1],
        data=np.asarray(data),
        x=np.asarray(frequency_hz, dtype=float),
        id1=f"frf {rsp}/{ref}",
        rsp_ent_name="spindle",
        ref_ent_name="spindle",
        abscissa_spacing=spacing,
        abscissa_spec_data_type=18,
        ordinate_spec_data_type=numerator,
        orddenom_spec_data_type=denominator,
        ordinate_axis_units_lab=num_label,
        orddenom_axis_units_lab=den_label,
    )
