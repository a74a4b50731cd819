"""Linear-elastic isotropic materials with hysteretic damping.

Built-ins follow ``docs/contract.md``: ``steel`` (E 210 GPa, ν 0.30, ρ 7850 kg/m³, η 0.002) and
``carbide`` (E 600 GPa, ν 0.22, ρ 14500 kg/m³, η 0.002). A hysteretic loss factor η damps
both moduli as E(1 + iη), G(1 + iη) (``docs/physics.md`` §2.6).

The other built-ins are the tool materials CAM libraries name (Fusion ``BMC`` "hss",
"ceramics"; FreeCAD ``Material`` "HSS", "HighCarbonToolSteel", "Sialon", ...; the readers
map those spellings, :mod:`rcsa.libraries.tool_materials`). Each value below is a room-
temperature handbook value; the range the sources give and why this value was taken are
stated with it. ``materials`` in a request overrides any of them by name.

===========  =======  =====  ========  =====  ==============================================
name         E, GPa   ν      ρ, kg/m³  η      grade it stands for
===========  =======  =====  ========  =====  ==============================================
hss          210      0.29   8150      0.002  M2 (1.3343, HS6-5-2), the common HSS
hss_cobalt   207      0.29   8140      0.002  M35 (1.3243, HS6-5-2-5, "HSS-Co", "HSS-E")
tool_steel   193      0.29   7810      0.002  O1 (1.2510), hardened high-carbon tool steel
ceramic      290      0.23   3300      0.002  SiAlON, the grade of solid ceramic end mills
===========  =======  =====  ========  =====  ==============================================

Sources
-------
* **hss** — AZoM, "M2 Molybdenum High Speed Tool Steel (UNS T11302)" (ASM data): ρ 8.16
  g/cm³, E 190–210 GPa, ν 0.27–0.30; ASTM Steel's M2 sheet gives ρ 8138 kg/m³; MakeItFrom
  (annealed M2, after ASTM A600 / ASM Specialty Handbook *Tool Materials*) 200 GPa, ν 0.29.
  Taken: E at the top of the range, 210 GPa, because a cutting tool is hardened and
  carbide-rich (annealed bar is the low end); ν 0.29 mid-range; ρ 8150, between 8138 and 8160.
* **hss_cobalt** — AZoM, "M35 Molybdenum High Speed Tool Steel": E 207 GPa, ρ 8.14 g/cm³;
  AZoM "M42" (8 % Co): E 190–210 GPa, ν 0.27–0.30, ρ 7.81 g/cm³, while MakeItFrom gives M42
  8.2 g/cm³, 200 GPa, ν 0.29. Taken: M35, the usual cobalt grade of end mills and drills
  ("HSS-Co5", "HSS-E"): E 207 GPa, ρ 8140; ν 0.29 as for the family (M35 has no ν given).
* **tool_steel** — O1 (UNS T31501) hardened to 62 HRC (ASM data as reproduced by AZoM-type
  sheets, e.g. Colt Materials "O1 tool steel"): E 193 GPa, ρ 7.81 g/cm³; MakeItFrom
  (hardened O1) 190 GPa, ν 0.29, 7.8 g/cm³. Taken: 193 GPa, 7810 kg/m³, ν 0.29.
* **ceramic** — MakeItFrom "SiAlON" (after the Springer Handbook of Condensed Matter and
  Materials Data, 2005, and the CRC Materials Science and Engineering Handbook): E 290 GPa,
  ν 0.23, ρ 3.3 g/cm³. Solid ceramic end mills are SiAlON; whisker-reinforced alumina
  (E ≈ 390 GPa, ρ ≈ 3.7 g/cm³) is an insert grade, and an indexable tool's body is steel.
* **η** — the intrinsic loss factor of steels is 2–6·10⁻⁴ (Cremer & Heckl, *Structure-Borne
  Sound*, 1988, as tabulated in the SOLIDWORKS Simulation help "viscous damping ratios":
  iron ζ = η/2 = 1–3·10⁻⁴). An assembly's damping comes from its joints, not from the
  material; every built-in therefore keeps the contract's η = 0.002 of ``steel`` and
  ``carbide``, so that choosing a tool material changes stiffness and mass, never the
  damping assumed.
"""

from __future__ import annotations

from dataclasses import dataclass

__all__ = ["BUILTIN_MATERIALS", "Material"]


@dataclass(frozen=True, slots=True)
class Material:
    """An isotropic material.

    Parameters
    ----------
    youngs_modulus_pa : float
        Young's modulus E, Pa.
    poisson_ratio : float
        Poisson's ratio ν (−1 < ν < 0.5); the shear modulus is G = E / (2 (1 + ν)).
    density_kg_m3 : float
        Density ρ, kg/m³.
    loss_factor : float
        Hysteretic loss factor η ≥ 0 applied to E and G.
    """

    youngs_modulus_pa: float
    poisson_ratio: float
    density_kg_m3: float
    loss_factor: float = 0.0

    @property
    def shear_modulus_pa(self) -> float:
        """G = E / (2 (1 + ν)), Pa."""
        return self.youngs_modulus_pa / (2.0 * (1.0 + self.poisson_ratio))


BUILTIN_MATERIALS: dict[str, Material] = {
    "steel": Material(210.0e9, 0.30, 7850.0, 0.002),
    "carbide": Material(600.0e9, 0.22, 14500.0, 0.002),
    "hss": Material(210.0e9, 0.29, 8150.0, 0.002),
    "hss_cobalt": Material(207.0e9, 0.29, 8140.0, 0.002),
    "tool_steel": Material(193.0e9, 0.29, 7810.0, 0.002),
    "ceramic": Material(290.0e9, 0.23, 3300.0, 0.002),
}
"""Materials every request knows by name (``materials`` adds or overrides)."""
