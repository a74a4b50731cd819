"""Exports of a stored library's results for other software: HDF5, and a zip of UFF 58 files.

Both take the document of :meth:`rcsa.libraries.sync.LibraryStore.results` and return bytes.

HDF5 (``application/x-hdf5``; every group and dataset carries ``schema`` and
``schema_version``)::

    /                    schema="rcsa.library-results", schema_version=1, library_id, revision,
                         synced_utc, exported_utc, source, library_sha256, model_version,
                         software_version, convention, tools_json (every tool: id, index,
                         status, reason, error, group)
    /frequency_hz        float64 (n,), units="Hz"
    /tools/<name>        one NXdata group per ok tool (name: the tool id, percent-encoded where
                         HDF5 needs it; attribute ``id`` holds it verbatim): signal="h",
                         axes=["frequency_hz"]; attributes index, description, number, teeth,
                         tool_type, natural_frequencies_hz, static_stiffness_n_m, result_sha256
    /tools/<name>/frequency_hz   hard link to /frequency_hz
    /tools/<name>/h, l, n, p     complex128 (n,) (h5py's compound {r, i}), units and
                                 quantity="receptance"

UFF (``application/zip``): ``index.json`` (id → file, description, T number, teeth) and one
``<tool>.uff`` per ok tool, written with pyuff: a dataset 164 (SI units: m, N, K) then a
dataset 58 — function type 4 (FRF), response and reference node 1 direction +X (the tool
tip), ordinate displacement (8) over force (13), abscissa frequency (18) in Hz, complex
double values of the tool-point receptance h in m/N (ASCII, about 13 significant digits).
"""

from __future__ import annotations

import io
import json
import re
import tempfile
import zipfile
from collections.abc import Mapping
from pathlib import Path
from typing import Any
from urllib.parse import quote

import numpy as np

from rcsa._version import __version__
from rcsa.infra.clock import utc_now_iso
from rcsa.model.wire import CONVENTION, RECEPTANCE_UNITS, complex_from_wire

__all__ = ["HDF5_SCHEMA", "library_hdf5", "library_uff_zip", "tool_file_names"]

HDF5_SCHEMA = "rcsa.library-results"
SCHEMA_VERSION = 1



def _group_name(tool_id: str) -> str:
    name = quote(tool_id, safe="")
    return name.replace(".", "%2E") if set(name) <= {"."} else name


def tool_file_names(ids: list[str]) -> list[str]:
    """File names (without suffix) for tool ids: safe characters only, unique.

    Examples
    --------
    >>> tool_file_names(["T1", "a/b", "a:b"])
    ['T1', 'a_b', 'a_b~2']
    """
    out, seen = [], set()
    for tool_id in ids:
        base = re.sub(r"[^A-Za-z0-9._-]", "_", tool_id).lstrip(".") or "tool"
        name, k = base, 1
        while name.lower() in seen:
            k += 1
            name = f"{base}~{k}"
        seen.add(name.lower())
        out.append(name)
    return out


def library_hdf5(results: Mapping[str, Any]) -> bytes:
    """The library's results as one HDF5 file (layout in the module docstring)."""
    import h5py

    lib = results["library"]
    ok = [r for r in results["results"] if r["status"] == "ok"]
    index = []
    for r in results["results"]:
        index.append({"id": r["id"], "index": r.get("index"), "status": r["status"], "reason": r.get("reason"),
                      "error": r.get("error"), "group": f"/tools/{_group_name(r['id'])}" if r["status"] == "ok"
                      else None})
    buffer = io.BytesIO()
    with h5py.File(buffer, "w") as f:
        a = f.attrs
        a["schema"], a["schema_version"] = HDF5_SCHEMA, SCHEMA_VERSION
        a["library_id"] = lib["id"]
        a["revision"] = int(lib["revision"])
        a["synced_utc"] = lib["synced_utc"]
        a["exported_utc"] = utc_now_iso()
        a["source"] = lib.get("source") or ""
        a["library_sha256"] = lib.get("library_sha256") or ""
        a["model_version"] = str(lib.get("model_version") or "")
        a["software_version"] = lib.get("software_version") or __version__
        a["convention"] = CONVENTION
        a["tools_json"] = json.dumps(index)
        freq = np.asarray(ok[0]["frequency_hz"], dtype=np.float64) if ok else np.zeros(0)
        fd = f.create_dataset("frequency_hz", data=freq)
        fd.attrs["schema"], fd.attrs["schema_version"], fd.attrs["units"] = "rcsa.frequency_hz", SCHEMA_VERSION, "Hz"
        tools = f.create_group("tools")
        for r in ok:
            g = tools.create_group(_group_name(r["id"]))
            ga = g.attrs
            ga["schema"], ga["schema_version"] = "rcsa.tool_point", SCHEMA_VERSION
            ga["NX_class"], ga["signal"], ga["axes"], ga["frequency_hz_indices"] = "NXdata", "h", ["frequency_hz"], 0
            ga["id"] = r["id"]
            ga["index"] = int(r.get("index") or 0)
            for name in ("description", "tool_type"):
                ga[name] = r.get(name) or ""
            for name in ("number", "teeth"):
                ga[name] = -1 if r.get(name) is None else int(r[name])
            ga["natural_frequencies_hz"] = np.asarray(r.get("natural_frequencies_hz") or [], dtype=np.float64)
            stiffness = r.get("static_stiffness_n_m")
            ga["static_stiffness_n_m"] = np.nan if stiffness is None else float(stiffness)
            ga["result_sha256"] = r.get("result_sha256") or ""
            if not np.array_equal(np.asarray(r["frequency_hz"], dtype=np.float64), freq):
                raise ValueError(f"tool {r['id']!r} is on another frequency grid than the library")
            g["frequency_hz"] = fd
            for name, pair in r["tool_point"].items():
                values = complex_from_wire(pair, f"{r['id']}.tool_point.{name}", finite=False)
                d = g.create_dataset(name, data=values, dtype=np.complex128)
                d.attrs["schema"], d.attrs["schema_version"] = "rcsa.frf", SCHEMA_VERSION
                d.attrs["units"], d.attrs["quantity"] = RECEPTANCE_UNITS[name], "receptance"
    return buffer.getvalue()


