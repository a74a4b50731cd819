"""The library stays free of web concerns; the service depends on the library, never the reverse."""

from __future__ import annotations

import subprocess
import sys

from tests.helpers import REPO


def test_importing_rcsa_pulls_in_no_web_framework():
    code = ("import sys, rcsa, rcsa.api, rcsa.store, rcsa.cli; "
            "bad = [m for m in ('fastapi', 'pydantic', 'starlette', 'service') if m in sys.modules]; "
            "print(','.join(bad))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True, cwd=REPO)
    assert out.stdout.strip() == ""


def test_library_sources_never_import_the_service():
    for path in (REPO / "src" / "rcsa").rglob("*.py"):
        text = path.read_text(encoding="utf-8")
        for banned in ("import fastapi", "from fastapi", "import pydantic", "from pydantic", "from service", "import service"):
            assert banned not in text, f"{path.relative_to(REPO)} contains {banned!r}"
