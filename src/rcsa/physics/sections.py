"""Beam cross-sections reduced to the four numbers the solvers need.

A :class:`Section` is ``(EI, κGA, ρA, ρI)``, complex when the material is damped
(E(1+iη), G(1+iη)). Geometry → section is a separate step: hollow circles
(:func:`tube`), and parallel stacking of a holder annulus and a tool core
(:func:`composite`, ``docs/physics.md`` §2.6: EI, κGA, ρA and ρI simply add).

Shear coefficients for a (hollow) circle with m = d_i/d_o (``docs/physics.md`` §2.6):

* Hutchinson (2001): κ = 6(1+ν)²(1+m²)² / [(7+12ν+4ν²)(1+m²)² + 4(5+6ν+2ν²)m²]
* Cowper (1966):     κ = 6(1+ν)(1+m²)² / [(7+6ν)(1+m²)² + (20+12ν)m²]

An Euler–Bernoulli section has no shear flexibility and no rotary inertia; it is a
:class:`Section` with ``shear_flexibility = 0`` (i.e. κGA → ∞) and ``rho_i = 0``.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, replace
from typing import Literal, TypeVar

import numpy as np

from rcsa.errors import InputError
from rcsa.physics.arrays import ComplexArray, ComplexParam, IntArray, RealParam
from rcsa.physics.materials import Material

__all__ = [
    "BeamTheory",
    "Section",
    "ShearModel",
    "composite",
    "shear_coefficient",
    "tube",
]

ShearModel = Literal["hutchinson", "cowper"]
BeamTheory = Literal["timoshenko", "euler_bernoulli"]


@dataclass(frozen=True, slots=True)
class Section:
    """Cross-section properties per unit length.

    Each is one number, or (in a chain stacked over several tools,
    :mod:`rcsa.physics.stacking`) an array with one value per row.

    Parameters
    ----------
    ei : complex
        Bending stiffness EI, N·m² (complex with hysteretic damping).
    shear_flexibility : complex
        1/(κGA), 1/N; 0 for Euler–Bernoulli (rigid in shear).
    rho_a : float
        Mass per unit length ρA, kg/m.
    rho_i : float
        Rotary inertia per unit length ρI, kg·m; 0 for Euler–Bernoulli.
    """

    ei: ComplexParam
    shear_flexibility: ComplexParam
    rho_a: RealParam
    rho_i: RealParam

    def undamped(self) -> Section:
        """The section with real moduli: damping removed, or itself when they are real; stacked too."""
        if not np.any(np.imag(np.asarray(self.ei))) and not np.any(np.imag(np.asarray(self.shear_flexibility))):
            return self
        flex = np.asarray(self.shear_flexibility)
        with np.errstate(divide="ignore"):
            real_flex = np.where(flex == 0, 0.0, 1.0 / np.real(1.0 / np.where(flex == 0, 1.0, flex)))
        real_ei = np.asarray(np.real(self.ei), dtype=float) + 0j
        return replace(self, ei=_like(real_ei, self.ei), shear_flexibility=_like(real_flex + 0j, flex))

    def euler_bernoulli(self) -> Section:
        """The Euler–Bernoulli counterpart: no shear flexibility, no rotary inertia."""
        return replace(self, shear_flexibility=0j, rho_i=0.0)

    @property
    def is_euler_bernoulli(self) -> bool:
        """True when rigid in shear (all stacked entries)."""
        return bool(np.all(np.asarray(self.shear_flexibility) == 0))

    @classmethod
    def stack(cls, sections: Sequence[Section]) -> Section:
        """One section whose properties are arrays over ``sections``, shape (nsections,) each.

        A property equal in all of them stays one value (so equal sections stay one hashable
        section whose waves the solvers compute once).

        Parameters
        ----------
        sections : sequence of Section
            One per stacked row (tool).
        """
        return cls(_stacked([s.ei for s in sections]), _stacked([s.shear_flexibility for s in sections]),
                   _stacked([s.rho_a for s in sections]), _stacked([s.rho_i for s in sections]))

    def take_rows(self, rows: IntArray) -> Section:
        """A stacked section with its property arrays indexed by ``rows`` (scalars kept as they are).

        Parameters
        ----------
        rows : numpy.ndarray of int
            Rows (tools) to keep, in the order given.
        """
        return Section(_rows(self.ei, rows), _rows(self.shear_flexibility, rows), _rows(self.rho_a, rows),
                       _rows(self.rho_i, rows))


_P = TypeVar("_P", ComplexParam, RealParam)


def _stacked(values: Sequence[_P]) -> _P:
    """One value if all are equal scalars, else an array over them."""
    first = values[0]
    if np.ndim(first) == 0 and all(np.ndim(v) == 0 and v == first for v in values):
        return first
    return np.array(values)


def _rows(value: _P, rows: IntArray) -> _P:
    """``value[rows]`` for a per-row array, the scalar itself otherwise."""
    return value if np.ndim(value) == 0 else np.asarray(value)[rows]


def _like(value: ComplexArray, template: ComplexParam) -> ComplexParam:
    """A Python complex for scalar sections (hashable, cacheable), an array for stacked ones."""
    return complex(value) if np.ndim(template) == 0 else np.asarray(value)


def shear_coefficient(poisson_ratio: float, inner_to_outer: float = 0.0,
                      model: ShearModel | float = "hutchinson") -> float:
    """Shear coefficient κ of a (hollow) circular section.

    Parameters
    ----------
    poisson_ratio : float
        ν.
    inner_to_outer : float
        m = d_i / d_o, 0 for a solid circle.
    model : {"hutchinson", "cowper"} or float
        Formula, or a fixed number used as is.

    Returns
    -------
    float

    References
    ----------
    Hutchinson, J. Appl. Mech. 68 (2001) 87–92; Cowper, J. Appl. Mech. 33 (1966) 335–340.

    Examples
    --------
    >>> round(shear_coefficient(0.3), 6)  # 6(1.3)²/10.96 (docs/physics.md prints 0.925185, a rounding slip)
    0.925182
    >>> round(shear_coefficient(0.3, model="cowper"), 4)
    0.8864
    """
    if not isinstance(model, str):
        return float(model)
    nu, m2 = poisson_ratio, inner_to_outer**2
    a = (1.0 + m2) ** 2
    if model == "hutchinson":
        return 6.0 * (1 + nu) ** 2 * a / ((7 + 12 * nu + 4 * nu**2) * a + 4 * (5 + 6 * nu + 2 * nu**2) * m2)
    if model == "cowper":
        return 6.0 * (1 + nu) * a / ((7 + 6 * nu) * a + (20 + 12 * nu) * m2)
    raise InputError("shear_coefficient", f"must be 'hutchinson', 'cowper' or a number, got {model!r}")


def tube(outer_diameter_m: float, inner_diameter_m: float, material: Material,
         shear_model: ShearModel | float = "hutchinson",
         theory: BeamTheory = "timoshenko") -> Section:
    """Section of a hollow (or, with ``inner_diameter_m = 0``, solid) circle.

    Parameters
    ----------
    outer_diameter_m, inner_diameter_m : float
        Diameters, m; ``0 <= inner < outer``.
    material : Material
    shear_model : {"hutchinson", "cowper"} or float
    theory : {"timoshenko", "euler_bernoulli"}

    Returns
    -------
    Section
    """
    do, di = outer_diameter_m, inner_diameter_m
    area_m2 = np.pi * (do**2 - di**2) / 4.0
    inertia_m4 = np.pi * (do**4 - di**4) / 64.0
    damping = 1.0 + 1j * material.loss_factor
    e = material.youngs_modulus_pa * damping
    g = material.shear_modulus_pa * damping
    kappa = shear_coefficient(material.poisson_ratio, di / do, shear_model)
    section = Section(ei=complex(e * inertia_m4), shear_flexibility=complex(1.0 / (kappa * g * area_m2)),
                      rho_a=material.density_kg_m3 * area_m2, rho_i=material.density_kg_m3 * inertia_m4)
    return section.euler_bernoulli() if theory == "euler_bernoulli" else section


def composite(*parts: Section) -> Section:
    """Parallel stacking of sections that bend together (holder annulus + tool core).

    EI, κGA, ρA and ρI add (``docs/physics.md`` §2.6). Any Euler–Bernoulli part makes the
    composite rigid in shear.

    Parameters
    ----------
    *parts : Section
        The sections bending together, at least one.
    """
    flex: ComplexParam
    if any(p.shear_flexibility == 0 for p in parts):
        flex = 0j
    else:
        flex = 1.0 / sum(1.0 / p.shear_flexibility for p in parts)
    return Section(ei=sum(p.ei for p in parts), shear_flexibility=complex(flex),
                   rho_a=sum(p.rho_a for p in parts), rho_i=sum(p.rho_i for p in parts))
