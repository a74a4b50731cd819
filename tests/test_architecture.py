"""The architecture holds: layers point down, no cycles, one application layer, no web in the library.

The contracts live in ``pyproject.toml`` (``[tool.importlinter]``) and are drawn in
``docs/architecture.md``; ``lint-imports`` checks them on the real import graph.
"""

from __future__ import annotations

import ast
import re
import shutil
import subprocess
import sys
import tomllib
from pathlib import Path

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


def _public_names(module: str) -> tuple[list[str], set[str], set[str]]:
    """``__all__`` of a module of ``src/``, the names it defines and the names it imports."""
    path = REPO / "src" / Path(*module.split("."))
    path = path / "__init__.py" if path.is_dir() else path.with_suffix(".py")
    tree = ast.parse(path.read_text(encoding="utf-8"))
    public: list[str] = []
    defined: set[str] = set()
    imported: set[str] = set()
    for node in tree.body:
        if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef | ast.ClassDef):
            defined.add(node.name)
        elif isinstance(node, ast.Assign | ast.AnnAssign):
            targets = node.targets if isinstance(node, ast.Assign) else [node.target]
            for target in targets:
                if isinstance(target, ast.Name):
                    defined.add(target.id)
                    if target.id == "__all__" and node.value is not None:
                        public = [e.value for e in ast.walk(node.value)
                                  if isinstance(e, ast.Constant) and isinstance(e.value, str)]
        elif isinstance(node, ast.ImportFrom | ast.Import):
            imported.update((a.asname or a.name).split(".")[0] for a in node.names)
    return public, defined, imported


def _app_modules() -> list[str]:
    root = REPO / "src" / "rcsa" / "app"
    return sorted("rcsa.app" + ("" if p.stem == "__init__" else "." + p.stem) for p in root.glob("*.py"))


@pytest.mark.parametrize("module", _app_modules())
def test_no_module_of_the_application_layer_re_exports(module):
    # the doors reach the domain through operations of rcsa.app, not through names it passes on
    # (rcsa.infra they import directly: pyproject's service-through-app / cli-through-app)
    public, defined, imported = _public_names(module)
    # constants (FORMATS, OPTION_FIELDS, the bounds table) are vocabulary the doors validate
    # against and may be published here; functions and classes may not be passed on
    passed_on = [name for name in public if name in imported and name not in defined and not name.isupper()]
    assert not passed_on, f"{module} re-exports {passed_on}: offer an operation, or let the caller import it"
    if module != "rcsa.app":
        assert [n for n in public if n in defined], f"{module} defines nothing of its own"


def test_the_re_export_check_sees_a_pass_through_module(tmp_path, monkeypatch):
    # the check above must be able to fail: a module that only passes names on is caught
    fake = tmp_path / "src" / "rcsa" / "app"
    fake.mkdir(parents=True)
    (fake / "relay.py").write_text('from rcsa.infra.sqlite import connect\n\n__all__ = ["connect"]\n')
    monkeypatch.setattr(sys.modules[__name__], "REPO", tmp_path)
    public, defined, imported = _public_names("rcsa.app.relay")
    assert public == ["connect"] and "connect" in imported and "connect" not in defined


def test_architecture_md_lists_exactly_the_contracts_of_pyproject():
    contracts = tomllib.loads((REPO / "pyproject.toml").read_text(encoding="utf-8"))["tool"]["importlinter"]["contracts"]
    ids = [c["id"] for c in contracts]
    text = (REPO / "docs" / "architecture.md").read_text(encoding="utf-8")
    table = re.findall(r"^\| `([a-z-]+)` \|", text, flags=re.MULTILINE)
    assert table == ids, f"docs/architecture.md's contract table {table} != pyproject.toml's {ids}"
    words = {6: "six", 7: "seven", 8: "eight", 9: "nine", 10: "ten"}
    assert f"holds {words.get(len(ids), len(ids))} contracts" in text
