"""Solids and the quadratic tetrahedral mesh (gmsh, OpenCASCADE kernel).

A case becomes a list of :class:`Piece` (coaxial cylinders, cones, tubes and straight fluted
prisms, a shank cut by a side-lock flat, the screw pressing on it, each belonging to the
``holder`` or the ``tool``); gmsh fragments them into one conforming mesh of 10-node
tetrahedra with curved (second-order) faces, fine in the tool and around the bore, growing
toward the flange. The quarter model keeps x ≥ 0, y ≥ 0, the half model y ≥ 0.
"""

from __future__ import annotations

import math
import signal
import threading
from dataclasses import dataclass
from typing import Literal

import gmsh
import numpy as np
from skfem import Basis, ElementTetP2, MeshTet2

from tests.oracles.solid3d.case import Flutes, MeshSize, SolidCase

__all__ = ["CORNER_RATIO", "ArcCut", "FineZone", "Piece", "SolidMesh", "case_arc_cuts", "case_pieces", "mesh_pieces",
           "tool_fine_zone"]

Part = Literal["holder", "tool"]
Symmetry = Literal["quarter", "half", "full"]
PARTS: tuple[Part, ...] = ("holder", "tool")
#: gmsh's 10-node tetrahedron lists its edge nodes as (0,1) (1,2) (2,0) (3,0) (3,2) (3,1);
#: scikit-fem (and VTK) as (0,1) (1,2) (0,2) (0,3) (1,3) (2,3): swap the last two.
GMSH_TO_SKFEM_TET10 = np.array([0, 1, 2, 3, 4, 5, 6, 7, 9, 8])
_EDGES = ((0, 1), (1, 2), (0, 2), (0, 3), (1, 3), (2, 3))


@dataclass(frozen=True, slots=True)
class Piece:
    """A coaxial solid between two axial stations.

    Parameters
    ----------
    part : {"holder", "tool"}
    z0_m, z1_m : float
        Axial extent, m (z0 < z1).
    outer_diameter_m : float
        m.
    inner_diameter_m : float
        Bore, m (0 = solid).
    flutes : Flutes or None
        A straight fluted prism cut from the outer circle instead of a round section.
    outer_diameter_end_m : float or None
        A cone: the outer diameter at ``z1_m`` (``outer_diameter_m`` at ``z0_m``), m.
    flat_x_m : float or None
        Cut by the plane x = ``flat_x_m`` (the solid keeps x ≤ it: a side-lock flat), m.
    radial_x_m : (float, float) or None
        Instead of a coaxial solid: a cylinder along x from x0 to x1 (a side-lock screw),
        of diameter ``outer_diameter_m``, centred at z = (z0 + z1)/2 on y = 0, m.
    """

    part: Part
    z0_m: float
    z1_m: float
    outer_diameter_m: float
    inner_diameter_m: float = 0.0
    flutes: Flutes | None = None
    outer_diameter_end_m: float | None = None
    flat_x_m: float | None = None
    radial_x_m: tuple[float, float] | None = None


@dataclass(frozen=True, slots=True)
class FineZone:
    """Where the mesh is fine.

    Parameters
    ----------
    radius_m : float
        The fine zone is r ≤ ``radius_m`` and z ≥ ``z_start_m`` (tool and bore wall), m.
    z_start_m : float
        m.
    corners : tuple of (float, float)
        Circles ``(r_m, z_m)`` where the interface ends (the shank leaving the bore, the
        ends of a contact region): the stress is singular there, so the mesh is graded
        toward them down to ``CORNER_RATIO · tool_m``.
    lines : tuple of (float, float, float, float)
        Axial lines ``(x_m, y_m, z0_m, z1_m)`` where the interface ends too (the edges of an
        arc of contact), graded the same way.
    spots : tuple of (float, float, float)
        Circles ``(x_m, z_m, r_m)`` in the plane x = x_m, centred on y = 0 (a screw's contact
        face), graded the same way.
    """

    radius_m: float
    z_start_m: float
    corners: tuple[tuple[float, float], ...] = ()
    lines: tuple[tuple[float, float, float, float], ...] = ()
    spots: tuple[tuple[float, float, float], ...] = ()


@dataclass(frozen=True, slots=True)
class ArcCut:
    """A half-plane through the axis at ``angle_deg`` (from +x toward +y), from the axis out to
    ``radius_m`` and over ``z0_m``–``z1_m``: it cuts the shank so that the bore surface carries
    the edge of an arc of contact as a mesh line."""

    angle_deg: float
    radius_m: float
    z0_m: float
    z1_m: float


