"""Universal File Format dataset 58 (ASCII and binary "58b") through pyuff.

What is read (the UFF 58 record layout, as printed by
``pyuff.datasets.dataset_58.get_structure_58()``):

* **Per-dataset selection.** Only datasets 58 and 164 are parsed; geometry, groups and
  other datasets (15, 151, 2411, 2467 …) are skipped unread. Of the 58s, function type 4
  (FRF) is imported and type 6 (coherence) attached to the FRF of the same DOFs; any other
  function type (time response, spectra …) is skipped and listed in the provenance.
* **Directions.** Response and reference must be translations along one axis (direction
  codes ±1 X, ±2 Y, ±3 Z); the value is multiplied by sign(rsp_dir)·sign(ref_dir) so that
  it is +/+. The file's axis is the measurement's direction: X is ``x``, Y is ``y``; a
  declared ``direction`` that the file contradicts is refused, and without one the file's
  is used. FRFs along other axes than the chosen one are skipped (a file may hold X and Y).
  Scalar FRFs (direction code 0) say no axis: they are imported only with
  ``scalar_direction`` (``"x"`` or ``"y"``). Rotational DOFs (±4…±6) are skipped.
* **Quantity** from record 9/10's specific data types: numerator 8 displacement →
  receptance, 11 velocity → mobility, 12 acceleration → accelerance; denominator 13
  (excitation force) or 9 (reaction force). Unknown codes (0, 1) need ``units`` declared.
* **Units** are never guessed. In order: ``units`` declared by the caller (e.g. ``"g/N"``,
  which dataset 164 cannot express); else dataset 164 (``SI = file / factor``, so an FRF
  length/force scales by force_factor / length_factor, time being always s); else the
  axis unit labels of records 9 and 10 when both name units; dataset 164 and labels that
  disagree, or none of the three, are refused.
* **Roles** map receptance names to ``(response node, reference node)``, e.g.
  ``{"h11": (1, 1), "h21": (2, 1), "h22": (2, 2)}``; a file holding one FRF (along the
  chosen direction) needs none for a ``direct_frf``.
* **Truncation.** A file that ends inside a dataset (no closing ``-1``) or a dataset that
  holds fewer values than its header's point count is refused, never read as a shorter
  measurement.
* **pyuff's output.** pyuff prints while reading some datasets (2467) and warns; its
  standard output is captured (``rcsa store import`` prints JSON there), and anything it
  said is logged and recorded in the provenance.
"""

from __future__ import annotations

import contextlib
import dataclasses
import io
import logging
import os
import tempfile
import threading
import warnings
from collections import Counter
from collections.abc import Iterator, Mapping
from pathlib import Path
from typing import Any

import numpy as np
import pyuff

from rcsa.errors import InputError
from rcsa.measured.importers._common import finish, read_source
from rcsa.measured.importers.units import FrfUnit, parse_frf_unit
from rcsa.measured.store.measurement import Measurement, MeasurementMeta, Provenance
from rcsa.model.bounds import MAX_FREQUENCY_LINES
from rcsa.model.input_policy import check_count, check_number, check_numbers

__all__ = ["read_uff"]

log = logging.getLogger(__name__)

FUNCTION_TYPES = {
    0: "general or unknown", 1: "time response", 2: "auto spectrum", 3: "cross spectrum",
    4: "frequency response function", 5: "transmissibility", 6: "coherence",
    7: "auto correlation", 8: "cross correlation", 9: "power spectral density",
    12: "spectrum",
}  # fmt: skip


def _function_type(code: object) -> str:
    """The name of a dataset 58 function type code (``unknown`` for anything else)."""
    return FUNCTION_TYPES.get(code, "unknown") if isinstance(code, int) else "unknown"


_NUMERATOR_QUANTITY = {8: "receptance", 11: "mobility", 12: "accelerance"}
_FORCE_CODES = {9, 13}
_AXES = {1: "X", 2: "Y", 3: "Z"}
_AXIS_OF_DIRECTION = {"x": 1, "y": 2}
_UNIT_SYSTEMS = {1: "SI", 2: "BG", 3: "MG", 4: "BA", 5: "MM", 6: "CM", 7: "IN", 8: "GM", 9: "US"}
#: Relative tolerance when comparing unit factors from dataset 164 and labels: 164 stores
#: factors to ~17 digits, but writers round conversion constants (e.g. 39.37 in/m).
_UNIT_AGREEMENT_RTOL = 1e-4
#: redirect_stdout swaps the process-wide sys.stdout: one reader at a time (service threads).
_STDOUT_LOCK = threading.Lock()
_NOISE = (DeprecationWarning, PendingDeprecationWarning, ResourceWarning)


