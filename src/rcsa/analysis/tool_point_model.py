"""The tool-point FRF of one assembly as its joint and tool parameters vary, fast.

The evaluator behind the joint identification and the effect analysis on measured
spindles, and behind the identification on analytical ones. The assembly is the chain::

    spindle | spindle–holder joint | holder | holder–tool joint | tool

and joint parameters change only the two springs. So, per frequency grid:

* what lies before the first spring is condensed once — an analytical spindle to its
  dynamic stiffness at the nose; a measured spindle is its receptance at its plane
  (``spindle_nose`` or ``holder_tip``), to which the joints in front of the first beam
  just add their compliance (it is never inverted: rotations may be estimates);
* the beam terms of holder and tool are computed once;

(both kept in a :class:`rcsa.physics.subassembly_cache.SubassemblyCache` per grid), and a
new set of joint values costs a few 2×2 operations per item and line. Several sets
are evaluated in one pass by stacking them along the frequency axis (the springs' values
become arrays, one per row), which is how the identification's finite-difference
Jacobians are vectorised. A tool parameter (stickout, fluted diameter ratio) rebuilds the
holder and tool chains.

A measured spindle is known on the grid it was resolved on (:class:`MeasuredSpindle`);
between its lines it is interpolated linearly (real and imaginary parts), never
extrapolated, as :mod:`rcsa.measured.hybrid` does for predictions.
"""

from __future__ import annotations

import hashlib
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from rcsa.errors import InputError
from rcsa.model.assembly import AssemblyModel, build_model
from rcsa.model.contract import AssemblySpec
from rcsa.model.parameters import set_parameter
from rcsa.model.spindle_side import MeasuredBase
from rcsa.physics.arrays import ComplexArray, FloatArray, RealParam
from rcsa.physics.chain import Chain, Spring
from rcsa.physics.subassembly_cache import DEFAULT_BEAMS, LruStore, SubassemblyCache

__all__ = ["GEOMETRY", "MeasuredSpindle", "ToolPointModel"]

_TWO_PI = 2.0 * np.pi
#: Parameters that change the holder and tool chains (the others change only the springs):
#: the tool's, and those of a holder–tool clamping along the insertion (in the holder chain).
GEOMETRY = ("tool.stickout_m", "tool.fluted_diameter_ratio", "holder_tool.interface_stiffness_scale",
            "holder_tool.interface_stiffness_n_m3")
#: Grids whose condensations are kept per model (least recently used dropped first).
_GRIDS_KEPT = 12
#: Chain models (tool geometries) kept per model.
_MODELS_KEPT = 64


@dataclass(frozen=True)
class MeasuredSpindle:
    """A measured spindle-side receptance on its grid, readable at any frequency inside it.

    Attributes
    ----------
    plane : {"spindle_nose", "holder_tip"}
    frequency_hz : numpy.ndarray, shape (nbase,)
        The grid it was resolved on, Hz, increasing.
    receptance : numpy.ndarray, shape (nbase, 2, 2), complex
        ``[[H, L], [N, P]]`` at the plane.
    alternatives : tuple of numpy.ndarray, shape (nbase, 2, 2)
        Receptances bounding an estimate (``direct_frf``: rotations at L/2 and 2L).
    notes : tuple of str
    report : dict
        What the measured layer did (kind, method, conditioning), JSON-ready.
    artifact_diameter_m : float or None
    """

    plane: str
    frequency_hz: FloatArray
    receptance: ComplexArray
    alternatives: tuple[ComplexArray, ...] = ()
    notes: tuple[str, ...] = ()
    report: Mapping[str, Any] = field(default_factory=dict)
    artifact_diameter_m: float | None = None

    @classmethod
    def from_base(cls, frequency_hz: FloatArray, base: MeasuredBase) -> MeasuredSpindle:
        """From the model layer's :class:`~rcsa.model.spindle_side.MeasuredBase` on ``frequency_hz``."""
        return cls(base.plane, np.asarray(frequency_hz, dtype=float), base.receptance, base.alternatives,
                   base.notes, dict(base.report), base.artifact_diameter_m)

    @property
    def kind(self) -> str:
        """The stored measurement's kind (``point_receptance``, ``artifact_frfs``, ``direct_frf``)."""
        return str(self.report.get("kind", ""))

    def alternative(self, k: int) -> MeasuredSpindle:
        """The same spindle with its ``k``-th bounding receptance."""
        return MeasuredSpindle(self.plane, self.frequency_hz, self.alternatives[k], (), self.notes, self.report,
                               self.artifact_diameter_m)

    def at(self, frequency_hz: FloatArray) -> ComplexArray:
        """The receptance at ``frequency_hz`` (linear interpolation), shape (nfreq, 2, 2).

        Raises
        ------
        InputError
            A frequency outside the resolved grid (never extrapolated).
        """
        f = np.asarray(frequency_hz, dtype=float)
        g = self.frequency_hz
        if f.size and (f.min() < g[0] * (1 - 1e-12) or f.max() > g[-1] * (1 + 1e-12)):
            raise InputError("spindle.measurement_id", f"{f.min():g}–{f.max():g} Hz is outside the measured "
                             f"spindle's band {g[0]:g}–{g[-1]:g} Hz; extrapolation is refused")
        if f.shape == g.shape and np.array_equal(f, g):
            return self.receptance
        flat = self.receptance.reshape(g.size, 4)
        cols = [np.interp(f, g, flat[:, j].real) + 1j * np.interp(f, g, flat[:, j].imag) for j in range(4)]
        return np.stack(cols, axis=-1).reshape(f.size, 2, 2)  # a loop over the four entries, not frequency