#: element size at an interface corner, as a fraction of the tool's size
CORNER_RATIO = 0.3


@dataclass(frozen=True, slots=True)
class SolidMesh:
    """A conforming quadratic tetrahedral mesh of holder and tool.

    Attributes
    ----------
    points_m : numpy.ndarray, shape (3, nnodes)
        Node coordinates (vertices and edge nodes), m.
    tets : numpy.ndarray, shape (10, nelements)
        Node indices per tetrahedron, scikit-fem's order (4 vertices, then edges
        (0,1) (1,2) (0,2) (0,3) (1,3) (2,3)).
    part : numpy.ndarray, shape (nelements,)
        0 = holder, 1 = tool.
    quarter : bool
        True for the quarter model (x ≥ 0, y ≥ 0).
    straightened : int
        Elements whose curved edges were made straight because their map folded.
    half : bool
        True for the half model (y ≥ 0).
    """

    points_m: np.ndarray
    tets: np.ndarray
    part: np.ndarray
    quarter: bool
    straightened: int = 0
    half: bool = False

    @property
    def multiplicity(self) -> int:
        """Copies of the mesh in the whole body: 4 (quarter), 2 (half) or 1."""
        return 4 if self.quarter else 2 if self.half else 1


def case_pieces(case: SolidCase) -> tuple[Piece, ...]:
    """The holder's segments and the tool's shank, overhang and flutes as pieces.

    The shank is split at the contact region's ends so the bore surface carries those
    circles as mesh lines.

    Parameters
    ----------
    case : SolidCase

    Returns
    -------
    tuple of Piece
    """
    pieces: list[Piece] = []
    z0 = 0.0
    outer_at: list[tuple[float, float, float, float]] = []      # (z0, z1, d0, d1) of the holder's outside
    for seg in case.holder_segments:
        end = seg.outer_diameter_end_m if seg.is_cone else None
        pieces.append(Piece("holder", z0, z0 + seg.length_m, seg.outer_diameter_m, seg.inner_diameter_m,
                            outer_diameter_end_m=end))
        outer_at.append((z0, z0 + seg.length_m, seg.outer_diameter_m, end or seg.outer_diameter_m))
        z0 += seg.length_m
    face, tool = case.holder_length_m, case.tool
    for ring in case.rings:
        front = face - ring.front_offset_m
        back, thread_end = front - ring.length_m, front - ring.length_m + ring.attached_length_m
        under = [o for o in outer_at if o[0] - 1e-12 <= back and thread_end <= o[1] + 1e-12]
        if not under or under[0][2] != under[0][3]:
            raise ValueError("a ring's attached length must sit on one cylindrical holder segment")
        seat = under[0][2]
        pieces.append(Piece("holder", back, thread_end, ring.outer_diameter_m, seat))
        if thread_end < front - 1e-12:
            pieces.append(Piece("holder", thread_end, front, ring.outer_diameter_m, seat + 2 * ring.clearance_m))
    cuts = {case.insertion_start_m, face}
    for depth in (case.interface.contact_start_m, case.interface.contact_stop_m):
        if depth is not None and case.insertion_start_m < face - depth < face:
            cuts.add(face - depth)
    flat = tool.flat
    flat_z = (face - flat.start_m - flat.length_m, face - flat.start_m) if flat is not None else None
    if flat_z is not None:
        cuts.update(z for z in flat_z if case.insertion_start_m < z < face)
    stations = sorted(cuts)
    for a, b in zip(stations[:-1], stations[1:], strict=True):
        on_flat = flat_z is not None and flat_z[0] - 1e-12 <= a and b <= flat_z[1] + 1e-12
        pieces.append(Piece("tool", a, b, tool.shank_diameter_m,
                            flat_x_m=tool.shank_diameter_m / 2 - flat.depth_m if on_flat and flat else None))
    if flat is not None and flat_z is not None:
        radius, centre = tool.shank_diameter_m / 2, 0.5 * (flat_z[0] + flat_z[1])
        pieces.append(Piece("holder", centre - flat.screw_diameter_m / 2, centre + flat.screw_diameter_m / 2,
                            flat.screw_diameter_m, radial_x_m=(radius - flat.depth_m, radius + 0.5 * flat.depth_m)))
    flute_start = face + tool.stickout_m - tool.flute_length_m
    if flute_start > face + 1e-12:
        pieces.append(Piece("tool", face, flute_start, tool.shank_diameter_m))
    if tool.flutes is None:
        pieces.append(Piece("tool", flute_start, case.tip_z_m, tool.fluted_diameter_ratio * tool.diameter_m))
    else:
        pieces.append(Piece("tool", flute_start, case.tip_z_m, tool.diameter_m, flutes=tool.flutes))
    return tuple(pieces)