@contextlib.contextmanager
def _quiet_pyuff(notes: list[str]) -> Iterator[None]:
    """Capture pyuff's prints and warnings; log them and note them for the provenance."""
    out = io.StringIO()
    with (
        _STDOUT_LOCK,
        contextlib.redirect_stdout(out),
        warnings.catch_warnings(record=True) as caught,
    ):
        warnings.simplefilter("always")
        try:
            yield
        finally:
            said = [str(w.message) for w in caught if not issubclass(w.category, _NOISE)]
            printed = " ".join(out.getvalue().split())
            if printed:
                said.append(f"printed: {printed[:300]}")
            for text in said:
                log.warning("pyuff: %s", text)
                notes.append(f"pyuff: {text}")


def _block_markers(data: bytes) -> int:
    """Number of ``    -1`` dataset delimiters, counted as pyuff counts them."""
    n, ind = 0, -1
    while (ind := data.find(b"    -1", ind + 1)) != -1:
        end = ind + 6
        if (
            end == len(data)
            or data[end] in (10, 13)
            or (end + 74 <= len(data) and data[end : end + 74] == b" " * 74)
        ):
            n += 1
    return n


def _label(s: Mapping[str, Any], key: str) -> str:
    v = str(s.get(key, "") or "").strip()
    return "" if v.upper() == "NONE" else v


def _frf_id(s: Mapping[str, Any]) -> str:
    return f"rsp {s['rsp_node']}:{s['rsp_dir']} ref {s['ref_node']}:{s['ref_dir']}"


def _describe(k: int, s: Mapping[str, Any]) -> str:
    return f"dataset #{k + 1} (58 {str(s.get('id1', '')).strip()!r}, {_frf_id(s)})"


def _unit_from_file(
    sets: list[dict[str, Any]], frfs: list[dict[str, Any]], quantity: str | None
) -> FrfUnit | None:
    u164 = [s for s in sets if s.get("type") == 164]
    if len({(s["units_code"], s["length"], s["force"]) for s in u164}) > 1:
        raise InputError(
            "units", "the file holds several different unit datasets (164); declare the units"
        )
    from164 = None
    if u164:
        s = u164[0]
        for key in ("length", "force"):
            value = float(s[key])
            check_number(value, "units")
            if not value > 0.0:
                raise InputError("units", f"dataset 164's {key} factor is {value:g}; unit factors are > 0 "
                                          "(1 for SI): the file's unit dataset is damaged; declare the units")
        factor = float(s["force"]) / float(s["length"])
        text = f"UFF 164 code {s['units_code']} ({_UNIT_SYSTEMS.get(s['units_code'], '?')})"
        from164 = FrfUnit(text, quantity or "", factor)
    labels = {
        (_label(s, "ordinate_axis_units_lab"), _label(s, "orddenom_axis_units_lab")) for s in frfs
    }
    from_labels = None
    if len(labels) == 1:
        num, den = next(iter(labels))
        if num and den:
            with contextlib.suppress(InputError):
                from_labels = parse_frf_unit(f"{num}/{den}")
    if from164 and from_labels:
        if not np.isclose(
            from164.factor_to_si, from_labels.factor_to_si, rtol=_UNIT_AGREEMENT_RTOL, atol=0
        ):
            raise InputError(
                "units",
                f"dataset 164 ({from164.text}) and the axis labels ({from_labels.text}) disagree; declare the units",
            )
        return from_labels if quantity in (None, from_labels.quantity) else from164
    return from164 or from_labels


