"""A seeded generator of hostile requests for every operation of the service, uploaded files included.

Each :class:`Case` is one request and what a correct service must answer:

* ``"4xx"`` — the request breaks the input policy (a number beyond 1e30, NaN or Infinity,
  nesting deeper than 32, a string beyond 16 384 characters, more rows than a file may have)
  or a physical bound (a 22 m holder segment, a 1e30 kg sensor, a 1e11 Hz line, a
  ``relative_step`` of 1e-300 ...): a 4xx problem, and anything else is wrong (a 2xx is a
  *wrong 2xx*);
* ``"item"`` — a physical bound broken inside one item of a tool library: a 4xx, or a 2xx
  in which that item is not ``ok`` (a library answers each item with ok, skipped or error);
* ``"any"`` — a mutation whose validity the generator does not know (a truncated file, a
  zero, a negative number, a type changed): any answer but a 5xx.

Every answer must be a problem document when it is not a 2xx, and never a 5xx. The same
generator feeds the suite's seeded slice (``tests/service/test_hostile_files.py``, in
process) and the full run against a real 2-worker uvicorn (``benchmarks/bench_hostile.py``).
"""

from __future__ import annotations

import copy
import functools
import io
import json
import random
import zipfile
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from rcsa.reference import ra1

REPO = Path(__file__).resolve().parents[2]
DATA = REPO / "tests" / "data"

__all__ = ["Case", "cases", "judge", "operations"]


@dataclass
class Case:
    """One hostile request."""

    operation: str
    label: str
    path: str
    expect: str  # "4xx", "item" or "any"
    json_body: bytes | None = None
    files: list[tuple[str, tuple[str, bytes]]] = field(default_factory=list)
    data: dict[str, str] = field(default_factory=dict)
    headers: dict[str, str] = field(default_factory=dict)
    item: int | None = None  # the library item a physical mutation broke ("item" cases)
    item_id: str | None = None  # its id (Fusion guid), for a sync report, when the seed item is ok

    def request_kwargs(self) -> dict[str, Any]:
        """Keyword arguments of ``httpx.Client.post`` / ``TestClient.post``."""
        if self.json_body is not None:
            return {"content": self.json_body, "headers": {"content-type": "application/json", **self.headers}}
        return {"files": self.files, "data": self.data, "headers": dict(self.headers)}


# ---------------------------------------------------------------------------- mutations of JSON

_BIG_INT = "1" + "0" * 400
#: (label, raw JSON text of the value) that break the number policy.
_POLICY_NUMBERS = [("1e308", "1e308"), ("-1e31", "-1e31"), ("400 digits", _BIG_INT), ("NaN", "NaN"),
                   ("Infinity", "Infinity"), ("-Infinity", "-Infinity"), ("1e400", "1e400")]
#: Values whose validity depends on the field.
_ODD_VALUES: list[tuple[str, Any]] = [("0", 0), ("-1", -1), ("1e-300", 1e-300), ("1e20", 1e20), ("true", True),
                                      ("null", None), ("string", "x"), ("list", [1]), ("object", {"a": 1}),
                                      ("2**63", 2**63), ("-0.0", -0.0), ("1e29", 1e29)]
#: Unit suffix of a field name → a value beyond every physical bound of such a field.
_PHYSICAL = {"_m": 22.0, "_kg": 1e30, "_hz": 1e11, "_pa": 1e20, "_n_m": 1e20, "_rpm": 1e9, "_kg_m3": 1e9,
             "_ns_m": 1e20, "_nm_rad": 1e20, "_nms_rad": 1e20, "_n_m2": 1e20}
_PHYSICAL_KEYS = {"height": 22000, "DC": 22000, "OAL": 22000, "LB": 22000, "LCF": 22000, "SFDM": 22000,
                  "lower-diameter": 22000, "upper-diameter": 22000, "gaugeLength": 22000,  # Fusion, mm
                  "relative_step": 1e-300, "n_averages": 1e11, "count": 10**9, "teeth": 10**6, "draws": 10**7,
                  "monte_carlo_draws": 10**7, "max_lines": 10**9, "steps_per_period": 10**6,
                  "modes_per_direction": 10**4, "loss_factor": 50.0, "poisson_ratio": 3.0, "radial_immersion": 7.0,
                  "radial_ratio": 1e9, "fluted_diameter_ratio": 5.0, "confidence": 2.0, "seed": 2**70}

