"""Plausibility bounds every imported array meets before it becomes a measurement.

An importer that reads the wrong column, the wrong unit or a damaged file usually still
produces finite numbers; these bounds turn the grossest of those mistakes into a refusal
that says what was found, instead of a stored FRF that is silently wrong. They are wide on
purpose: a value outside them cannot be a machine-tool FRF, whatever unit was meant.

Bounds apply after conversion to the stored quantity (receptance in m/N, l and n in 1/N or
rad/N, p in rad/(N·m)), per value, so an accelerance file is judged on what it becomes.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from rcsa.errors import InputError
from rcsa.measured.store.schema import frf_unit

__all__ = [
    "BOUNDS_BY_UNIT",
    "LEVER_ARM_MAX_M",
    "LEVER_ARM_MIN_M",
    "MAX_ABS_PHASE_RAD",
    "MAX_FREQUENCY_HZ",
    "MAX_RECEPTANCE_M_N",
    "MIN_RECEPTANCE_M_N",
    "check_frequency",
    "check_magnitudes",
    "row_label",
]

#: Highest frequency line accepted, Hz. Machine-tool structural dynamics end below ~50 kHz
#: (impact hammers excite up to ~20 kHz, ultrasonic spindles run at 20-40 kHz); 1 MHz keeps a
#: factor 20 of margin and still refuses a column in the wrong unit (mHz, rad/s x 1e3) or
#: garbage such as 1.8e308.
MAX_FREQUENCY_HZ = 1.0e6

#: Largest receptance magnitude accepted, m/N. 1 m/N is a spring of 1 N/m (a sheet of
#: paper). The softest tool points are ~1e-4 m/N at resonance (a 6 mm carbide tool at 10
#: diameters stickout: k = 3EI/L^3 = 5e5 N/m, peak 1/(2 zeta k) = 1e-4 m/N at zeta = 1 %), and
#: the integration noise of a tap test at its 1 Hz line reaches 1.2e-2 m/N (the leekunhwee
#: Point_1 file), which is why the bound is not tighter. It refuses garbage and gross unit
#: errors (nm/N read as m/N); the common um/N-vs-m/N mix-up is caught by reading the units
#: from the file's header, not by this bound.
MAX_RECEPTANCE_M_N = 1.0

#: Smallest receptance magnitude accepted, m/N. 1e-15 m/N is a dynamic stiffness of 1e15 N/m,
#: six decades stiffer than a spindle nose (1e8-1e9 N/m) and four below the deepest
#: anti-resonance of a measured cross FRF; exact zeros (empty lines of an analyser export,
#: zero padding) and m/N values read as nm/N (x 1e-9) land below it.
MIN_RECEPTANCE_M_N = 1.0e-15

#: Largest phase magnitude accepted in a column declared in radians, rad. An unwrapped phase
#: loses at most pi per mode, so 8 turns (16 pi, 50 rad) leave room for cross FRFs over many
#: modes, while a phase in degrees read as radians exceeds it as soon as it passes 51 deg,
#: which every FRF through a resonance (-90 deg) does.
MAX_ABS_PHASE_RAD = 16.0 * np.pi

#: Lever arms that relate the rotational receptances to h: l, n ~ h/a and p ~ h/a^2 with a
#: between the shortest and longest holder or tool lengths, m.
LEVER_ARM_MIN_M, LEVER_ARM_MAX_M = 0.01, 0.1

#: (smallest, largest) magnitude per stored unit: the m/N bounds carried through the lever
#: arms (l, n: m/N / a, widest at a = 0.1 m below and a = 0.01 m above; p: m/N / a^2).
BOUNDS_BY_UNIT: dict[str, tuple[float, float]] = {
    "m/N": (MIN_RECEPTANCE_M_N, MAX_RECEPTANCE_M_N),
    "m/(N*m)": (MIN_RECEPTANCE_M_N / LEVER_ARM_MAX_M, MAX_RECEPTANCE_M_N / LEVER_ARM_MIN_M),
    "rad/N": (MIN_RECEPTANCE_M_N / LEVER_ARM_MAX_M, MAX_RECEPTANCE_M_N / LEVER_ARM_MIN_M),
    "rad/(N*m)": (
        MIN_RECEPTANCE_M_N / LEVER_ARM_MAX_M**2,
        MAX_RECEPTANCE_M_N / LEVER_ARM_MIN_M**2,
    ),
}


def row_label(i: int, lines: Sequence[int] | None) -> str:
    """``"row 3 (line 5)"`` for row index ``i`` of a text file, ``"index 2"`` without lines."""
    return f"row {i + 1} (line {lines[i]})" if lines is not None else f"index {i}"


def check_frequency(frequency_hz: np.ndarray, lines: Sequence[int] | None = None) -> None:
    """Refuse frequency lines above :data:`MAX_FREQUENCY_HZ` (finiteness is checked before).

    Raises
    ------
    InputError
        Field ``frequency_hz``, naming the first offending row.
    """
    bad = np.flatnonzero(np.asarray(frequency_hz) > MAX_FREQUENCY_HZ)
    if bad.size:
        i = int(bad[0])
        raise InputError(
            "frequency_hz",
            f"{row_label(i, lines)} is at {frequency_hz[i]:.6g} Hz, above {MAX_FREQUENCY_HZ:g} Hz: not a "
            "machine-tool FRF line; check the frequency column and its unit (Hz, kHz, rad/s)",
        )


def check_magnitudes(
    name: str,
    values: np.ndarray,
    frequency_hz: np.ndarray,
    *,
    lines: Sequence[int] | None = None,
    read_as: str = "",
    hint: str = "",
) -> None:
    """Refuse magnitudes outside :data:`BOUNDS_BY_UNIT` for the stored unit of ``name``.

    Parameters
    ----------
    name : str
        Stored FRF name (``h``, ``l``, ``n``, ``p`` or ``h21`` …), which fixes its unit.
    values : numpy.ndarray, shape (nfreq,), complex
        The FRF as it would be stored.
    frequency_hz : numpy.ndarray, shape (nfreq,)
    lines : sequence of int, optional
        Source line of each value, for the message.
    read_as : str
        How the file's values were read (e.g. ``"um/N (declared)"``), for the message.
    hint : str
        Appended to the message (e.g. the tap importer's advice to limit the band).

    Raises
    ------
    InputError
        Field ``name``, naming the first offending row, its value and the bound.
    """
    unit = frf_unit(name)
    lo, hi = BOUNDS_BY_UNIT[unit]
    mag = np.abs(values)
    for bad, side, bound in ((mag > hi, "above", hi), (mag < lo, "below", lo)):
        idx = np.flatnonzero(bad)
        if idx.size:
            i = int(idx[0])
            what = "the most" if side == "above" else "the least"
            read = f"; the file's values were read as {read_as}" if read_as else ""
            raise InputError(
                name,
                f"{row_label(i, lines)} at {frequency_hz[i]:.6g} Hz has |{name}| = {mag[i]:.3g} {unit}, "
                f"{side} {bound:g} {unit}, {what} a machine-tool structure can give "
                f"({idx.size} of {mag.size} values are {side}){read}. Check the declared units and "
                "columns" + (f"; {hint}" if hint else ""),
            )
