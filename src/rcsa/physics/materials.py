"""Linear-elastic isotropic materials with hysteretic damping.

Built-ins follow ``contract.md``: ``steel`` (E 210 GPa, ν 0.30, ρ 7850 kg/m³, η 0.002) and
``carbide`` (E 600 GPa, ν 0.22, ρ 14500 kg/m³, η 0.002). A hysteretic loss factor η damps
both moduli as E(1 + iη), G(1 + iη) (``domain.md`` §2.6).
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
}
