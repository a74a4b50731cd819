"""Documentation stays true: every public name has a docstring, and the doctests run.

The ``Examples`` sections themselves run as pytest items (``--doctest-modules`` over
``src/rcsa``, configured in pyproject.toml; the root ``conftest.py`` pins numpy's print
style for them). The numpydoc sections are checked by ``tests/test_docstrings.py``.
"""

from __future__ import annotations

import importlib
import inspect
import pkgutil
import re
import tomllib

import pytest

import rcsa
from tests.helpers import REPO

MODULES = ["rcsa", *sorted(m.name for m in pkgutil.walk_packages(rcsa.__path__, "rcsa."))]


@pytest.mark.parametrize("name", MODULES)
def test_public_names_have_docstrings(name):
    module = importlib.import_module(name)
    assert inspect.getdoc(module), f"module {name} has no docstring"
    for attr in getattr(module, "__all__", []):
        obj = getattr(module, attr)
        if inspect.isfunction(obj) or inspect.isclass(obj):
            assert inspect.getdoc(obj), f"{name}.{attr} has no docstring"


def test_the_suite_runs_the_doctests_of_the_library():
    """The Examples sections are collected by the suite's own configuration, not by chance."""
    config = tomllib.loads((REPO / "pyproject.toml").read_text())["tool"]["pytest"]["ini_options"]
    assert "--doctest-modules" in config["addopts"].split()
    assert "src/rcsa" in config["testpaths"]
    assert {"ELLIPSIS", "NORMALIZE_WHITESPACE", "NUMBER"} <= set(config["doctest_optionflags"])


def _resolve(dotted: str) -> object:
    """Import the longest importable prefix of ``dotted``, then follow attributes."""
    parts = dotted.split(".")
    for i in range(len(parts), 0, -1):
        try:
            obj = importlib.import_module(".".join(parts[:i]))
        except ModuleNotFoundError:
            continue
        for attr in parts[i:]:
            obj = getattr(obj, attr)
        return obj
    raise ModuleNotFoundError(dotted)


def test_the_architecture_document_names_only_what_exists():
    """docs/architecture.md stays true through renames: every module path and dotted name it
    quotes (``rcsa/measured/hybrid.py``, ``rcsa.model.contract.parse_assembly``) exists."""
    text = (REPO / "docs" / "architecture.md").read_text()
    quoted = set(re.findall(r"`([^`\s]+)`", text))
    paths = {q for q in quoted if re.fullmatch(r"(rcsa|service)/[\w/]*(\.py)?", q)}
    names = {q for q in quoted if re.fullmatch(r"rcsa(\.\w+)+", q)}
    assert len(paths) >= 10 and len(names) >= 10, (paths, names)
    missing = [p for p in sorted(paths) if not ((REPO / "src" / p).exists() or (REPO / p).exists())]
    unresolved = []
    for name in sorted(names):
        try:
            _resolve(name)
        except (ImportError, AttributeError):
            unresolved.append(name)
    assert not missing and not unresolved, f"no such path: {missing}; no such name: {unresolved}"
