"""The 3-D reference's entry point: ``solve(case, frequency_hz, base) -> SolidFRF``.

Example (a few seconds)::

    from tests.oracles.solid3d.case import HolderSegment, MeshSize, SolidCase, ToolGeometry
    from tests.oracles.solid3d.solve import solve
    case = SolidCase((HolderSegment(0.024, 0.063, 0.010), HolderSegment(0.030, 0.040, 0.010),
                      HolderSegment(0.040, 0.026, 0.010)),
                     ToolGeometry(0.010, 0.010, 0.080, 0.020, 0.040))
    frf = solve(case, np.arange(100.0, 6001.0), "clamped")
    frf.h           # (nfreq,) tool-point receptance, m/N
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np

from tests.oracles.solid3d.assembly import BaseKind, Matrices, assemble
from tests.oracles.solid3d.case import Interface, MeshSize, SolidCase, SolidMaterial
from tests.oracles.solid3d.geometry import (
    ArcCut,
    FineZone,
    Piece,
    SolidMesh,
    case_arc_cuts,
    case_pieces,
    mesh_pieces,
    tool_fine_zone,
)
from tests.oracles.solid3d.reduction import (
    ReducedModel,
    direct_tip_receptance,
    reduce,
    tip_receptance,
)

__all__ = ["CUTOFF_FACTOR", "ReceptanceBase", "SolidFRF", "SolidModel", "build", "build_body", "largest_peak",
           "solve", "solve_model", "truncation_error", "undamped_poles_hz"]

#: fixed-interface modes are kept up to this multiple of the highest frequency asked for
CUTOFF_FACTOR = 2.5


@dataclass(frozen=True, slots=True)
class ReceptanceBase:
    """An elastic base: the point receptance at the gauge line the base face is coupled to.

    Parameters
    ----------
    frequency_hz : numpy.ndarray, shape (nfreq,)
        Must be the frequencies the FRF is asked at.
    receptance : numpy.ndarray, shape (nfreq, 2, 2)
        ``[[h, l], [n, p]]`` in rcsa's convention (x–z plane: w = u_x, ψ = θ_y); the same
        receptance acts in the y–z plane with the rotation's sign turned (ψ = −θ_x).
    undamped_receptance : numpy.ndarray, shape (nfreq, 2, 2), optional
        The same base with all damping removed; with it the undamped natural frequencies
        of the coupled body are given (the poles of its undamped tool-point h).
    """

    frequency_hz: np.ndarray
    receptance: np.ndarray
    undamped_receptance: np.ndarray | None = None

    def __post_init__(self) -> None:
        n = np.asarray(self.frequency_hz).size
        if np.shape(self.receptance) != (n, 2, 2):
            raise ValueError("base receptance must have shape (nfreq, 2, 2)")
        if self.undamped_receptance is not None and np.shape(self.undamped_receptance) != (n, 2, 2):
            raise ValueError("base undamped_receptance must have shape (nfreq, 2, 2)")


Base = ReceptanceBase | str


@dataclass(frozen=True, slots=True)
class SolidModel:
    """A meshed, assembled and reduced case (reusable for several bases of one kind).

    Attributes
    ----------
    case : SolidCase or None
    mesh : SolidMesh
    matrices : Matrices
    reduced : ReducedModel
    timings_s : dict
        Wall time of the steps, s (for the record; never asserted).
    """

    case: SolidCase | None
    mesh: SolidMesh
    matrices: Matrices
    reduced: ReducedModel
    timings_s: dict[str, float] = field(default_factory=dict)


@dataclass(frozen=True, slots=True)
class SolidFRF:
    """The 3-D reference's answer.

    Attributes
    ----------
    frequency_hz : numpy.ndarray, shape (nfreq,)
    tip : numpy.ndarray, shape (nfreq, 2, 2)
        Tool-point receptance ``[[h, l], [n, p]]``: mean x displacement / rotation about +y
        of the tip face under a unit x force spread uniformly over it / a unit moment
        about +y (linear traction); m/N, rad/N, rad/(N·m). e^{iωt}.
    natural_frequencies_hz : numpy.ndarray or None
        Undamped natural frequencies in the band (bending in x–z for the quarter model):
        exact for a clamped base, the poles of the undamped h for an elastic base given
        its undamped receptance, None otherwise.
    n_dof : int
        DOFs of the constrained 3-D model.
    n_dof_mesh : int
        3 × nodes of the mesh.
    n_elements : int
    n_modes : int
        Fixed-interface modes in the reduced model.
    quarter : bool
    timings_s : dict
        Wall times, s (for the record).
    """

    frequency_hz: np.ndarray
    tip: np.ndarray
    natural_frequencies_hz: np.ndarray | None
    n_dof: int
    n_dof_mesh: int
    n_elements: int
    n_modes: int
    quarter: bool
    timings_s: dict[str, float]

    @property
    def h(self) -> np.ndarray:
        """Tool-point translational receptance, m/N, shape (nfreq,)."""
        return self.tip[:, 0, 0]


def _kind(base: Base) -> BaseKind:
    if isinstance(base, ReceptanceBase):
        return "elastic"
    if base == "clamped":
        return "clamped"
    raise ValueError("base must be 'clamped' or a ReceptanceBase")


def build_body(pieces: tuple[Piece, ...], materials: tuple[SolidMaterial, SolidMaterial], size: MeshSize,
               base_kind: BaseKind, cutoff_hz: float, *, quarter: bool = True, fine: FineZone | None = None,
               interface: Interface | None = None, insertion: tuple[float, float] | None = None,
               rigid_holder: bool = False, case: SolidCase | None = None, half: bool = False,
               arc_cuts: tuple[ArcCut, ...] = ()) -> SolidModel:
    """Mesh, assemble and reduce any coaxial body (rods for verification, or a case's pieces).

    Parameters
    ----------
    pieces : tuple of Piece
        The tip face is the largest z of the pieces.
    materials : (SolidMaterial, SolidMaterial)
        Of the ``holder`` and ``tool`` parts.
    size : MeshSize
    base_kind : {"clamped", "elastic"}
    cutoff_hz : float
        Fixed-interface modes kept up to here, Hz.
    quarter : bool
    fine : FineZone or None
    interface : Interface or None
        Default: bonded.
    insertion : (float, float) or None
        z of the shank's end and of the holder face (contact-region depths count from it), m.
    rigid_holder : bool
    case : SolidCase or None
        Recorded in the model.
    half : bool
        The half model (y ≥ 0; with ``quarter`` False).
    arc_cuts : tuple of ArcCut
        Half-planes putting the edges of an arc of contact into the mesh.

    Returns
    -------
    SolidModel
    """
    t0 = time.perf_counter()
    mesh = mesh_pieces(pieces, size, quarter, fine, half=half, arc_cuts=arc_cuts)
    t1 = time.perf_counter()
    mats = assemble(mesh, materials, interface or Interface(), base_kind, max(p.z1_m for p in pieces),
                    insertion, rigid_holder)
    t2 = time.perf_counter()
    red = reduce(mats, cutoff_hz)
    t3 = time.perf_counter()
    return SolidModel(case, mesh, mats, red, {"mesh": t1 - t0, "assemble": t2 - t1, "reduce": t3 - t2})


def build(case: SolidCase, base_kind: BaseKind, cutoff_hz: float) -> SolidModel:
    """Mesh, assemble and reduce a case.

    Parameters
    ----------
    case : SolidCase
    base_kind : {"clamped", "elastic"}
    cutoff_hz : float
        Fixed-interface modes kept up to here, Hz.

    Returns
    -------
    SolidModel
    """
    return build_body(case_pieces(case), (case.holder_material, case.tool_material), case.mesh, base_kind,
                      cutoff_hz, quarter=case.uses_quarter(), fine=tool_fine_zone(case), interface=case.interface,
                      insertion=(case.insertion_start_m, case.holder_length_m), rigid_holder=case.rigid_holder,
                      case=case, half=case.uses_half(), arc_cuts=case_arc_cuts(case))


def undamped_poles_hz(frequency_hz: np.ndarray, h: np.ndarray) -> np.ndarray:
    """Poles of an undamped (real) receptance sampled on a grid, Hz.

    A pole is a sign change of h between two lines where |h| grows toward the change from
    both sides (an anti-resonance, where |h| falls, is not); its frequency is the zero of
    1/h interpolated linearly between the two lines.

    Parameters
    ----------
    frequency_hz : numpy.ndarray, shape (nfreq,)
    h : numpy.ndarray, shape (nfreq,)
        Real.

    Returns
    -------
    numpy.ndarray
    """
    f, h = np.asarray(frequency_hz), np.real(np.asarray(h))
    a = np.abs(h)
    i = np.flatnonzero(np.sign(h[1:-2]) != np.sign(h[2:-1])) + 1
    i = i[(a[i] > a[i - 1]) & (a[i + 1] > a[i + 2])]
    g0, g1 = 1.0 / h[i], 1.0 / h[i + 1]
    return f[i] + (f[i + 1] - f[i]) * g0 / (g0 - g1)


def largest_peak(frequency_hz: np.ndarray, h: np.ndarray) -> tuple[float, float]:
    """Frequency (Hz) and magnitude (m/N) of the largest |h| peak, parabolic interpolation in |h|.

    Parameters
    ----------
    frequency_hz : numpy.ndarray, shape (nfreq,)
    h : numpy.ndarray, shape (nfreq,)

    Returns
    -------
    (float, float)
    """
    a = np.abs(np.asarray(h))
    j = int(np.clip(np.argmax(a), 1, a.size - 2))
    y0, y1, y2 = a[j - 1], a[j], a[j + 1]
    den = y0 - 2 * y1 + y2
    d = 0.5 * (y0 - y2) / den if den < 0 else 0.0
    step = frequency_hz[j + 1] - frequency_hz[j]
    return float(frequency_hz[j] + d * step), float(y1 - 0.25 * (y0 - y2) * d)


def solve(case: SolidCase, frequency_hz: np.ndarray, base: Base = "clamped") -> SolidFRF:
    """The tool-point FRF of a holder + tool case by 3-D linear elasticity.

    Parameters
    ----------
    case : SolidCase
    frequency_hz : numpy.ndarray, shape (nfreq,)
        Frequencies > 0, Hz.
    base : "clamped" or ReceptanceBase
        The holder's base face (z = 0) is rigid (6 DOF; axial and torsion clamped) and
        either fixed or coupled to the base receptance in both bending planes.

    Returns
    -------
    SolidFRF
    """
    f = _frequencies(frequency_hz)
    return solve_model(build(case, _kind(base), CUTOFF_FACTOR * float(f.max())), f, base)


def _frequencies(frequency_hz: np.ndarray) -> np.ndarray:
    f = np.asarray(frequency_hz, dtype=float)
    if f.ndim != 1 or not np.all(f > 0):
        raise ValueError("frequency_hz must be a 1-D array of frequencies > 0")
    return f


def solve_model(model: SolidModel, frequency_hz: np.ndarray, base: Base = "clamped") -> SolidFRF:
    """The tip FRF of a model already built (:func:`build`, :func:`build_body`).

    Parameters
    ----------
    model : SolidModel
        Built with ``base_kind="elastic"`` (serves both bases) or ``"clamped"``, with a cut-off ≥ ``CUTOFF_FACTOR`` × the highest frequency.
    frequency_hz : numpy.ndarray, shape (nfreq,)
    base : "clamped" or ReceptanceBase

    Returns
    -------
    SolidFRF
    """
    f = _frequencies(frequency_hz)
    kind = _kind(base)
    if kind == "elastic" and model.matrices.n_boundary == 0:
        raise ValueError("model was built with a clamped base: build it with base_kind='elastic'")
    if model.reduced.cutoff_hz < CUTOFF_FACTOR * float(f.max()) * (1 - 1e-9):
        raise ValueError("frequency_hz goes above the model's cut-off / CUTOFF_FACTOR")
    t0 = time.perf_counter()
    omega = 2 * np.pi * f
    stiff = undamped = None
    natural: np.ndarray | None = None
    if isinstance(base, ReceptanceBase):
        if np.asarray(base.frequency_hz).size != f.size or not np.allclose(base.frequency_hz, f, rtol=1e-12):
            raise ValueError("the base receptance must be given at frequency_hz")
        stiff = np.linalg.inv(base.receptance)
        if base.undamped_receptance is not None:
            undamped = np.linalg.inv(base.undamped_receptance.real)
    tip = tip_receptance(model.reduced, omega, stiff)
    if kind == "clamped":
        fb = model.reduced.fixed_base_frequencies_hz
        natural = fb[(fb >= f.min()) & (fb <= f.max())]
    elif undamped is not None:
        h_u = tip_receptance(model.reduced, omega, undamped, damped=False)[:, 0, 0]
        natural = undamped_poles_hz(f, h_u.real)
    timings = dict(model.timings_s, frf=time.perf_counter() - t0)
    return SolidFRF(frequency_hz=f, tip=tip, natural_frequencies_hz=natural, n_dof=model.matrices.n_dof,
                    n_dof_mesh=model.matrices.n_dof_mesh, n_elements=int(model.mesh.tets.shape[1]),
                    n_modes=model.reduced.n_modes, quarter=model.mesh.quarter, timings_s=timings)


def truncation_error(model: SolidModel, frequency_hz: np.ndarray, base: Base = "clamped") -> float:
    """max |h_reduced − h_direct| / max |h_direct| at a few frequencies (sparse complex solves).

    Parameters
    ----------
    model : SolidModel
    frequency_hz : numpy.ndarray, shape (nfreq,)
        A handful of frequencies, Hz.
    base : "clamped" or ReceptanceBase
        With an elastic base, its ``frequency_hz`` must be these frequencies.

    Returns
    -------
    float
    """
    omega = 2 * np.pi * np.asarray(frequency_hz, dtype=float)
    stiff = np.linalg.inv(base.receptance) if isinstance(base, ReceptanceBase) else None
    red = tip_receptance(model.reduced, omega, stiff)[:, 0, 0]
    direct = direct_tip_receptance(model.matrices, omega, stiff)[:, 0, 0]
    return float(np.max(np.abs(red - direct)) / np.max(np.abs(direct)))