Path_ = tuple[str | int, ...]


def _leaves(doc: Any, path: Path_ = ()) -> Iterator[tuple[Path_, Any]]:
    if isinstance(doc, dict):
        for k, v in doc.items():
            yield from _leaves(v, (*path, k))
    elif isinstance(doc, list):
        # long numeric lists: a few positions stand for all
        idx = range(len(doc)) if len(doc) <= 8 else (0, 1, len(doc) // 2, len(doc) - 1)
        for i in idx:
            yield from _leaves(doc[i], (*path, i))
    else:
        yield path, doc


def _set(doc: Any, path: Path_, value: Any) -> Any:
    out = copy.deepcopy(doc)
    node = out
    for key in path[:-1]:
        node = node[key]
    node[path[-1]] = value
    return out


_MARK = "__rcsa_hostile__"


def _with_raw(doc: Any, path: Path_, raw: str) -> bytes:
    """``doc`` as JSON text with the raw text ``raw`` at ``path`` (NaN, 400 digits ...)."""
    return json.dumps(_set(doc, path, _MARK)).replace(f'"{_MARK}"', raw, 1).encode()


def _physical(key: str) -> Any | None:
    if key in _PHYSICAL_KEYS:
        return _PHYSICAL_KEYS[key]
    for suffix in sorted(_PHYSICAL, key=len, reverse=True):
        if key.endswith(suffix):
            return _PHYSICAL[suffix]
    return None


def json_mutations(doc: Any, rng: random.Random, n: int) -> Iterator[tuple[str, bytes, str, Path_]]:
    """``n`` mutated JSON texts of ``doc``: (label, text, expectation, path mutated); the
    expectation is ``"4xx"`` for the policy, ``"physical"`` for a physical bound, ``"any"``."""
    leaves = [(p, v) for p, v in _leaves(doc) if p]
    numeric = [(p, v) for p, v in leaves if isinstance(v, int | float) and not isinstance(v, bool)]
    strings = [(p, v) for p, v in leaves if isinstance(v, str)]
    physical = [(p, _physical(str(p[-1]) if isinstance(p[-1], str) else str(p[-2]) if len(p) > 1 else ""))
                for p, v in numeric]
    physical += [(p, "22000 mm") for p, v in strings if v.endswith(" mm")]  # FreeCAD quantities
    physical = [(p, x) for p, x in physical if x is not None]
    shapes = ["number", "physical", "deep", "string", "odd", "odd", "number"]
    for _ in range(n):
        shape = rng.choice(shapes)
        if shape == "physical" and physical:
            p, x = rng.choice(physical)
            yield f"{_dotted(p)} = {x}", json.dumps(_set(doc, p, x)).encode(), "physical", p
        elif shape == "number" and numeric:
            p, _ = rng.choice(numeric)
            name, raw = rng.choice(_POLICY_NUMBERS)
            yield f"{_dotted(p)} = {name}", _with_raw(doc, p, raw), "4xx", p
        elif shape == "deep":
            p, _ = rng.choice(leaves)
            depth = rng.choice((33, 40, 200, 5000))
            yield f"{_dotted(p)} nested {depth} deep", _with_raw(doc, p, "[" * depth + "]" * depth), "4xx", p
        elif shape == "string" and strings:
            p, _ = rng.choice(strings)
            yield f"{_dotted(p)} = 20 000 characters", json.dumps(_set(doc, p, "x" * 20_000)).encode(), "4xx", p
        else:
            p, _ = rng.choice(leaves)
            name, value = rng.choice(_ODD_VALUES)
            yield f"{_dotted(p)} = {name}", json.dumps(_set(doc, p, value)).encode(), "any", p


def _dotted(path: Path_) -> str:
    return "".join(f"[{k}]" if isinstance(k, int) else f".{k}" for k in path).lstrip(".")


# ---------------------------------------------------------------------------- mutations of text files

_NUMBER_TOKENS = ("1e308", "-1e31", "nan", "inf", "-Infinity", _BIG_INT, "1.0D+308")


def table_mutations(text: str, rng: random.Random, n: int, *, policy_rows: int,
                    number_sep: str | None = None, columns: int | None = None) -> Iterator[tuple[str, bytes, str]]:
    """Mutated text tables (CSV, TSV, CutPro, tap): policy numbers, truncations, garbage
    (``columns``: only the first so many columns are data; CutPro's first line carries labels
    after its three numbers)."""
    lines = text.splitlines(keepends=True)
    data_idx = [i for i, ln in enumerate(lines) if ln.strip() and (ln.strip()[0].isdigit() or ln.strip()[0] == "-")]
    for _ in range(n):
        shape = rng.choice(("number", "number", "truncate", "garbage", "flip"))
        if shape == "number" and data_idx:
            i = rng.choice(data_idx)
            toks = lines[i].rstrip("\r\n")
            sep = number_sep or ("," if "," in toks else "\t" if "\t" in toks else None)
            parts = toks.split(sep) if sep else toks.split()
            j = rng.randrange(min(len(parts), columns or len(parts)))
            token = rng.choice(_NUMBER_TOKENS[:6])
            parts[j] = token
            new = (sep or "\t").join(parts) + "\n"
            yield (f"line {i + 1} column {j + 1} = {token[:12]}",
                   "".join(lines[:i] + [new] + lines[i + 1:]).encode(), "4xx")
        elif shape == "truncate":
            cut = rng.randrange(1, max(2, len(text)))
            yield f"truncated at byte {cut}", text[:cut].encode(), "any"
        elif shape == "garbage" and data_idx:
            i = rng.choice(data_idx)
            yield f"garbage at line {i + 1}", "".join(lines[:i] + ["1.0,abc,;;\n"] + lines[i:]).encode(), "any"
        else:
            raw = bytearray(text.encode())
            for _ in range(rng.randint(1, 8)):
                raw[rng.randrange(len(raw))] = rng.randrange(256)
            yield "bytes flipped", bytes(raw), "any"
    if policy_rows and data_idx:
        row = lines[data_idx[-1]]
        head = "".join(lines[:data_idx[-1]])
        yield f"{policy_rows} rows", (head + row * policy_rows).encode(), "4xx"


def uff_mutations(text: str, rng: random.Random, n: int) -> Iterator[tuple[str, bytes, str]]:
    """Mutated UFF 58 files: numbers beyond the policy, unit factors of 0, truncations."""
    lines = text.splitlines(keepends=True)
    numeric = [i for i, ln in enumerate(lines) if "E+" in ln.upper() or "D+" in ln.upper() or "E-" in ln.upper()]
    unit_line = next((i for i, ln in enumerate(lines) if ln.strip().startswith("1.0000000000000000D+00")), None)
    for _ in range(n):
        shape = rng.choice(("number", "units", "truncate", "flip"))
        if shape == "units" and unit_line is not None:
            k = rng.randrange(3)
            parts = lines[unit_line].split()
            parts[k] = rng.choice(("0.0000000000000000D+00", "-1.0000000000000000D+00", "1.0000000000000000D+308"))
            new = "".join(f"{p:>25s}" for p in parts) + "\n"
            yield (f"unit factor {k + 1} = {parts[k]}", "".join(lines[:unit_line] + [new] + lines[unit_line + 1:])
                   .encode(), "4xx" if k < 2 else "any")  # length, force; the third is temperature
        elif shape == "number" and numeric:
            i = rng.choice(numeric[len(numeric) // 2:])  # a data line, not a header
            parts = lines[i].split()
            j = rng.randrange(len(parts))
            width = len(lines[i].rstrip("\r\n")) // max(1, len(parts))
            parts[j] = rng.choice(("1.00000E+308", "-1.00000E+31", "        NaN", "   Infinity"))
            new = "".join(f"{p:>{width}s}" for p in parts) + "\n"
            yield f"line {i + 1} value {j + 1} = {parts[j].strip()}", "".join(lines[:i] + [new] + lines[i + 1:]).encode(), \
                "any"  # pyuff's fixed columns may read a shifted field as something else: 4xx or refused later
        elif shape == "truncate":
            cut = rng.randrange(1, len(text))
            yield f"truncated at byte {cut}", text[:cut].encode(), "any"
        else:
            raw = bytearray(text.encode())
            for _ in range(rng.randint(1, 8)):
                raw[rng.randrange(len(raw))] = rng.randrange(256)
            yield "bytes flipped", bytes(raw), "any"


def _zip(name: str, payload: bytes) -> bytes:
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w", zipfile.ZIP_DEFLATED) as zf:
        zf.writestr(name, payload)
    return buf.getvalue()


# ---------------------------------------------------------------------------- the seed requests


def _tap(stickout: float, lines: int = 200) -> dict[str, Any]:
    from rcsa.app.predictions import predict

    p = predict({**ra1({"start_hz": 100.0, "stop_hz": 3000.0, "step_hz": 2900.0 / (lines - 1)}),
                 "tool": {**ra1()["tool"], "stickout_m": stickout}})
    h = p.tool_point.h
    return {"tool": {"stickout_m": stickout}, "frequency_hz": p.frequency_hz.tolist(),
            "h": {"real": h.real.tolist(), "imag": h.imag.tolist()}}


@functools.cache
def _seeds() -> dict[str, tuple[str, Any]]:
    """operation → (path, JSON document) of a valid, cheap request (never mutated: every
    mutation works on a copy)."""
    grid = {"start_hz": 5.0, "stop_hz": 2000.0, "step_hz": 10.0}
    asm = ra1(grid)
    taps = [_tap(0.074), _tap(0.06)]
    bare = {k: v for k, v in asm.items() if k != "frequency"}
    lobes = {"assembly": asm, "teeth": 4, "tangential_coefficient_n_m2": 6e8, "radial_ratio": 0.3,
             "radial_immersion": 0.5, "milling": "down", "spindle_speed_rpm": {"start": 2000, "stop": 30000,
                                                                               "count": 50}}
    frf = {"frequency_hz": taps[0]["frequency_hz"], "h": taps[0]["h"]}
    fusion = json.loads((DATA / "tool-libraries" / "fusion-synthetic" / "synthetic_library.json").read_text())
    measurement = json.loads((DATA / "measurements" / "point_receptance.json").read_text())
    return {
        "prediction": ("/v1/tool-point-frf", asm),
        "prediction+uncertainty": ("/v1/tool-point-frf", {**asm, "uncertainty": {"draws": 20, "seed": 1}}),
        "batch": ("/v1/tool-point-frf/batch", {"spindle": asm["spindle"], "frequency": grid, "combinations": [
            {"id": "T1", "holder": asm["holder"], "tool": asm["tool"], "joints": asm["joints"]},
            {"id": "T2", "holder": asm["holder"], "tool": {**asm["tool"], "stickout_m": 0.05}}]}),
        "lobes": ("/v1/stability-lobes", lobes),
        "lobes frf": ("/v1/stability-lobes", {**{k: v for k, v in lobes.items() if k != "assembly"}, "frf_x": frf}),
        "lobes sdm": ("/v1/stability-lobes", {**lobes, "method": "semi_discretization", "steps_per_period": 20,
                                              "modes_per_direction": 2,
                                              "spindle_speed_rpm": {"start": 5000, "stop": 20000, "count": 10}}),
        "effects": ("/v1/effects", {"assembly": asm, "band_hz": [5.0, 2000.0],
                                    "parameters": ["holder_tool.stiffness_n_m", "tool.stickout_m"]}),
        "identification": ("/v1/identifications", {"assembly": asm, "measurements": taps[:1]}),
        "diagnosis": ("/v1/diagnoses", {"assembly": bare, "measurements": taps,
                                        "options": {"monte_carlo_draws": 50, "max_lines": 200}}),
        "plot frf": ("/v1/plots/frf", {"assembly": asm, "title": "RA-1 $\\omega$"}),
        "plot lobes": ("/v1/plots/lobes", {**lobes, "title": "lobes"}),
        "export frf.csv": ("/v1/exports/frf.csv", asm),
        "export lobes.csv": ("/v1/exports/lobes.csv", lobes),
        "measurement json body": ("/v1/measurements", measurement),
        "library predict json": ("/v1/tool-libraries:predict", {"library": fusion, "spindle": asm["spindle"],
                                                                 "frequency": grid}),
        "library entries json": ("/v1/tool-libraries:entries", {"library": fusion}),
    }


def _file_seeds() -> dict[str, tuple[str, str, str, dict[str, str], str]]:
    """operation → (path, field, file name, form fields, kind of file) of a valid upload."""
    meta = {"spindle_id": "hostile", "direction": "x", "plane": "spindle_nose"}
    spindle = json.dumps(ra1()["spindle"])
    grid = json.dumps({"start_hz": 5.0, "stop_hz": 2000.0, "step_hz": 10.0})
    out: dict[str, tuple[str, str, str, dict[str, str], str]] = {}
    for door, path in (("upload", "/v1/measurements"), ("read", "/v1/measurements:read")):
        m = meta if door == "upload" else {}
        out[f"{door} csv"] = (path, "file", "tip.csv", {**m, "units": "um/N"}, "csv")
        out[f"{door} tsv"] = (path, "file", "tip.tsv", {**m, "units": "m/N"}, "tsv")
        out[f"{door} frf"] = (path, "file", "tip.frf", {**m, "units": "m/N"}, "frf")
        out[f"{door} tap"] = (path, "file", "tap.txt", {**m, "format": "tap", "force_unit": "N",
                                                         "response_unit": "m/s^2"}, "tap")
        out[f"{door} uff"] = (path, "file", "tip.uff", {**m, "kind": "artifact_frfs", "points_m": "0,0.025",
                                                         "artifact": json.dumps({"diameter_m": 0.0127,
                                                                                 "stickout_m": 0.06,
                                                                                 "material": "carbide"}),
                                                         "roles": "h11=1:1,h21=2:1,h22=2:2"}, "uff")
        out[f"{door} json file"] = (path, "file", "tip.json", {}, "json")
    out["entries fusion .json"] = ("/v1/tool-libraries:entries", "library", "lib.json", {}, "fusion")
    out["entries fusion .tools"] = ("/v1/tool-libraries:entries", "library", "lib.tools", {}, "tools")
    lib_form = {"spindle": spindle, "frequency": grid}
    out["library predict fusion"] = ("/v1/tool-libraries:predict", "library", "lib.json", lib_form, "fusion")
    out["library predict fctb"] = ("/v1/tool-libraries:predict", "library", "a.fctb",
                                   {**lib_form, "options": json.dumps({"stickout_m": 0.03})}, "fctb")
    out["library predict fcholder"] = ("/v1/tool-libraries:predict", "holder", "h.fcholder",
                                       {**lib_form, "options": json.dumps({"stickout_m": 0.03})}, "fcholder")
    out["library sync fusion"] = ("/v1/libraries/hostile:sync", "library", "lib.json", lib_form, "fusion")
    return out


def _file_text(kind: str) -> str:
    m = DATA / "measurements"
    lib = DATA / "tool-libraries"
    return {"csv": (m / "direct_frf_um_per_n.csv"), "tsv": (m / "direct_frf_mag_phase_deg.tsv"),
            "frf": (m / "direct_frf.frf"), "tap": (m / "tap_synthetic.txt"),
            "uff": (m / "artifact_frfs_accelerance.uff"), "json": (m / "point_receptance.json"),
            "fusion": lib / "fusion-synthetic" / "synthetic_library.json",
            "tools": lib / "fusion-synthetic" / "synthetic_library.json",
            "fctb": lib / "freecad" / "5mm_Endmill.fctb",
            "fcholder": lib / "freecad" / "ER32_Standard.fcholder"}[kind].read_text()


def _file_mutations(kind: str, rng: random.Random, n: int, heavy: bool) -> Iterator[tuple[str, bytes, str]]:
    """Mutated files of ``kind``: (label, bytes, expectation)."""
    text = _file_text(kind)
    if kind in ("csv", "tsv", "frf"):
        yield from table_mutations(text, rng, n, policy_rows=250_000 if heavy else 0,
                                   columns=3 if kind == "frf" else None)
    elif kind == "tap":
        yield from table_mutations(text, rng, n, policy_rows=2_100_000 if heavy else 0)
    elif kind == "uff":
        yield from uff_mutations(text, rng, n)
    else:
        doc = json.loads(text)
        for label, body, expect, path in json_mutations(doc, rng, n):
            if kind == "tools":
                body = _zip("tools.json", body)
            yield label, body, _expectation(expect, path, kind != "json")
        if kind == "tools":
            raw = bytearray(_zip("tools.json", text.encode()))
            for _ in range(max(1, n // 10)):
                bad = bytearray(raw)
                bad[rng.randrange(30, len(bad))] ^= 0xFF
                yield "zip byte flipped", bytes(bad), "any"


def _expectation(expect: str, path: Path_, library: bool) -> str:
    """A physical bound broken inside a library item: that item is refused ("item:<index>")."""
    if expect != "physical":
        return expect
    if not library:
        return "4xx"
    for key in ("data", "combinations"):  # a Fusion library's data[i], a batch's combinations[i]
        if key in path:
            return f"item:{path[path.index(key) + 1]}"
    if "toolbits" in path or "holder" in path:  # FreeCAD in JSON: its one toolbit
        return "item:0"
    if path and path[0] == "library":
        return "4xx"
    return "item:0"  # a FreeCAD file: its one toolbit


def operations() -> list[str]:
    """Names of every operation the generator covers."""
    return [*_seeds(), *_file_seeds()]


def cases(seed: int, per_operation: int, *, heavy: bool = False, write_headers: dict[str, str] | None = None,
          only: Callable[[str], bool] | None = None) -> list[Case]:
    """The hostile cases of ``seed``: ``per_operation`` mutations of each operation's seed request.

    Parameters
    ----------
    seed : int
        Seed of the generator (the same seed gives the same cases).
    per_operation : int
        Mutations per operation (about; a few operations add fixed cases).
    heavy : bool
        Add the largest files (250 000-row tables, a 2 100 000-row tap test).
    write_headers : dict, optional
        Headers with a write key (uploads and syncs need one; sent with every request).
    only : callable, optional
        Keep the operations for which it is true.
    """
    rng = random.Random(seed)
    headers = dict(write_headers or {})
    out: list[Case] = []
    for op, (path, doc) in _seeds().items():
        if only is not None and not only(op):
            continue
        for label, body, expect, where in json_mutations(doc, rng, per_operation):
            if op.startswith("library") and where[:1] == ("library",):
                expect = _expectation(expect, where[1:], True)
            else:
                expect = _expectation(expect, where, op == "batch" and where[:1] == ("combinations",))
            out.append(_case(op, label, path, expect, json_body=body, headers=headers))
    for op, (path, field_name, name, form, kind) in _file_seeds().items():
        if only is not None and not only(op):
            continue
        for label, body, expect in _file_mutations(kind, rng, per_operation, heavy):
            files = [(field_name, (name, body))]
            if kind == "fcholder":
                files.insert(0, ("library", ("a.fctb", _file_text("fctb").encode())))
            case = _case(op, label, path, expect, files=files, data=dict(form), headers=headers)
            if case.item is not None and kind in ("fusion", "tools"):
                item = json.loads(_file_text(kind))["data"][case.item]
                case.item_id = item.get("guid") if "holder" in item else None
            out.append(case)
    return out


def _case(op: str, label: str, path: str, expect: str, **kw: Any) -> Case:
    if expect.startswith("item:"):
        return Case(op, label, path, "item", item=int(expect[5:]), **kw)
    return Case(op, label, path, expect, **kw)


def judge(case: Case, status: int, content_type: str, body: bytes) -> str:
    """``"ok"``, ``"500"`` (a server error), ``"wrong 2xx"`` or ``"not a problem"`` (an error
    answer that is not an RFC 9457 problem document)."""
    if status >= 500:
        return "500"
    if status >= 400:
        return "ok" if content_type.startswith("application/problem+json") else "not a problem"
    if case.expect == "4xx":
        return "wrong 2xx"
    if case.expect == "item" and status == 200:
        try:
            doc = json.loads(body)
        except ValueError:
            return "wrong 2xx"
        if "failed" in doc:  # a sync report: the broken tool is among the failed ones
            failed = {f.get("id") for f in doc["failed"] if isinstance(f, dict)}
            return "wrong 2xx" if case.item_id is not None and case.item_id not in failed else "ok"
        items = doc.get("results") or doc.get("entries") or []  # in library (batch) order
        if not isinstance(items, list) or len(items) <= (case.item or 0):
            return "wrong 2xx"
        if isinstance(items[case.item or 0], dict) and items[case.item or 0].get("status") == "ok":
            return "wrong 2xx"
    return "ok"
