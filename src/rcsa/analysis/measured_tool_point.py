"""Measured tool-point FRFs in requests: the ``measurements`` list of identifications and diagnoses.

Both ``docs/contract.md`` "Joint identification" and "Diagnosis" send a base assembly and tap
tests of it, each with some ``tool`` fields overridden (typically several stickouts)::

    {"tool": {"stickout_m": 0.050}, "frequency_hz": [...],
     "h": {"real": [...], "imag": [...]}, "coherence": [...]}

:func:`parse_tap_tests` checks that list once, for both, and names the offending field.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from rcsa.errors import InputError
from rcsa.model import fields
from rcsa.model.bounds import MAX_FREQUENCY_LINES, MAX_FRF_VALUE
from rcsa.model.contract import ToolSpec, parse_tool
from rcsa.model.wire import complex_from_wire, number_list
from rcsa.physics.materials import Material
from rcsa.physics.receptance import check_frequency_hz

__all__ = ["MAX_TAP_TESTS", "TOOL_OVERRIDES", "TapTest", "parse_tap_tests"]

MAX_TAP_TESTS = 20
TOOL_OVERRIDES = ("material", "diameter_m", "shank_diameter_m", "overall_length_m", "flute_length_m",
                  "stickout_m", "fluted_diameter_ratio", "fluted_mass_diameter_ratio",
                  "shoulder_length_m", "shoulder_diameter_m")
_BASE_FIELDS = ("tool", "frequency_hz", "h", "coherence")


@dataclass(frozen=True)
class TapTest:
    """One measured tool-point receptance and the tool it was measured with.

    Attributes
    ----------
    tool : ToolSpec
        The base assembly's tool with the overrides applied (validated).
    overrides : dict
        The ``tool`` fields as given (echoed in results).
    frequency_hz : numpy.ndarray, shape (nfreq,)
        Strictly increasing, > 0 Hz; read-only.
    h : numpy.ndarray, shape (nfreq,), complex
        Measured receptance, m/N; non-zero on every line; read-only.
    coherence : numpy.ndarray, shape (nfreq,), or None
        Ordinary coherence γ² in [0, 1]; read-only.
    extra : dict
        The caller's additional fields, as given (validated by the caller).
    path : str
        Where this measurement sits in the request (``measurements[i]``), for messages.
    """

    tool: ToolSpec
    overrides: Mapping[str, Any]
    frequency_hz: np.ndarray
    h: np.ndarray
    coherence: np.ndarray | None
    extra: Mapping[str, Any]
    path: str


def _numbers(value: object, field: str, n: int | None = None) -> np.ndarray:
    return number_list(value, field, n, nonempty=True)


def _readonly(x: np.ndarray) -> np.ndarray:
    x.flags.writeable = False
    return x


def _tap_test(raw: object, path: str, base_tool: Mapping[str, Any], materials: Mapping[str, Material],
              extra_fields: tuple[str, ...], min_lines: int, max_lines: int) -> TapTest:
    raw = fields.json_object(raw, path, (*_BASE_FIELDS, *extra_fields))
    overrides = fields.json_object(raw.get("tool") or {}, f"{path}.tool", TOOL_OVERRIDES)
    tool = parse_tool({**base_tool, **overrides}, materials, f"{path}.tool")
    for key in ("frequency_hz", "h"):
        if key not in raw:
            raise InputError(f"{path}.{key}", "is required")
    f_raw = raw["frequency_hz"]
    if isinstance(f_raw, list) and len(f_raw) > max_lines:
        raise InputError(f"{path}.frequency_hz", f"at most {max_lines} lines, got {len(f_raw)}")
    f = np.array(check_frequency_hz(_numbers(f_raw, f"{path}.frequency_hz"), f"{path}.frequency_hz"))
    if f.size < min_lines:
        raise InputError(f"{path}.frequency_hz", f"needs at least {min_lines} lines, got {f.size}")
    h = complex_from_wire(raw["h"], f"{path}.h", f.size, nonempty=True)
    if np.any(np.abs(h.real) > MAX_FRF_VALUE) or np.any(np.abs(h.imag) > MAX_FRF_VALUE):
        raise InputError(f"{path}.h", f"real and imaginary parts must lie within ±{MAX_FRF_VALUE:g} m/N")
    if np.any(h == 0):
        raise InputError(f"{path}.h", "must be non-zero on every line")
    coherence = None
    if raw.get("coherence") is not None:
        coherence = _numbers(raw["coherence"], f"{path}.coherence", f.size)
        if np.any((coherence < 0) | (coherence > 1)):
            raise InputError(f"{path}.coherence", "values must lie in [0, 1] (γ², not γ in %)")
        coherence = _readonly(coherence)
    extra = {k: raw[k] for k in extra_fields if k in raw}
    return TapTest(tool, dict(overrides), _readonly(f), _readonly(h), coherence, extra, path)


def parse_tap_tests(raw: object, base_tool: Mapping[str, Any], materials: Mapping[str, Material], *,
                    extra_fields: tuple[str, ...] = (), min_lines: int = 1,
                    max_lines: int = MAX_FREQUENCY_LINES, max_tests: int = MAX_TAP_TESTS) -> tuple[TapTest, ...]:
    """Validate a request's ``measurements`` list.

    Parameters
    ----------
    raw : list
        The ``measurements`` value.
    base_tool : dict
        The base assembly's ``tool`` object (the overrides apply to it).
    materials : mapping
        Materials of the base assembly (for the tool's material).
    extra_fields : tuple of str
        Further keys a measurement may carry (returned in :attr:`TapTest.extra`).
    min_lines, max_lines : int
        Bounds on the number of frequency lines of each measurement.
    max_tests : int
        Largest number of measurements.

    Returns
    -------
    tuple of TapTest

    Raises
    ------
    InputError
        Naming the field: unknown keys, unknown tool overrides, invalid tool geometry, arrays
        of unequal length, frequencies not > 0 or not increasing, zero receptance, coherence
        outside [0, 1].
    """
    if not isinstance(raw, list) or not raw:
        raise InputError("measurements", "must be a non-empty list")
    if len(raw) > max_tests:
        raise InputError("measurements", f"at most {max_tests} measurements, got {len(raw)}")
    return tuple(_tap_test(m, f"measurements[{i}]", base_tool, materials, extra_fields, min_lines, max_lines)
                 for i, m in enumerate(raw))
