"""The manual builds as a static site, offline, and the front page stays a front page.

* ``mkdocs build --strict`` (``mkdocs.yml``: MkDocs' own theme, highlight.js off) builds
  ``docs/`` into a temporary folder: a link to a missing page or anchor, a page left out of
  the nav or a bad link fails it (``validation`` in ``mkdocs.yml`` makes them warnings,
  ``--strict`` errors). The site loads nothing from the network: every script, style sheet
  and image of every page is a file of the site.
* ``README.md`` is a front page: at most ~200 lines, its first code block the install-and-run
  line and the test line (``.ci/run`` runs the second), no blocking ``rcsa serve`` in it, a
  picture that exists, and a link to every page of the manual.
* The site's output folder is git-ignored.

The commands of every page run in ``tests/test_examples.py``; the figures are checked
against their JSON in ``tests/test_figures_rendered.py``.
"""

from __future__ import annotations

import re
import subprocess
import sys
from html.parser import HTMLParser

import yaml

from tests.helpers import REPO, manual_pages

README = REPO / "README.md"


class _Assets(HTMLParser):
    """Every ``src`` of a page and every ``href`` of its ``<link>`` elements."""

    def __init__(self) -> None:
        super().__init__()
        self.urls: list[str] = []

    def handle_starttag(self, tag: str, attrs: list[tuple[str, str | None]]) -> None:
        for name, value in attrs:
            if value and (name == "src" or (tag == "link" and name == "href")):
                self.urls.append(value)


def test_the_manual_builds_strictly_and_offline(tmp_path):
    # never --quiet: it hides the warnings that --strict counts, and the build would pass anything
    site = tmp_path / "site"
    run = subprocess.run([sys.executable, "-m", "mkdocs", "build", "--strict",
                          "--config-file", str(REPO / "mkdocs.yml"), "--site-dir", str(site)],
                         capture_output=True, text=True, timeout=300, cwd=REPO)
    assert run.returncode == 0, run.stderr[-3000:]
    pages = sorted(site.rglob("*.html"))
    for page in manual_pages():
        built = site / "index.html" if page.stem == "index" else site / page.stem / "index.html"
        assert built.is_file(), f"{page.name} was not built"
    for page in pages:
        parser = _Assets()
        parser.feed(page.read_text(encoding="utf-8"))
        remote = [u for u in parser.urls if re.match(r"(https?:)?//", u)]
        assert not remote, f"{page.relative_to(site)} loads {remote}"
        local = [u.split("#")[0].split("?")[0] for u in parser.urls]  # "/x" from the site's root (404.html)
        missing = [u for u in local if not (site / u.lstrip("/") if u.startswith("/") else page.parent / u).exists()]
        assert not missing, f"{page.relative_to(site)}: no such file in the site: {missing}"


def test_a_broken_link_fails_the_build(tmp_path):
    """The build is strict about anchors: the check above is not vacuous."""
    docs = tmp_path / "docs"
    docs.mkdir()
    (docs / "index.md").write_text("# Home\n\n[a section that is not there](#nowhere)\n", encoding="utf-8")
    config = yaml.safe_load((REPO / "mkdocs.yml").read_text(encoding="utf-8"))
    config.update(docs_dir=str(docs), nav=[{"Home": "index.md"}])
    (tmp_path / "mkdocs.yml").write_text(yaml.safe_dump(config), encoding="utf-8")
    run = subprocess.run([sys.executable, "-m", "mkdocs", "build", "--strict",
                          "--site-dir", str(tmp_path / "site")], capture_output=True, text=True, timeout=300,
                         cwd=tmp_path)
    assert run.returncode != 0 and "nowhere" in run.stderr, run.stderr[-2000:]


def _first_block(text: str) -> list[str]:
    return re.search(r"```bash\n(.*?)```", text, re.S).group(1).splitlines()


def test_the_readme_is_a_front_page():
    text = README.read_text(encoding="utf-8")
    assert len(text.splitlines()) <= 200
    install, tests = _first_block(text)
    assert "pip install" in install and ".venv/bin/rcsa " in install and "rcsa serve" not in install
    assert tests.endswith('.venv/bin/python -m pytest -m "not benchmark"')  # CI's set: all but the benchmark tier
    # the server runs in a second terminal: a block of its own holding nothing else
    serve_blocks = [b for b in re.findall(r"```bash\n(.*?)```", text, re.S) if "rcsa serve" in b]
    assert serve_blocks and all(b.strip() == ".venv/bin/rcsa serve" for b in serve_blocks), serve_blocks
    assert re.search(r"second terminal", text)
    assert re.search(r"^curl .*http://127\.0\.0\.1:8000/v1/", text, re.M), "no curl against the service"
    pictures = re.findall(r"!\[[^\]]*\]\(([^)]+)\)", text)
    assert len(pictures) == 1 and (REPO / pictures[0]).is_file(), pictures
    linked = {(REPO / target).resolve() for target in re.findall(r"\]\(([^)#]+\.md)(?:#[^)]*)?\)", text)}
    unlinked = [p.name for p in manual_pages() if p.resolve() not in linked]
    assert not unlinked, f"README.md links no manual page {unlinked}"


def test_the_site_is_not_committed():
    site_dir = yaml.safe_load((REPO / "mkdocs.yml").read_text(encoding="utf-8")).get("site_dir", "site")
    ignored = subprocess.run(["git", "check-ignore", "-q", f"{site_dir}/index.html"], cwd=REPO)
    assert ignored.returncode == 0, f"{site_dir}/ is not git-ignored"

