"""Tool-library importers: CAM tool libraries → tool–holder combinations (contract format).

:mod:`rcsa.libraries.fusion` reads Autodesk Fusion / HSM libraries (``.json``, ``.tools``);
:mod:`rcsa.libraries.freecad` maps FreeCAD toolbits (``.fctb``) in a holder (``.fcholder``),
one by one or as a library (:mod:`rcsa.libraries.freecad_library`: ``.fctl``, a folder or a
zip); :mod:`rcsa.libraries.formats` tells them apart. Every importer returns one
:class:`Combination` per library item with ``status`` ``"ok"``, ``"skipped"`` or
``"error"``; the ``ok`` ones carry ``holder`` and ``tool`` dicts in the contract's assembly
format (SI metres).
"""

from __future__ import annotations

from rcsa.libraries.combination import Combination, LibraryImport
from rcsa.libraries.freecad import freecad_combination, load_freecad_object, parse_length_m
from rcsa.libraries.fusion import (
    SUPPORTED_TOOL_TYPES,
    FusionLibrary,
    library_combinations,
    load_fusion_library,
)
from rcsa.libraries.profiles import cone_cylinders, cone_steps
from rcsa.libraries.quantities import unit_to_metres

__all__ = [
    "SUPPORTED_TOOL_TYPES",
    "Combination",
    "FusionLibrary",
    "LibraryImport",
    "cone_cylinders",
    "cone_steps",
    "freecad_combination",
    "library_combinations",
    "load_freecad_object",
    "load_fusion_library",
    "parse_length_m",
    "unit_to_metres",
]
