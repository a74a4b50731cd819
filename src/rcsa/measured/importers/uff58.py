"""Universal File Format dataset 58 (ASCII and binary "58b") through pyuff.

What is read (``ecosystem.md`` §2.1, the UFF 58 spec printed by
``pyuff.datasets.dataset_58.get_structure_58()``):

* Only function type 4 (FRF) is imported; type 6 (coherence) is attached to the FRF of the
  same DOFs; any other type is refused.
* The quantity comes from record 9/10's specific data types: numerator 8 displacement →
  receptance, 11 velocity → mobility, 12 acceleration → accelerance; denominator 13
  (excitation force) or 9 (reaction force). Unknown codes (0, 1) need ``units`` declared.
* Units are never guessed. In order: ``units`` declared by the caller (e.g. ``"g/N"``,
  which dataset 164 cannot express); else dataset 164 (``SI = file / factor``, so an FRF
  length/force scales by force_factor / length_factor, time being always s); else the
  axis unit labels of records 9 and 10 when both name units; dataset 164 and labels that
  disagree, or none of the three, are refused.
* Response and reference must be translations along one axis (direction codes ±1, ±2,
  ±3); the value is multiplied by sign(rsp_dir)·sign(ref_dir) so that it is +/+.
* ``roles`` maps receptance names to ``(response node, reference node)``, e.g.
  ``{"h11": (1, 1), "h21": (2, 1), "h22": (2, 2)}``; a file holding one FRF needs none for
  a ``direct_frf``.
"""

from __future__ import annotations

import contextlib
import os
import tempfile
import warnings
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np
import pyuff

from rcsa.errors import InputError
from rcsa.measured.importers._common import finish, read_source
from rcsa.measured.importers.units import FrfUnit, parse_frf_unit
from rcsa.measured.store.measurement import Measurement, MeasurementMeta, Provenance

__all__ = ["read_uff"]

FUNCTION_TYPES = {
    0: "general or unknown", 1: "time response", 2: "auto spectrum", 3: "cross spectrum",
    4: "frequency response function", 5: "transmissibility", 6: "coherence",
    7: "auto correlation", 8: "cross correlation", 9: "power spectral density",
    12: "spectrum",
}  # fmt: skip
_NUMERATOR_QUANTITY = {8: "receptance", 11: "mobility", 12: "accelerance"}
_FORCE_CODES = {9, 13}
_AXES = {1: "X", 2: "Y", 3: "Z"}
_UNIT_SYSTEMS = {1: "SI", 2: "BG", 3: "MG", 4: "BA", 5: "MM", 6: "CM", 7: "IN", 8: "GM", 9: "US"}
#: Relative tolerance when comparing unit factors from dataset 164 and labels: 164 stores
#: factors to ~17 digits, but writers round conversion constants (e.g. 39.37 in/m).
_UNIT_AGREEMENT_RTOL = 1e-4


def _read_sets(path: Path) -> list[dict[str, Any]]:
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # pyuff's own deprecations and unclosed handles
            uff = pyuff.UFF(str(path))
            types = list(uff.get_set_types())
            return [uff.read_sets(i) for i in range(len(types))]
    except Exception as e:  # pyuff raises bare Exception for malformed files
        raise InputError("file", f"cannot be read as a universal file (UFF): {e}") from None


def _label(s: Mapping[str, Any], key: str) -> str:
    v = str(s.get(key, "") or "").strip()
    return "" if v.upper() == "NONE" else v


def _frf_id(s: Mapping[str, Any]) -> str:
    return f"rsp {s['rsp_node']}:{s['rsp_dir']} ref {s['ref_node']}:{s['ref_dir']}"


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


