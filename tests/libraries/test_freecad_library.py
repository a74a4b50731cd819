"""FreeCAD libraries: .fctb, .fctl, folders, zips and the JSON form; format detection; stable ids.

Built in tmp from the copied FreeCAD samples (LGPL, see SOURCE.md): the FreeCAD layout
``Tools/Bit``, ``Tools/Library``, ``Tools/Holder``. The samples ship no ``.fctl``; the one
here is written the way FreeCAD's ``FCTLSerializer`` writes it.
"""

from __future__ import annotations

import io
import json
import shutil
import zipfile
from pathlib import Path

import pytest

from rcsa.errors import InputError
from rcsa.libraries import freecad_combination
from rcsa.libraries.formats import detect_format, import_library, read_library
from rcsa.libraries.freecad_library import FreeCADLibrary, freecad_library_combinations
from rcsa.libraries.fusion import FusionLibrary

DATA = Path(__file__).resolve().parents[1] / "data" / "tool-libraries"
FREECAD = DATA / "freecad"
FUSION = DATA / "fusion-synthetic" / "synthetic_library.json"
BITS = ("5mm_Endmill", "6mm_Ball_End")


def tools_folder(tmp_path: Path, *, fctl: bool = True, holder: bool = True) -> Path:
    """``Tools/{Bit,Library,Holder}`` as FreeCAD keeps them."""
    root = tmp_path / "Tools"
    for sub in ("Bit", "Library", "Holder"):
        (root / sub).mkdir(parents=True, exist_ok=True)
    for name in BITS:
        shutil.copy(FREECAD / f"{name}.fctb", root / "Bit")
    if holder:
        shutil.copy(FREECAD / "ER32_Standard.fcholder", root / "Holder")
    if fctl:
        (root / "Library" / "Shop.fctl").write_text(json.dumps(
            {"version": 1, "tools": [{"nr": 7, "path": "6mm_Ball_End.fctb"}, {"nr": 3, "path": "5mm_Endmill.fctb"},
                                     {"nr": 9, "path": "missing.fctb"}]}))
    return root


def bundle_zip(with_holder: bool = True, with_fctl: bool = False) -> bytes:
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w") as zf:
        for name in BITS:
            zf.writestr(f"Bit/{name}.fctb", (FREECAD / f"{name}.fctb").read_bytes())
        if with_holder:
            zf.writestr("Holder/ER32_Standard.fcholder", (FREECAD / "ER32_Standard.fcholder").read_bytes())
        if with_fctl:
            zf.writestr("Library/lib.fctl", json.dumps({"version": 1, "tools": [{"nr": 1, "path": "5mm_Endmill.fctb"}]}))
    return buf.getvalue()


def test_fctl_orders_numbers_and_reports_missing_toolbits(tmp_path):
    root = tools_folder(tmp_path)
    lib = read_library(root / "Library" / "Shop.fctl", holder=root / "Holder" / "ER32_Standard.fcholder")
    out = import_library(lib, stickout_m=0.040)
    assert [(c.id, c.number, c.status) for c in out] == [
        ("6mm_Ball_End@ER32_Standard", 7, "ok"), ("5mm_Endmill@ER32_Standard", 3, "ok"),
        ("missing@ER32_Standard", 9, "error")]
    assert out.combinations[2].reason == "toolbit: toolbit file 'missing.fctb' not found"
    # the same toolbit and holder as freecad_combination on the files
    single = freecad_combination(FREECAD / "5mm_Endmill.fctb", FREECAD / "ER32_Standard.fcholder", stickout_m=0.040)
    assert out.combinations[1].tool == single.tool and out.combinations[1].holder == single.holder


def test_folder_zip_json_and_single_toolbit_give_the_same_entries(tmp_path):
    root = tools_folder(tmp_path, fctl=False)
    folder = tmp_path / "flat"
    folder.mkdir()
    for p in [*(root / "Bit").iterdir(), *(root / "Holder").iterdir()]:
        shutil.copy(p, folder)
    doc = {"format": "freecad",
           "toolbits": {name: json.loads((FREECAD / f"{name}.fctb").read_text()) for name in BITS},
           "holder": {"ER32_Standard": json.loads((FREECAD / "ER32_Standard.fcholder").read_text())}}

    def entries(source, **kw):
        return [(c.id, c.status, c.tool, c.holder) for c in import_library(read_library(source, **kw), stickout_m=0.04)]

    ref = entries(folder)
    assert [e[0] for e in ref] == ["5mm_Endmill@ER32_Standard", "6mm_Ball_End@ER32_Standard"]
    assert entries(bundle_zip(), file_name="tools.zip") == ref
    assert entries(doc) == ref
    assert entries(json.dumps(doc).encode(), file_name="lib.json") == ref
    one = entries((FREECAD / "5mm_Endmill.fctb").read_bytes(), file_name="5mm_Endmill.fctb",
                  holder=(FREECAD / "ER32_Standard.fcholder").read_bytes(), holder_name="ER32_Standard.fcholder")
    assert one == ref[:1]


