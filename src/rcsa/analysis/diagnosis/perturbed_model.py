"""The base model with its knobs turned: nuisance tolerances and candidate effects.

Everything the diagnosis varies — a material's modulus within its grade tolerance, a
re-clamped joint, a sensor on the tip, an effective clamping point inside the holder — is a
field of one frozen :class:`Knobs` value. :class:`PartsBuilder` turns (base assembly, one
measurement's tool, knobs) into the three sub-chains that are solved one after the other::

    analytical:             spindle (rear → nose, bearings) | nose corrections, SH joint, holder | HT joint, tool, tip mass
    measured, spindle_nose: (measured receptance)           | nose corrections, SH joint, holder | HT joint, tool, tip mass
    measured, holder_tip:   (measured receptance)           | corrections at the holder tip      | HT joint, tool, tip mass

and :class:`Solver` condenses them item by item (each chain item's own elimination step; a
measured receptance is absorbed, never inverted), keeping the condensed state after the
spindle and after the middle sub-chain and each beam's stiffness terms in the one
subassembly cache (:class:`rcsa.physics.subassembly_cache.SubassemblyCache`). The builder hands
out the very same sub-chain objects for equal inputs, so a change of a tool-side knob costs
three beams per measurement, not the twenty of the whole chain.

Modelling of the effect knobs (the candidates' own formulas; the benchmark's truth uses
different, physical realisations, see ``tests/analysis/diagnosis/truth.py``):

* ``shear_scale`` multiplies the shear flexibility 1/(κGA) and the rotary inertia ρI of every
  Timoshenko section (0 = Euler–Bernoulli, 1 = Timoshenko with the assembly's κ).
* ``fluted_stiffness_ratio`` / ``fluted_mass_ratio`` are the fluted section's equivalent
  diameters over DC for EI (and ρI) and for ρA (``docs/physics.md`` §5.1).
* ``tip_mass_kg`` is a point mass (no rotary inertia) on the tool, ``tip_mass_distance_m``
  behind the tip (the last beam is split there).
* ``insertion_offset_m`` moves the clamping point that far into the holder: the holder's last
  δ of length is cut off the chain, its annulus is lumped as a mass and rotary inertia on the
  new holder end (the w–ψ coupling of the offset centre is neglected), and the tool's free
  length grows by δ (its overall length is unchanged).
* ``nose_cross_compliance_rad_n`` / ``nose_rotational_residual_rad_nm`` add a residual
  compliance ``[[0, c_wψ], [c_wψ, c_ψψ]]`` to the spindle's receptance at its nose (before the
  spindle–holder joint), or to a measured receptance at its plane: the rotational receptances
  l = n and p are off by a frequency-independent amount (the residual-compensation form of
  Duarte & Ewins 2000; :class:`~rcsa.analysis.diagnosis.chain_items.AddedCompliance`).
* ``base_rotation_scale`` s and ``base_rotation_shape`` c scale the rotational entries of
  the spindle's receptance (l, n × s, p × s²c;
  :class:`~rcsa.analysis.diagnosis.chain_items.RotationRescale`): for a ``direct_frf``
  spindle, whose rotations are an equivalent-cantilever estimate, the estimate with effective
  length L/s instead of L and shape PH/N² = 4c/3 instead of 4/3.
* At ``holder_tip`` the holder is inside the measurement: ``insertion_offset_m`` only
  lengthens the tool's free length (the holder's annulus over δ is part of the measurement).
* With a holder–tool clamping along the insertion (model ``bonded``/``contact``) the holder-tool
  knobs act on the clamping, which belongs to the holder chain: ``ht_translational_scale``
  scales its whole interface stiffness (softening over the insertion), ``ht_damping_scale``
  its interface loss factor (``ht_interface_loss_added`` adds to it: a bonded clamping has none
  of its own), and ``insertion_offset_m`` is contact lost over that length
  at the front of the bore (its ``front_gap_length_m``): holder and tool keep their geometry.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace

import numpy as np

from rcsa.analysis.diagnosis.chain_items import AddedCompliance, CachedInsertion, RotationRescale
from rcsa.model.assembly import holder_chain, joint_spring, spindle_chain, tool_chain
from rcsa.model.contract import (
    AssemblySpec,
    BearingSpec,
    ClampingSpec,
    HolderSpec,
    SegmentSpec,
    SpindleSpec,
    ToolSpec,
)
from rcsa.model.tolerances import scaled_joint
from rcsa.physics.arrays import ComplexArray, FloatArray, IntArray
from rcsa.physics.chain import Beam, Chain, ChainItem, Ground
from rcsa.physics.insertion import Insertion
from rcsa.physics.materials import Material
from rcsa.physics.sections import BeamTheory, Section, ShearModel
from rcsa.physics.subassembly_cache import Condensed, LruStore, SubassemblyCache

__all__ = ["AddedCompliance", "BaseReceptance", "Knobs", "Parts", "PartsBuilder", "RotationRescale", "Solver",
           "config_parts", "null_shear_scale"]


@dataclass(frozen=True, slots=True)
class Knobs:
    """Deviations from the base model; the defaults reproduce it exactly.

    Scales are dimensionless multipliers of the base value; ``None`` means "as in the base".
    """

    tool_youngs_scale: float = 1.0
    tool_density_scale: float = 1.0
    structure_youngs_scale: float = 1.0
    structure_density_scale: float = 1.0
    loss_factor_scale: float = 1.0
    bearing_stiffness_scale: float = 1.0
    bearing_damping_scale: float = 1.0
    sh_translational_scale: float = 1.0
    sh_rotational_scale: float = 1.0
    sh_damping_scale: float = 1.0
    ht_translational_scale: float = 1.0
    ht_rotational_scale: float = 1.0
    ht_damping_scale: float = 1.0
    ht_interface_loss_added: float = 0.0
    stickout_offset_m: float = 0.0
    shear_scale: float | None = None
    fluted_stiffness_ratio: float | None = None
    fluted_mass_ratio: float | None = None
    tip_mass_kg: float = 0.0
    tip_mass_distance_m: float = 0.0
    insertion_offset_m: float = 0.0
    nose_cross_compliance_rad_n: float = 0.0
    nose_rotational_residual_rad_nm: float = 0.0
    base_rotation_scale: float = 1.0
    base_rotation_shape: float = 1.0


def null_shear_scale(spec: AssemblySpec) -> float:
    """The ``shear_scale`` that reproduces the base: 0 for Euler–Bernoulli, 1 for Timoshenko."""
    return 0.0 if spec.beam_theory == "euler_bernoulli" else 1.0


def _materials(spec: AssemblySpec, k: Knobs) -> Mapping[str, Material]:
    out = {}
    for name, m in spec.materials.items():
        tool = name == spec.tool.material
        e = k.tool_youngs_scale if tool else k.structure_youngs_scale
        rho = k.tool_density_scale if tool else k.structure_density_scale
        out[name] = Material(m.youngs_modulus_pa * e, m.poisson_ratio, m.density_kg_m3 * rho,
                             m.loss_factor * k.loss_factor_scale)
    return out


def _spindle(spindle: SpindleSpec, k: Knobs) -> SpindleSpec:
    bearings = tuple(BearingSpec(b.position_m, b.stiffness_n_m * k.bearing_stiffness_scale,
                                 b.damping_ns_m * k.bearing_damping_scale,
                                 b.rotational_stiffness_nm_rad * k.bearing_stiffness_scale,
                                 b.rotational_damping_nms_rad * k.bearing_damping_scale)
                     for b in spindle.bearings)
    return SpindleSpec(spindle.segments, bearings)


def _trim_holder(holder: HolderSpec, cut_m: float, materials: Mapping[str, Material]
                 ) -> tuple[HolderSpec, Ground | None]:
    """Cut ``cut_m`` off the holder's tool end; return the rest and the cut annulus as a lumped body.

    The body's rotary inertia is taken about the new holder end: ρIℓ + m(e² + ℓ²/12) per piece,
    e the distance of the piece's centre from that end.
    """
    if cut_m <= 0.0:
        return holder, None
    keep: list[SegmentSpec] = []
    remaining = holder.length_m - cut_m
    mass_kg = inertia_kg_m2 = 0.0
    x0 = 0.0
    for seg in holder.segments:
        x1 = x0 + seg.length_m
        kept = min(max(remaining - x0, 0.0), seg.length_m)
        if kept > 1e-12:
            keep.append(replace(seg, length_m=kept))
        lost = seg.length_m - kept
        if lost > 1e-12:
            rho = materials[seg.material].density_kg_m3
            area = np.pi * (seg.outer_diameter_m**2 - seg.inner_diameter_m**2) / 4.0
            second = np.pi * (seg.outer_diameter_m**4 - seg.inner_diameter_m**4) / 64.0
            m = rho * area * lost
            e = max(x0, remaining) + lost / 2.0 - remaining
            mass_kg += m
            inertia_kg_m2 += rho * second * lost + m * (e**2 + lost**2 / 12.0)
        x0 = x1
    return HolderSpec(tuple(keep)), Ground(mass_kg=mass_kg, rotary_inertia_kg_m2=inertia_kg_m2)


def _scale_shear(chain: Chain, s: float) -> Chain:
    def scaled(sec: Section) -> Section:
        return Section(sec.ei, complex(sec.shear_flexibility * s), sec.rho_a, sec.rho_i * s)

    return tuple(item.map_sections(scaled) for item in chain)


#: Spindle, holder and tool chains built from specs, by their arguments (each is built once
#: across the problems of a process; the chains are immutable).
_CHAINS: LruStore[tuple[object, ...], Chain] = LruStore(768)


def _spindle_chain(spindle: SpindleSpec, mats: tuple[tuple[str, Material], ...], shear: ShearModel | float,
                   theory: BeamTheory) -> Chain:
    return _CHAINS.get(("spindle", spindle, mats, shear, theory),
                       lambda: spindle_chain(spindle, dict(mats), shear, theory))


def _holder_chain(holder: HolderSpec, tool: ToolSpec, mats: tuple[tuple[str, Material], ...], shear: ShearModel | float,
                  theory: BeamTheory, clamping: ClampingSpec | None = None) -> Chain:
    return _CHAINS.get(("holder", holder, tool, mats, shear, theory, clamping),
                       lambda: holder_chain(holder, tool, dict(mats), shear, theory, clamping))


def _tool_chain(tool: ToolSpec, mats: tuple[tuple[str, Material], ...], shear: ShearModel | float,
                theory: BeamTheory) -> Chain:
    return _CHAINS.get(("tool", tool, mats, shear, theory), lambda: tool_chain(tool, dict(mats), shear, theory))


def _with_mass(chain: list[ChainItem], mass_kg: float, distance_m: float) -> list[ChainItem]:
    """A point mass ``distance_m`` behind the chain's end (splits the beam it falls on)."""
    if distance_m <= 0.0:
        return [*chain, Ground(mass_kg=mass_kg)]
    out = list(chain)
    left = distance_m
    for i in range(len(out) - 1, -1, -1):
        item = out[i]
        if isinstance(item, Beam):
            if left < item.length_m:
                return [*out[:i], Beam(item.section, item.length_m - left), Ground(mass_kg=mass_kg),
                        Beam(item.section, left), *out[i + 1:]]
            left -= float(item.length_m)
    raise ValueError("tip mass lies beyond the tool")