class _File:
    """A UFF file on disk: dataset types, then datasets read one by one, pyuff kept quiet."""

    def __init__(self, path: Path, data: bytes, notes: list[str]) -> None:
        self.notes = notes
        if _block_markers(data) % 2:
            raise InputError(
                "file",
                "the file ends inside a dataset (the line -1 that closes it is missing): it "
                "looks truncated; export or copy it again",
            )
        try:
            with _quiet_pyuff(notes):
                self.uff = pyuff.UFF(str(path))
                self.types = [int(t) for t in self.uff.get_set_types()]
        except Exception as e:  # pyuff raises bare Exception for malformed files
            raise InputError("file", f"cannot be read as a universal file (UFF): {e}") from None

    def read(self, i: int, *, header_only: bool = False) -> dict[str, Any]:
        try:
            with _quiet_pyuff(self.notes):
                s = self.uff.read_sets(i, header_only=header_only)
        except Exception as e:
            raise InputError(
                "file", f"dataset #{i + 1} (type {self.types[i]}) cannot be read: {e}"
            ) from None
        out: dict[str, Any] = s
        return out


def _classify(s: Mapping[str, Any]) -> str | int:
    """The FRF's translational axis (1, 2, 3), ``"scalar"``, or why it cannot be used."""
    r, f = int(s["rsp_dir"]), int(s["ref_dir"])
    if 0 in (r, f):
        other = abs(r or f)
        return "scalar" if other in (0, *_AXES) else "rotational DOF (direction code 4-6)"
    if abs(r) not in _AXES or abs(f) not in _AXES:
        return "rotational DOF (direction code 4-6)"
    if abs(r) != abs(f):
        return f"response along {_AXES[abs(r)]} but reference along {_AXES[abs(f)]}"
    return abs(r)


def _choose_axis(
    usable: list[tuple[int, dict[str, Any], int | str]],
    direction: str | None,
    scalar_direction: str | None,
) -> int:
    """The axis to import: the declared direction's, else the file's one axis."""
    scalars = [(k, s) for k, s, a in usable if a == "scalar"]
    axes = sorted({a for _, _, a in usable if isinstance(a, int)})
    if scalar_direction is not None:
        if not scalars:
            raise InputError(
                "scalar_direction",
                "applies to scalar FRFs (direction code 0); the file's FRFs carry directions "
                f"({', '.join(_AXES[a] for a in axes)}); leave scalar_direction out",
            )
        if direction is not None and direction != scalar_direction:
            raise InputError(
                "scalar_direction",
                f"{scalar_direction!r} but direction {direction!r} was given; they must agree",
            )
    want = _AXIS_OF_DIRECTION[direction] if direction is not None else None
    if scalar_direction is not None:
        axes = sorted({*axes, _AXIS_OF_DIRECTION[scalar_direction]})
    if want is not None:
        if want in axes:
            return want
        if scalars and scalar_direction is None and not axes:
            raise InputError(
                "scalar_direction",
                f"the file's FRFs are scalar (direction code 0: {_describe(*scalars[0])}); say "
                f"which direction they are along: scalar_direction={direction!r} "
                f"(CLI --scalar-direction {direction}; form field scalar_direction)",
            )
        along = ", ".join(f"{_AXES[a]} (direction code {a})" for a in axes)
        raise InputError(
            "direction",
            f"the file's FRFs are along {along}, but direction {direction!r} was given; import "
            "with the file's direction, or leave direction out to take it from the file",
        )
    if not axes:
        raise InputError(
            "scalar_direction",
            f"the file's FRFs are scalar (direction code 0: {_describe(*scalars[0])}); say "
            "which direction they are along: scalar_direction='x' or 'y' (CLI "
            "--scalar-direction x; form field scalar_direction)",
        )
    if len(axes) > 1:
        raise InputError(
            "direction",
            f"the file holds FRFs along {' and '.join(_AXES[a] for a in axes)}; say which "
            "direction to import (direction x or y)",
        )
    if axes[0] not in _AXIS_OF_DIRECTION.values():
        raise InputError(
            "direction",
            f"the file's FRFs are along {_AXES[axes[0]]} (direction code {axes[0]}); a spindle "
            "measurement is lateral, x or y: export it with the response direction of the "
            "machine axis it was measured along",
        )
    return axes[0]


def _meta_and_direction(
    meta: MeasurementMeta | Mapping[str, Any],
) -> tuple[MeasurementMeta, str | None]:
    """The metadata (direction provisionally x when not given) and the declared direction."""
    if isinstance(meta, MeasurementMeta):
        return meta, meta.direction
    fields = {k: v for k, v in meta.items() if v is not None and v != ""}
    direction = fields.pop("direction", None)
    fields.setdefault("kind", "direct_frf")
    given = MeasurementMeta(**{**fields, "direction": direction or "x"})  # validates the rest
    return given, direction


