"""Tables people download next to the JSON: a prediction's and a lobe diagram's CSV files.

Numbers are written with Python's shortest round-trip ``repr``, so they equal the JSON
results exactly; a missing value (no lobe reaches that speed) is an empty cell. CSV is
RFC 4180 with CRLF line ends, one header row naming every unit.
"""

from __future__ import annotations

import csv
import io
from collections.abc import Mapping, Sequence
from typing import Any

from rcsa.model.wire import complex_from_wire

__all__ = ["BAND_PERCENTILES", "FRF_COLUMNS", "LOBES_COLUMNS", "ROBUST_COLUMN", "frf_csv", "lobes_csv"]

#: Columns of the FRF export: (receptance, SI unit suffix of its column names).
FRF_COLUMNS = (("h", "m_n"), ("l", "1_n"), ("n", "rad_n"), ("p", "rad_n_m"))
#: Columns of the lobes export.
LOBES_COLUMNS = ("spindle_speed_rpm", "depth_limit_m", "chatter_frequency_hz", "governing_lobe")
#: Percentiles of ``|h|`` a prediction with an uncertainty band adds (``h_magnitude_<p>_m_n``).
BAND_PERCENTILES = ("p05", "p50", "p95")
#: Column a robust stability-lobes response adds.
ROBUST_COLUMN = "depth_limit_robust_m"


def frf_csv(result: Mapping[str, Any]) -> bytes:
    """A prediction result (``to_dict()``, lists) as CSV: frequency, then the real and
    imaginary parts of h (m/N), l (1/N), n (rad/N) and p (rad/(N·m)); with an uncertainty
    band, also its p05, p50 and p95 of ``|h|`` (m/N)."""
    header = ["frequency_hz"]
    columns: list[Sequence[float | None]] = [result["frequency_hz"]]
    for name, unit in FRF_COLUMNS:
        header += [f"{name}_real_{unit}", f"{name}_imag_{unit}"]
        z = complex_from_wire(result["tool_point"][name], f"tool_point.{name}", finite=False)
        columns += [z.real.tolist(), z.imag.tolist()]
    band = result.get("uncertainty")
    if band is not None:  # the band's percentiles of |h| (m/N) over the draws
        for p in BAND_PERCENTILES:
            header.append(f"h_magnitude_{p}_m_n")
            columns.append(band["h_magnitude_m_n"][p])
    return _csv(header, columns)


def lobes_csv(lobes: Mapping[str, Any]) -> bytes:
    """The lower envelope of a stability-lobes response as CSV: speed (rpm), depth limit (m),
    chatter frequency (Hz) and the governing lobe's index; a robust response adds its robust
    depth limit (m)."""
    names = [*LOBES_COLUMNS, *((ROBUST_COLUMN,) if lobes.get(ROBUST_COLUMN) is not None else ())]
    return _csv(names, [lobes[name] for name in names])


def _csv(header: list[str], columns: Sequence[Sequence[float | None]]) -> bytes:
    """CSV (RFC 4180, CRLF) of equal-length columns; None is an empty cell."""
    buf = io.StringIO()
    writer = csv.writer(buf)
    writer.writerow(header)
    for row in zip(*columns, strict=True):
        writer.writerow(["" if v is None else repr(v) for v in row])
    return buf.getvalue().encode()
