"""The physics and the model are statically typed: ``mypy --strict`` on them reports nothing.

The configuration (which packages are strict, which are only followed) lives in
``pyproject.toml`` ``[tool.mypy]``; this runs the same check as a plain ``mypy`` in the
repository. Its cache lives in the temporary directory, one per checkout, so reruns take
a couple of seconds.
"""

from __future__ import annotations

import hashlib
import importlib.util
import subprocess
import sys
import tempfile
import tomllib
from pathlib import Path

import pytest

from tests.helpers import REPO

STRICT_PACKAGES = ("rcsa.physics.*", "rcsa.model.*")


def test_physics_and_model_are_configured_strict():
    config = tomllib.loads((REPO / "pyproject.toml").read_text(encoding="utf-8"))["tool"]["mypy"]
    strict = {m for o in config.get("overrides", []) if o.get("strict") for m in o["module"]}
    assert set(STRICT_PACKAGES) <= strict
    assert {"src/rcsa/physics", "src/rcsa/model"} <= set(config["files"])


@pytest.mark.slow
@pytest.mark.skipif(importlib.util.find_spec("mypy") is None,
                    reason="mypy is not installed (it comes with the test extra: pip install -e '.[test]')")
def test_physics_and_model_pass_mypy_strict():
    cache = Path(tempfile.gettempdir()) / f"rcsa-mypy-{hashlib.sha256(str(REPO).encode()).hexdigest()[:12]}"
    out = subprocess.run([sys.executable, "-m", "mypy", "--cache-dir", str(cache), "--no-error-summary",
                          "--config-file", str(REPO / "pyproject.toml")],
                         cwd=REPO, capture_output=True, text=True, check=False)
    assert out.returncode == 0, out.stdout + out.stderr
