"""The chains of an uncertainty band's draws, built stacked (one item per position, one row per draw).

A draw (:func:`rcsa.model.tolerances.perturbed_spec`) scales the materials' moduli, densities
and loss factors, the bearings and the joints, and moves the stickout. Building each draw's
assembly model from its spec (:func:`rcsa.model.draws.drawn_models`) repeats for every draw
what is the same for all — geometry, sections, shear coefficients — and costs about as much
as a prediction per 150 draws. Every number of a drawn chain is instead a simple function of
the draw's knobs and of a few nominal models:

* a beam's section properties are sums over the materials in it (a holder annulus and the
  tool core add): ``EI = Σ_m E_m(1 + iη_m) I_m`` and likewise ``κGA``, ``ρA``, ``ρI``, so
  ``EI_d = Σ_m EI_m · s_E,m (1 + iη_m s_η) / (1 + iη_m)`` with each material's part ``EI_m``
  read off a nominal model built with that material's modulus doubled (and density doubled
  for ``ρA``, ``ρI``);
* a beam's length is affine in the stickout (the tool's overhang, the holder's insertion
  split), read off models at the least and largest drawn stickout;
* bearings and joints are scaled by their knobs.

The result is checked against a draw built the plain way (the one farthest in stickout): every
number must agree to 1e-12, else — and whenever the draws' stickouts change
the chain's structure (an insertion start crossing a holder segment end), or an item is of a
kind this module does not know — the draws are built the plain way and stacked
(:func:`rcsa.physics.stacking.stack_chains`).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, replace
from types import MappingProxyType
from typing import Any

import numpy as np

from rcsa.model.assembly import AssemblyModel, build_model
from rcsa.model.contract import AssemblySpec, SpindleSpec, ToolSpec
from rcsa.model.tolerances import NuisanceDraws, perturbed_spec, shortest_stickout_m
from rcsa.physics.arrays import IntArray
from rcsa.physics.chain import Beam, Chain, ChainItem, Ground, Spring
from rcsa.physics.materials import Material
from rcsa.physics.sections import Section
from rcsa.physics.stacking import chain_signature, stack_chains, take_rows

__all__ = ["CHECK_RTOL", "DrawGroup", "DrawnChains", "drawn_chains", "stacked_from_models"]

#: Agreement required between the stacked fast build and a plain build of the same draw.
CHECK_RTOL = 1e-12


@dataclass(frozen=True)
class DrawGroup:
    """Draws of one chain structure and their chain, stacked.

    Attributes
    ----------
    draws : numpy.ndarray of int, shape (nrows,)
        The draws, in the order of the stacked rows.
    chain : Chain
        Stacked: row ``j`` is draw ``draws[j]``.
    """

    draws: IntArray
    chain: Chain


@dataclass(frozen=True)
class DrawnChains:
    """Every draw's chain, stacked by structure (usually one group).

    Attributes
    ----------
    groups : tuple of DrawGroup
    n_draws : int
    fast : bool
        Built stacked from the knobs (module docstring), not draw by draw.
    """

    groups: tuple[DrawGroup, ...]
    n_draws: int
    fast: bool = False

    def chain(self, draw: int) -> Chain:
        """One draw's chain, with scalar parameters.

        Parameters
        ----------
        draw : int
            Index of the draw.
        """
        for g in self.groups:
            hit = np.flatnonzero(g.draws == draw)
            if hit.size:
                row: Any = int(hit[0])
                return take_rows(g.chain, row)
        raise IndexError(draw)


def stacked_from_models(models: Sequence[AssemblyModel]) -> DrawnChains:
    """The drawn chains of models built one by one, stacked by structure.

    Parameters
    ----------
    models : sequence of AssemblyModel
        One per draw, in draw order.

    Returns
    -------
    DrawnChains
    """
    chains = [m.chain() for m in models]
    groups: dict[tuple[tuple[object, ...], ...], list[int]] = {}
    for i, chain in enumerate(chains):
        groups.setdefault(chain_signature(chain), []).append(i)
    return DrawnChains(tuple(DrawGroup(np.array(g), stack_chains([chains[i] for i in g])) for g in groups.values()),
                       len(chains))


def drawn_chains(spec: AssemblySpec, knobs: NuisanceDraws, base_plane: str | None = None) -> DrawnChains:
    """The chains of every draw of ``spec`` under ``knobs`` (configuration 0), stacked.

    Parameters
    ----------
    spec : AssemblySpec
        The nominal assembly.
    knobs : NuisanceDraws
    base_plane : {None, "spindle_nose", "holder_tip"}
        Plane of a measured spindle (:func:`rcsa.model.assembly.build_model`).

    Returns
    -------
    DrawnChains
        Equal, to 1e-12, to :func:`stacked_from_models` of the draws built one by one.
    """
    fast = _fast_chain(spec, knobs, base_plane)
    if fast is not None:
        return DrawnChains((DrawGroup(np.arange(knobs.n_draws), fast),), knobs.n_draws, True)
    return stacked_from_models([build_model(perturbed_spec(spec, knobs.fields(d)), base_plane)
                                for d in range(knobs.n_draws)])


def _roles(model: AssemblyModel) -> list[str] | None:
    """What each item of the model's chain is ("beam", "bearing", "sh", "ht"); None if unknown."""
    roles: list[str] = []
    for item in model.spindle:
        if isinstance(item, Beam):
            roles.append("beam")
        elif isinstance(item, Ground):
            roles.append("bearing")
        else:
            return None
    roles += ["sh"] if model.spindle_holder is not None else []
    roles += ["beam" if isinstance(item, Beam) else "?" for item in model.holder]
    roles += ["ht"] if model.holder_tool is not None else []
    roles += ["beam" if isinstance(item, Beam) else "?" for item in model.tool]
    return None if "?" in roles else roles


