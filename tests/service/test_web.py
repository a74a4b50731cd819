"""The web view's page and assets, and the endpoints it uses: figures, CSV exports, the
RA-1 example and the library entries (TestClient; the browser test is test_web_browser.py)."""

from __future__ import annotations

import csv
import io
import json
import re
from html.parser import HTMLParser

import pytest

from rcsa.reference import ra1
from tests.helpers import REPO

from .conftest import READ, assert_problem

LIBRARIES = REPO / "tests" / "data" / "tool-libraries" / "fusion-synthetic"
PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"
LOBES = {"teeth": 4, "tangential_coefficient_n_m2": 6.0e8, "radial_ratio": 0.3, "radial_immersion": 0.5,
         "milling": "down", "spindle_speed_rpm": {"start": 2000.0, "stop": 30000.0, "count": 300}}


class _Page(HTMLParser):
    """Ids, label targets, form controls and external references of an HTML page."""

    def __init__(self) -> None:
        super().__init__()
        self.ids: set[str] = set()
        self.label_for: set[str] = set()
        self.controls: list[tuple[str, str | None, str | None]] = []
        self.refs: list[str] = []
        self._label_depth = 0

    def handle_starttag(self, tag: str, attrs: list[tuple[str, str | None]]) -> None:
        a = dict(attrs)
        if a.get("id"):
            self.ids.add(a["id"])
        if tag == "label":
            self._label_depth += 1
            if a.get("for"):
                self.label_for.add(a["for"])
        if tag in ("input", "select", "textarea"):
            self.controls.append((tag, a.get("id"), "wrapped" if self._label_depth else None))
        for key in ("src", "href"):
            if a.get(key):
                self.refs.append(a[key])

    def handle_endtag(self, tag: str) -> None:
        if tag == "label":
            self._label_depth -= 1


def _page(client) -> _Page:
    r = client.get("/ui/")
    parser = _Page()
    parser.feed(r.text)
    return parser


# --------------------------------------------------------------------------- page and assets

def test_root_redirects_to_the_page(client):
    r = client.get("/", follow_redirects=False)
    assert r.status_code == 307 and r.headers["location"] == "ui/"
    r = client.get("/")
    assert r.status_code == 200 and str(r.url).endswith("/ui/")
    assert client.get("/ui").url.path == "/ui/"


def test_page_is_self_contained_with_a_same_origin_policy(client):
    r = client.get("/ui/")
    assert r.status_code == 200 and r.headers["content-type"] == "text/html; charset=utf-8"
    csp = r.headers["content-security-policy"]
    assert "default-src 'none'" in csp and "script-src 'self'" in csp and "connect-src 'self'" in csp
    assert r.headers["x-content-type-options"] == "nosniff"
    page = _page(client)
    assert page.refs, "the page references its script and style sheet"
    for ref in page.refs:  # nothing from another host: the page works offline
        assert not re.match(r"^(https?:)?//", ref), ref
    for name, media in (("app.js", "text/javascript"), ("app.css", "text/css")):
        asset = client.get(f"/ui/{name}")
        assert asset.status_code == 200 and asset.headers["content-type"].startswith(media)
        assert asset.headers["cache-control"] == "no-cache"
        text = asset.text.replace('"http://www.w3.org/2000/svg"', "")  # the SVG namespace is a name, not a fetch
        assert "http://" not in text and "https://" not in text and "url(//" not in text


@pytest.mark.parametrize("name", ["nope.js", "..%2Fapp.js", "index.htm", "%2e%2e"])
def test_only_the_page_files_are_served(client, name):
    r = client.get(f"/ui/{name}")
    assert r.status_code == 404