def _contact_z(case: SolidCase) -> tuple[float, float]:
    """The contact region's axial extent along the bore, z0 < z1, m."""
    face, start = case.holder_length_m, case.insertion_start_m
    stop = case.interface.contact_stop_m
    return (start if stop is None else max(start, face - stop)), face - case.interface.contact_start_m


def case_arc_cuts(case: SolidCase) -> tuple[ArcCut, ...]:
    """The half-planes that put an arc of contact's edges into the mesh (none for a full circle)."""
    arc = case.interface.arc_deg
    if arc >= 360.0:
        return ()
    z0, z1 = case.insertion_start_m, case.holder_length_m
    radius = case.tool.shank_diameter_m / 2
    return tuple(ArcCut(a, radius, z0, z1) for a in (180.0 - arc / 2, 180.0 + arc / 2)
                 if not case.uses_half() or 0.0 < a % 360.0 < 180.0)


def tool_fine_zone(case: SolidCase) -> FineZone:
    """The fine zone of a case: the tool and one shank radius of steel around the bore."""
    face, radius = case.holder_length_m, case.tool.shank_diameter_m / 2
    depths = {0.0, case.interface.contact_start_m, face - case.insertion_start_m}
    if case.interface.contact_stop_m is not None:
        depths.add(min(case.interface.contact_stop_m, face - case.insertion_start_m))
    z0, z1 = _contact_z(case)
    lines = tuple((radius * math.cos(math.radians(c.angle_deg)), radius * math.sin(math.radians(c.angle_deg)), z0, z1)
                  for c in case_arc_cuts(case))
    spots: tuple[tuple[float, float, float], ...] = ()
    if case.tool.flat is not None:
        fl = case.tool.flat
        spots = ((radius - fl.depth_m, face - fl.start_m - 0.5 * fl.length_m, 0.5 * fl.screw_diameter_m),)
    return FineZone(radius_m=case.tool.shank_diameter_m, z_start_m=case.insertion_start_m - 0.5
                    * case.tool.shank_diameter_m, corners=tuple((radius, face - d) for d in sorted(depths)),
                    lines=lines, spots=spots)


def _fluted_surface(piece: Piece) -> int:
    occ = gmsh.model.occ
    fl = piece.flutes
    assert fl is not None
    disk = occ.addDisk(0, 0, piece.z0_m, piece.outer_diameter_m / 2, piece.outer_diameter_m / 2)
    centre = fl.core_diameter_m / 2 + fl.gullet_radius_m
    gullets = []
    for k in range(fl.count):
        a = math.radians(fl.angle_deg) + 2 * math.pi * k / fl.count
        gullets.append((2, occ.addDisk(centre * math.cos(a), centre * math.sin(a), piece.z0_m,
                                       fl.gullet_radius_m, fl.gullet_radius_m)))
    out, _ = occ.cut([(2, disk)], gullets)
    assert len(out) == 1, out
    return out[0][1]


def _piece_volume(piece: Piece, symmetry: Symmetry, big_m: float) -> list[tuple[int, int]]:
    occ = gmsh.model.occ
    length = piece.z1_m - piece.z0_m
    if piece.radial_x_m is not None:
        x0, x1 = piece.radial_x_m
        vol = [(3, occ.addCylinder(x0, 0, 0.5 * (piece.z0_m + piece.z1_m), x1 - x0, 0, 0, piece.outer_diameter_m / 2))]
    elif piece.flutes is not None:
        surf = _fluted_surface(piece)
        ext = occ.extrude([(2, surf)], 0, 0, length)
        vol = [e for e in ext if e[0] == 3]
    else:
        if piece.outer_diameter_end_m is not None and piece.outer_diameter_end_m != piece.outer_diameter_m:
            vol = [(3, occ.addCone(0, 0, piece.z0_m, 0, 0, length, piece.outer_diameter_m / 2,
                                   piece.outer_diameter_end_m / 2))]
        else:
            vol = [(3, occ.addCylinder(0, 0, piece.z0_m, 0, 0, length, piece.outer_diameter_m / 2))]
        if piece.inner_diameter_m > 0:
            bore = occ.addCylinder(0, 0, piece.z0_m - 1e-3, 0, 0, length + 2e-3, piece.inner_diameter_m / 2)
            vol, _ = occ.cut(vol, [(3, bore)])
        if piece.flat_x_m is not None:
            cutter = occ.addBox(piece.flat_x_m, -big_m, piece.z0_m - 1e-3, big_m, 2 * big_m, length + 2e-3)
            vol, _ = occ.cut(vol, [(3, cutter)])
    if symmetry != "full":
        box = occ.addBox(0 if symmetry == "quarter" else -big_m, 0, piece.z0_m - 1e-3,
                         big_m if symmetry == "quarter" else 2 * big_m, big_m, length + 2e-3)
        vol, _ = occ.intersect(vol, [(3, box)])
    return vol