def test_ids_are_stable_across_exports_and_a_change_shows_in_the_content_hash(tmp_path):
    a = read_library(bundle_zip())
    b = read_library(bundle_zip())
    assert isinstance(a, FreeCADLibrary) and a.sha256 == b.sha256
    doc = {"format": "freecad", "toolbits": {n: json.loads((FREECAD / f"{n}.fctb").read_text()) for n in BITS}}
    doc["toolbits"]["5mm_Endmill"]["parameter"]["Length"] = "60.0000 mm"
    changed = import_library(doc, stickout_m=0.04)
    assert [c.id for c in changed] == ["5mm_Endmill", "6mm_Ball_End"]  # same ids, no holder: skipped
    assert {c.status for c in changed} == {"skipped"} and {c.reason for c in changed} == {"no holder"}
    assert read_library(doc).sha256 != read_library({**doc, "toolbits": {**doc["toolbits"], "5mm_Endmill": {
        **doc["toolbits"]["5mm_Endmill"], "name": "renamed"}}}).sha256


def test_stickout_per_toolbit_and_missing_ones(tmp_path):
    lib = read_library(bundle_zip())
    out = freecad_library_combinations(lib, stickout_m={"5mm_Endmill": 0.035})
    assert [c.status for c in out] == ["ok", "error"]
    assert out.combinations[0].tool["stickout_m"] == 0.035
    assert out.combinations[1].reason.startswith("stickout_m.6mm_Ball_End: missing")
    with pytest.raises(InputError, match="^stickout_m: required for FreeCAD"):
        import_library(lib)
    with pytest.raises(InputError, match="^stickout_m: must be > 0"):
        import_library(lib, stickout_m=-1)


def test_shallow_insertion_and_hss_in_freecad(tmp_path):
    doc = {"format": "freecad", "toolbits": {"bit": json.loads((FREECAD / "5mm_Endmill.fctb").read_text())},
           "holder": {"ER32": json.loads((FREECAD / "ER32_Standard.fcholder").read_text())}}
    doc["toolbits"]["bit"]["attribute"] = {"Material": "HSS"}
    (combo,) = import_library(doc, stickout_m=0.047)  # Length 50 mm: 3 mm of the 3 mm shank clamped
    assert combo.tool["material"] == "hss"
    assert any("shallow insertion: 3 mm of the 3 mm shank" in w for w in combo.warnings)


@pytest.mark.parametrize(("options", "field"), [({"shaft_origin": "shoulder", "stickout_m": 0.04}, "shaft_origin"),
                                                ({"default_holder": "x", "stickout_m": 0.04}, "default_holder")])
def test_fusion_only_options_are_refused_for_freecad(options, field):
    with pytest.raises(InputError, match=f"^{field}: applies to a Fusion library"):
        import_library(bundle_zip(), **options)


def test_fusion_libraries_refuse_freecad_only_inputs():
    with pytest.raises(InputError, match="^stickout_m: applies to a FreeCAD library"):
        import_library(FUSION, stickout_m=0.04)
    with pytest.raises(InputError, match="^holder: a Fusion library carries its holders"):
        read_library(FUSION, holder=FREECAD / "ER32_Standard.fcholder")
    assert isinstance(read_library(FUSION.read_bytes(), file_name="x.json"), FusionLibrary)


@pytest.mark.parametrize(("data", "name", "ctype", "expected"), [
    (FUSION.read_bytes(), "lib.json", None, "fusion"),
    ((FREECAD / "5mm_Endmill.fctb").read_bytes(), "bit.json", None, "freecad"),
    ((FREECAD / "5mm_Endmill.fctb").read_bytes(), None, "application/x-freecad-toolbit", "freecad"),
    (bundle_zip(), "Tools.zip", "application/zip", "freecad"),
    (b"not json", "x.fctb", None, "freecad"),
])
def test_detection_by_content_name_and_media_type(data, name, ctype, expected):
    assert detect_format(data, file_name=name, content_type=ctype) == expected


@pytest.mark.parametrize(("data", "name", "ctype"), [
    (FUSION.read_bytes(), "renamed.fctb", None),
    (bundle_zip(), "library.tools", None),
    (FUSION.read_bytes(), None, "application/x-freecad-toolbit-library"),
])
def test_a_name_contradicting_the_content_is_refused(data, name, ctype):
    with pytest.raises(InputError, match="^library: .* says a .* file, but the content is a"):
        read_library(data, file_name=name, content_type=ctype)


def test_unreadable_freecad_inputs_name_the_problem(tmp_path):
    with pytest.raises(InputError, match="holder alone is not a library"):
        read_library(FREECAD / "ER32_Standard.fcholder")
    two = tmp_path / "two"
    two.mkdir()
    for name in ("a", "b"):
        shutil.copy(FREECAD / "ER32_Standard.fcholder", two / f"{name}.fcholder")
    shutil.copy(FREECAD / "5mm_Endmill.fctb", two)
    with pytest.raises(InputError, match="^holder: .* has 2 holders"):
        read_library(two)
    with pytest.raises(InputError, match="already has its holder"):
        read_library(bundle_zip(), holder=FREECAD / "ER32_Standard.fcholder")
    with pytest.raises(InputError, match="no FreeCAD toolbit"):
        buf = io.BytesIO()
        with zipfile.ZipFile(buf, "w") as zf:
            zf.writestr("readme.txt", "hi")
        read_library(buf.getvalue(), file_name="x.zip", content_type="application/x-freecad-toolbit-library")
    bad = {"format": "freecad", "toolbits": {"broken": [1, 2]}}
    (combo,) = import_library(bad, stickout_m=0.04)
    assert combo.status == "error" and combo.reason == "toolbit: not a JSON object"
