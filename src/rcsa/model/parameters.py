"""Named assembly parameters: the bearing, joint and tool values that sensitivity studies,
joint identification and diagnoses vary.

Names are stable strings: ``bearings[i].stiffness_n_m``, ``spindle_holder.damping_ns_m``,
``holder_tool.rotational_stiffness_nm_rad``, ``tool.stickout_m``,
``tool.fluted_diameter_ratio``; for a holder–tool clamping along the insertion (model
``bonded``/``contact``) ``holder_tool.interface_stiffness_scale`` (a factor on its whole interface
stiffness) and, for ``contact``, ``holder_tool.interface_stiffness_n_m3``. :func:`get_parameter` reads one from an
:class:`~rcsa.model.contract.AssemblySpec`; :func:`set_parameter` returns a new spec with it changed.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import replace
from typing import Any

from rcsa.errors import InputError
from rcsa.model.contract import AssemblySpec, ClampingSpec, SpindleSpec

__all__ = ["chosen_parameters", "get_parameter", "is_damping", "parameter_names", "set_parameter"]

_JOINT_FIELDS = ("stiffness_n_m", "damping_ns_m", "rotational_stiffness_nm_rad", "rotational_damping_nms_rad")
_BEARING_FIELDS = ("stiffness_n_m", "damping_ns_m")
_TOOL_FIELDS = ("stickout_m", "fluted_diameter_ratio")
_CLAMPING_FIELDS = ("interface_stiffness_scale", "interface_stiffness_n_m3")


def parameter_names(spec: AssemblySpec) -> tuple[str, ...]:
    """Names of the parameters an effect analysis varies, in report order.

    Each bearing's ``stiffness_n_m`` and ``damping_ns_m``, each elastic joint's four
    values, then ``tool.stickout_m`` and ``tool.fluted_diameter_ratio``. Parameters that are
    zero or rigid (``None``) are left out: their normalised sensitivity is not defined.

    Parameters
    ----------
    spec : AssemblySpec
        An assembly with an analytical spindle.

    Returns
    -------
    tuple of str
        E.g. ``("bearings[0].stiffness_n_m", ..., "holder_tool.rotational_damping_nms_rad",
        "tool.stickout_m", "tool.fluted_diameter_ratio")``.
    """
    names: list[str] = []
    if isinstance(spec.spindle, SpindleSpec):
        for i, _ in enumerate(spec.spindle.bearings):
            names.extend(f"bearings[{i}].{k}" for k in _BEARING_FIELDS)
    for joint in ("spindle_holder", "holder_tool"):
        fields = _CLAMPING_FIELDS if isinstance(getattr(spec, joint), ClampingSpec) else _JOINT_FIELDS
        names.extend(f"{joint}.{k}" for k in fields)
    names.extend(f"tool.{k}" for k in _TOOL_FIELDS)
    return tuple(n for n in names if (v := get_parameter(spec, n)) is not None and v > 0)


def _split(name: str) -> tuple[str, int | None, str]:
    head, _, field = name.partition(".")
    if head.startswith("bearings[") and head.endswith("]"):
        index = head[len("bearings["):-1]
        if not index.isdigit():
            raise InputError("parameters", f"bad bearing index in {name!r}")
        return "bearings", int(index), field
    return head, None, field


def chosen_parameters(spec: AssemblySpec, requested: Sequence[str] | None,
                      available: tuple[str, ...]) -> tuple[str, ...]:
    """The parameters an analysis varies: ``requested`` checked against ``available``, or all of them.

    Parameters
    ----------
    spec : AssemblySpec
    requested : sequence of str or None
        Names asked for (None: every available one).
    available : tuple of str
        The names the analysis can vary in ``spec`` (non-zero, non-rigid).

    Raises
    ------
    InputError
        ``parameters``: an unknown name, one that is zero or rigid in this assembly (its
        normalised sensitivity is not defined), or a name given twice.

    Examples
    --------
    >>> from rcsa.model.contract import parse_assembly
    >>> from rcsa.reference import ra1
    >>> spec = parse_assembly(ra1())
    >>> chosen_parameters(spec, ["holder_tool.stiffness_n_m"], parameter_names(spec))
    ('holder_tool.stiffness_n_m',)
    """
    if requested is None:
        return available
    names = tuple(requested)
    for n in names:
        if n not in available:
            get_parameter(spec, n)  # raises for an unknown name
            raise InputError("parameters", f"{n!r} is zero or rigid in this assembly: its normalised "
                             "sensitivity is not defined")
    if len(set(names)) != len(names):
        raise InputError("parameters", "names must be unique")
    return names


def get_parameter(spec: AssemblySpec, name: str) -> float | None:
    """Value of a named parameter in SI units (``None`` when rigid or absent).

    Parameters
    ----------
    spec : AssemblySpec
    name : str
        A parameter name, e.g. ``"bearings[0].stiffness_n_m"`` or ``"tool.stickout_m"``.

    Raises
    ------
    InputError
        For an unknown name.
    """
    group, index, field = _split(name)
    if group == "bearings":
        if field not in _BEARING_FIELDS or not isinstance(spec.spindle, SpindleSpec) \
                or index is None or index >= len(spec.spindle.bearings):
            raise InputError("parameters", f"unknown parameter {name!r}")
        return float(getattr(spec.spindle.bearings[index], field))
    if group in ("spindle_holder", "holder_tool") and field in (*_JOINT_FIELDS, *_CLAMPING_FIELDS):
        joint = getattr(spec, group)
        if joint is None or (field in _CLAMPING_FIELDS) != isinstance(joint, ClampingSpec):
            return None  # rigid, or a field of the other kind of joint
        value = getattr(joint, field)
        return None if value is None else float(value)
    if group == "tool" and field in _TOOL_FIELDS:
        return float(getattr(spec.tool, field))
    raise InputError("parameters", f"unknown parameter {name!r}")


def set_parameter(spec: AssemblySpec, name: str, value: float) -> AssemblySpec:
    """A copy of ``spec`` with one named parameter replaced (no re-validation).

    The value is set as given, so a derivative may be taken at a bound (e.g. a fluted
    diameter ratio of exactly 1). A stickout change keeps the overall length: the inserted
    length changes with it (``docs/contract.md`` "Assembly").

    Parameters
    ----------
    spec : AssemblySpec
    name : str
        As in :func:`parameter_names`.
    value : float
        New value, SI units.
    """
    group, index, field = _split(name)
    if group == "bearings":
        get_parameter(spec, name)  # validates
        spindle = spec.spindle
        assert isinstance(spindle, SpindleSpec) and index is not None
        bearings = list(spindle.bearings)
        bearings[index] = replace(bearings[index], **{field: float(value)})
        return replace(spec, spindle=replace(spindle, bearings=tuple(bearings)))
    if group in ("spindle_holder", "holder_tool") and field in (*_JOINT_FIELDS, *_CLAMPING_FIELDS):
        joint = getattr(spec, group)
        if joint is None:
            raise InputError("parameters", f"{name!r}: the joint {group} is rigid in this assembly")
        if (field in _CLAMPING_FIELDS) != isinstance(joint, ClampingSpec):
            kind = f"a clamping along the insertion (model {joint.model!r})" if isinstance(joint, ClampingSpec) \
                else "a point joint"
            raise InputError("parameters", f"{name!r}: {group} is {kind} in this assembly")
        if getattr(joint, field) is None:
            raise InputError("parameters", f"{name!r}: {group} has no {field} (model {joint.model!r})")
        return replace(spec, **{group: replace(joint, **{field: float(value)})})
    if group == "tool" and field in _TOOL_FIELDS:
        change: dict[str, Any] = {field: float(value)}  # a float field of ToolSpec (_TOOL_FIELDS)
        return replace(spec, tool=replace(spec.tool, **change))
    raise InputError("parameters", f"unknown parameter {name!r}")


def is_damping(name: str) -> bool:
    """True for a damping parameter (``..._damping_ns_m`` or ``..._damping_nms_rad``).

    Parameters
    ----------
    name : str
        A parameter name.
    """
    return name.endswith(("damping_ns_m", "damping_nms_rad"))
