"""Canonical example assemblies shared by the README, doctests, tests and benchmarks.

RA-1 (``domain.md`` §1.4): a BT40-class spindle on four bearings, a shrink-fit holder with
the tool shank inside, a Ø12.7 mm carbide end mill at 74 mm stickout, the seed paper's
Table 2 joint values. Its undamped natural frequencies are 599.85, 921.69, 1115.51,
1383.61, 1444.68, 3115.94, 4025.97, 5102.79, 6080.83 and 7717.51 Hz.
"""

from __future__ import annotations

import copy
import json
from functools import cache
from importlib import resources
from typing import Any

__all__ = ["ra1"]


@cache
def _ra1_text() -> str:
    return resources.files("rcsa.model").joinpath("data/ra1.json").read_text(encoding="utf-8")


def ra1(frequency: dict[str, Any] | None = None) -> dict[str, Any]:
    """The RA-1 assembly as a contract document (a fresh copy the caller may edit).

    Parameters
    ----------
    frequency : dict, optional
        Replaces the document's frequency grid (5–10 000 Hz, 1 Hz).

    Examples
    --------
    >>> doc = ra1({"start_hz": 100.0, "stop_hz": 200.0, "step_hz": 50.0})
    >>> doc["tool"]["stickout_m"]
    0.074
    """
    doc: dict[str, Any] = copy.deepcopy(json.loads(_ra1_text()))
    if frequency is not None:
        doc["frequency"] = dict(frequency)
    return doc