def test_every_control_has_a_label_and_the_test_ids_exist(client):
    page = _page(client)
    for tag, ident, wrapped in page.controls:
        assert ident, f"a {tag} without id"
        assert ident in page.label_for or wrapped, f"{tag}#{ident} has no label"
    assert page.label_for <= page.ids, page.label_for - page.ids
    for ident in ("spindle", "library-file", "entry", "joints-ra1", "freq-start", "freq-stop", "freq-step",
                  "assembly-json", "api-key", "predict", "frf-plot", "nat-freqs", "peaks", "static-stiffness",
                  "min-real", "teeth", "kt", "kr", "immersion", "milling", "speed-start", "speed-stop",
                  "speed-count", "op-speed", "op-depth", "lobes", "lobes-plot", "error", "download-frf-csv",
                  "download-frf-png", "download-frf-svg", "download-lobes-csv", "download-lobes-png",
                  "download-lobes-svg"):
        assert ident in page.ids, ident


def test_script_calls_only_documented_endpoints(client):
    script = client.get("/ui/app.js").text
    paths = client.get("/openapi.json").json()["paths"]
    called = set(re.findall(r'"(v1/[^"?]+)', script))
    assert {"v1/examples/ra1", "v1/measurements", "v1/tool-libraries:entries", "v1/tool-point-frf",
            "v1/stability-lobes", "v1/exports/frf.csv", "v1/exports/lobes.csv", "v1/plots/frf",
            "v1/plots/lobes"} <= called
    for path in called:
        assert "/" + path in paths, path


def test_page_needs_no_key_but_the_api_may(make_client):
    with make_client(anonymous_read=False) as client:
        assert client.get("/ui/").status_code == 200
        assert client.get("/ui/app.js").status_code == 200
        assert_problem(client.get("/v1/examples/ra1"), 401)
        assert client.get("/v1/examples/ra1", headers=READ).status_code == 200


def test_ra1_example_is_the_reference_assembly(client):
    r = client.get("/v1/examples/ra1")
    assert r.status_code == 200 and r.json() == ra1()


# --------------------------------------------------------------------------- figures

def test_frf_figure_of_an_assembly_png_and_svg(client, assembly):
    r = client.post("/v1/plots/frf", json={"assembly": assembly, "title": "RA-1"})
    assert r.status_code == 200 and r.headers["content-type"] == "image/png"
    assert r.content[:8] == PNG_SIGNATURE
    assert 'filename="tool-point-frf.png"' in r.headers["content-disposition"]
    r = client.post("/v1/plots/frf?format=svg", json={"assembly": assembly, "layout": "bode"})
    assert r.status_code == 200 and r.headers["content-type"].startswith("image/svg+xml")
    assert "<svg" in r.text[:1000]
    r = client.post("/v1/plots/frf", json={"assembly": assembly}, headers={"Accept": "image/svg+xml"})
    assert r.headers["content-type"].startswith("image/svg+xml")
    r = client.post("/v1/plots/frf", json={"assembly": assembly}, headers={"Accept": "image/png, image/svg+xml"})
    assert r.headers["content-type"] == "image/png"


def test_frf_figure_of_an_inline_frf(client, assembly):
    result = client.post("/v1/tool-point-frf?tool_point=h", json=assembly).json()
    frf = {"frequency_hz": result["frequency_hz"], "h": result["tool_point"]["h"]}
    r = client.post("/v1/plots/frf", json={"frf": frf, "layout": "real_imag"})
    assert r.status_code == 200 and r.content[:8] == PNG_SIGNATURE