def _arc_surface(cut: ArcCut) -> tuple[int, int]:
    """The half-plane of an :class:`ArcCut` as an OpenCASCADE surface."""
    occ = gmsh.model.occ
    tag = occ.addRectangle(0, 0, 0, cut.radius_m, cut.z1_m - cut.z0_m)    # x ∈ [0, r], y ∈ [0, l]
    occ.rotate([(2, tag)], 0, 0, 0, 1, 0, 0, math.pi / 2)                  # y → z
    occ.translate([(2, tag)], 0, 0, cut.z0_m)
    occ.rotate([(2, tag)], 0, 0, 0, 0, 0, 1, math.radians(cut.angle_deg))
    return (2, tag)


def mesh_pieces(pieces: tuple[Piece, ...], size: MeshSize, quarter: bool, fine: FineZone | None = None,
                *, half: bool = False, arc_cuts: tuple[ArcCut, ...] = ()) -> SolidMesh:
    """Mesh the pieces as one conforming body of 10-node tetrahedra.

    Parameters
    ----------
    pieces : tuple of Piece
        Touching faces become shared (conforming) mesh faces; pieces of one part may overlap
        (a screw reaching into the holder), a holder and a tool piece may not.
    size : MeshSize
        ``tool_m`` inside the fine zone, growing by ``growth`` per metre of distance from
        it up to ``holder_m``.
    quarter : bool
        Keep only x ≥ 0, y ≥ 0.
    fine : FineZone or None
        Without one the size is ``tool_m`` everywhere.
    half : bool
        Keep only y ≥ 0 (with ``quarter`` False).
    arc_cuts : tuple of ArcCut
        Half-planes cutting the shank (the edges of an arc of contact).

    Returns
    -------
    SolidMesh
    """
    symmetry: Symmetry = "quarter" if quarter else "half" if half else "full"
    big = 2 * max(max(p.outer_diameter_m, p.outer_diameter_end_m or 0.0) for p in pieces)
    gmsh.initialize(interruptible=False)
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.option.setNumber("General.NumThreads", 1)
        gmsh.model.add("solid3d")
        occ = gmsh.model.occ
        inputs: list[tuple[int, int]] = []
        owner: list[Part] = []
        for piece in pieces:
            for v in _piece_volume(piece, symmetry, big):
                inputs.append(v)
                owner.append(piece.part)
        tools = [_arc_surface(c) for c in arc_cuts]
        if len(inputs) > 1 or tools:
            _, children = occ.fragment(inputs, tools)
            children = children[:len(inputs)]
        else:
            children = [inputs]
        occ.synchronize()
        volume_part: dict[int, int] = {}
        for part, kids in zip(owner, children, strict=True):
            for dim, tag in kids:
                if dim == 3:
                    prev = volume_part.setdefault(tag, PARTS.index(part))
                    if prev != PARTS.index(part):
                        raise ValueError("pieces of the holder and the tool overlap")
        if fine is None:
            expr = f"{size.tool_m}"
        else:
            expr = (f"Min({size.holder_m}, {size.tool_m} + {size.growth}*(Max(0, Sqrt(x*x+y*y) - {fine.radius_m})"
                    f" + Max(0, {fine.z_start_m} - z)))")
            for r, z in fine.corners:
                expr = (f"Min({expr}, {CORNER_RATIO * size.tool_m} + {size.growth}"
                        f"*Sqrt((Sqrt(x*x+y*y) - {r})^2 + (z - {z})^2))")
            for x0, y0, z0, z1 in fine.lines:     # numbers in brackets: the parser takes no "- -1"
                expr = (f"Min({expr}, {CORNER_RATIO * size.tool_m} + {size.growth}"
                        f"*Sqrt((x - ({x0}))^2 + (y - ({y0}))^2 + (Max(0, {z0} - z) + Max(0, z - {z1}))^2))")
            for x0, z0, r in fine.spots:
                expr = (f"Min({expr}, {CORNER_RATIO * size.tool_m} + {size.growth}"
                        f"*Sqrt((x - ({x0}))^2 + (Sqrt(y*y + (z - {z0})^2) - {r})^2))")
        field = gmsh.model.mesh.field.add("MathEval")
        gmsh.model.mesh.field.setString(field, "F", expr)
        gmsh.model.mesh.field.setAsBackgroundMesh(field)
        for name, value in (("Mesh.MeshSizeExtendFromBoundary", 0), ("Mesh.MeshSizeFromPoints", 0),
                            ("Mesh.MeshSizeFromCurvature", 0), ("Mesh.ElementOrder", 2),
                            ("Mesh.HighOrderOptimize", 0), ("Mesh.SecondOrderLinear", 0),
                            ("Mesh.MeshSizeMin", 0.25 * size.tool_m), ("Mesh.MeshSizeMax", size.holder_m)):
            gmsh.option.setNumber(name, value)
        gmsh.model.mesh.generate(3)
        node_tags, coords, _ = gmsh.model.mesh.getNodes()
        coords = coords.reshape(-1, 3).T
        index = np.full(int(node_tags.max()) + 1, -1, dtype=np.int64)
        index[node_tags.astype(np.int64)] = np.arange(node_tags.size)
        tets, parts = [], []
        for tag, part in sorted(volume_part.items()):
            types, _, elem_nodes = gmsh.model.mesh.getElements(3, tag)
            for etype, nodes in zip(types, elem_nodes, strict=True):
                if etype != 11:
                    raise RuntimeError(f"unexpected gmsh element type {etype} (want 10-node tetrahedra)")
                t = index[nodes.astype(np.int64)].reshape(-1, 10).T[GMSH_TO_SKFEM_TET10]
                tets.append(t)
                parts.append(np.full(t.shape[1], part, dtype=np.int8))
    finally:
        gmsh.finalize()
        # gmsh.initialize sets SIGPIPE back to the default disposition (terminate) in this
        # process; Python ignores it so that a write to a closed socket raises BrokenPipeError.
        # Left so, the next test that writes to a socket its server closed (the hostile and
        # slow-client tests do) killed the xdist worker without a traceback.
        if threading.current_thread() is threading.main_thread():
            signal.signal(signal.SIGPIPE, signal.SIG_IGN)
    t = np.hstack(tets)
    used, inverse = np.unique(t, return_inverse=True)
    t = inverse.reshape(t.shape).astype(np.int64)
    points = np.ascontiguousarray(coords[:, used])
    _check_edge_nodes(points, t)
    points, straightened = _straighten_inverted(points, t)
    return SolidMesh(points_m=points, tets=t, part=np.concatenate(parts), quarter=quarter,
                     straightened=straightened, half=symmetry == "half")