def read_uff(
    source: str | os.PathLike[str] | bytes,
    meta: MeasurementMeta | Mapping[str, Any],
    *,
    roles: Mapping[str, tuple[int, int]] | None = None,
    units: str | None = None,
    scalar_direction: str | None = None,
    drop_nonpositive: bool = False,
    sensor_mass_kg: float | None = None,
    file_name: str = "",
) -> Measurement:
    """Import the FRFs of a UFF 58 file (ASCII or binary) as receptances in m/N.

    Parameters
    ----------
    source : path or bytes
    meta : MeasurementMeta or mapping
        ``direct_frf`` or ``artifact_frfs`` (UFF FRFs are translational here). A mapping of
        :class:`~rcsa.measured.store.MeasurementMeta` fields may leave ``direction`` out:
        the file's response direction is then used.
    roles : mapping of str to (int, int), optional
        Receptance name → (response node, reference node).
    units : str, optional
        FRF unit, when the file has no dataset 164 and no unit labels, or to override them
        (e.g. ``"g/N"``). See :mod:`rcsa.measured.importers.units`.
    scalar_direction : {"x", "y"}, optional
        The direction of scalar FRFs (direction code 0), which the file does not say.
    drop_nonpositive, sensor_mass_kg, file_name :
        As in :func:`rcsa.measured.importers.read_csv`.

    Raises
    ------
    InputError
        Naming the field: ``file`` (unreadable, truncated), ``direction`` (the file says
        another), ``scalar_direction``, ``roles``, ``units``, ``func_type`` …
    """
    meta, direction = _meta_and_direction(meta)
    if meta.kind == "point_receptance":
        raise InputError(
            "kind",
            "UFF import gives translational FRFs; import a point_receptance as contract JSON",
        )
    if scalar_direction is not None and scalar_direction not in _AXIS_OF_DIRECTION:
        raise InputError("scalar_direction", f"must be x or y, got {scalar_direction!r}")
    data, name, sha = read_source(source, file_name)
    notes: list[str] = []
    with tempfile.TemporaryDirectory() as d:
        if isinstance(source, bytes | bytearray):
            path = Path(d) / "upload.uff"
            path.write_bytes(data)
        else:
            path = Path(source)
        uff = _File(path, data, notes)
        return _read(uff, data, name, sha, meta, direction, roles, units, scalar_direction,
                     drop_nonpositive, sensor_mass_kg, notes)  # fmt: skip


