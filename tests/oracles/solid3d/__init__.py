"""A 3-D linear-elastic finite-element reference of holder + tool (issue 24; a test oracle).

Independent of rcsa's beam physics (rcsa is used only to compare with, and to condense a
spindle to the base receptance the holder is coupled to). Quadratic tetrahedra with curved
faces (gmsh, OpenCASCADE) and quadratic Lagrange displacements (scikit-fem bases, own
vectorised element kernels); hysteretic damping E(1 + iη) per part.

Modules
-------
case
    ``SolidCase`` and its parts (``HolderSegment``, ``ToolGeometry``, ``Flutes``,
    ``Interface``, ``SolidMaterial``, ``MeshSize``), in the contract's terms, SI units.
geometry
    Pieces and the conforming mesh (quarter model by symmetry where valid).
assembly
    Stiffness per part, mass, the shank–bore interface (bonded, spring layer, contact
    region), tip loads, and the constraints as one transformation (symmetry, rigid base
    face with DOFs q, rigid holder).
reduction
    Craig–Bampton with static tip and base-inertia vectors; the stacked frequency solve;
    the direct sparse solve it is checked against.
solve
    ``solve(case, frequency_hz, base) -> SolidFRF``, ``build``/``solve_model`` to reuse a
    model for both bases, ``ReceptanceBase``, ``largest_peak``.
dataset
    The reference data set's cases, files (``tests/data/solid3d``) and the beam model's view
    of each case.
"""