class BaseReceptance:
    """A measured spindle's receptance at its plane, on the solver's grid.

    Compared and hashed by identity: the solver caches what is condensed on it, and every
    Monte-Carlo draw of the spindle is its own object.

    Parameters
    ----------
    compliance : numpy.ndarray, shape (nfreq, 2, 2), complex
        ``[[h, l], [n, p]]`` (m/N, m/(N·m), rad/N, rad/(N·m)); stored read-only.
    """

    __slots__ = ("compliance",)

    def __init__(self, compliance: ComplexArray) -> None:
        c = np.array(compliance, dtype=complex)
        c.flags.writeable = False
        self.compliance = c


@dataclass(frozen=True, slots=True)
class Parts:
    """The sub-chains of one configuration (see the module docstring).

    ``spindle`` is empty and ``base`` set for a measured spindle (the chain starts from its
    receptance); ``base`` is None for an analytical one.
    """

    spindle: Chain
    middle: Chain
    tool: Chain
    base: BaseReceptance | None = None


#: Sub-chains kept per builder and kind (materials, spindles, middles, tails).
_MAX_CACHED = 4096


class PartsBuilder:
    """Sub-chains of the base assembly with knobs applied, each built once per distinct input.

    The spindle, middle and tool sub-chains are cached under the knobs that change them, so
    configurations that differ only on the tool side share the very same spindle and middle
    objects (the :class:`Solver` caches their condensation by identity).

    Parameters
    ----------
    spec : AssemblySpec
        Base assembly.
    plane : {None, "spindle_nose", "holder_tip"}
        ``None`` for an analytical spindle; for a measured one, the plane of its receptance:
        at ``spindle_nose`` the spindle–holder joint and the holder are modelled, at
        ``holder_tip`` only the tool (its clamping and the holder are inside the measurement).
    base : BaseReceptance, optional
        The measured spindle's receptance (default base of every configuration).
    """

    def __init__(self, spec: AssemblySpec, plane: str | None = None, base: BaseReceptance | None = None) -> None:
        if plane is None and (not isinstance(spec.spindle, SpindleSpec) or spec.holder is None):
            raise TypeError("an analytical diagnosis needs an analytical spindle and a holder")
        if plane == "spindle_nose" and spec.holder is None:
            raise TypeError("a spindle_nose base needs a holder")
        self.spec, self.plane, self.base = spec, plane, base
        # the package's one eviction policy: the sub-chains are shared by identity (the Solver's
        # cache keys), so a kept one stays the very same object until it is the least recently used
        self._mats: LruStore[tuple[float, ...], tuple[tuple[str, Material], ...]] = LruStore(_MAX_CACHED)
        self._spindles: LruStore[tuple[object, ...], Chain] = LruStore(_MAX_CACHED)
        self._middles: LruStore[tuple[object, ...], Chain] = LruStore(_MAX_CACHED)
        self._tails: LruStore[tuple[object, ...], Chain] = LruStore(_MAX_CACHED)

    def parts(self, tool: ToolSpec, k: Knobs, base: BaseReceptance | None = None) -> Parts:
        """Sub-chains of the configuration with ``tool`` under ``k`` (on ``base``, default the builder's)."""
        spec = self.spec
        mkey = (k.tool_youngs_scale, k.tool_density_scale, k.structure_youngs_scale, k.structure_density_scale,
                k.loss_factor_scale)
        mats = self._mats.get(mkey, lambda: tuple(sorted(_materials(spec, k).items())))
        s = null_shear_scale(spec) if k.shear_scale is None else k.shear_scale
        theory: BeamTheory = "euler_bernoulli" if (spec.beam_theory == "euler_bernoulli" and s == 0.0) else "timoshenko"
        scale = 1.0 if theory == "euler_bernoulli" else s
        shear = spec.shear_coefficient

        def shear_scaled(chain: Sequence[ChainItem]) -> Chain:
            return tuple(chain) if scale == 1.0 else _scale_shear(tuple(chain), scale)

        spindle: Chain = ()
        if self.plane is None:
            assert isinstance(spec.spindle, SpindleSpec)
            sp = spec.spindle
            spindle = self._spindles.get((mkey, s, k.bearing_stiffness_scale, k.bearing_damping_scale),
                                         lambda: shear_scaled(_spindle_chain(_spindle(sp, k), mats, shear, theory)))
        # a clamping along the insertion belongs to the holder chain, with the holder-tool knobs
        clamping = scaled_joint(spec.holder_tool, k.ht_translational_scale, k.ht_rotational_scale,
                                k.ht_damping_scale) if isinstance(spec.holder_tool, ClampingSpec) else None
        if clamping is not None and k.ht_interface_loss_added != 0.0:
            clamping = replace(clamping, interface_loss_factor=clamping.interface_loss_factor
                               + k.ht_interface_loss_added)
        front_gap = clamping is not None and self.plane != "holder_tip"
        if front_gap and k.insertion_offset_m > 0.0:
            assert isinstance(clamping, ClampingSpec)
            clamping = replace(clamping, front_gap_length_m=clamping.front_gap_length_m + k.insertion_offset_m)
        stickout = tool.stickout_m + k.stickout_offset_m + (0.0 if front_gap else k.insertion_offset_m)
        r_i = tool.fluted_diameter_ratio if k.fluted_stiffness_ratio is None else k.fluted_stiffness_ratio
        r_a = tool.fluted_mass_diameter_ratio if k.fluted_mass_ratio is None else k.fluted_mass_ratio
        made: list[ToolSpec] = []

        def tool_of() -> ToolSpec:  # the tool with its knobs, built only when a sub-chain is (a cache miss)
            if not made:
                made.append(replace(tool, stickout_m=stickout, fluted_diameter_ratio=r_i,
                                    fluted_mass_diameter_ratio=r_a))
            return made[0]

        def middle() -> Chain:
            items: list[ChainItem] = []
            if k.base_rotation_scale != 1.0 or k.base_rotation_shape != 1.0:
                items.append(RotationRescale(k.base_rotation_scale, k.base_rotation_shape))
            if k.nose_cross_compliance_rad_n != 0.0 or k.nose_rotational_residual_rad_nm != 0.0:
                items.append(AddedCompliance(k.nose_cross_compliance_rad_n, k.nose_rotational_residual_rad_nm))
            if self.plane == "holder_tip":
                return tuple(items)
            assert spec.holder is not None
            holder, ring = _trim_holder(spec.holder, 0.0 if front_gap else k.insertion_offset_m, dict(mats))
            sh = joint_spring(scaled_joint(spec.spindle_holder, k.sh_translational_scale, k.sh_rotational_scale,
                                           k.sh_damping_scale))
            if sh is not None:
                items.append(sh)
            items.extend(CachedInsertion(item) if isinstance(item, Insertion) else item
                         for item in shear_scaled(_holder_chain(holder, tool_of(), mats, shear, theory, clamping)))
            if ring is not None:
                items.append(ring)
            return tuple(items)

        mid_key: tuple[object, ...] = (mkey, s, k.base_rotation_scale, k.base_rotation_shape, k.nose_cross_compliance_rad_n,
                   k.nose_rotational_residual_rad_nm, clamping)
        if self.plane != "holder_tip":
            assert spec.holder is not None
            # the holder chain sees the tool only through the inserted length inside the (trimmed) holder
            filled = round(min(tool.overall_length_m - stickout,
                               spec.holder.length_m - (0.0 if front_gap else k.insertion_offset_m)), 12)
            mid_key += (k.sh_translational_scale, k.sh_rotational_scale, k.sh_damping_scale, k.insertion_offset_m,
                        filled, tool.shank_diameter_m, tool.material)
        mid = self._middles.get(mid_key, middle)

        def tail() -> Chain:
            items: list[ChainItem] = []
            ht = joint_spring(scaled_joint(spec.holder_tool, k.ht_translational_scale, k.ht_rotational_scale,
                                           k.ht_damping_scale))
            if ht is not None:
                items.append(ht)
            items.extend(shear_scaled(_tool_chain(tool_of(), mats, shear, theory)))
            if k.tip_mass_kg > 0.0:
                items = _with_mass(items, k.tip_mass_kg, k.tip_mass_distance_m)
            return tuple(items)

        tail_key = (mkey, s, tool, stickout, r_i, r_a, k.ht_translational_scale, k.ht_rotational_scale, k.ht_damping_scale,
                    k.tip_mass_kg, k.tip_mass_distance_m)
        return Parts(spindle, mid, self._tails.get(tail_key, tail), self.base if base is None else base)