@pytest.mark.parametrize(("body", "field"), [
    ({}, "frf"),
    ({"frf": {"frequency_hz": [1.0, 2.0], "h": {"real": [1e-6, 1e-6], "imag": [0.0, 0.0]}},
      "assembly": ra1({"start_hz": 5.0, "stop_hz": 50.0, "step_hz": 5.0})}, "frf"),
    ({"frf": {"frequency_hz": [1.0, 2.0], "h": {"real": [1e-6, 1e-6], "imag": [0.0]}}}, "frf.h.imag"),
    ({"frf": {"frequency_hz": [1.0], "h": {"real": [1e-6], "imag": [0.0]}}}, "frf.frequency_hz"),
    ({"frf": {"frequency_hz": [1.0, 2.0], "h": {"real": [0.0, 0.0], "imag": [0.0, 0.0]}}}, "frf.h"),
    ({"frf": {"frequency_hz": [2.0, 1.0], "h": {"real": [1e-6, 1e-6], "imag": [0.0, 0.0]}}}, None),
    ({"frf": {"frequency_hz": [1.0, 2.0], "h": {"real": [1e-6, "x"], "imag": [0.0, 0.0]}}}, "frf.h.real[1]"),
    ({"assembly": ra1({"start_hz": 5.0, "stop_hz": 5.0, "step_hz": 1.0})}, "assembly.frequency"),
    ({"assembly": {**ra1(), "tool": {**ra1()["tool"], "stickout_m": -1.0}}}, "assembly.tool.stickout_m"),
    ({"frf": {"frequency_hz": [1.0, 2.0], "h": {"real": [1e-6, 1e-6], "imag": [0.0, 0.0]}}, "layout": "x"}, "layout"),
])
def test_frf_figure_refuses_bad_input_with_a_problem(client, body, field):
    assert_problem(client.post("/v1/plots/frf", json=body), 422, field)


def test_frf_figure_zero_h_is_fine_without_a_log_axis(client):
    frf = {"frequency_hz": [1.0, 2.0], "h": {"real": [0.0, 0.0], "imag": [0.0, 0.0]}}
    r = client.post("/v1/plots/frf", json={"frf": frf, "layout": "real_imag"})
    assert r.status_code == 200 and r.content[:8] == PNG_SIGNATURE


def test_figure_format_and_media_type_errors(client, assembly):
    assert_problem(client.post("/v1/plots/frf?format=gif", json={"assembly": assembly}), 422, "format")
    r = client.post("/v1/plots/frf", content=b"x", headers={"Content-Type": "text/plain"})
    assert_problem(r, 415)


def test_lobes_figure_png_and_svg(client, assembly):
    body = {"assembly": assembly, **LOBES, "operating_point": {"spindle_speed_rpm": 12000.0, "depth_m": 2e-4},
            "title": "RA-1", "depth_max_mm": 3.0}
    r = client.post("/v1/plots/lobes", json=body)
    assert r.status_code == 200 and r.content[:8] == PNG_SIGNATURE
    r = client.post("/v1/plots/lobes?format=svg", json={**body, "show_lobes": False})
    assert r.status_code == 200 and "<svg" in r.text[:1000]
    assert 'filename="stability-lobes.svg"' in r.headers["content-disposition"]


@pytest.mark.parametrize(("change", "field"), [
    ({"teeth": 0}, "teeth"),
    ({"operating_point": {"spindle_speed_rpm": 1000.0}}, "operating_point.depth_m"),
    ({"depth_max_mm": -1.0}, "depth_max_mm"),
    ({"milling": "sideways"}, "milling"),
])
def test_lobes_figure_refuses_bad_input(client, assembly, change, field):
    assert_problem(client.post("/v1/plots/lobes", json={"assembly": assembly, **LOBES, **change}), 422, field)


# --------------------------------------------------------------------------- CSV exports

def _rows(response) -> tuple[list[str], list[list[str]]]:
    assert response.status_code == 200, response.text
    assert response.headers["content-type"] == "text/csv; charset=utf-8"
    rows = list(csv.reader(io.StringIO(response.text)))
    return rows[0], rows[1:]


