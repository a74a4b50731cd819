"""Canonical example assemblies (public name; they live in :mod:`rcsa.model.reference`).

>>> from rcsa.reference import ra1
>>> ra1()["tool"]["stickout_m"]
0.074
"""

from __future__ import annotations

from rcsa.model.reference import ra1

__all__ = ["ra1"]