def _with_stickout(spec: AssemblySpec, stickout_m: float) -> AssemblySpec:
    tool: ToolSpec = replace(spec.tool, stickout_m=stickout_m)
    return replace(spec, tool=tool)


def _with_material(spec: AssemblySpec, name: str, e: float, rho: float) -> AssemblySpec:
    m = spec.materials[name]
    materials = {**spec.materials, name: Material(m.youngs_modulus_pa * e, m.poisson_ratio, m.density_kg_m3 * rho,
                                                  m.loss_factor)}
    return replace(spec, materials=MappingProxyType(materials))


def _beams(model: AssemblyModel) -> list[Beam]:
    return [item for item in model.chain() if isinstance(item, Beam)]


def _kga(section: Section) -> complex:
    flex = complex(section.shear_flexibility)
    return 0j if flex == 0 else 1.0 / flex


def _fast_chain(spec: AssemblySpec, knobs: NuisanceDraws, base_plane: str | None) -> Chain | None:
    """The stacked chain of the draws (module docstring), or None when the fast build does not apply."""
    nominal = build_model(spec, base_plane)
    roles = _roles(nominal)
    if roles is None:
        return None
    v = {name: np.asarray(values[:, 0], dtype=float) for name, values in knobs.values.items()}
    t = spec.tool
    stickouts = np.clip(t.stickout_m + v["stickout_offset_m"], shortest_stickout_m(t), t.overall_length_m)
    s_lo, s_hi = float(np.min(stickouts)), float(np.max(stickouts))
    ends = [build_model(_with_stickout(spec, s), base_plane) for s in (s_lo, s_hi)]
    signature = chain_signature(nominal.chain())
    if any(chain_signature(m.chain()) != signature for m in ends):
        return None
    beams0, beams_lo, beams_hi = _beams(nominal), _beams(ends[0]), _beams(ends[1])
    if any(a.section != b.section or a.section != c.section for a, b, c in zip(beams0, beams_lo, beams_hi,
                                                                                strict=True)):
        return None
    lengths = _lengths(beams_lo, beams_hi, s_lo, s_hi, stickouts)
    parts = _material_parts(spec, base_plane, beams0, t.material)
    if parts is None:
        return None
    sections = _sections(beams0, parts, v)
    chain = _assemble(nominal.chain(), roles, sections, lengths, v)
    checks = [int(np.argmax(np.abs(v["stickout_offset_m"])))]
    for d in checks:  # the fast build must reproduce a plain build
        plain = build_model(perturbed_spec(spec, knobs.fields(d)), base_plane).chain()
        row: Any = d
        if not _same(take_rows(chain, row), plain):
            return None
    return chain


def _lengths(lo: list[Beam], hi: list[Beam], s_lo: float, s_hi: float, stickouts: np.ndarray) -> list[np.ndarray]:
    """Each beam's length per draw, affine in the stickout between the two end models."""
    if s_hi - s_lo <= 0.0:
        return [np.full(stickouts.size, float(b.length_m)) for b in lo]
    x = (stickouts - s_lo) / (s_hi - s_lo)
    return [float(a.length_m) + x * (float(b.length_m) - float(a.length_m)) for a, b in zip(lo, hi, strict=True)]


@dataclass(frozen=True)
class _Part:
    """One material's share of every beam's section (index: the beam)."""

    ei: np.ndarray
    kga: np.ndarray
    rho_a: np.ndarray
    rho_i: np.ndarray
    loss_factor: float
    is_tool: bool


