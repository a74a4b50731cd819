"""Tool-library importers: CAM tool libraries → tool–holder combinations (contract format).

:mod:`rcsa.libraries.fusion` reads Autodesk Fusion / HSM libraries (``.json``, ``.tools``).
Every importer returns one :class:`Combination` per library item with ``status`` ``"ok"``,
``"skipped"`` or ``"error"``; the ``ok`` ones carry ``holder`` and ``tool`` dicts in the
contract's assembly format (SI metres).
"""

from __future__ import annotations

from .fusion import (
    SUPPORTED_TOOL_TYPES,
    Combination,
    FusionLibrary,
    LibraryImport,
    cone_cylinders,
    library_combinations,
    load_fusion_library,
    unit_to_metres,
)

__all__ = [
    "SUPPORTED_TOOL_TYPES",
    "Combination",
    "FusionLibrary",
    "LibraryImport",
    "cone_cylinders",
    "library_combinations",
    "load_fusion_library",
    "unit_to_metres",
]
