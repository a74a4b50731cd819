"""Every document the code, the tests and the README cite is in this repository, down to the section.

A citation is a ``*.md`` name; after it may come section numbers (``docs/physics.md`` §2.1,
§1.4–1.5, §2 and §5.1) or a quoted section name (``docs/contract.md`` "Measured spindles").
The file must exist (a path from the repository root, or a bare name found in the
repository), every cited number must be a numbered heading of it (``## 2.``, ``### 2.1``), and
a quoted name must be in one of its headings.
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from tests.helpers import REPO

SCANNED = [REPO / "README.md", *(p for root in ("src", "service", "tests", "benchmarks", "examples", "docs")
                                 for p in sorted((REPO / root).rglob("*"))
                                 if p.suffix in {".py", ".md", ".js", ".html"} and ".venv" not in p.parts
                                 and p != Path(__file__).resolve())]  # this file cites missing things on purpose
_FILE = re.compile(r"(?<![\w/.-])((?:[\w.-]+/)*[\w.-]+\.md)\b")
_NUMBERS = re.compile(r"[`'\s]*((?:§\s*\d+(?:\.\d+)?(?:\s*[–-]\s*\d+(?:\.\d+)?)?(?:\s*(?:,|and|/)\s*(?=§))?)+)")
_NAME = re.compile(r"[`'\s]*\"([^\"\n]{2,60})\"")
_HEADING = re.compile(r"^#+\s+(\d+(?:\.\d+)?)\.?\s", re.MULTILINE)


def _headings(path: Path) -> tuple[set[str], list[str]]:
    text = path.read_text(encoding="utf-8")
    return set(_HEADING.findall(text)), [h.lower() for h in re.findall(r"^#+\s+(.+)$", text, re.MULTILINE)]


def citations(text: str) -> list[tuple[str, list[str], str | None]]:
    """``(file, section numbers, quoted section name)`` of every citation in ``text``."""
    out = []
    for m in _FILE.finditer(text):
        rest = text[m.end():m.end() + 200]
        numbers = _NUMBERS.match(rest)
        name = _NAME.match(rest)
        out.append((m.group(1), re.findall(r"\d+(?:\.\d+)?", numbers.group(1)) if numbers else [],
                    name.group(1) if name else None))
    return out


def _resolve(cited: str, here: Path = REPO) -> Path | None:
    if "/" in cited:  # from the repository root, or from the citing file's folder
        path = next((p for p in (REPO / cited, here / cited) if p.is_file()), None)
        return path
    found = [p for p in REPO.rglob(cited) if ".venv" not in p.parts]
    return found[0] if found else None


def problems(text: str, here: Path = REPO) -> list[str]:
    """What in ``text`` (a file in the folder ``here``) cites something this repository does not have."""
    out = []
    for cited, numbers, name in citations(text):
        path = _resolve(cited, here)
        if path is None:
            out.append(f"{cited}: no such file in the repository")
            continue
        sections, headings = _headings(path)
        out += [f"{cited} §{n}: no such section" for n in numbers if n not in sections]
        if name is not None and cited.startswith("docs/") and not any(name.lower() in h for h in headings):
            out.append(f'{cited} "{name}": no such section')
    return out


@pytest.mark.parametrize("path", SCANNED, ids=lambda p: str(p.relative_to(REPO)))
def test_every_citation_resolves_inside_the_repository(path):
    found = problems(path.read_text(encoding="utf-8"), path.parent)
    assert not found, found


def test_the_project_documents_are_cited_and_cite_by_section():
    text = "\n".join(p.read_text(encoding="utf-8") for p in SCANNED)
    found = citations(text)
    by_file = {f for f, _, _ in found}
    assert {"docs/physics.md", "docs/contract.md", "docs/diagnosis.md", "docs/architecture.md"} <= by_file
    assert sum(1 for f, numbers, _ in found if f == "docs/physics.md" and numbers) >= 50
    assert sum(1 for f, _, name in found if f == "docs/contract.md" and name) >= 20


def test_the_checker_sees_what_does_not_exist():
    assert citations('see ``docs/physics.md`` §1.4–1.5, §6 O10') == [("docs/physics.md", ["1.4", "1.5", "6"], None)]
    assert citations('``docs/contract.md`` "Measured spindles"') == [("docs/contract.md", [], "Measured spindles")]
    assert problems("``docs/physics.md`` §2.1 and docs/contract.md \"Assembly\"") == []
    assert problems("``domain.md`` §2.1") == ["domain.md: no such file in the repository"]
    assert problems("``docs/physics.md`` §9.9") == ["docs/physics.md §9.9: no such section"]
    assert problems('``docs/contract.md`` "Teleportation"') == ['docs/contract.md "Teleportation": no such section']