def library_uff_zip(results: Mapping[str, Any]) -> bytes:
    """A zip of one UFF 58 file per ok tool (tool-point h) and ``index.json``."""
    import pyuff

    lib = results["library"]
    ok = [r for r in results["results"] if r["status"] == "ok"]
    names = tool_file_names([r["id"] for r in ok])
    buffer = io.BytesIO()
    with tempfile.TemporaryDirectory(prefix="rcsa-uff-") as tmp, \
            zipfile.ZipFile(buffer, "w", compression=zipfile.ZIP_DEFLATED) as zf:
        index = []
        for r, name in zip(ok, names, strict=True):
            f = np.asarray(r["frequency_hz"], dtype=np.float64)
            h = complex_from_wire(r["tool_point"]["h"], f"{r['id']}.tool_point.h", finite=False)
            steps = np.diff(f)
            even = f.size > 1 and bool(np.allclose(steps, steps[0], rtol=1e-9, atol=0.0))
            units = pyuff.prepare_164(units_code=1, units_description="SI", temp_mode=2, length=1.0, force=1.0,
                                      temp=1.0, temp_offset=273.15)
            d58 = pyuff.prepare_58(
                binary=0, id1=f"tool-point h {r['id']}"[:80], id2=(r.get("description") or "")[:80],
                id3=f"library {lib['id']} revision {lib['revision']}"[:80], id4=lib.get("synced_utc", "")[:80],
                id5=f"rcsa {__version__} model {lib.get('model_version')}"[:80],
                func_type=4, ver_num=0, load_case_id=0, rsp_ent_name="tooltip", rsp_node=1, rsp_dir=1,
                ref_ent_name="tooltip", ref_node=1, ref_dir=1, ord_data_type=6, num_pts=int(f.size),
                abscissa_spacing=1 if even else 0, abscissa_min=float(f[0]),
                abscissa_inc=float(steps[0]) if even else 0.0, z_axis_value=0.0,
                abscissa_spec_data_type=18, abscissa_len_unit_exp=0, abscissa_force_unit_exp=0,
                abscissa_temp_unit_exp=0, abscissa_axis_units_lab="Hz",
                ordinate_spec_data_type=8, ordinate_len_unit_exp=1, ordinate_force_unit_exp=0,
                ordinate_temp_unit_exp=0, ordinate_axis_units_lab="m",
                orddenom_spec_data_type=13, orddenom_len_unit_exp=0, orddenom_force_unit_exp=1,
                orddenom_temp_unit_exp=0, orddenom_axis_units_lab="N",
                z_axis_spec_data_type=0, z_axis_len_unit_exp=0, z_axis_force_unit_exp=0, z_axis_temp_unit_exp=0,
                z_axis_axis_units_lab="NONE", data=h, x=f)
            path = Path(tmp) / f"{name}.uff"
            pyuff.UFF(str(path)).write_sets([units, d58], mode="overwrite")
            zf.write(path, f"{name}.uff")
            index.append({"id": r["id"], "file": f"{name}.uff", "index": r.get("index"),
                          "description": r.get("description"), "number": r.get("number"), "teeth": r.get("teeth"),
                          "quantity": "receptance h (tool tip, +X/+X)", "units": "m/N", "result_sha256":
                          r.get("result_sha256")})
        zf.writestr("index.json", json.dumps({"library_id": lib["id"], "revision": lib["revision"],
                                              "synced_utc": lib.get("synced_utc"), "tools": index}, indent=1))
    return buffer.getvalue()
