"""Nuisance tolerances: what the base model is known to be uncertain about, and draws of it.

One definition shared by the diagnosis (its discrepancy covariance, ``docs/diagnosis.md`` §4.3)
and by predictions with uncertainty bands (``docs/contract.md`` "Additions in v1.1"): the
tolerance names, their defaults (one standard deviation), the order in which a random
generator draws them, and how a draw changes an assembly.

==================================  =======  =============================================
key                                 default  meaning
==================================  =======  =============================================
tool_youngs_modulus_rel             0.03     carbide E (grade/Co content: ±6 % at 2σ)
tool_density_rel                    0.01     tool ρ
structure_youngs_modulus_rel        0.02     E of the other materials (spindle, holder)
structure_density_rel               0.01     ρ of the other materials
loss_factor_log                     0.25     ln-scale of every material loss factor
bearing_stiffness_log               0.08     ln-scale of all bearing stiffnesses
bearing_damping_log                 0.25     ln-scale of all bearing dampers
spindle_holder_stiffness_log        0.15     ln-scale of k_t and k_r (independent draws)
spindle_holder_damping_log          0.25     ln-scale of the spindle–holder dampers
holder_tool_stiffness_log           0.15     per configuration (re-clamp), k_t and k_r
holder_tool_damping_log             0.25     per configuration
stickout_m                          0.0003   per configuration, m
==================================  =======  =============================================

A measured spindle (predictions only, :data:`MEASURED_SPINDLE_TOLERANCES`) adds its own:

==================================  =======  =============================================
spindle_effective_length_log        0.35     ``direct_frf``: ln-scale of the equivalent-
                                             cantilever length of the estimated rotations
                                             (its bounds L/2 and 2L at 2σ; draws are kept
                                             between them)
spindle_noise_rel                   0.005    relative noise of a stored FRF that has no
                                             coherence (with one: Bendat & Piersol from it)
==================================  =======  =============================================

A draw (:func:`draw_nuisance`) takes, from one generator, ``len(SHARED_KNOBS) + 4 ·
n_configs`` standard normal numbers per draw in a fixed order: the shared knobs, then the
per-configuration ones of each configuration. A relative knob is ``1 + σz`` (never below
:data:`MIN_SCALE`), a log-scale knob ``exp(σz)``, the stickout an offset ``σz`` (m).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, replace
from types import MappingProxyType
from typing import TYPE_CHECKING, Literal, TypeVar, overload

import numpy as np

from rcsa.model.bounds import MAX_TOLERANCE, MAX_TOLERANCE_STICKOUT_M
from rcsa.model.contract import (
    AssemblySpec,
    BearingSpec,
    ClampingSpec,
    JointSpec,
    SpindleSpec,
    ToolSpec,
)
from rcsa.model.fields import Fields
from rcsa.physics.arrays import FloatArray
from rcsa.physics.materials import Material

if TYPE_CHECKING:
    from _typeshed import DataclassInstance

__all__ = [
    "DEFAULT_TOLERANCES",
    "MEASURED_SPINDLE_TOLERANCES",
    "MIN_SCALE",
    "PER_CONFIG_KNOBS",
    "SHARED_KNOBS",
    "NuisanceDraws",
    "apply_nuisance",
    "draw_nuisance",
    "parse_tolerances",
    "perturbed_spec",
    "scaled_joint",
    "shortest_stickout_m",
]

#: Tolerances of the base model, one standard deviation (see the module docstring).
DEFAULT_TOLERANCES: Mapping[str, float] = MappingProxyType({
    "tool_youngs_modulus_rel": 0.03,
    "tool_density_rel": 0.01,
    "structure_youngs_modulus_rel": 0.02,
    "structure_density_rel": 0.01,
    "loss_factor_log": 0.25,
    "bearing_stiffness_log": 0.08,
    "bearing_damping_log": 0.25,
    "spindle_holder_stiffness_log": 0.15,
    "spindle_holder_damping_log": 0.25,
    "holder_tool_stiffness_log": 0.15,
    "holder_tool_damping_log": 0.25,
    "stickout_m": 0.0003,
})

#: A measured spindle's own uncertainty in predictions (see the module docstring).
MEASURED_SPINDLE_TOLERANCES: Mapping[str, float] = MappingProxyType({
    "spindle_effective_length_log": 0.35,
    "spindle_noise_rel": 0.005,
})

#: Smallest relative scale a draw gives (a modulus or density never reaches zero, whatever
#: the tolerance).
MIN_SCALE = 1e-3

_Kind = Literal["rel", "log", "offset"]

#: Knobs drawn once per draw: (knob, tolerance, kind), in the generator's order.
SHARED_KNOBS: tuple[tuple[str, str, _Kind], ...] = (
    ("tool_youngs_scale", "tool_youngs_modulus_rel", "rel"),
    ("tool_density_scale", "tool_density_rel", "rel"),
    ("structure_youngs_scale", "structure_youngs_modulus_rel", "rel"),
    ("structure_density_scale", "structure_density_rel", "rel"),
    ("loss_factor_scale", "loss_factor_log", "log"),
    ("bearing_stiffness_scale", "bearing_stiffness_log", "log"),
    ("bearing_damping_scale", "bearing_damping_log", "log"),
    ("sh_translational_scale", "spindle_holder_stiffness_log", "log"),
    ("sh_rotational_scale", "spindle_holder_stiffness_log", "log"),
    ("sh_damping_scale", "spindle_holder_damping_log", "log"),
)
#: Knobs drawn once per configuration (a re-clamp, a stickout setting), after the shared ones.
PER_CONFIG_KNOBS: tuple[tuple[str, str, _Kind], ...] = (
    ("ht_translational_scale", "holder_tool_stiffness_log", "log"),
    ("ht_rotational_scale", "holder_tool_stiffness_log", "log"),
    ("ht_damping_scale", "holder_tool_damping_log", "log"),
    ("stickout_offset_m", "stickout_m", "offset"),
)

_K = TypeVar("_K", bound="DataclassInstance")


def _knob(kind: _Kind, sd: float, z: FloatArray) -> FloatArray:
    if kind == "rel":
        out: FloatArray = np.maximum(1.0 + sd * z, MIN_SCALE)
    elif kind == "log":
        out = np.exp(sd * z)
    else:
        out = sd * z
    return out


@dataclass(frozen=True)
class NuisanceDraws:
    """Knob values of ``n_draws`` nuisance draws of ``n_configs`` configurations each.

    Attributes
    ----------
    values : mapping of str to numpy.ndarray, each shape (n_draws, n_configs)
        Every knob of :data:`SHARED_KNOBS` (the same in every configuration of a draw) and
        :data:`PER_CONFIG_KNOBS`: dimensionless scales, ``stickout_offset_m`` in m.
    """

    values: Mapping[str, FloatArray]

    @property
    def n_draws(self) -> int:
        """Number of draws."""
        return int(next(iter(self.values.values())).shape[0])

    @property
    def n_configs(self) -> int:
        """Configurations per draw."""
        return int(next(iter(self.values.values())).shape[1])

    def fields(self, draw: int, config: int = 0) -> dict[str, float]:
        """The knobs of one draw and configuration, by name (for :func:`apply_nuisance`).

        Parameters
        ----------
        draw : int
            Index of the draw.
        config : int
            Index of the configuration.
        """
        return {name: float(v[draw, config]) for name, v in self.values.items()}


def draw_nuisance(rng: np.random.Generator, tolerances: Mapping[str, float], n_draws: int,
                  n_configs: int = 1) -> NuisanceDraws:
    """Draws of every nuisance knob under ``tolerances``, all at once.

    The generator's numbers are taken in the order of the module docstring, so one draw of
    ``n_configs`` configurations consumes exactly what the diagnosis's draw of the same
    configurations does, and ``n_draws`` draws what ``n_draws`` such draws in a row do.

    Parameters
    ----------
    rng : numpy.random.Generator
    tolerances : mapping of str to float
        One standard deviation per name of :data:`DEFAULT_TOLERANCES` (all required).
    n_draws : int
        Number of draws.
    n_configs : int
        Configurations per draw (the diagnosis's measurements; 1 for a prediction).

    Returns
    -------
    NuisanceDraws
    """
    z = rng.standard_normal((n_draws, len(SHARED_KNOBS) + len(PER_CONFIG_KNOBS) * n_configs))
    values: dict[str, FloatArray] = {}
    for i, (name, tol, kind) in enumerate(SHARED_KNOBS):
        values[name] = np.repeat(_knob(kind, tolerances[tol], z[:, i])[:, None], n_configs, axis=1)
    per = z[:, len(SHARED_KNOBS):].reshape(n_draws, n_configs, len(PER_CONFIG_KNOBS))
    for j, (name, tol, kind) in enumerate(PER_CONFIG_KNOBS):
        values[name] = _knob(kind, tolerances[tol], per[:, :, j])
    return NuisanceDraws(MappingProxyType(values))


def apply_nuisance(base: _K, fields: Mapping[str, float]) -> _K:
    """A knobs dataclass with one draw applied: scales multiply, ``stickout_offset_m`` adds.

    Parameters
    ----------
    base : dataclass
        Has a field for every knob of ``fields`` (e.g. the diagnosis's ``Knobs``).
    fields : mapping of str to float
        :meth:`NuisanceDraws.fields`.
    """
    return replace(base, **{k: (getattr(base, k) + v if k == "stickout_offset_m" else getattr(base, k) * v)
                            for k, v in fields.items()})


@overload
def scaled_joint(joint: ClampingSpec, kt: float, kr: float, c: float) -> ClampingSpec: ...


@overload
def scaled_joint(joint: JointSpec | None, kt: float, kr: float, c: float) -> JointSpec | None: ...


@overload
def scaled_joint(joint: JointSpec | ClampingSpec | None, kt: float, kr: float, c: float
                 ) -> JointSpec | ClampingSpec | None: ...


def scaled_joint(joint: JointSpec | ClampingSpec | None, kt: float, kr: float, c: float
                 ) -> JointSpec | ClampingSpec | None:
    """A joint with its stiffnesses and dampers scaled (a rigid one stays rigid).

    A point joint: ``k_t`` by ``kt``, ``k_r`` by ``kr``, both dampers by ``c``. A clamping
    along the insertion: its whole interface stiffness by ``kt`` (``interface_stiffness_scale``) and its
    interface loss factor by ``c``.

    Parameters
    ----------
    joint : JointSpec, ClampingSpec or None
    kt, kr, c : float
        Scales (dimensionless).

    Returns
    -------
    JointSpec, ClampingSpec or None
    """
    if joint is None:
        return None
    if isinstance(joint, ClampingSpec):
        return replace(joint, interface_stiffness_scale=joint.interface_stiffness_scale * kt,
                       interface_loss_factor=joint.interface_loss_factor * c)
    return JointSpec(joint.stiffness_n_m * kt, joint.damping_ns_m * c,
                     None if joint.rotational_stiffness_nm_rad is None else joint.rotational_stiffness_nm_rad * kr,
                     joint.rotational_damping_nms_rad * c)


def shortest_stickout_m(tool: ToolSpec) -> float:
    """The stickout below which the tool's shank would vanish: flutes and neck, m.

    Parameters
    ----------
    tool : ToolSpec
    """
    if tool.shoulder_length_m is not None and not tool.neck_segments:
        return tool.shoulder_length_m
    return tool.flute_length_m + sum(length for length, _ in tool.neck_segments)


def perturbed_spec(spec: AssemblySpec, fields: Mapping[str, float]) -> AssemblySpec:
    """The assembly with one nuisance draw applied (the diagnosis's knobs, on the spec).

    * materials: the tool's material by the tool scales, every other by the structure
      scales (E and ρ); every loss factor by ``loss_factor_scale``;
    * bearings (analytical spindle): stiffnesses (translational and rotational) by
      ``bearing_stiffness_scale``, dampers by ``bearing_damping_scale``;
    * joints: ``k_t``, ``k_r`` and both dampers of each by its three scales;
    * the tool's stickout moved by ``stickout_offset_m``, kept between the flutes (and
      neck) and the overall length.

    Parameters
    ----------
    spec : AssemblySpec
    fields : mapping of str to float
        One draw's knobs (:meth:`NuisanceDraws.fields`).

    Returns
    -------
    AssemblySpec
    """
    tool_name = spec.tool.material
    materials = {}
    for name, m in spec.materials.items():
        tool = name == tool_name
        e = fields["tool_youngs_scale" if tool else "structure_youngs_scale"]
        rho = fields["tool_density_scale" if tool else "structure_density_scale"]
        materials[name] = Material(m.youngs_modulus_pa * e, m.poisson_ratio, m.density_kg_m3 * rho,
                                   m.loss_factor * fields["loss_factor_scale"])
    spindle = spec.spindle
    if isinstance(spindle, SpindleSpec):
        k, c = fields["bearing_stiffness_scale"], fields["bearing_damping_scale"]
        spindle = SpindleSpec(spindle.segments, tuple(
            BearingSpec(b.position_m, b.stiffness_n_m * k, b.damping_ns_m * c, b.rotational_stiffness_nm_rad * k,
                        b.rotational_damping_nms_rad * c) for b in spindle.bearings))
    t = spec.tool
    stickout = min(max(t.stickout_m + fields["stickout_offset_m"], shortest_stickout_m(t)), t.overall_length_m)
    return replace(spec, materials=MappingProxyType(materials), spindle=spindle,
                   tool=replace(t, stickout_m=stickout),
                   spindle_holder=scaled_joint(spec.spindle_holder, fields["sh_translational_scale"],
                                         fields["sh_rotational_scale"], fields["sh_damping_scale"]),
                   holder_tool=scaled_joint(spec.holder_tool, fields["ht_translational_scale"],
                                      fields["ht_rotational_scale"], fields["ht_damping_scale"]))


def parse_tolerances(value: object, path: str = "tolerances", *, measured_spindle: bool = False
                     ) -> dict[str, float]:
    """Tolerances of a request: every default, overridden by the names given.

    Parameters
    ----------
    value : dict or None
        ``{name: one standard deviation}``; names of :data:`DEFAULT_TOLERANCES` (and, with
        ``measured_spindle``, of :data:`MEASURED_SPINDLE_TOLERANCES`).
    path : str
        Where the value sits in the request, for error messages.
    measured_spindle : bool
        Also accept (and fill in) a measured spindle's tolerances.

    Returns
    -------
    dict of str to float
        Every tolerance, dimensionless (``stickout_m`` in m), each in
        ``[0, MAX_TOLERANCE]`` (``stickout_m``: ``[0, MAX_TOLERANCE_STICKOUT_M]``).

    Raises
    ------
    InputError
        An unknown name (the allowed ones listed), or a value out of bounds.
    """
    defaults = {**DEFAULT_TOLERANCES, **(MEASURED_SPINDLE_TOLERANCES if measured_spindle else {})}
    o = Fields(value if value is not None else {}, path, tuple(defaults))
    out = dict(defaults)
    for key in o.value:
        out[key] = o.number(key, ge=0.0, le=MAX_TOLERANCE_STICKOUT_M if key == "stickout_m" else MAX_TOLERANCE)
    return out
