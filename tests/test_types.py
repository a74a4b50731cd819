"""rcsa is statically typed: ``mypy --strict`` on every package of ``src/rcsa`` reports nothing.

The configuration lives in ``pyproject.toml`` ``[tool.mypy]`` (all of ``src/rcsa`` strict, the
pending modules below checked but their errors not yet reported); this runs the same check as a
plain ``mypy`` in the repository. Its cache lives in the temporary directory, one per checkout,
so reruns take a few seconds.
"""

from __future__ import annotations

import hashlib
import importlib.util
import pkgutil
import subprocess
import sys
import tempfile
import tomllib
from pathlib import Path

import pytest

import rcsa
from tests.helpers import REPO

#: Not yet at 0 errors: being reworked on the lobes branch, which brings them to strict (then
#: this tuple and the pyproject override go).
PENDING = ("rcsa.analysis.lobes.*", "rcsa.libraries.recommend")  # lobes branch


def _mypy_config() -> dict:
    return tomllib.loads((REPO / "pyproject.toml").read_text(encoding="utf-8"))["tool"]["mypy"]


def test_every_package_of_src_is_checked_strict():
    config = _mypy_config()
    assert config["files"] == ["src/rcsa"]
    strict = {m for o in config.get("overrides", []) if o.get("strict") for m in o["module"]}
    assert {"rcsa", "rcsa.*"} <= strict
    relaxed = [o for o in config.get("overrides", []) if any(str(m).startswith("rcsa") for m in o["module"])
               and not o.get("strict")]
    # the one relaxation is the pending list, nothing more (no flag of strict turned off anywhere)
    assert [sorted(o["module"]) for o in relaxed] == [sorted(PENDING)]
    assert set(relaxed[0]) == {"module", "ignore_errors"}


def test_the_pending_modules_exist():
    """A pending entry that no longer names a module would silently exempt nothing (or a new file)."""
    names = {m.name for m in pkgutil.walk_packages(rcsa.__path__, "rcsa.")}
    for pattern in PENDING:
        prefix = pattern.removesuffix(".*")
        assert prefix in names, pattern


@pytest.mark.slow
@pytest.mark.skipif(importlib.util.find_spec("mypy") is None,
                    reason="mypy is not installed (it comes with the test extra: pip install -e '.[test]')")
def test_src_passes_mypy_strict():
    cache = Path(tempfile.gettempdir()) / f"rcsa-mypy-{hashlib.sha256(str(REPO).encode()).hexdigest()[:12]}"
    out = subprocess.run([sys.executable, "-m", "mypy", "--cache-dir", str(cache), "--no-error-summary",
                          "--config-file", str(REPO / "pyproject.toml")],
                         cwd=REPO, capture_output=True, text=True, check=False)
    assert out.returncode == 0, out.stdout + out.stderr
