"""Tool-material names as CAM libraries write them → the built-in materials.

Fusion writes ``BMC`` in lower case: ``"carbide"``, ``"hss"``, ``"ti coated"``, ``"ceramics"``,
``"unspecified"`` (knipknap/better-tool-library ``fusionserializer.py``: "fusion allows for
ceramics or unspecified tool materials"). FreeCAD toolbits write ``Material`` ``"HSS"`` or
``"Carbide"`` (``Path/Tool/toolbit/models/base.py``); its legacy tools wrote
``HighSpeedSteel``, ``HighCarbonToolSteel``, ``CastAlloy``, ``Carbide``, ``Ceramics``,
``Diamond``, ``Sialon``. Vendor exports add their own (``HSS-Co``, ``HSSE``, ``VHM``...).

A spelling is compared in lower case with spaces, ``-`` and ``_`` removed, so ``"HSS-Co"``,
``"hss co"`` and ``"HSSCO"`` are one name. Each recognised name maps to a built-in of
:data:`rcsa.physics.materials.BUILTIN_MATERIALS`; where the mapping is an interpretation (a
coated HSS, a ceramic) the reader adds a warning saying what was assumed. Anything else
(``"unspecified"``, ``"diamond"``, a grade name) is not guessed: the caller's
``tool_material_default`` is used, with a warning.
"""

from __future__ import annotations

import re

__all__ = ["TOOL_MATERIAL_SPELLINGS", "tool_material"]

#: Normalised spelling → (built-in material, note for the item's warnings or None).
TOOL_MATERIAL_SPELLINGS: dict[str, tuple[str, str | None]] = {}
for _names, _target, _note in (
    (("carbide", "solidcarbide", "tungstencarbide", "cementedcarbide", "hm", "vhm", "hartmetall"), "carbide", None),
    (("hss", "highspeedsteel", "hs", "hssm2", "m2"), "hss", None),
    (("ticoated", "ticoatedhss", "tincoated", "tincoatedhss", "hsstin", "hssticn"), "hss",
     "taken as coated HSS (the coating does not change the beam)"),
    (("hssco", "hssco5", "hssco8", "hsse", "hssepm", "hsco", "cobalt", "cobalthss", "hsscobalt", "m35", "m42"),
     "hss_cobalt", None),
    (("toolsteel", "highcarbontoolsteel", "carbontoolsteel", "o1", "w1"), "tool_steel", None),
    (("ceramic", "ceramics", "sialon"), "ceramic",
     "taken as solid SiAlON ceramic; an indexable tool's body is steel: set its material if so"),
):
    for _name in _names:
        TOOL_MATERIAL_SPELLINGS[_name] = (_target, _note)

_SEPARATORS = re.compile(r"[\s_\-]+")


def tool_material(raw: object) -> tuple[str | None, str | None]:
    """The built-in material a library's tool-material text names.

    Parameters
    ----------
    raw : object
        The text as read (``BMC``, ``Material``); anything but a string names nothing.

    Returns
    -------
    (str or None, str or None)
        The built-in material's name (None when not recognised) and a note on what was
        assumed (None when the spelling is unambiguous).

    Examples
    --------
    >>> tool_material("HSS-Co")
    ('hss_cobalt', None)
    >>> tool_material("unspecified")
    (None, None)
    """
    if not isinstance(raw, str):
        return None, None
    key = _SEPARATORS.sub("", raw.strip().lower())
    return TOOL_MATERIAL_SPELLINGS.get(key, (None, None))