def _read(
    uff: _File,
    data: bytes,
    name: str,
    sha: str,
    meta: MeasurementMeta,
    direction: str | None,
    roles: Mapping[str, tuple[int, int]] | None,
    units: str | None,
    scalar_direction: str | None,
    drop_nonpositive: bool,
    sensor_mass_kg: float | None,
    notes: list[str],
) -> Measurement:
    other_types = Counter(t for t in uff.types if t not in (58, 164))
    steps: list[str] = []
    if other_types:
        steps.append(
            "skipped datasets of type "
            + ", ".join(f"{t} (x{n})" if n > 1 else str(t) for t, n in sorted(other_types.items()))
        )
    heads = [(k, uff.read(k, header_only=True)) for k, t in enumerate(uff.types) if t == 58]
    units164 = [uff.read(k) for k, t in enumerate(uff.types) if t == 164]
    if not heads:
        raise InputError("file", "holds no dataset 58 (function at nodal DOF)")
    for k, s in heads:
        ft = s.get("func_type")
        if ft not in (4, 6):
            steps.append(
                f"skipped {_describe(k, s)}: function type {ft} ({_function_type(ft)})"
            )
    frf_heads = [(k, s) for k, s in heads if s.get("func_type") == 4]
    if not frf_heads:
        found = Counter(s.get("func_type") for _, s in heads)
        raise InputError(
            "func_type",
            "the file holds no FRF (function type 4); it holds "
            + ", ".join(
                f"{n} dataset(s) 58 of function type {ft} ({_function_type(ft)})"
                for ft, n in sorted(found.items(), key=lambda kv: str(kv[0]))
            )
            + "; only 4 (FRF) is imported, with 6 (coherence) attached",
        )

    # --- direction: which axis, which FRFs
    usable: list[tuple[int, dict[str, Any], int | str]] = []
    for k, s in frf_heads:
        axis = _classify(s)
        if isinstance(axis, str) and axis != "scalar":
            steps.append(f"skipped {_describe(k, s)}: {axis}")
        else:
            usable.append((k, s, axis))
    if not usable:
        raise InputError(
            "rsp_dir",
            "no FRF of the file is translational along one axis (direction codes ±1, ±2, ±3): "
            + "; ".join(
                st.removeprefix("skipped ") for st in steps if st.startswith("skipped dataset")
            ),
        )
    axis = _choose_axis(usable, direction, scalar_direction)
    chosen_dir = next(d for d, a in _AXIS_OF_DIRECTION.items() if a == axis)
    candidates = []
    for k, s, a in usable:
        if a == axis or (a == "scalar" and scalar_direction is not None):
            candidates.append((k, s))
        else:
            what = "scalar (direction code 0)" if a == "scalar" else f"along {_AXES[int(a)]}"
            steps.append(f"skipped {_describe(k, s)}: {what}, not {chosen_dir}")
    if direction is None:
        steps.append(f"direction {chosen_dir} from the file (FRFs along {_AXES[axis]})")
        meta = dataclasses.replace(meta, direction=chosen_dir)
    if any(a == "scalar" for _, _, a in usable) and scalar_direction is not None:
        steps.append(
            f"scalar FRFs (direction code 0) taken as {scalar_direction} (scalar_direction)"
        )

    # --- roles: which FRF is which receptance
    by_nodes: dict[tuple[int, int], tuple[int, dict[str, Any]]] = {}
    for k, s in candidates:
        key = (int(s["rsp_node"]), int(s["ref_node"]))
        if key in by_nodes:
            raise InputError(
                "roles",
                f"two FRFs with response node {key[0]} and reference node {key[1]} along "
                f"{chosen_dir}: {_describe(*by_nodes[key])} and {_describe(k, s)}",
            )
        by_nodes[key] = (k, s)
    if roles is None:
        if meta.kind == "direct_frf" and len(candidates) == 1:
            roles = {"h": next(iter(by_nodes))}
        else:
            raise InputError(
                "roles",
                f"the file holds FRFs at (response, reference) nodes {sorted(by_nodes)} along "
                f"{chosen_dir}; say which is which, "
                + (
                    "e.g. {'h': (1, 1)} (CLI --roles h=1:1)"
                    if meta.kind == "direct_frf"
                    else "e.g. {'h11': (1, 1), 'h21': (2, 1), 'h22': (2, 2)}"
                ),
            )
    chosen: dict[str, dict[str, Any]] = {}
    for role, nodes in roles.items():
        try:
            key = (int(nodes[0]), int(nodes[1]))
        except (TypeError, ValueError, IndexError):
            raise InputError(f"roles.{role}", "must be (response node, reference node)") from None
        if key not in by_nodes:
            raise InputError(
                f"roles.{role}",
                f"no FRF at response node {key[0]}, reference node {key[1]} along {chosen_dir}; "
                f"the file has {sorted(by_nodes)}",
            )
        k, _ = by_nodes[key]
        chosen[role] = _full(uff, k)
    return _frfs_to_measurement(
        chosen, heads, uff, units164, units, meta, steps, notes, name, sha,
        drop_nonpositive, sensor_mass_kg,
    )  # fmt: skip


def _full(uff: _File, k: int) -> dict[str, Any]:
    """Dataset ``k`` with its data, checked against its header's point count and the input
    policy (at most ``MAX_FREQUENCY_LINES`` lines, every number finite and within range)."""
    head = uff.read(k, header_only=True)
    check_count(int(head.get("num_pts") or 0), "file", MAX_FREQUENCY_LINES,
                f"frequency lines in {_describe(k, head)}")
    s = uff.read(k)
    n = int(s.get("num_pts") or 0)
    got = len(s["data"]) if s.get("data") is not None else 0
    if got != n or len(s["x"]) != n:
        raise InputError(
            "file",
            f"{_describe(k, s)} holds {got} values but its header says {n}: the file looks "
            "truncated or damaged; export or copy it again",
        )
    if s["abscissa_spec_data_type"] not in (0, 18) or _label(
        s, "abscissa_axis_units_lab"
    ).lower() not in ("", "hz"):
        raise InputError(
            "abscissa_spec_data_type", f"{_describe(k, s)}: the abscissa must be frequency in Hz"
        )
    return s


