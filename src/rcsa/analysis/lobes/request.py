"""Validation of stability-lobes request bodies (contract "Stability lobes").

Turns the JSON body of ``POST /v1/stability-lobes`` / ``rcsa lobes REQUEST.json`` into a
:class:`LobesRequest` of numpy arrays, or raises :class:`~rcsa.errors.InputError` naming
the offending field. No web framework is imported here.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from rcsa.analysis.lobes.modal_model import ModalModel, fit_modal_model, modal_model_from_table
from rcsa.analysis.lobes.options import MAX_SDM_SPEED_COUNT, OPTION_KEYS, LobesMethod, parse_method
from rcsa.analysis.lobes.semi_discretization import (
    SemiDiscretizationResult,
    semi_discretization_lobes,
)
from rcsa.analysis.lobes.zoa import (
    LobeResult,
    Milling,
    check_cut,
    check_frf,
    check_speed_grid,
    stability_lobes,
)
from rcsa.errors import FrequencyMismatch, InputError
from rcsa.model import fields
from rcsa.model.bounds import (
    MAX_FREQUENCY_LINES,
    MAX_FRF_VALUE,
    MAX_MODAL_DAMPING_RATIO,
    MAX_MODAL_FREQUENCY_HZ,
    MAX_MODAL_MASS_KG,
    MAX_MODAL_STIFFNESS_N_M,
    MAX_MODAL_TABLE_MODES,
    MAX_SPEED_COUNT,
    MAX_SPEED_RPM,
    MIN_MODAL_DAMPING_RATIO,
    MIN_MODAL_FREQUENCY_HZ,
    MIN_MODAL_MASS_KG,
    MIN_MODAL_STIFFNESS_N_M,
    MIN_SPEED_COUNT,
    MIN_SPEED_RPM,
)
from rcsa.model.input_policy import check_count
from rcsa.model.wire import complex_from_wire, number_list
from rcsa.physics.receptance import check_frequency_hz

__all__ = ["LobesRequest", "SdmSolver", "parse_lobes_request"]

#: How a semi-discretization is solved: ``solver(modal_model, spindle_speed_rpm, settings)`` with
#: ``settings`` the keywords of :func:`semi_discretization_lobes` besides those two — by default
#: that function itself, in this process; the application layer may spread the speeds over
#: worker processes or a cluster and merge the parts (:func:`~rcsa.analysis.lobes.
#: semi_discretization.merged_result`).
SdmSolver = Callable[[ModalModel, np.ndarray, dict[str, Any]], SemiDiscretizationResult]


def _here(model: ModalModel, spindle_speed_rpm: np.ndarray, settings: dict[str, Any]) -> SemiDiscretizationResult:
    """:data:`SdmSolver` in this process: :func:`semi_discretization_lobes` over every speed at once."""
    return semi_discretization_lobes(model, spindle_speed_rpm=spindle_speed_rpm, **settings)


@dataclass(frozen=True, slots=True)
class LobesRequest:
    """A validated stability-lobes request (contract "Stability lobes").

    Exactly one of the inline FRFs (``frequency_hz``, ``frf_xx`` and optionally ``frf_yy``),
    a modal table (``modal_model``) or ``assembly`` (returned untouched for the caller to
    predict the tool-point FRF) is set. ``x`` is the feed direction, ``y`` the normal to the
    feed in the plane of the cut; a request with one direction only uses it for both (a tool
    whose holder and spindle are round), and the result says so.

    Attributes
    ----------
    frequency_hz : numpy.ndarray or None, shape (nfreq,)
    frf_xx, frf_yy : numpy.ndarray or None, shape (nfreq,)
        Complex receptances, m/N.
    modal_model : ModalModel or None
        A modal table's modes (``modal_x``, ``modal_y``).
    assembly : Mapping or None
        The request's ``assembly`` object, unvalidated here.
    teeth, tangential_coefficient_n_m2, radial_ratio, radial_immersion, milling
        As in :func:`stability_lobes`.
    spindle_speed_rpm : numpy.ndarray, shape (count,)
        ``linspace(start, stop, count)`` or the list given, rpm.
    method : LobesMethod
        ``"zoa"`` or ``"semi_discretization"`` (``"auto"``, the default, resolved) and its options.
    """

    frequency_hz: np.ndarray | None
    frf_xx: np.ndarray | None
    frf_yy: np.ndarray | None
    assembly: Mapping[str, Any] | None
    teeth: int
    tangential_coefficient_n_m2: float
    radial_ratio: float
    radial_immersion: float
    milling: Milling
    spindle_speed_rpm: np.ndarray
    method: LobesMethod = LobesMethod()
    modal_model: ModalModel | None = None

    def sdm_settings(self) -> dict[str, Any]:
        """The keywords of :func:`semi_discretization_lobes` this request sets besides the modes and
        the speeds (the cut and ``steps_per_period``)."""
        return {"teeth": self.teeth, "tangential_coefficient_n_m2": self.tangential_coefficient_n_m2,
                "radial_ratio": self.radial_ratio, "radial_immersion": self.radial_immersion,
                "milling": self.milling, "steps_per_period": self.method.steps_per_period}

    def solve(
        self,
        frequency_hz: object | None = None,
        frf_xx: object | None = None,
        frf_yy: object | None = None,
        *,
        modal_model: ModalModel | None = None,
        sdm_solver: SdmSolver | None = None,
    ) -> LobeResult:
        """Run :func:`stability_lobes` (or the semi-discretization) with this request.

        The inline receptances (or the modal table) are used unless given here (e.g. the
        tool-point FRF the caller predicted from ``assembly``); ``frf_yy=None`` then means "same
        as x". With ``method.name == "semi_discretization"`` the modes are ``modal_model`` when
        given (e.g. the exact modes of an analytical assembly), else the request's table, else
        fitted to the receptances (:func:`~rcsa.analysis.lobes.modal_model.fit_modal_model`).
        Zero-order lobes of a modal table use its receptances on a grid that resolves every
        mode (:meth:`ModalModel.frf_grid`). ``sdm_solver`` solves the semi-discretization
        (:data:`SdmSolver`; default: here, every speed at once).
        """
        table = self.modal_model
        if frequency_hz is None:
            if self.frequency_hz is None and table is None:
                raise InputError(
                    "frf_x", "the request has an assembly: predict its FRF and pass it to solve()"
                )
            if table is not None and self.frequency_hz is None:
                grid = table.frf_grid()
                frequency_hz, frf_xx = grid, table.receptance(grid, 0)
                frf_yy = None if table.same_in_y else table.receptance(grid, 1)
                modal_model = modal_model or table
            else:
                frequency_hz, frf_xx, frf_yy = self.frequency_hz, self.frf_xx, self.frf_yy
        if self.method.name == "semi_discretization":
            if modal_model is None:
                modal_model = fit_modal_model(
                    np.asarray(frequency_hz, dtype=float),
                    np.asarray(frf_xx, dtype=complex),
                    None if frf_yy is None else np.asarray(frf_yy, dtype=complex),
                    modes_per_direction=self.method.modes_per_direction,
                )
            return (sdm_solver or _here)(modal_model, self.spindle_speed_rpm, self.sdm_settings())
        return stability_lobes(
            frequency_hz,
            frf_xx,
            frf_yy,
            teeth=self.teeth,
            tangential_coefficient_n_m2=self.tangential_coefficient_n_m2,
            radial_ratio=self.radial_ratio,
            radial_immersion=self.radial_immersion,
            milling=self.milling,
            spindle_speed_rpm=self.spindle_speed_rpm,
        )


_REQUEST_KEYS = {
    "frf_x",
    "frf_y",
    "modal_x",
    "modal_y",
    "assembly",
    "teeth",
    "tangential_coefficient_n_m2",
    "radial_ratio",
    "radial_immersion",
    "milling",
    "spindle_speed_rpm",
    *OPTION_KEYS,
}
_REQUIRED_KEYS = (
    "teeth",
    "tangential_coefficient_n_m2",
    "radial_ratio",
    "radial_immersion",
    "milling",
    "spindle_speed_rpm",
)


def _mapping(value: object, field: str, keys: set[str]) -> Mapping[str, Any]:
    body = fields.json_object(value, field, sorted(keys))
    missing = sorted(keys - set(body))
    if missing and field:  # nested objects: every key is required
        raise InputError(fields.join(field, missing[0]), "is required")
    return body


def _parse_frf(value: object, field: str) -> tuple[np.ndarray, np.ndarray]:
    body = _mapping(value, field, {"frequency_hz", "h"})
    if isinstance(body["frequency_hz"], list):
        check_count(len(body["frequency_hz"]), f"{field}.frequency_hz", MAX_FREQUENCY_LINES, "frequency lines")
    f = check_frequency_hz(
        number_list(body["frequency_hz"], f"{field}.frequency_hz", finite=False), f"{field}.frequency_hz"
    )
    h = complex_from_wire(body["h"], f"{field}.h", f.size, finite=False)
    if np.any(np.abs(h.real) > MAX_FRF_VALUE) or np.any(np.abs(h.imag) > MAX_FRF_VALUE):
        raise InputError(f"{field}.h", f"real and imaginary parts must lie within ±{MAX_FRF_VALUE:g} m/N")
    return f, check_frf(h, f.size, field)


_MODE_KEYS = {"frequency_hz", "damping_ratio", "modal_mass_kg", "stiffness_n_m"}


def _parse_modal_table(value: object, field: str) -> list[tuple[float, float, float]]:
    """A modal table of one direction: ``[{"frequency_hz", "damping_ratio", "modal_mass_kg" |
    "stiffness_n_m"}, ...]`` → ``(f, ζ, m)`` rows."""
    if not isinstance(value, list):
        raise InputError(field, f"must be a list of modes, got {type(value).__name__}")
    check_count(len(value), field, MAX_MODAL_TABLE_MODES, "modes")
    rows = []
    for i, item in enumerate(value):
        where = f"{field}[{i}]"
        mode = fields.Fields(item, where, sorted(_MODE_KEYS))
        f = mode.number("frequency_hz", gt=0.0, ge=MIN_MODAL_FREQUENCY_HZ, le=MAX_MODAL_FREQUENCY_HZ)
        zeta = mode.number("damping_ratio", gt=0.0, ge=MIN_MODAL_DAMPING_RATIO, le=MAX_MODAL_DAMPING_RATIO)
        given = [k for k in ("modal_mass_kg", "stiffness_n_m") if mode.value.get(k) is not None]
        if len(given) != 1:
            raise InputError(fields.join(where, "modal_mass_kg"),
                             "give exactly one of modal_mass_kg or stiffness_n_m (the modal stiffness)")
        if given[0] == "modal_mass_kg":
            mass = mode.number("modal_mass_kg", gt=0.0, ge=MIN_MODAL_MASS_KG, le=MAX_MODAL_MASS_KG)
        else:
            k = mode.number("stiffness_n_m", gt=0.0, ge=MIN_MODAL_STIFFNESS_N_M, le=MAX_MODAL_STIFFNESS_N_M)
            mass = k / (2.0 * np.pi * f) ** 2
        rows.append((f, zeta, mass))
    return rows


def _parse_speeds(value: object) -> np.ndarray:
    """``{"start", "stop", "count"}`` (equally spaced) or a list of speeds (strictly increasing), rpm."""
    if isinstance(value, list):
        check_count(len(value), "spindle_speed_rpm", MAX_SPEED_COUNT, "speeds")
        if len(value) < MIN_SPEED_COUNT:
            raise InputError("spindle_speed_rpm", f"give at least {MIN_SPEED_COUNT} speeds, got {len(value)}")
        return check_speed_grid(number_list(value, "spindle_speed_rpm"))
    speed = fields.Fields(_mapping(value, "spindle_speed_rpm", {"start", "stop", "count"}), "spindle_speed_rpm")
    start = speed.number("start", gt=0.0, ge=MIN_SPEED_RPM, le=MAX_SPEED_RPM)
    stop = speed.number("stop", gt=0.0, ge=MIN_SPEED_RPM, le=MAX_SPEED_RPM)
    if not start < stop:
        raise InputError(
            "spindle_speed_rpm.stop", f"must be greater than start ({start}), got {stop}"
        )
    count = speed.integer("count", ge=MIN_SPEED_COUNT, le=MAX_SPEED_COUNT)
    grid = np.linspace(start, stop, count)
    grid.flags.writeable = False
    return grid


def parse_lobes_request(body: object) -> LobesRequest:
    """Validate a stability-lobes request body (contract "Stability lobes").

    Parameters
    ----------
    body : Mapping
        Parsed JSON: one of ``frf_x`` (``{"frequency_hz": [...], "h": {"real": [...],
        "imag": [...]}}``, the feed direction), ``modal_x`` (a modal table of the feed direction:
        ``[{"frequency_hz", "damping_ratio", "modal_mass_kg" or "stiffness_n_m"}, ...]``) or
        ``assembly``; optional ``frf_y`` / ``modal_y`` (the normal direction, same form; null =
        same as x; ``modal_y: []`` = rigid in y), ``teeth``, ``tangential_coefficient_n_m2``,
        ``radial_ratio``, ``radial_immersion``, ``milling`` (``"up"``/``"down"``) and
        ``spindle_speed_rpm`` (``{"start", "stop", "count"}`` or a list of speeds); optional
        ``method`` (``"auto"``, the default, ``"zoa"`` or ``"semi_discretization"``, with
        ``steps_per_period`` and ``modes_per_direction``:
        :func:`~rcsa.analysis.lobes.options.parse_method`).

    Returns
    -------
    LobesRequest

    Raises
    ------
    InputError
        Unknown or missing fields, wrong types, or a rule broken (``teeth`` integer ≥ 1,
        ``Kt > 0``, ``0 < radial_immersion <= 1``, ``start < stop``,
        ``2 <= count <= MAX_SPEED_COUNT``, exactly one of ``frf_x``/``modal_x``/``assembly``).

    Examples
    --------
    >>> req = parse_lobes_request({
    ...     "frf_x": {"frequency_hz": [100.0, 200.0], "h": {"real": [1e-7, -1e-7], "imag": [-1e-8, -2e-7]}},
    ...     "teeth": 4, "tangential_coefficient_n_m2": 6e8, "radial_ratio": 0.3,
    ...     "radial_immersion": 0.5, "milling": "down",
    ...     "spindle_speed_rpm": {"start": 2000, "stop": 30000, "count": 3}})
    >>> req.spindle_speed_rpm.tolist(), req.frf_yy is None, req.method.name
    ([2000.0, 16000.0, 30000.0], True, 'semi_discretization')
    >>> req = parse_lobes_request({
    ...     "modal_x": [{"frequency_hz": 565.1, "damping_ratio": 0.0322, "modal_mass_kg": 0.1966}],
    ...     "teeth": 3, "tangential_coefficient_n_m2": 7.96e8, "radial_ratio": 0.3,
    ...     "radial_immersion": 0.17, "milling": "down", "spindle_speed_rpm": [3000, 10000, 15000]})
    >>> req.modal_model.source, req.spindle_speed_rpm.tolist()
    ('given', [3000.0, 10000.0, 15000.0])
    """
    body = _mapping(body, "", _REQUEST_KEYS)
    for key in _REQUIRED_KEYS:
        if key not in body:
            raise InputError(key, "is required")

    frf_x, frf_y, assembly = body.get("frf_x"), body.get("frf_y"), body.get("assembly")
    modal_x, modal_y = body.get("modal_x"), body.get("modal_y")
    if sum(v is not None for v in (frf_x, modal_x, assembly)) != 1:
        raise InputError("frf_x", "give exactly one of frf_x (inline FRF), modal_x (a modal table) or assembly")
    if frf_y is not None and frf_x is None:
        raise InputError("frf_y", "only allowed together with frf_x (an assembly gives both directions)")
    if modal_y is not None and modal_x is None:
        raise InputError("modal_y", "only allowed together with modal_x")
    freq = hxx = hyy = None
    table_x = table_y = None
    if frf_x is not None:
        freq, hxx = _parse_frf(frf_x, "frf_x")
        if frf_y is not None:
            freq_y, hyy = _parse_frf(frf_y, "frf_y")
            if freq_y.shape != freq.shape or not np.array_equal(freq_y, freq):
                raise FrequencyMismatch(
                    "frf_y.frequency_hz", "must equal frf_x.frequency_hz exactly"
                )
    elif modal_x is not None:
        table_x = _parse_modal_table(modal_x, "modal_x")
        if not table_x:
            raise InputError("modal_x", "give at least one mode of the feed direction")
        table_y = None if modal_y is None else _parse_modal_table(modal_y, "modal_y")
    elif not isinstance(assembly, Mapping):
        raise InputError("assembly", f"must be an object, got {type(assembly).__name__}")

    cut = check_cut(body["teeth"], body["tangential_coefficient_n_m2"], body["radial_ratio"],
                    body["radial_immersion"], body["milling"])
    grid = _parse_speeds(body["spindle_speed_rpm"])
    method = parse_method(body, teeth=cut.teeth, radial_immersion=cut.radial_immersion)
    if method.name == "semi_discretization" and grid.size > MAX_SDM_SPEED_COUNT:
        raise InputError("spindle_speed_rpm.count",
                         f"at most {MAX_SDM_SPEED_COUNT} speeds with method 'semi_discretization', got {grid.size}")
    table = None if table_x is None else modal_model_from_table(table_x, table_y,
                                                                modes_per_direction=method.modes_per_direction)

    return LobesRequest(
        frequency_hz=freq,
        frf_xx=hxx,
        frf_yy=hyy,
        assembly=assembly,
        teeth=cut.teeth,
        tangential_coefficient_n_m2=cut.tangential_coefficient_n_m2,
        radial_ratio=cut.radial_ratio,
        radial_immersion=cut.radial_immersion,
        milling=cut.milling,
        spindle_speed_rpm=grid,
        method=method,
        modal_model=table,
    )
