"""No module imports another module's private names.

A leading underscore says "this module's business": importing such a name from elsewhere
couples two modules through a detail neither promised. Such a name is made public (and
documented) or the code is restructured. Checked on the source with :mod:`ast`:
``from X import _name`` (absolute or relative) where X is an ``rcsa`` or ``service``
module. Dunder names (``__version__``) are public by convention.
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

from tests.helpers import REPO

ROOTS = (REPO / "src" / "rcsa", REPO / "service")
OWN_PACKAGES = ("rcsa", "service")


def _module_name(path: Path, repo: Path) -> tuple[str, bool]:
    """Dotted name of a source file, and whether it is a package's ``__init__``."""
    rel = path.relative_to(repo / "src" if path.is_relative_to(repo / "src") else repo).with_suffix("")
    parts = rel.parts
    is_package = parts[-1] == "__init__"
    return ".".join(parts[:-1] if is_package else parts), is_package


def _imported_from(node: ast.ImportFrom, module: str, is_package: bool) -> str:
    """The absolute module a ``from ... import`` reads from."""
    if not node.level:
        return node.module or ""
    base = module.split(".") if is_package else module.split(".")[:-1]
    base = base[:len(base) - (node.level - 1)]
    return ".".join([*base, node.module] if node.module else base)


def _is_private(name: str) -> bool:
    return name.startswith("_") and not (name.startswith("__") and name.endswith("__"))


def private_imports(roots: tuple[Path, ...] = ROOTS, repo: Path = REPO) -> list[str]:
    """``path:line: from X import _name`` for every offending import under ``roots``."""
    found = []
    for root in roots:
        for path in sorted(root.rglob("*.py")):
            module, is_package = _module_name(path, repo)
            for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"), filename=str(path))):
                if not isinstance(node, ast.ImportFrom):
                    continue
                source = _imported_from(node, module, is_package)
                if source.split(".")[0] not in OWN_PACKAGES or source == module:
                    continue
                for alias in node.names:
                    if _is_private(alias.name):
                        found.append(f"{path.relative_to(repo)}:{node.lineno}: from {source} import {alias.name}")
    return found


def test_no_module_imports_another_modules_private_names():
    offences = private_imports()
    assert not offences, "private names imported across modules:\n" + "\n".join(offences)


@pytest.mark.parametrize(("source", "expected"), [
    ("from rcsa.physics.segments import _Waves", ["_Waves"]),
    ("from .segments import _blocks, dynamic_stiffness", ["_blocks"]),
    ("from rcsa._version import __version__", []),
    ("from numpy import _globals", []),
])
def test_the_check_sees_absolute_and_relative_imports(tmp_path, source, expected):
    package = tmp_path / "src" / "rcsa" / "physics"
    package.mkdir(parents=True)
    (package / "elimination.py").write_text(source + "\n", encoding="utf-8")
    found = private_imports((tmp_path / "src" / "rcsa",), tmp_path)
    assert [line.rsplit(" ", 1)[-1] for line in found] == expected