def _key(frequency_hz: FloatArray, rows: int) -> tuple[int, int, bytes]:
    return frequency_hz.size, rows, hashlib.blake2b(frequency_hz.tobytes(), digest_size=16).digest()


class ToolPointModel:
    """Tool-point ``h`` of one assembly at given joint and tool parameters.

    Parameters
    ----------
    spec : AssemblySpec
        The assembly; its values are the defaults of every parameter.
    base : MeasuredSpindle, optional
        The measured spindle (hybrid); then ``spec.spindle`` is ignored and the chain starts
        at ``base.plane``.

    Examples
    --------
    >>> from rcsa.model.contract import parse_assembly
    >>> from rcsa.reference import ra1
    >>> spec = parse_assembly(ra1({"start_hz": 1000.0, "stop_hz": 1500.0, "step_hz": 1.0}))
    >>> tpm = ToolPointModel(spec)
    >>> h = tpm.h(spec.frequency_hz, {"holder_tool.stiffness_n_m": 2.0e7})
    >>> h.shape, tpm.h_sets(spec.frequency_hz, [{}, {"holder_tool.damping_ns_m": 50.0}]).shape
    ((501,), (2, 501))
    """

    def __init__(self, spec: AssemblySpec, base: MeasuredSpindle | None = None) -> None:
        self.spec = spec
        self.base = base
        self.plane = None if base is None else base.plane
        self._models: LruStore[tuple[float, ...], AssemblyModel] = LruStore(_MODELS_KEPT)
        self._caches: LruStore[tuple[int, int, bytes], SubassemblyCache] = LruStore(_GRIDS_KEPT)
        self._spindle = self._model({}).spindle

    @property
    def hybrid(self) -> bool:
        """True on a measured spindle."""
        return self.base is not None

    def spec_at(self, values: Mapping[str, float]) -> AssemblySpec:
        """The assembly with the named parameters set (SI)."""
        spec = self.spec
        for name, value in values.items():
            spec = set_parameter(spec, name, float(value))
        return spec

    def model_at(self, values: Mapping[str, float]) -> AssemblyModel:
        """The chain model at these tool parameters (raises :class:`InputError` for an assembly
        that does not fit the spindle's plane, e.g. a holder on a holder-tip measurement)."""
        return self._model(values)

    def _model(self, values: Mapping[str, float]) -> AssemblyModel:
        geometry = tuple(float(values[g]) if g in values else float("nan") for g in GEOMETRY)

        def build() -> AssemblyModel:
            spec = self.spec_at({g: values[g] for g in GEOMETRY if g in values})
            return build_model(spec, self.plane) if self.hybrid else build_model(spec)

        return self._models.get(geometry, build)

    def _springs(self, values_sets: Sequence[Mapping[str, float]], model: AssemblyModel, nf: int
                 ) -> tuple[Spring | None, Spring | None]:
        """The two joints, with array values (one per row) when the sets differ."""
        out: list[Spring | None] = []
        for joint, nominal in (("spindle_holder", model.spindle_holder), ("holder_tool", model.holder_tool)):
            if nominal is None:
                out.append(None)
                continue
            damping = _joint_column(values_sets, joint, "damping_ns_m", nominal.damping_ns_m, nf)
            rotational_damping = _joint_column(values_sets, joint, "rotational_damping_nms_rad",
                                               nominal.rotational_damping_nms_rad, nf)
            assert damping is not None and rotational_damping is not None  # a damping is never None
            out.append(Spring(_joint_column(values_sets, joint, "stiffness_n_m", nominal.stiffness_n_m, nf), damping,
                              _joint_column(values_sets, joint, "rotational_stiffness_nm_rad",
                                            nominal.rotational_stiffness_nm_rad, nf), rotational_damping))
        return out[0], out[1]

    def _cache(self, frequency_hz: FloatArray, rows: int) -> SubassemblyCache:
        """The spindle condensed (or the measured receptance read) on this grid, ``rows`` times over."""
        def make() -> SubassemblyCache:
            omega = np.tile(_TWO_PI * frequency_hz, rows)
            base = None if self.base is None else np.tile(self.base.at(frequency_hz), (rows, 1, 1))
            return SubassemblyCache(omega, base, max_states=2, max_beams=DEFAULT_BEAMS)

        return self._caches.get(_key(frequency_hz, rows), make)

    def _tip(self, cache: SubassemblyCache, chain: Chain) -> ComplexArray:
        """``h`` at the tip of ``chain`` attached to the condensed spindle (or the measured base)."""
        start = cache.condensed(()) if self.base is not None else cache.condensed((self._spindle,))
        return cache.tip_h(start, chain)

    def h_sets(self, frequency_hz: FloatArray, value_sets: Sequence[Mapping[str, float]]) -> ComplexArray:
        """Tool-point ``h`` for several parameter sets, shape (nsets, nfreq), m/N.

        Sets that differ only in joint values are evaluated in one stacked pass; a set that
        changes a tool parameter (:data:`GEOMETRY`) is evaluated on its own chain.

        Parameters
        ----------
        frequency_hz : numpy.ndarray, shape (nfreq,)
            Inside the measured spindle's band when hybrid.
        value_sets : sequence of dict
            Parameter name → value (SI); names not given keep the assembly's values.
        """
        f = np.asarray(frequency_hz, dtype=float)
        out = np.empty((len(value_sets), f.size), dtype=complex)
        groups: dict[tuple[float, ...], list[int]] = {}
        for k, values in enumerate(value_sets):
            geometry = tuple(float(values[g]) if g in values else float("nan") for g in GEOMETRY)
            groups.setdefault(geometry, []).append(k)
        for idx in groups.values():
            sets = [value_sets[k] for k in idx]
            model = self._model(sets[0])
            sh, ht = self._springs(sets, model, f.size)
            stacked = len(sets) > 1 and any(s is not None and s.is_stacked for s in (sh, ht))
            rows = len(sets) if stacked else 1
            chain: Chain = (*(() if sh is None else (sh,)), *model.holder, *(() if ht is None else (ht,)),
                            *model.tool)
            h = self._tip(self._cache(f, rows), chain)
            out[idx] = h.reshape(rows, f.size) if stacked else h[None, :]
        return out

    def h(self, frequency_hz: FloatArray, values: Mapping[str, float] | None = None) -> ComplexArray:
        """Tool-point ``h`` at ``frequency_hz`` (Hz) for one parameter set, shape (nfreq,), m/N."""
        h: ComplexArray = self.h_sets(frequency_hz, [values or {}])[0]
        return h


def _joint_column(values_sets: Sequence[Mapping[str, float]], joint: str, field_name: str, nominal: RealParam | None,
                  nf: int) -> RealParam | None:
    """One joint value over the sets: None for a rigid DOF (it stays rigid), a float when every set
    agrees, else one row per set (each repeated over the ``nf`` lines)."""
    if nominal is None:
        return None
    vals = [s.get(f"{joint}.{field_name}", nominal) for s in values_sets]
    if len(values_sets) == 1 or all(v == vals[0] for v in vals):
        return float(vals[0])
    return np.repeat(np.asarray(vals, dtype=float), nf)