def test_frf_csv_equals_the_json_prediction(client, assembly):
    r = client.post("/v1/exports/frf.csv", json=assembly)
    assert 'attachment; filename="tool-point-frf.csv"' == r.headers["content-disposition"]
    header, rows = _rows(r)
    assert header == ["frequency_hz", "h_real_m_n", "h_imag_m_n", "l_real_1_n", "l_imag_1_n", "n_real_rad_n",
                      "n_imag_rad_n", "p_real_rad_n_m", "p_imag_rad_n_m"]
    result = client.post("/v1/tool-point-frf", json=assembly).json()
    assert len(rows) == len(result["frequency_hz"]) == 1000
    columns = list(zip(*rows, strict=True))
    assert [float(v) for v in columns[0]] == result["frequency_hz"]
    for k, name in enumerate(("h", "l", "n", "p")):
        assert [float(v) for v in columns[1 + 2 * k]] == result["tool_point"][name]["real"]
        assert [float(v) for v in columns[2 + 2 * k]] == result["tool_point"][name]["imag"]
    assert r.text.endswith("\r\n")


def test_frf_csv_refuses_a_bad_assembly(client, assembly):
    del assembly["tool"]
    assert_problem(client.post("/v1/exports/frf.csv", json=assembly), 422, "tool")


def test_lobes_csv_equals_the_json_lobes(client, assembly):
    request = {"assembly": assembly, **LOBES}
    header, rows = _rows(client.post("/v1/exports/lobes.csv", json=request))
    assert header == ["spindle_speed_rpm", "depth_limit_m", "chatter_frequency_hz", "governing_lobe"]
    lobes = client.post("/v1/stability-lobes", json=request).json()
    assert len(rows) == LOBES["spindle_speed_rpm"]["count"]
    for i, row in enumerate(rows):
        speed, depth, chatter, lobe = row
        assert float(speed) == lobes["spindle_speed_rpm"][i]
        assert (None if depth == "" else float(depth)) == lobes["depth_limit_m"][i]
        assert (None if chatter == "" else float(chatter)) == lobes["chatter_frequency_hz"][i]
        assert int(lobe) == lobes["governing_lobe"][i]


def test_lobes_csv_refuses_bad_input(client, assembly):
    assert_problem(client.post("/v1/exports/lobes.csv", json={"assembly": assembly, **LOBES, "radial_immersion": 2.0}),
                   422, "radial_immersion")
    assert_problem(client.post("/v1/exports/lobes.csv", json={**LOBES}), 422)  # neither frf_x nor assembly


# --------------------------------------------------------------------------- library entries

def _check_entries(doc):
    assert doc["library"]["summary"] == {"ok": 2, "skipped": 2, "error": 0}
    entries = doc["entries"]
    assert [e["status"] for e in entries] == ["ok", "ok", "skipped", "skipped"]
    first = entries[0]
    assert first["id"] == "00000000-0000-4000-8000-000000000101" and first["teeth"] == 4 and first["number"] == 1
    assert first["description"].startswith("SYNTH 10mm 4FL")
    assert first["reason"] is None and first["holder"]["segments"] and first["tool"]["stickout_m"] == pytest.approx(0.04)
    assert entries[2]["reason"] == "no holder" and entries[2]["holder"] is None and entries[2]["tool"] is None
    return doc


def test_entries_of_a_json_and_a_tools_library(client):
    docs = []
    for name in ("synthetic_library.json", "synthetic_library.tools"):
        with (LIBRARIES / name).open("rb") as fh:
            r = client.post("/v1/tool-libraries:entries", files={"library": (name, fh)})
        assert r.status_code == 200, r.text
        docs.append(_check_entries(r.json()))
        assert docs[-1]["library"]["file_name"] == name
    assert docs[0]["library"]["library_sha256"] == docs[1]["library"]["library_sha256"]
    assert docs[0]["entries"] == docs[1]["entries"]


def test_entries_plug_into_a_prediction(client, assembly):
    with (LIBRARIES / "synthetic_library.json").open("rb") as fh:
        entry = client.post("/v1/tool-libraries:entries", files={"library": ("lib.json", fh)}).json()["entries"][1]
    r = client.post("/v1/tool-point-frf", json={**assembly, "holder": entry["holder"], "tool": entry["tool"]})
    assert r.status_code == 200, r.text