def read_uff(
    source: str | os.PathLike[str] | bytes,
    meta: MeasurementMeta,
    *,
    roles: Mapping[str, tuple[int, int]] | None = None,
    units: str | None = None,
    drop_nonpositive: bool = False,
    sensor_mass_kg: float | None = None,
    file_name: str = "",
) -> Measurement:
    """Import the FRFs of a UFF 58 file (ASCII or binary) as receptances in m/N.

    Parameters
    ----------
    source : path or bytes
    meta : MeasurementMeta
        ``direct_frf`` or ``artifact_frfs`` (UFF FRFs are translational here).
    roles : mapping of str to (int, int), optional
        Receptance name → (response node, reference node).
    units : str, optional
        FRF unit, when the file has no dataset 164 and no unit labels, or to override them
        (e.g. ``"g/N"``). See :mod:`rcsa.measured.importers.units`.
    drop_nonpositive, sensor_mass_kg, file_name :
        As in :func:`rcsa.measured.importers.read_csv`.
    """
    if meta.kind == "point_receptance":
        raise InputError(
            "kind",
            "UFF import gives translational FRFs; import a point_receptance as contract JSON",
        )
    data, name, sha = read_source(source, file_name)
    if isinstance(source, bytes | bytearray):
        with tempfile.TemporaryDirectory() as d:
            tmp = Path(d) / "upload.uff"
            tmp.write_bytes(data)
            sets = _read_sets(tmp)
    else:
        sets = _read_sets(Path(source))
    s58 = [s for s in sets if s.get("type") == 58]
    if not s58:
        raise InputError("file", "holds no dataset 58 (function at nodal DOF)")
    for k, s in enumerate(s58):
        ft = s.get("func_type")
        if ft not in (4, 6):
            raise InputError(
                "func_type",
                f"dataset 58 #{k + 1} ({s.get('id1', '').strip()!r}) has function type {ft} "
                f"({FUNCTION_TYPES.get(ft, 'unknown')}); only 4 (FRF) is imported, with 6 (coherence) attached",
            )
    frf_sets = [s for s in s58 if s["func_type"] == 4]
    if not frf_sets:
        raise InputError("func_type", "the file holds no FRF (function type 4)")
    for s in s58:
        if abs(s["rsp_dir"]) not in _AXES or abs(s["ref_dir"]) != abs(s["rsp_dir"]):
            raise InputError(
                "rsp_dir",
                f"{_frf_id(s)}: only translational FRFs along one axis (direction codes ±1, ±2, ±3)",
            )
        if s["abscissa_spec_data_type"] not in (0, 18) or _label(
            s, "abscissa_axis_units_lab"
        ).lower() not in ("", "hz"):
            raise InputError(
                "abscissa_spec_data_type", f"{_frf_id(s)}: the abscissa must be frequency in Hz"
            )
    axes = {abs(s["rsp_dir"]) for s in frf_sets}
    if len(axes) > 1:
        raise InputError(
            "rsp_dir",
            f"the file mixes FRFs along {sorted(_AXES[a] for a in axes)}; split it per direction",
        )

    # --- roles: which FRF is which receptance
    by_nodes: dict[tuple[int, int], dict[str, Any]] = {}
    for s in frf_sets:
        key = (int(s["rsp_node"]), int(s["ref_node"]))
        if key in by_nodes:
            raise InputError(
                "roles", f"two FRFs with response node {key[0]} and reference node {key[1]}"
            )
        by_nodes[key] = s
    if roles is None:
        if meta.kind == "direct_frf" and len(frf_sets) == 1:
            roles = {"h": next(iter(by_nodes))}
        else:
            raise InputError(
                "roles",
                f"the file holds FRFs at (response, reference) nodes {sorted(by_nodes)}; say which is which, "
                + (
                    "e.g. {'h': (1, 1)}"
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
                f"no FRF at response node {key[0]}, reference node {key[1]}; the file has {sorted(by_nodes)}",
            )
        chosen[role] = by_nodes[key]

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
        unit = _unit_from_file(sets, list(chosen.values()), coded)
        if unit is None:
            raise InputError(
                "units",
                "the file has no units dataset 164 and its axis unit labels are NONE; declare the FRF unit "
                "(e.g. units='m/N', 'm/s^2/N' or 'g/N'; CLI --units)",
            )
        origin = "from the file"
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
    values, coherence, steps = {}, {}, []
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
        sign = int(np.sign(s["rsp_dir"]) * np.sign(s["ref_dir"]))
        if sign < 0:
            steps.append(f"{role}: sign flipped ({_frf_id(s)} -> +/+)")
        values[role] = np.asarray(s["data"], dtype=np.complex128) * (sign * unit.factor_to_si)
        steps.append(f"{role} <- UFF 58 {_frf_id(s)} ({s.get('id1', '').strip()})")
        for c in s58:
            if (
                c["func_type"] == 6
                and _frf_id(c) == _frf_id(s)
                and np.array_equal(np.asarray(c["x"], float), freq)
            ):
                coherence[role] = np.real(np.asarray(c["data"]))
    if unit.factor_to_si != 1.0:
        steps.append(f"scaled {unit.text} -> SI by {unit.factor_to_si:.17g}")
    binary = any(bool(s.get("binary")) for s in chosen.values())
    prov = Provenance(
        source_format="uff58b" if binary else "uff58",
        source_file=name,
        source_sha256=sha,
        original_quantity=quantity,
        original_units=f"{unit.text} ({origin})",
        conversions=tuple(steps),
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
