"""Conical pieces of holders and tool necks as stepped cylinders: how many, and how thick.

The beam model is made of uniform segments, so a cone (a holder's nose, a tapered neck, a
chamfer of a FreeCAD outline) becomes ``n`` cylinders of equal length, each at the cone's
diameter at the middle of its piece (length and mean diameter kept exactly; the volume is
low by π·h·Δd²/(48·n²)).

How many steps: the rule
------------------------
The error of the stepped cone in the tip static compliance and the first natural frequency
of a cantilevered cone falls as 1/n², and to first order grows *linearly* with the taper
r = |d₁ − d₀| / min(d₀, d₁): it comes from the bending moment varying along each step
(the load-weighted 1/EI inside a step), so error ≈ c·r/n², with c ≈ 0.5–0.95 measured on
cones from r = 0.05 to r = 3, short and slender (``tests/libraries/test_profiles.py``).
:func:`cone_steps` therefore takes

    n = ⌈√(r / ε)⌉,  ε = :data:`CONE_STEP_TOLERANCE` = 0.005,

so that c·r/n² ≤ ε: every cone is within 0.5 % of its converged (fine-step) tip compliance
and first mode, and a cylinder stays one piece. A per-step rule on the diameter jump
(``Δd/n ≤ f·d``) would give a gentle taper a single step (a 5 % taper in one cylinder is
≈ 5 % off) while over-refining steep ones. The result is capped at
:data:`MAX_CONE_STEPS`. A caller's ``holder_segments_per_cone`` overrides the rule.

Which diameter: each step takes the cone's diameter at its middle. The "stiffness-
equivalent" diameter of a step under a uniform moment (d⁴ = 3d₀³d₁³/(d₀² + d₀d₁ + d₁²), the
harmonic mean of I) converges at the same 1/n² but measured 1.5–2× further off in the tip
compliance (the test compares both): for a cantilever the step's error is set by how the
moment varies along it, not by how I is averaged, and the middle diameter also keeps the
mass right.
"""

from __future__ import annotations

import math

from rcsa.model.bounds import MAX_HOLDER_SEGMENTS_PER_CONE

__all__ = ["CONE_STEP_TOLERANCE", "MAX_CONE_STEPS", "cone_cylinders", "cone_steps"]

#: Relative error allowed for a stepped cone's tip compliance and first mode (module docstring).
CONE_STEP_TOLERANCE = 0.005
#: Most cylinders one cone becomes (a taper beyond r = 12.5 is capped, with a warning).
MAX_CONE_STEPS = MAX_HOLDER_SEGMENTS_PER_CONE


def cone_steps(lower: float, upper: float, *, tolerance: float = CONE_STEP_TOLERANCE) -> int:
    """Number of cylinders for a cone from diameter ``lower`` to ``upper`` (any one unit).

    Parameters
    ----------
    lower, upper : float
        End diameters, > 0.
    tolerance : float
        Allowed relative error ε of the stepped cone (module docstring).

    Returns
    -------
    int
        ⌈√(r/ε)⌉ with r = |upper − lower| / min(lower, upper), at least 1 (a cylinder is 1)
        and at most :data:`MAX_CONE_STEPS`.

    Examples
    --------
    >>> cone_steps(42.0, 46.0), cone_steps(6.0, 10.0), cone_steps(50.0, 50.0)
    (5, 12, 1)
    """
    if upper == lower:
        return 1
    if not min(lower, upper) > 0.0:  # a cone to a point: as finely as allowed
        return MAX_CONE_STEPS
    taper = abs(upper - lower) / min(lower, upper)
    return max(1, min(MAX_CONE_STEPS, math.ceil(math.sqrt(taper / tolerance) - 1e-9)))


def cone_cylinders(height: float, lower: float, upper: float, n: int | None = None) -> list[tuple[float, float]]:
    """Approximate a cone by ``n`` equal-length cylinders at their mid-length diameters.

    Parameters
    ----------
    height : float
        Cone length (any length unit; the output uses the same).
    lower, upper : float
        Diameters at the first and the last end.
    n : int, optional
        Number of cylinders; default :func:`cone_steps`. A cylinder (``lower == upper``)
        always gives one.

    Returns
    -------
    list of (length, diameter)
        From the ``lower`` end to the ``upper`` end. The lengths add up to ``height`` and the
        mean diameter is kept; the volume is low by π·height·(upper − lower)²/(48·n²).

    Examples
    --------
    >>> cone_cylinders(8.0, 42.0, 50.0, 4)
    [(2.0, 43.0), (2.0, 45.0), (2.0, 47.0), (2.0, 49.0)]
    """
    if upper == lower:
        return [(height, lower)]
    if n is None:
        n = cone_steps(lower, upper)
    return [(height / n, lower + (upper - lower) * (2 * k + 1) / (2 * n)) for k in range(n)]