def test_entries_from_a_json_body_with_options(client):
    library = json.loads((LIBRARIES / "synthetic_library.json").read_text())
    plain = client.post("/v1/tool-libraries:entries", json={"library": library}).json()
    _check_entries(plain)
    assert plain["library"]["file_name"] is None
    r = client.post("/v1/tool-libraries:entries", json={"library": library, "options": {"holder_segments_per_cone": 1}})
    coarse = _check_entries(r.json())
    assert len(coarse["entries"][0]["holder"]["segments"]) < len(plain["entries"][0]["holder"]["segments"])
    r = client.post("/v1/tool-libraries:entries", files={"library": ("lib.json", json.dumps(library))},
                    data={"options": json.dumps({"holder_segments_per_cone": 1})})
    assert r.json()["entries"] == coarse["entries"]


@pytest.mark.parametrize(("kwargs", "status", "field"), [
    ({"files": {"library": ("lib.json", b"not json")}}, 422, ""),
    ({"files": {"library": ("lib.json", b'{"version": 1}')}}, 422, "data"),
    ({"files": {"library": ("lib.tools", b"PK\x03\x04broken")}}, 422, ""),
    ({"files": {"library": ("lib.json", b'{"data": []}')}, "data": {"colour": "red"}}, 422, "colour"),
    ({"files": {"library": ("lib.json", b'{"data": []}')}, "data": {"options": "{"}}, 422, "options"),
    ({"files": {"library": ("lib.json", b'{"data": []}')}, "data": {"options": '{"x": 1}'}}, 422, "options.x"),
    ({"files": {"library": ("lib.json", b'{"data": []}')}, "data": {"options": '[1]'}}, 422, "options"),
    ({"files": [("library", ("a.json", b'{"data": []}')), ("library", ("b.json", b'{"data": []}'))]}, 422,
     "library"),
    ({"data": {"options": "{}"}}, 415, None),  # a form without a file is url-encoded
    ({"json": {"options": {}}}, 422, "library"),
    ({"json": {"library": []}}, 422, "library"),
    ({"content": b"x", "headers": {"Content-Type": "text/plain"}}, 415, None),
])
def test_entries_errors_are_problems(client, kwargs, status, field):
    assert_problem(client.post("/v1/tool-libraries:entries", **kwargs), status, field)


def test_entries_of_an_empty_library(client):
    r = client.post("/v1/tool-libraries:entries", files={"library": ("lib.json", b'{"data": []}')})
    assert r.status_code == 200 and r.json()["entries"] == []


def test_upload_limit_applies_to_libraries(make_client):
    with make_client(max_upload_bytes=1024) as client:
        big = json.dumps({"data": [], "pad": "x" * 4096}).encode()
        assert_problem(client.post("/v1/tool-libraries:entries", files={"library": ("lib.json", big)}), 413, "library")


# --------------------------------------------------------------------------- documentation

def test_new_endpoints_are_documented(client):
    paths = client.get("/openapi.json").json()["paths"]
    assert set(paths["/v1/plots/frf"]["post"]["responses"]["200"]["content"]) == {"image/png", "image/svg+xml"}
    assert set(paths["/v1/plots/lobes"]["post"]["responses"]["200"]["content"]) == {"image/png", "image/svg+xml"}
    for path in ("/v1/exports/frf.csv", "/v1/exports/lobes.csv"):
        assert set(paths[path]["post"]["responses"]["200"]["content"]) == {"text/csv"}
    entries = paths["/v1/tool-libraries:entries"]["post"]
    assert set(entries["requestBody"]["content"]) == {"multipart/form-data", "application/json"}
    assert "/v1/examples/ra1" in paths
    assert "/" not in paths and "/ui/" not in paths


# --------------------------------------------------------------------------- the diagnosis part of the page

