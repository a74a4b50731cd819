"""What every library reader returns: one :class:`Combination` per item, in a :class:`LibraryImport`.

Shared by the Fusion (:mod:`rcsa.libraries.fusion`) and FreeCAD (:mod:`rcsa.libraries.freecad`)
readers, so that a library's import report and its predictions have one shape whatever the
CAM system: per item ``ok`` (holder and tool in the contract's assembly format, SI metres),
``skipped`` with the reason, or ``error`` naming the field; ``warnings`` on every item.
"""

from __future__ import annotations

import copy
from collections.abc import Iterator
from dataclasses import dataclass
from typing import Any, Literal

from rcsa.errors import InputError

__all__ = ["Combination", "LibraryImport", "Status"]

Status = Literal["ok", "skipped", "error"]


@dataclass(frozen=True, slots=True)
class Combination:
    """One library item mapped to a tool–holder combination.

    Parameters
    ----------
    id : str
        Stable identifier, the same across exports of an unchanged item (each reader's
        docstring, "Ids").
    index : int
        Position of the item in the library (Fusion ``data``, FreeCAD toolbits in order).
    status : {"ok", "skipped", "error"}
    description : str
    number : int or None
        T number (Fusion ``post-process.number``, FreeCAD ``.fctl`` ``nr``).
    teeth : int or None
        Number of flutes (Fusion ``NOF``, FreeCAD ``Flutes``; for stability lobes).
    tool_type : str or None
        Fusion ``type`` or FreeCAD ``shape-type``.
    reason : str or None
        Why the item was skipped or rejected (``"field: rule"`` for errors).
    holder : dict or None
        ``{"segments": [{"length_m", "outer_diameter_m", "inner_diameter_m", "material"}]}``
        from the gauge line toward the tool end, metres; ``ok`` entries only. Treat as read-only.
    tool : dict or None
        Contract tool (``material, diameter_m, shank_diameter_m, overall_length_m,
        flute_length_m, stickout_m, fluted_diameter_ratio`` and, for necked tools,
        ``shoulder_length_m, shoulder_diameter_m`` (one neck) or ``neck_segments`` (a
        stepped or conical neck)), metres; ``ok`` entries only.
    warnings : tuple of str
        Approximations and inconsistencies noticed on the way.
    """

    id: str
    index: int
    status: Status
    description: str = ""
    number: int | None = None
    teeth: int | None = None
    tool_type: str | None = None
    reason: str | None = None
    holder: dict[str, Any] | None = None
    tool: dict[str, Any] | None = None
    warnings: tuple[str, ...] = ()

    def to_dict(self) -> dict[str, Any]:
        """Return a JSON-ready dict (fresh copies of ``holder`` and ``tool``)."""
        return {"id": self.id, "index": self.index, "status": self.status,
                "description": self.description, "number": self.number, "teeth": self.teeth,
                "tool_type": self.tool_type, "reason": self.reason,
                "warnings": list(self.warnings), "holder": copy.deepcopy(self.holder),
                "tool": copy.deepcopy(self.tool)}

    def batch_item(self) -> dict[str, Any]:
        """Return ``{"id", "holder", "tool"}`` for the batch endpoint (``ok`` entries only).

        Raises
        ------
        InputError
            The entry is skipped or in error.
        """
        if self.status != "ok":
            raise InputError(self.id, f"is {self.status} ({self.reason}), not a combination")
        return {"id": self.id, "holder": copy.deepcopy(self.holder), "tool": copy.deepcopy(self.tool)}


@dataclass(frozen=True, slots=True)
class LibraryImport:
    """All items of one library, in library order, with a count by status.

    Parameters
    ----------
    combinations : tuple of Combination
    summary : dict
        ``{"ok": n, "skipped": n, "error": n}``.
    source : str
    library_sha256 : str
    """

    combinations: tuple[Combination, ...]
    summary: dict[str, int]
    source: str
    library_sha256: str

    def __iter__(self) -> Iterator[Combination]:
        """Iterate over the combinations in library order."""
        return iter(self.combinations)

    def __len__(self) -> int:
        """Return the number of library items."""
        return len(self.combinations)

    def to_dict(self) -> dict[str, Any]:
        """Return a JSON-ready dict."""
        return {"source": self.source, "library_sha256": self.library_sha256,
                "summary": dict(self.summary),
                "combinations": [c.to_dict() for c in self.combinations]}