def _straighten_inverted(points: np.ndarray, t: np.ndarray) -> tuple[np.ndarray, int]:
    """Move the edge nodes of elements whose curved map folds back to their edges' midpoints.

    gmsh places edge nodes on the curved CAD faces; on a coarse mesh a thin element at a
    curved face can fold (negative Jacobian). Its edges are made straight instead (a local
    linear approximation of the face there); the count is reported in the mesh.
    """
    points = points.copy()
    done: set[int] = set()
    for _ in range(5):
        basis = Basis(MeshTet2(points, t), ElementTetP2(), intorder=4)
        det = basis.mapping.detDF(basis.X)                          # (nel, nq), signed
        p0, p1, p2, p3 = (points[:, t[i]] for i in range(4))
        volume6 = np.einsum("ie,ie->e", np.cross((p1 - p0).T, (p2 - p0).T).T, p3 - p0)
        bad = np.flatnonzero(np.min(det * np.sign(volume6)[:, None], axis=1) <= 0)
        if bad.size == 0:
            return points, len(done)
        done.update(bad.tolist())
        for k, (a, b) in enumerate(_EDGES):
            points[:, t[4 + k, bad]] = 0.5 * (points[:, t[a, bad]] + points[:, t[b, bad]])
    raise RuntimeError("could not untangle the curved mesh")


def _check_edge_nodes(points: np.ndarray, t: np.ndarray) -> None:
    """Every edge node lies near its edge's midpoint (the node order is the expected one)."""
    for k, (a, b) in enumerate(_EDGES):
        mid = 0.5 * (points[:, t[a]] + points[:, t[b]])
        length = np.linalg.norm(points[:, t[a]] - points[:, t[b]], axis=0)
        off = np.linalg.norm(points[:, t[4 + k]] - mid, axis=0)
        if np.any(off > 0.3 * length):
            raise RuntimeError("10-node tetrahedra: an edge node is far from its edge (node order?)")