def test_diagnosis_script_is_served_and_calls_only_documented_endpoints(client):
    page = _page(client)
    assert "diagnosis.js" in page.refs
    for ident in ("tap-rows", "tap-add", "tap-units", "diag-effort", "diagnose", "diag-verdict", "gap-plot",
                  "diag-frf-plot"):
        assert ident in page.ids, ident
    r = client.get("/ui/diagnosis.js")
    assert r.status_code == 200 and r.headers["content-type"].startswith("text/javascript")
    assert "default-src 'none'" in r.headers["content-security-policy"]
    text = r.text.replace('"http://www.w3.org/2000/svg"', "")
    assert "http://" not in text and "https://" not in text
    paths = client.get("/openapi.json").json()["paths"]
    called = set(re.findall(r'"(v1/[^"?]+)', r.text))
    assert called == {"v1/measurements:read", "v1/diagnoses", "v1/tool-point-frf"}, called
    for path in called:
        assert "/" + path in paths, path


def test_measurement_file_is_read_not_stored(client):
    csv_text = "frequency [Hz],real [um/N],imag [um/N]\n100,0.1,-0.01\n200,0.12,-0.05\n300,-0.3,-0.2\n"
    r = client.post("/v1/measurements:read", files={"file": ("tap-60mm.csv", csv_text.encode(), "text/csv")})
    assert r.status_code == 200, r.text
    doc = r.json()
    assert doc["frequency_hz"] == [100.0, 200.0, 300.0] and doc["kind"] == "direct_frf"
    assert doc["h"]["real"] == pytest.approx([1e-7, 1.2e-7, -3e-7]) and doc["units"]["h"] == "m/N"
    assert doc["source"]["original_units"] == "um/N" and "id" not in doc
    assert client.get("/v1/measurements").json()["items"] == []  # nothing stored
    # the importer's rules and names, as for POST /v1/measurements
    r = client.post("/v1/measurements:read", files={"file": ("x.csv", b"1,2,3\n", "text/csv")})
    assert_problem(r, 422, "columns")
    r = client.post("/v1/measurements:read", files={"file": ("x.csv", csv_text.encode(), "text/csv")},
                    data={"units": "m/N"})
    assert_problem(r, 422)  # a declaration that contradicts the header is refused
    r = client.post("/v1/measurements:read", files={"file": ("x.csv", csv_text.encode(), "text/csv")},
                    data={"colour": "red"})
    assert_problem(r, 422, "colour")
    assert_problem(client.post("/v1/measurements:read", json={"frequency_hz": [1.0]}), 415)
    assert_problem(client.post("/v1/measurements:read", files={"units": (None, "m/N")}), 422, "file")


def test_the_web_endpoints_read_their_forms_as_the_api_routes_do(client):
    # one reading of a measurement form (POST /v1/measurements and :read) and of a library
    # upload (POST /v1/tool-libraries:predict and :entries): the same refusals, word for word
    from tests.service.conftest import WRITE

    def detail(path, headers=None, **form):
        r = client.post(path, headers=headers or {}, **form)
        assert r.status_code == 422, r.text
        return r.json()["errors"][0]

    unknown = {"files": {"file": ("x.csv", b"f,re,im\n", "text/csv")}, "data": {"colour": "red"}}
    assert detail("/v1/measurements:read", **unknown) == detail("/v1/measurements", WRITE, **unknown)
    no_file = {"files": {"format": (None, "csv")}}  # multipart, with no file in it
    assert detail("/v1/measurements:read", **no_file) == detail("/v1/measurements", WRITE, **no_file) == \
        {"field": "file", "detail": "is required: the measurement file as a multipart part"}
    two = {"files": [("library", ("a.json", b"{}", "application/json")), ("library", ("b.json", b"{}", "application/json"))]}
    entries, predict = detail("/v1/tool-libraries:entries", **two), detail("/v1/tool-libraries:predict", **two)
    assert entries == predict and entries["field"] == "library"