def _material_parts(spec: AssemblySpec, base_plane: str | None, beams0: list[Beam], tool_material: str
                    ) -> list[_Part] | None:
    """Each material's part of the beams' EI, κGA, ρA, ρI (their sums must give the nominal)."""
    ei0 = np.array([complex(b.section.ei) for b in beams0])
    kga0 = np.array([_kga(b.section) for b in beams0])
    ra0 = np.array([float(b.section.rho_a) for b in beams0])
    ri0 = np.array([float(b.section.rho_i) for b in beams0])
    used = {spec.tool.material, *(seg.material for seg in (spec.holder.segments if spec.holder is not None else ())),
            *(seg.material for seg in (spec.spindle.segments if isinstance(spec.spindle, SpindleSpec) else ()))}
    parts = []
    for name in sorted(used):  # a loop over the few materials of the assembly
        material = spec.materials[name]
        stiff = _beams(build_model(_with_material(spec, name, 2.0, 1.0), base_plane))
        heavy = _beams(build_model(_with_material(spec, name, 1.0, 2.0), base_plane))
        if len(stiff) != len(beams0) or len(heavy) != len(beams0):
            return None
        ei = np.array([complex(b.section.ei) for b in stiff]) - ei0
        kga = np.array([_kga(b.section) for b in stiff]) - kga0
        ra = np.array([float(b.section.rho_a) for b in heavy]) - ra0
        ri = np.array([float(b.section.rho_i) for b in heavy]) - ri0
        if np.any(ei) or np.any(kga) or np.any(ra) or np.any(ri):
            parts.append(_Part(ei, kga, ra, ri, material.loss_factor, name == tool_material))
    total = [sum((getattr(p, f) for p in parts), np.zeros(len(beams0))) for f in ("ei", "kga", "rho_a", "rho_i")]
    for got, want in zip(total, (ei0, kga0, ra0, ri0), strict=True):
        if not np.allclose(got, want, rtol=CHECK_RTOL, atol=0.0):
            return None
    return parts


def _sections(beams0: list[Beam], parts: list[_Part], v: dict[str, np.ndarray]) -> list[Section]:
    """Every beam's section per draw from the material parts and the knobs."""
    n = v["loss_factor_scale"].size
    nb = len(beams0)
    ei = np.zeros((nb, n), dtype=complex)
    kga = np.zeros((nb, n), dtype=complex)
    rho_a = np.zeros((nb, n))
    rho_i = np.zeros((nb, n))
    for p in parts:  # a loop over the few materials
        e = v["tool_youngs_scale" if p.is_tool else "structure_youngs_scale"]
        rho = v["tool_density_scale" if p.is_tool else "structure_density_scale"]
        factor = e * (1.0 + 1j * p.loss_factor * v["loss_factor_scale"]) / (1.0 + 1j * p.loss_factor)
        ei += p.ei[:, None] * factor
        kga += p.kga[:, None] * factor
        rho_a += p.rho_a[:, None] * rho
        rho_i += p.rho_i[:, None] * rho
    out = []
    for j, beam in enumerate(beams0):
        rigid_in_shear = complex(beam.section.shear_flexibility) == 0
        flex = np.zeros(n, dtype=complex) if rigid_in_shear else 1.0 / kga[j]
        out.append(Section(_collapse(ei[j]), _collapse(flex), _collapse(rho_a[j]), _collapse(rho_i[j])))
    return out


def _collapse(a: np.ndarray) -> Any:
    """One value when every row holds it (so equal sections stay hashable and shared), else the array."""
    return a[0].item() if np.all(a == a[0]) else a


def _assemble(chain0: Chain, roles: list[str], sections: list[Section], lengths: list[np.ndarray],
              v: dict[str, np.ndarray]) -> Chain:
    """The stacked chain: beams from ``sections``/``lengths``, bearings and joints scaled."""
    out: list[ChainItem] = []
    beam = 0
    for item, role in zip(chain0, roles, strict=True):
        if role == "beam":
            out.append(Beam(sections[beam], lengths[beam]))
            beam += 1
        elif role == "bearing":
            assert isinstance(item, Ground)
            k, c = v["bearing_stiffness_scale"], v["bearing_damping_scale"]
            out.append(Ground(item.stiffness_n_m * k, item.damping_ns_m * c, item.rotational_stiffness_nm_rad * k,
                              item.rotational_damping_nms_rad * c, item.mass_kg * np.ones(k.size),
                              item.rotary_inertia_kg_m2 * np.ones(k.size)))
        else:
            assert isinstance(item, Spring)
            kt, kr, c = (v[f"{role}_translational_scale"], v[f"{role}_rotational_scale"], v[f"{role}_damping_scale"])
            out.append(Spring(None if item.stiffness_n_m is None else item.stiffness_n_m * kt,
                              item.damping_ns_m * c,
                              None if item.rotational_stiffness_nm_rad is None else item.rotational_stiffness_nm_rad * kr,
                              item.rotational_damping_nms_rad * c))
    return tuple(out)


def _numbers(item: ChainItem) -> list[Any]:
    """Every number of an item (section properties and length of a beam, fields of a lumped one)."""
    if isinstance(item, Beam):
        s = item.section
        return [s.ei, s.shear_flexibility, s.rho_a, s.rho_i, item.length_m]
    values: dict[str, Any] = {name: getattr(item, name) for name in item.__dataclass_fields__}  # type: ignore[attr-defined]
    return list(values.values())


def _same(a: Chain, b: Chain) -> bool:
    """Two chains of one structure whose numbers agree to :data:`CHECK_RTOL`."""
    if chain_signature(a) != chain_signature(b):
        return False
    for x, y in zip(a, b, strict=True):
        for p, q in zip(_numbers(x), _numbers(y), strict=True):
            if (p is None) != (q is None):
                return False
            if p is not None and not np.allclose(np.asarray(p), np.asarray(q), rtol=CHECK_RTOL, atol=0.0):
                return False
    return True
