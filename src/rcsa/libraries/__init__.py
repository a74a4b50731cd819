"""Tool-library importers: CAM tool libraries → tool–holder combinations (contract format).

:mod:`rcsa.libraries.fusion` reads Autodesk Fusion / HSM libraries (``.json``, ``.tools``);
:mod:`rcsa.libraries.freecad` maps a FreeCAD toolbit (``.fctb``) in a holder (``.fcholder``).
Every importer returns one :class:`Combination` per library item with ``status`` ``"ok"``,
``"skipped"`` or ``"error"``; the ``ok`` ones carry ``holder`` and ``tool`` dicts in the
contract's assembly format (SI metres).
"""

from __future__ import annotations

from rcsa.libraries.freecad import freecad_combination, load_freecad_object, parse_length_m
from rcsa.libraries.fusion import (
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
    "freecad_combination",
    "library_combinations",
    "load_freecad_object",
    "load_fusion_library",
    "parse_length_m",
    "unit_to_metres",
]
