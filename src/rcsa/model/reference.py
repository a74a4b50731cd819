"""The reference assemblies shared by the README, doctests, tests, benchmarks and the demo store.

RA-1 (``docs/physics.md`` §1.4): a BT40-class spindle on four bearings, a shrink-fit holder with
the tool shank inside, a Ø12.7 mm carbide end mill at 74 mm stickout, the seed paper's
Table 2 joint values. Its undamped natural frequencies are 599.85, 921.69, 1115.51,
1383.61, 1444.68, 3115.94, 4025.97, 5102.79, 6080.83 and 7717.51 Hz.

:func:`ra1_spindle_receptance` is RA-1's analytical spindle-nose receptance: what a
``point_receptance`` measurement of that spindle would hold (the demo measurement a fresh
store is seeded with, and the tests' stand-in for a measured spindle).
"""

from __future__ import annotations

import copy
import json
from functools import cache
from importlib import resources
from typing import Any

import numpy as np

from rcsa.model.assembly import build_model
from rcsa.model.contract import parse_assembly
from rcsa.physics.elimination import tip_receptance
from rcsa.physics.receptance import Receptance

__all__ = ["ra1", "ra1_spindle_receptance"]


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


def ra1_spindle_receptance(frequency: dict[str, Any] | None = None) -> Receptance:
    """RA-1's spindle alone (shaft and bearings), its receptance at the spindle nose.

    Parameters
    ----------
    frequency : dict, optional
        The contract's frequency grid (default 1–10 000 Hz in 1 Hz steps).

    Returns
    -------
    Receptance
        ``[[h, l], [n, p]]`` at the nose, shape (nfreq, 2, 2): m/N, 1/N, rad/N, rad/(N·m).

    Examples
    --------
    >>> r = ra1_spindle_receptance({"start_hz": 100.0, "stop_hz": 300.0, "step_hz": 100.0})
    >>> r.values.shape, bool(abs(r.l - r.n).max() < 1e-12 * abs(r.l).max())
    ((3, 2, 2), True)
    """
    spec = parse_assembly(ra1(dict(frequency or {"start_hz": 1.0, "stop_hz": 10000.0, "step_hz": 1.0})))
    values = tip_receptance(build_model(spec).spindle, 2.0 * np.pi * spec.frequency_hz)
    return Receptance(spec.frequency_hz, values)
