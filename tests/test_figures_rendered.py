"""Every published figure is its JSON's: the documents agree with ``benchmarks/results/*.json``.

``scripts/render_figures.py`` renders each figure written between ``<!-- figure: NAME -->`` and
``<!-- /figure -->`` from the benchmarks' JSON; here a document whose figure differs from its
rendering fails, naming the figure, its text and what the JSON says (run the script to
rewrite them). The renderer's own pieces are checked too: a changed number is caught, an
unknown figure or key is an error, and the exact binomial bound agrees with SciPy's beta
quantile. A picture drawn from a JSON (``docs/default_lobes.png``,
``benchmarks/plot_default_lobes.py``) carries the digest of the JSON it shows.
"""

from __future__ import annotations

import doctest
import importlib.util
import sys

import pytest

from tests.helpers import REPO

_SPEC = importlib.util.spec_from_file_location("render_figures", REPO / "scripts" / "render_figures.py")
assert _SPEC is not None and _SPEC.loader is not None
render_figures = importlib.util.module_from_spec(_SPEC)
sys.modules["render_figures"] = render_figures
_SPEC.loader.exec_module(render_figures)
_PLOT = importlib.util.spec_from_file_location("plot_default_lobes", REPO / "benchmarks" / "plot_default_lobes.py")
assert _PLOT is not None and _PLOT.loader is not None
plot_default_lobes = importlib.util.module_from_spec(_PLOT)
_PLOT.loader.exec_module(plot_default_lobes)


def _png_source(path) -> str | None:
    from PIL import Image

    with Image.open(path) as image:
        return image.text.get("Source")  # type: ignore[attr-defined]


def test_the_default_lobes_picture_shows_the_json_of_today():
    expected = plot_default_lobes.source_digest(plot_default_lobes.RESULTS.read_bytes())
    assert _png_source(plot_default_lobes.OUT) == expected, "run benchmarks/plot_default_lobes.py"


def test_the_default_lobes_picture_is_drawn_with_its_digest(tmp_path):
    data = plot_default_lobes.RESULTS.read_bytes()
    out = plot_default_lobes.draw(data, tmp_path / "lobes.png")
    assert _png_source(out) == plot_default_lobes.source_digest(data)
    assert _png_source(out) != plot_default_lobes.source_digest(data + b" ")


def test_every_document_agrees_with_its_json():
    stale = [d for path in render_figures.documents() for d in render_figures.differences(path)]
    assert not stale, "run scripts/render_figures.py:\n" + "\n".join(stale)


def test_the_manual_renders_its_figures_from_json():
    """The check is not vacuous: the manual's benchmark table and the named figures are marked,
    and every page of the manual and the front page are among the documents rendered."""
    documents = set(render_figures.documents())
    assert {REPO / "README.md", *(REPO / "docs").glob("*.md")} <= documents
    text = "\n".join(p.read_text(encoding="utf-8") for p in sorted((REPO / "docs").glob("*.md")))
    names = {m["name"] for m in render_figures.MARKER.finditer(text)}
    assert {"benchmarks-table", "hybrid-accuracy-table", "modal-fit-sd", "clamping-cost",
            "scatter2-false-claims", "diagnosis-evaluation-table", "solid3d-table"} <= names
    assert sum(1 for _ in render_figures.MARKER.finditer(text)) >= 25


def test_a_changed_number_is_caught(tmp_path):
    doc = tmp_path / "page"
    good = render_figures.render("rms <!-- figure: modal_fit.json:figures.rms_z_pooled|.2f -->?<!-- /figure -->")
    value = render_figures.value("modal_fit", "figures.rms_z_pooled")
    assert good == f"rms <!-- figure: modal_fit.json:figures.rms_z_pooled|.2f -->{value:.2f}<!-- /figure -->"
    doc.write_text(good.replace(f"{value:.2f}", f"{value + 0.1:.2f}"))
    (stale,) = render_figures.differences(doc)
    assert f"{value + 0.1:.2f}" in stale and f"{value:.2f}" in stale


def test_a_table_is_written_on_lines_of_its_own():
    text = render_figures.render("before\n<!-- figure: hybrid-accuracy-table -->\n<!-- /figure -->\nafter")
    lines = text.splitlines()
    assert lines[1] == "<!-- figure: hybrid-accuracy-table -->" and lines[2].startswith("| complex noise")
    assert lines[-2] == "<!-- /figure -->" and render_figures.render(text) == text  # stable


@pytest.mark.parametrize("name", ["no-such-figure", "nothing.json:a.b", "modal_fit.json:figures.nope",
                                  "modal_fit.json:figures.rms_z_pooled|.2q"])
def test_a_figure_that_cannot_be_rendered_is_an_error(name):
    with pytest.raises(render_figures.FigureError):
        render_figures.render(f"<!-- figure: {name} -->x<!-- /figure -->")


@pytest.mark.parametrize(("k", "n"), [(0, 60), (1, 405), (2, 75), (7, 20)])
def test_the_binomial_bound_is_the_beta_quantile(k, n):
    """Clopper–Pearson's one-sided upper bound is the beta quantile B(0.95; k + 1, n − k)."""
    from scipy.stats import beta

    assert render_figures.clopper_pearson_upper(k, n) == pytest.approx(beta.ppf(0.95, k + 1, n - k), rel=1e-9)


def test_the_renderers_examples():
    assert doctest.testmod(render_figures).failed == 0
