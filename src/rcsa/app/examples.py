"""The canonical example assemblies the service and the CLI offer (:mod:`rcsa.reference`)."""

from __future__ import annotations

from rcsa.reference import ra1

__all__ = ["ra1"]
