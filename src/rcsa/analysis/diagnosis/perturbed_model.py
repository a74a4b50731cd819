"""The base model with its knobs turned: nuisance tolerances and candidate effects.

Everything the diagnosis varies — a material's modulus within its grade tolerance, a
re-clamped joint, a sensor on the tip, an effective clamping point inside the holder — is a
field of one frozen :class:`Knobs` value. :func:`config_parts` turns (base assembly, one
measurement's tool, knobs) into the three sub-chains that are solved one after the other::

    spindle (rear → nose, bearings)  |  nose residual, SH joint, holder  |  HT joint, tool, tip mass

and :class:`Solver` condenses them with :func:`rcsa.physics.elimination.march`, caching each condensed
stiffness under the sub-chain itself (chain items are frozen and hashable) and each beam's
stiffness terms. A change of a tool-side knob then costs three beams per measurement, not
the twenty of the whole chain.

Modelling of the effect knobs (the candidates' own formulas; the benchmark's truth uses
different, physical realisations, see ``tests/analysis/diagnosis/truth.py``):

* ``shear_scale`` multiplies the shear flexibility 1/(κGA) and the rotary inertia ρI of every
  Timoshenko section (0 = Euler–Bernoulli, 1 = Timoshenko with the assembly's κ).
* ``fluted_stiffness_ratio`` / ``fluted_mass_ratio`` are the fluted section's equivalent
  diameters over DC for EI (and ρI) and for ρA (``domain.md`` §5.1).
* ``tip_mass_kg`` is a point mass (no rotary inertia) on the tool, ``tip_mass_distance_m``
  behind the tip (the last beam is split there).
* ``insertion_offset_m`` moves the clamping point that far into the holder: the holder's last
  δ of length is cut off the chain, its annulus is lumped as a mass and rotary inertia on the
  new holder end (the w–ψ coupling of the offset centre is neglected), and the tool's free
  length grows by δ (its overall length is unchanged).
* ``nose_cross_compliance_rad_n`` / ``nose_rotational_residual_rad_nm`` add a residual
  compliance ``[[0, c_wψ], [c_wψ, c_ψψ]]`` to the spindle's receptance at its nose (before the
  spindle–holder joint): the spindle's rotational receptances l = n and p are off by a
  frequency-independent amount (the residual-compensation form of Duarte & Ewins 2000).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, replace
from functools import lru_cache

import numpy as np

from rcsa.model.assembly import holder_chain, joint_spring, spindle_chain, tool_chain
from rcsa.model.contract import (
    AssemblySpec,
    BearingSpec,
    HolderSpec,
    JointSpec,
    SegmentSpec,
    SpindleSpec,
    ToolSpec,
)
from rcsa.physics.arrays import ComplexArray, FloatArray, IntArray
from rcsa.physics.chain import Beam, Chain, ChainItem, Grid, Ground, Lumped, Sym
from rcsa.physics.elimination import march
from rcsa.physics.materials import Material
from rcsa.physics.sections import Section
from rcsa.physics.segments import SixTerms, segment_terms

__all__ = ["Knobs", "Parts", "Solver", "config_parts", "null_shear_scale"]


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
    stickout_offset_m: float = 0.0
    shear_scale: float | None = None
    fluted_stiffness_ratio: float | None = None
    fluted_mass_ratio: float | None = None
    tip_mass_kg: float = 0.0
    tip_mass_distance_m: float = 0.0
    insertion_offset_m: float = 0.0
    nose_cross_compliance_rad_n: float = 0.0
    nose_rotational_residual_rad_nm: float = 0.0


@dataclass(frozen=True, slots=True)
class AddedCompliance(Lumped):
    """A residual compliance added to the receptance at this node: R → R + [[0, c_wψ], [c_wψ, c_ψψ]].

    ``c_wψ`` in rad/N (= m/(N·m)), ``c_ψψ`` in rad/(N·m). A correction term of the kind used to
    compensate truncated or estimated rotational receptances (Duarte & Ewins 2000), not a spring.
    A chain item (:class:`rcsa.physics.chain.ChainItem`): frequency-independent and undamped,
    it eliminates no node.

    Parameters
    ----------
    cross_rad_n : float
        ``c_wψ``, rad/N.
    rotational_rad_nm : float
        ``c_ψψ``, rad/(N·m).
    """

    cross_rad_n: float
    rotational_rad_nm: float

    def eliminate(self, k: Sym, grid: Grid, count: bool = False) -> tuple[Sym, IntArray | None]:
        """``K ← (K⁻¹ + C)⁻¹`` with ``C = [[0, c_wψ], [c_wψ, c_ψψ]]``; no pivot."""
        k11, k12, k22 = k
        det = k11 * k22 - k12 * k12
        r11, r12, r22 = k22 / det, -k12 / det + self.cross_rad_n, k11 / det + self.rotational_rad_nm
        det_r = r11 * r22 - r12 * r12
        return (r22 / det_r, -r12 / det_r, r11 / det_r), None

    def eliminate_static(self, k: Sym) -> Sym:
        """The same as :meth:`eliminate`: the compliance does not depend on frequency."""
        return self.eliminate(k, Grid(np.zeros(1)))[0]

    def absorb_compliance(self, compliance: ComplexArray, grid: Grid) -> tuple[ComplexArray, bool]:
        """``S ← S + C``."""
        c = np.array([[0.0, self.cross_rad_n], [self.cross_rad_n, self.rotational_rad_nm]])
        return compliance + c, False

    def undamped(self) -> AddedCompliance:
        """Real already: itself."""
        return self


class _BeamTermsGrid(Grid):
    """A grid that keeps the six stiffness terms of the most recently used beams."""

    def __init__(self, omega_rad_s: FloatArray, max_beams: int) -> None:
        super().__init__(omega_rad_s)
        self._terms = lru_cache(maxsize=max_beams)(self._segment_terms)

    def _segment_terms(self, beam: Beam) -> SixTerms:
        return segment_terms(self.omega_rad_s, beam.section, beam.length_m)

    def beam_terms(self, beam: Beam) -> SixTerms:
        """Six-term dynamic stiffness of ``beam``, cached by beam (section and length)."""
        return self._terms(beam)


@dataclass(frozen=True, slots=True)
class Parts:
    """The three sub-chains of one configuration (see the module docstring)."""

    spindle: Chain
    middle: Chain
    tool: Chain


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


def _joint(joint: JointSpec | None, kt: float, kr: float, c: float) -> JointSpec | None:
    if joint is None:
        return None
    return JointSpec(joint.stiffness_n_m * kt, joint.damping_ns_m * c,
                     None if joint.rotational_stiffness_nm_rad is None else joint.rotational_stiffness_nm_rad * kr,
                     joint.rotational_damping_nms_rad * c)


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


@lru_cache(maxsize=256)
def _spindle_chain(spindle: SpindleSpec, mats: tuple, shear: object, theory: str) -> Chain:
    return spindle_chain(spindle, dict(mats), shear, theory)  # type: ignore[arg-type]


@lru_cache(maxsize=256)
def _holder_chain(holder: HolderSpec, tool: ToolSpec, mats: tuple, shear: object, theory: str) -> Chain:
    return holder_chain(holder, tool, dict(mats), shear, theory)  # type: ignore[arg-type]


@lru_cache(maxsize=256)
def _tool_chain(tool: ToolSpec, mats: tuple, shear: object, theory: str) -> Chain:
    return tool_chain(tool, dict(mats), shear, theory)  # type: ignore[arg-type]


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
            left -= item.length_m
    raise ValueError("tip mass lies beyond the tool")


def config_parts(spec: AssemblySpec, tool: ToolSpec, k: Knobs) -> Parts:
    """Sub-chains of the base assembly with ``tool`` and the knobs applied.

    Parameters
    ----------
    spec : AssemblySpec
        Base assembly (analytical spindle).
    tool : ToolSpec
        The measurement's tool (base tool with its overrides).
    k : Knobs

    Returns
    -------
    Parts
    """
    if not isinstance(spec.spindle, SpindleSpec) or spec.holder is None:
        raise TypeError("config_parts needs an analytical spindle and a holder")
    mats = _materials(spec, k)
    shear = spec.shear_coefficient
    base_theory = spec.beam_theory
    s = null_shear_scale(spec) if k.shear_scale is None else k.shear_scale
    theory = "euler_bernoulli" if (base_theory == "euler_bernoulli" and s == 0.0) else "timoshenko"
    scale = 1.0 if theory == "euler_bernoulli" else s

    stickout = tool.stickout_m + k.stickout_offset_m + k.insertion_offset_m
    t = replace(tool, stickout_m=stickout,
                fluted_diameter_ratio=(tool.fluted_diameter_ratio if k.fluted_stiffness_ratio is None
                                       else k.fluted_stiffness_ratio),
                fluted_mass_diameter_ratio=(tool.fluted_mass_diameter_ratio if k.fluted_mass_ratio is None
                                            else k.fluted_mass_ratio))
    holder, ring = _trim_holder(spec.holder, k.insertion_offset_m, mats)

    items = tuple(sorted(mats.items()))
    spindle = _spindle_chain(_spindle(spec.spindle, k), items, shear, theory)
    middle: list[ChainItem] = []
    if k.nose_cross_compliance_rad_n != 0.0 or k.nose_rotational_residual_rad_nm != 0.0:
        middle.append(AddedCompliance(k.nose_cross_compliance_rad_n, k.nose_rotational_residual_rad_nm))
    sh = joint_spring(_joint(spec.spindle_holder, k.sh_translational_scale, k.sh_rotational_scale,
                             k.sh_damping_scale))
    if sh is not None:
        middle.append(sh)
    middle.extend(_holder_chain(holder, t, items, shear, theory))
    if ring is not None:
        middle.append(ring)
    tail: list[ChainItem] = []
    ht = joint_spring(_joint(spec.holder_tool, k.ht_translational_scale, k.ht_rotational_scale,
                             k.ht_damping_scale))
    if ht is not None:
        tail.append(ht)
    tail.extend(_tool_chain(t, items, shear, theory))
    if k.tip_mass_kg > 0.0:
        tail = _with_mass(tail, k.tip_mass_kg, k.tip_mass_distance_m)
    parts = Parts(spindle, tuple(middle), tuple(tail))
    if scale != 1.0:
        parts = Parts(*(_scale_shear(p, scale) for p in (parts.spindle, parts.middle, parts.tool)))
    return parts




class Solver:
    """Tool-point ``h`` of many configurations on one frequency grid, with caches.

    The chain is condensed from the spindle rear to the tool tip by
    :func:`rcsa.physics.elimination.march`, with two caches: the condensed stiffness after
    each sub-chain (keyed by the sub-chains themselves), and the six stiffness terms of each
    beam (keyed by section and length, in the grid the march runs on), so a changed bearing
    or joint re-uses every beam.

    Parameters
    ----------
    frequency_hz : numpy.ndarray, shape (nfreq,)
        The common (union) analysis grid, Hz.
    cache_size : int
        Condensed stiffnesses kept (least recently used are dropped); beam terms keep 4×.
    """

    def __init__(self, frequency_hz: FloatArray, cache_size: int = 128) -> None:
        self.frequency_hz = np.asarray(frequency_hz, dtype=float)
        self.omega_rad_s = 2.0 * np.pi * self.frequency_hz
        self._grid = _BeamTermsGrid(self.omega_rad_s, 4 * cache_size)
        self._condensed = lru_cache(maxsize=cache_size)(self._condense)
        self.evaluations = 0

    def _condense(self, key: tuple[Chain, ...]) -> ComplexArray | None:
        """Dynamic stiffness at the end of the sub-chains ``key``, shape (nfreq, 2, 2); None if empty."""
        if not key:
            return None
        k = march(key[-1], self.omega_rad_s, self._condensed(key[:-1]), grid=self._grid)[0]
        k.flags.writeable = False  # shared by every later configuration with this prefix
        return k

    def tip_h(self, parts: Parts, lines: IntArray | slice = slice(None)) -> ComplexArray:
        """Driving-point tool-tip receptance ``h`` (m/N), shape (nlines,)."""
        k = march(parts.tool, self.omega_rad_s, self._condensed((parts.spindle, parts.middle)), grid=self._grid)[0]
        self.evaluations += 1
        k11, k12, k22 = k[:, 0, 0], k[:, 0, 1], k[:, 1, 1]
        return (k22 / (k11 * k22 - k12 * k12))[lines]

    def nose_stiffness(self, parts: Parts) -> ComplexArray:
        """Condensed dynamic stiffness of the spindle at its nose, shape (nfreq, 2, 2)."""
        k = self._condensed((parts.spindle,))
        assert k is not None
        return k.copy()
