"""The architecture holds: layers point down, no cycles, one application layer, no web in the library.

The contracts live in ``pyproject.toml`` (``[tool.importlinter]``) and are drawn in
``docs/architecture.md``; ``lint-imports`` checks them on the real import graph.
"""

from __future__ import annotations

import shutil
import subprocess
import sys

import pytest

from tests.helpers import REPO


def test_import_linter_contracts_are_kept():
    lint = shutil.which("lint-imports", path=str(REPO / ".venv" / "bin")) or shutil.which("lint-imports")
    if lint is None:
        pytest.skip("import-linter is not installed (it comes with the test extra: pip install -e '.[test]')")
    out = subprocess.run([lint, "--no-cache"], cwd=REPO, capture_output=True, text=True, check=False)
    assert out.returncode == 0, out.stdout + out.stderr
    assert "0 broken" in out.stdout


def test_importing_rcsa_pulls_in_no_web_framework():
    code = ("import sys, rcsa, rcsa.app.predictions, rcsa.measured.store, rcsa.cli; "
            "bad = [m for m in ('fastapi', 'pydantic', 'starlette', 'service') if m in sys.modules]; "
            "print(','.join(bad))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True, cwd=REPO)
    assert out.stdout.strip() == ""


def test_the_top_level_holds_packages_and_a_handful_of_modules():
    top = REPO / "src" / "rcsa"
    modules = sorted(p.name for p in top.glob("*.py"))
    packages = sorted(p.name for p in top.iterdir() if (p / "__init__.py").exists())
    assert modules == ["__init__.py", "_version.py", "errors.py", "reference.py"], modules
    assert packages == ["analysis", "app", "cli", "infra", "libraries", "measured", "model", "physics"], packages