def config_parts(spec: AssemblySpec, tool: ToolSpec, k: Knobs, plane: str | None = None,
                 base: BaseReceptance | None = None) -> Parts:
    """Sub-chains of the base assembly with ``tool`` and the knobs applied.

    Parameters
    ----------
    spec : AssemblySpec
        Base assembly (analytical spindle, or a measured one with ``plane`` and ``base``).
    tool : ToolSpec
        The measurement's tool (base tool with its overrides).
    k : Knobs
    plane : {None, "spindle_nose", "holder_tip"}
        See :class:`PartsBuilder`.
    base : BaseReceptance, optional
        The measured spindle's receptance.

    Returns
    -------
    Parts
    """
    return PartsBuilder(spec, plane, base).parts(tool, k)


class Solver:
    """Tool-point ``h`` of many configurations on one frequency grid, with caches.

    The chain is condensed from the spindle rear (or a measured spindle's receptance at its
    plane) to the tool tip, each item doing its own elimination step
    (:meth:`rcsa.physics.chain.ChainItem.eliminate`, and
    :meth:`~rcsa.physics.chain.ChainItem.absorb_compliance` on a measured base, which is never
    inverted), on one :class:`~rcsa.physics.subassembly_cache.SubassemblyCache`: the condensed
    state after the spindle and after the middle sub-chain (found by the identity of the base
    and of the sub-chain objects, which :class:`PartsBuilder` shares), and the six stiffness
    terms of each beam (keyed by section and length), so a changed joint or tool re-uses every
    beam. What the cache hands out is read-only; nothing is copied to stay safe.

    Parameters
    ----------
    frequency_hz : numpy.ndarray, shape (nfreq,)
        The common (union) analysis grid, Hz.
    cache_size : int
        Condensed states kept (least recently used are dropped); beam terms keep 4×.
    """

    def __init__(self, frequency_hz: FloatArray, cache_size: int = 128) -> None:
        self.frequency_hz = np.asarray(frequency_hz, dtype=float)
        self.omega_rad_s = 2.0 * np.pi * self.frequency_hz
        self._cache = SubassemblyCache(self.omega_rad_s, max_states=cache_size, max_beams=4 * cache_size)
        self.evaluations = 0

    def _state(self, parts: Parts) -> Condensed:
        """Condensed state after the spindle and the middle sub-chain (cached by identity)."""
        base = None if parts.base is None else parts.base.compliance
        return self._cache.condensed((parts.spindle, parts.middle), base)

    def tip_h(self, parts: Parts, lines: IntArray | slice = slice(None)) -> ComplexArray:
        """Driving-point tool-tip receptance ``h`` (m/N), shape (nlines,)."""
        h = self._cache.tip_h(self._state(parts), parts.tool)
        self.evaluations += 1
        return h[lines]

    def tip_h_many(self, parts: Sequence[Parts], lines: IntArray | slice = slice(None)) -> ComplexArray:
        """:meth:`tip_h` of many configurations, shape (n, nlines)."""
        return np.stack([self.tip_h(p, lines) for p in parts])

    def nose_stiffness(self, parts: Parts) -> ComplexArray:
        """Condensed dynamic stiffness of an analytical spindle at its nose, shape (nfreq, 2, 2), read-only."""
        k = self._cache.condensed((parts.spindle,)).stiffness
        assert k is not None
        return k
