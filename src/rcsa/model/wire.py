"""The wire form of numbers: one place that reads and writes the contract's arrays.

JSON has no complex type, so the contract carries a complex array as
``{"real": [...], "imag": [...]}`` (``docs/contract.md`` "Units"). Every parser of a request or
file in that form, and every writer of a result, goes through these functions, so the rules
(numbers only, finite, one value per frequency line) and their error messages are the same
everywhere. The units and the sign convention every receptance on the wire (and in every
file rcsa writes) is expressed in are stated here once: :data:`RECEPTANCE_UNITS`,
:data:`CONVENTION`.

>>> import numpy as np
>>> complex_to_wire(np.array([1 - 2j]))
{'real': [1.0], 'imag': [-2.0]}
>>> complex_from_wire({"real": [1.0, 2.0], "imag": [0.0, -1.0]}, "h")
array([1.+0.j, 2.-1.j])
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any, Literal

import numpy as np

from rcsa.errors import InputError

__all__ = ["CONVENTION", "RECEPTANCE_UNITS", "WIRE_KEYS", "complex_from_wire", "complex_to_wire", "json_float",
           "json_list", "number_list"]

#: The two keys of a complex array on the wire.
WIRE_KEYS = frozenset({"real", "imag"})

#: Units of the receptances h, l, n, p (``docs/contract.md`` "Units").
RECEPTANCE_UNITS = {"h": "m/N", "l": "m/(N*m)", "n": "rad/N", "p": "rad/(N*m)"}

#: The axis and sign conventions of every receptance (``docs/physics.md`` §2.1, ``docs/contract.md``).
CONVENTION = (
    "rcsa docs/physics.md 2.1: axis x from spindle rear to tool tip; w lateral displacement (m), "
    "psi rotation counter-clockwise positive = dw/dx (rad); F force (N), M moment (N*m); "
    "h=w/F, l=w/M, n=psi/F, p=psi/M; time dependence exp(+i*omega*t), "
    "so a damped driving-point receptance has Im h <= 0"
)


def number_list(value: object, field: str, n: int | None = None, *, nonempty: bool = False,
                finite: bool = True) -> np.ndarray:
    """A JSON list of numbers as a float64 array, shape (len,).

    Parameters
    ----------
    value : object
        The parsed JSON value, or a 1-D real numpy array (a document rcsa wrote with
        ``arrays="numpy"``).
    field : str
        Dotted path of the value, for the error.
    n : int, optional
        Required length (one value per frequency line).
    nonempty : bool
        Refuse an empty list.
    finite : bool
        Refuse NaN and infinities.

    Raises
    ------
    InputError
        Naming ``field`` and the rule broken.
    """
    is_array = isinstance(value, np.ndarray) and value.ndim == 1 and value.dtype.kind in "fiu"
    if not is_array and (not isinstance(value, list | tuple)
                         or any(isinstance(v, bool) or not isinstance(v, int | float) for v in value)):
        raise InputError(field, "must be a non-empty list of numbers" if nonempty else "must be a list of numbers")
    if nonempty and not len(value):  # type: ignore[arg-type]
        raise InputError(field, "must be a non-empty list of numbers")
    if n is not None and len(value) != n:  # type: ignore[arg-type]
        raise InputError(field, f"must have one value per frequency line ({n}), got {len(value)}")  # type: ignore[arg-type]
    try:
        x = np.array(value, dtype=float)
    except OverflowError:  # an integer beyond float range
        raise InputError(field, "must contain only finite numbers") from None
    if finite and not np.all(np.isfinite(x)):
        raise InputError(field, "must contain only finite numbers")
    return x


def complex_from_wire(value: object, field: str, n: int | None = None, *, nonempty: bool = False,
                      finite: bool = True) -> np.ndarray:
    """``{"real": [...], "imag": [...]}`` as a complex128 array, shape (len,).

    Parameters
    ----------
    value : object
        The parsed JSON value.
    field : str
        Dotted path of the value, for the error.
    n : int, optional
        Required length of both parts.
    nonempty, finite : bool
        As in :func:`number_list`.
    """
    if not isinstance(value, Mapping) or set(value) != WIRE_KEYS:
        raise InputError(field, 'must be {"real": [...], "imag": [...]}')
    re = number_list(value["real"], f"{field}.real", n, nonempty=nonempty, finite=finite)
    im = number_list(value["imag"], f"{field}.imag", n, nonempty=nonempty, finite=finite)
    if re.shape != im.shape:
        raise InputError(f"{field}.imag", f"has {im.size} values but {field}.real has {re.size}")
    out = np.empty(re.shape, dtype=np.complex128)
    out.real, out.imag = re, im  # exact, also for non-finite parts (re + 1j*im is not: 1j*inf has a NaN)
    return out


def complex_to_wire(x: Any, arrays: Literal["list", "numpy"] = "list", *,
                    nonfinite_as_none: bool = False) -> dict[str, Any]:
    """A complex array as ``{"real": [...], "imag": [...]}``.

    Parameters
    ----------
    x : array_like, complex
    arrays : {"list", "numpy"}
        ``"list"``: JSON-ready Python lists. ``"numpy"``: contiguous float64 arrays (for
        serialisers such as orjson that write numpy directly).
    nonfinite_as_none : bool
        Write a part that is not finite (a value that does not exist, such as the multiplier
        of a speed that never turns unstable) as ``null`` (:func:`json_list`); lists only.

    Examples
    --------
    >>> complex_to_wire(np.array([1 - 2j, complex("nan")]), nonfinite_as_none=True)
    {'real': [1.0, None], 'imag': [-2.0, 0.0]}
    """
    z = np.asarray(x)
    if nonfinite_as_none:
        return {"real": json_list(z.real), "imag": json_list(z.imag)}
    if arrays == "list":
        return {"real": z.real.tolist(), "imag": z.imag.tolist()}
    return {"real": np.ascontiguousarray(z.real), "imag": np.ascontiguousarray(z.imag)}


def json_float(x: float) -> float | None:
    """``x`` for JSON: a float, or None where it is not finite (no depth limit, no frequency).

    Parameters
    ----------
    x : float

    Examples
    --------
    >>> json_float(np.float64(0.5)), json_float(float("inf"))
    (0.5, None)
    """
    return float(x) if math.isfinite(x) else None


def json_list(a: Any) -> list[float | None]:
    """A real array for JSON, non-finite entries as None (see :func:`json_float`).

    Parameters
    ----------
    a : numpy.ndarray, shape (n,)

    Examples
    --------
    >>> json_list(np.array([1.0, np.nan]))
    [1.0, None]
    """
    return [float(x) if math.isfinite(x) else None for x in np.asarray(a, dtype=float).tolist()]