def _frfs_to_measurement(
    chosen: dict[str, dict[str, Any]],
    heads: list[tuple[int, dict[str, Any]]],
    uff: _File,
    units164: list[dict[str, Any]],
    units: str | None,
    meta: MeasurementMeta,
    steps: list[str],
    notes: list[str],
    name: str,
    sha: str,
    drop_nonpositive: bool,
    sensor_mass_kg: float | None,
) -> Measurement:
    # --- quantity and units
    codes = {(s["ordinate_spec_data_type"], s["orddenom_spec_data_type"]) for s in chosen.values()}
    quantities = {_NUMERATOR_QUANTITY.get(n) if d in _FORCE_CODES else None for n, d in codes}
    coded = quantities.pop() if len(quantities) == 1 else None
    if len(quantities) > 0:
        raise InputError("ordinate_spec_data_type", "the chosen FRFs are of different quantities")
    if units is not None:
        unit = parse_frf_unit(units)
        if coded is not None and unit.quantity != coded:
            raise InputError(
                "units",
                f"{unit.text!r} is {unit.quantity} but the file's data-type codes say {coded} {sorted(codes)}",
            )
        origin = "declared"
    else:
        from_file = _unit_from_file(units164, list(chosen.values()), coded)
        if from_file is None:
            raise InputError(
                "units",
                "the file has no units dataset 164 and its axis unit labels are NONE; declare the FRF unit "
                "(e.g. units='m/N', 'm/s^2/N' or 'g/N'; CLI --units)",
            )
        unit, origin = from_file, "from the file"
    if coded is not None and unit.quantity and unit.quantity != coded:
        raise InputError(
            "units",
            f"the file's unit ({unit.text}) is {unit.quantity} but its data-type codes say {coded}; declare the units",
        )
    quantity = coded or unit.quantity
    if not quantity:
        raise InputError(
            "units",
            f"the file's data-type codes {sorted(codes)} do not say whether this is receptance, mobility or "
            "accelerance; declare the unit (e.g. units='m/s^2/N')",
        )

    # --- frequency axis, values, coherence
    freq = np.asarray(next(iter(chosen.values()))["x"], dtype=float)
    values, coherence = {}, {}
    for role, s in chosen.items():
        x = np.asarray(s["x"], dtype=float)
        if x.shape != freq.shape or not np.array_equal(x, freq):
            raise InputError(
                "frequency_hz",
                f"{role} ({_frf_id(s)}) is not on the same frequency axis as the others",
            )
        if s["ord_data_type"] not in (5, 6):
            raise InputError(
                "ord_data_type", f"{role} ({_frf_id(s)}) is not complex (ordinate data type 5 or 6)"
            )
        data = np.asarray(s["data"])
        check_numbers(x, "frequency_hz")
        check_numbers(np.column_stack([data.real, data.imag]), role, columns=["real", "imag"])
        sign = int(np.sign(s["rsp_dir"] or 1) * np.sign(s["ref_dir"] or 1))
        if sign < 0:
            steps.append(f"{role}: sign flipped ({_frf_id(s)} -> +/+)")
        with np.errstate(over="ignore", invalid="ignore"):
            values[role] = np.asarray(s["data"], dtype=np.complex128) * (sign * unit.factor_to_si)
        steps.append(f"{role} <- UFF 58 {_frf_id(s)} ({s.get('id1', '').strip()})")
        for k, c in heads:
            if c.get("func_type") == 6 and _frf_id(c) == _frf_id(s):
                full = _full(uff, k)
                if np.array_equal(np.asarray(full["x"], float), freq):
                    coherence[role] = np.real(np.asarray(full["data"]))
    if unit.factor_to_si != 1.0:
        steps.append(f"scaled {unit.text} -> SI by {unit.factor_to_si:.17g}")
    binary = any(bool(s.get("binary")) for s in chosen.values())
    prov = Provenance(
        source_format="uff58b" if binary else "uff58",
        source_file=name,
        source_sha256=sha,
        original_quantity=quantity,
        original_units=f"{unit.text} ({origin})",
        conversions=tuple(steps + notes),
    )
    return finish(
        freq,
        values,
        quantity=quantity,
        meta=meta,
        provenance=prov,
        coherence=coherence,
        drop_nonpositive=drop_nonpositive,
        sensor_mass_kg=sensor_mass_kg,
    )
