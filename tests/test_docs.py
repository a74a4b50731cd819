"""Documentation stays true: every public name has a docstring, and the doctests run.

The ``Examples`` sections themselves run as pytest items (``--doctest-modules`` over
``src/rcsa``, configured in pyproject.toml; the root ``conftest.py`` pins numpy's print
style for them). The numpydoc sections are checked by ``tests/test_docstrings.py``.
"""

from __future__ import annotations

import importlib
import inspect
import pkgutil
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
