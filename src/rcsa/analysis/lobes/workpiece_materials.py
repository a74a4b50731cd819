"""Workpiece materials for chatter-safe presets: cutting coefficients and surface-speed limits.

A small table, each number with its source. Two kinds of data:

Cutting coefficients (``tangential_coefficient_n_m2`` ``Kt`` and ``radial_ratio`` ``Kr = Krc/Ktc``)
    For the **linear edge-force milling model** ``F_t = K_tc h a + K_te a``,
    ``F_r = K_rc h a + K_re a`` (Altintas 2012, §2.4): the stability lobes
    (:func:`rcsa.analysis.lobes.zoa.stability_lobes`, the average / zero-order directional
    factors) use only the *shearing* coefficients ``K_tc`` and ``K_rc``; the edge (ploughing)
    terms ``K_te``, ``K_re`` do not depend on the chip thickness and so do not enter the
    regenerative loop. Coefficients identified with a different force model (Kienzle's
    ``k_c1.1``, a specific force ``K_s`` with a force angle) are not mixed in. Only rows with a
    citable, identified value are listed; for the others (steels, titanium, cast iron) no
    citable value was found and the caller must give ``tangential_coefficient_n_m2`` and
    ``radial_ratio`` (from a cutting test, a vendor, or their own identification).

    * **aluminium-7075**: ``K_tc = 1319.41 N/mm²``, ``K_rc = 788.83 N/mm²`` (cemented carbide,
      dry): Table 5 ("Model coefficients of milling force for aerospace aluminum alloy"),
      row [47], of the review "Milling Force Model for Aviation Aluminum Alloy: Academic
      Insight and Perspective Analysis", *Chinese Journal of Mechanical Engineering* (2021),
      https://doi.org/10.1186/s10033-021-00536-9. The same
      pair (``Kt = 1319.4e6 N/m²``, ``Kn/Kt = 788.8/1319.4``) drives the Manufacturing
      Automation Laboratory's zero-order lobe example (J. Li, UBC MAL, ``LobeZOAAltintas.m``
      in github.com/leekunhwee/Dynamics, citing Altintas 2012, p. 156). Of the four Al 7075
      rows of that table (767.01, 600.46, 951.365 and 1319.41 N/mm²) it is the largest ``K_tc``:
      the depth limit scales as ``1/K_t``, so it is the conservative choice.
    * **aluminium-6082**: ``K_tc = 631 N/mm²``, ``K_rc = 99 N/mm²`` (Al 6082-T6, cemented
      carbide, dry): the same Table 5, row [189].

Surface-speed limits (carbide tools)
    The upper end of the range the vendor recommends for **solid carbide end mills**: Tungaloy
    General Catalogue 2020–2021, solid-carbide end mills, "Standard cutting conditions"
    (mirrored at https://docs.steelcam.org/tungaloy/obshij-katalog-tungaloy-2020-2021-page1084),
    in three bands of radial engagement: slotting / roughing (``a_e >= 0.4 D``),
    semi-finishing / shouldering (``0.1 D <= a_e < 0.4 D``) and finishing (``a_e < 0.1 D``).
    The rows used (``v_c`` m/min, upper ends): aluminium alloy 750 / 850 / 900, carbon steel
    180 / 220 / 280, alloy steel 150 / 160 / 220, stainless steel 100 / 130 / 160, cast iron
    180 / 220 / 280, titanium alloy 50 / 60 / 70, hardened steel 30 / 70 / 80. The table says
    nothing about HSS tools: for them the caller gives the limit.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass

from rcsa.errors import InputError

__all__ = [
    "COEFFICIENT_MODEL",
    "SPEED_SOURCE",
    "WORKPIECE_MATERIALS",
    "WorkpieceMaterial",
    "engagement_band",
    "material_key",
    "workpiece_material",
]

#: The milling force model the table's coefficients belong to.
COEFFICIENT_MODEL = ("linear edge-force model, shearing coefficients only (K_tc, K_rc); the edge coefficients "
                     "do not enter the stability lobes")

_CJME_REVIEW = ("'Milling Force Model for Aviation Aluminum Alloy: Academic Insight and Perspective Analysis', "
                "Chinese Journal of Mechanical Engineering (2021), doi:10.1186/s10033-021-00536-9, Table 5")

#: Where the surface-speed limits come from.
SPEED_SOURCE = ("Tungaloy General Catalogue 2020-2021, solid carbide end mills, standard cutting conditions "
                "(upper end of the recommended v_c; docs.steelcam.org/tungaloy/"
                "obshij-katalog-tungaloy-2020-2021-page1084)")


@dataclass(frozen=True, slots=True)
class WorkpieceMaterial:
    """One row of the table.

    Attributes
    ----------
    key : str
        The name to ask for (``"aluminium-7075"``).
    name : str
        Display name, written into the preset's name (``"aluminium 7075"``).
    aliases : tuple of str
        Other spellings that select this row (compared by :func:`material_key`).
    tangential_coefficient_n_m2 : float or None
        ``K_tc``, N/m² (None: no citable value; the caller gives it).
    radial_ratio : float or None
        ``K_rc / K_tc`` (dimensionless).
    coefficient_source : str or None
        Citation of the coefficients.
    carbide_surface_speed_m_min : tuple of float
        Highest cutting speed ``v_c`` for solid-carbide end mills, m/min, in the engagement
        bands (slotting/roughing, semi-finishing, finishing) of :func:`engagement_band`.
    """

    key: str
    name: str
    aliases: tuple[str, ...]
    tangential_coefficient_n_m2: float | None
    radial_ratio: float | None
    coefficient_source: str | None
    carbide_surface_speed_m_min: tuple[float, float, float]

    def max_surface_speed_m_min(self, radial_immersion: float) -> float:
        """The carbide surface-speed limit at a radial immersion ``a_e / D``, m/min.

        Examples
        --------
        >>> workpiece_material("al7075").max_surface_speed_m_min(0.5)
        750.0
        """
        return self.carbide_surface_speed_m_min[engagement_band(radial_immersion)]

    def to_dict(self) -> dict[str, object]:
        """JSON-ready row (with its sources)."""
        return {"key": self.key, "name": self.name, "aliases": list(self.aliases),
                "tangential_coefficient_n_m2": self.tangential_coefficient_n_m2,
                "radial_ratio": self.radial_ratio, "coefficient_model": COEFFICIENT_MODEL,
                "coefficient_source": self.coefficient_source,
                "carbide_surface_speed_m_min": dict(zip(("slotting_roughing", "semi_finishing", "finishing"),
                                                        self.carbide_surface_speed_m_min, strict=True)),
                "surface_speed_source": SPEED_SOURCE}


def _row(key: str, name: str, aliases: tuple[str, ...], ktc_n_mm2: float | None, krc_n_mm2: float | None,
         source: str | None, vc: tuple[float, float, float]) -> WorkpieceMaterial:
    kt = None if ktc_n_mm2 is None else ktc_n_mm2 * 1e6
    kr = None if ktc_n_mm2 is None or krc_n_mm2 is None else krc_n_mm2 / ktc_n_mm2
    return WorkpieceMaterial(key, name, aliases, kt, kr, source, vc)


_ALUMINIUM_VC = (750.0, 850.0, 900.0)

#: The table, by key.
WORKPIECE_MATERIALS: dict[str, WorkpieceMaterial] = {m.key: m for m in (
    _row("aluminium-7075", "aluminium 7075",
         ("aluminium", "aluminum", "al", "7075", "al7075", "aa7075", "al7075t6", "aluminium7075t6",
          "aluminum7075", "aluminum7075t6", "7075t6"),
         1319.41, 788.83, f"{_CJME_REVIEW}, row [47] (cemented carbide, dry)", _ALUMINIUM_VC),
    _row("aluminium-6082", "aluminium 6082",
         ("6082", "al6082", "aa6082", "al6082t6", "aluminum6082", "aluminium6082t6", "aluminum6082t6", "6082t6"),
         631.0, 99.0, f"{_CJME_REVIEW}, row [189] (Al6082-T6, cemented carbide, dry)", _ALUMINIUM_VC),
    _row("carbon-steel", "carbon steel", ("steel", "c45", "1045", "aisi1045", "s45c", "ck45", "mildsteel"),
         None, None, None, (180.0, 220.0, 280.0)),
    _row("alloy-steel", "alloy steel", ("42crmo4", "4140", "aisi4140", "scm440"), None, None, None,
         (150.0, 160.0, 220.0)),
    _row("stainless-steel", "stainless steel", ("stainless", "304", "316", "aisi304", "aisi316", "sus304"),
         None, None, None, (100.0, 130.0, 160.0)),
    _row("cast-iron", "cast iron", ("castiron", "gg25", "gjl250", "fc250"), None, None, None,
         (180.0, 220.0, 280.0)),
    _row("titanium-alloy", "titanium alloy", ("titanium", "ti6al4v", "ti64", "tial6v4"), None, None, None,
         (50.0, 60.0, 70.0)),
    _row("hardened-steel", "hardened steel", ("hardenedsteel",), None, None, None, (30.0, 70.0, 80.0)),
)}

_SEPARATORS = re.compile(r"[\s_\-./]+")


def material_key(name: str) -> str:
    """A material name compared without case, spaces, ``-``, ``_``, ``.`` or ``/``.

    Examples
    --------
    >>> material_key("Al 7075-T6")
    'al7075t6'
    """
    return _SEPARATORS.sub("", name.strip().lower())


_LOOKUP: dict[str, WorkpieceMaterial] = {}
for _m in WORKPIECE_MATERIALS.values():
    for _spelling in (_m.key, _m.name, *_m.aliases):
        _LOOKUP.setdefault(material_key(_spelling), _m)


def workpiece_material(name: object) -> WorkpieceMaterial | None:
    """The table row a material name selects, or None for a name the table does not know.

    Raises
    ------
    InputError
        ``material`` is not a non-empty string.

    Examples
    --------
    >>> workpiece_material("Aluminum 7075-T6").key
    'aluminium-7075'
    >>> workpiece_material("Inconel 718") is None
    True
    """
    if not isinstance(name, str) or not name.strip():
        raise InputError("material", "must name the workpiece material (e.g. aluminium-7075)")
    return _LOOKUP.get(material_key(name))


def engagement_band(radial_immersion: float) -> int:
    """Which surface-speed band a radial immersion ``a_e / D`` falls in.

    Returns
    -------
    int
        0: slotting / roughing (``a_e >= 0.4 D``), 1: semi-finishing (``0.1 D <= a_e < 0.4 D``),
        2: finishing (``a_e < 0.1 D``).

    Examples
    --------
    >>> [engagement_band(x) for x in (1.0, 0.4, 0.25, 0.05)]
    [0, 0, 1, 2]
    """
    if not math.isfinite(radial_immersion) or radial_immersion <= 0:
        raise InputError("radial_immersion", f"must be in (0, 1], got {radial_immersion}")
    if radial_immersion >= 0.4:
        return 0
    return 1 if radial_immersion >= 0.1 else 2
