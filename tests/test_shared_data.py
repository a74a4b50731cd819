"""``RCSA_SHARED_DATA`` acts: the suite keeps it while it clears every other ``RCSA_*`` setting.

The shared research data (the third-party tap tests, never copied into the repository) is
found beside the repository or where ``RCSA_SHARED_DATA`` says (``tests/helpers.py``).
"""

from __future__ import annotations

import os
import subprocess
import sys
from types import SimpleNamespace

import pytest

from tests import conftest
from tests.helpers import REPO


def _shared_data_seen_with(env: dict[str, str]) -> str:
    code = "from tests.helpers import SHARED_DATA; print(SHARED_DATA)"
    out = subprocess.run([sys.executable, "-c", code], cwd=REPO, capture_output=True, text=True, check=True,
                         env={k: v for k, v in {**os.environ, **env}.items() if v is not None})
    return out.stdout.strip()


def test_the_helpers_read_rcsa_shared_data_and_fall_back_to_the_sibling_directory(tmp_path):
    assert _shared_data_seen_with({"RCSA_SHARED_DATA": str(tmp_path)}) == str(tmp_path)
    assert _shared_data_seen_with({"RCSA_SHARED_DATA": ""}) == str(REPO.parent / "shared" / "data")


def test_the_suite_keeps_rcsa_shared_data_and_clears_the_settings_of_rcsa(monkeypatch, tmp_path):
    monkeypatch.setenv("RCSA_SHARED_DATA", str(tmp_path))
    monkeypatch.setenv("RCSA_STORE", str(tmp_path / "someone's store"))
    monkeypatch.setenv("RCSA_API_KEYS", "secret:write")
    config = SimpleNamespace(stash=pytest.Stash(), option=SimpleNamespace(numprocesses=None))
    before = os.environ.get("XDG_DATA_HOME")
    conftest.pytest_configure(config)
    try:
        assert os.environ["RCSA_SHARED_DATA"] == str(tmp_path)
        assert "RCSA_STORE" not in os.environ and "RCSA_API_KEYS" not in os.environ
        assert os.environ["XDG_DATA_HOME"] != before
    finally:
        conftest.pytest_unconfigure(config)
    assert os.environ["RCSA_STORE"] == str(tmp_path / "someone's store")  # given back afterwards
    assert os.environ.get("XDG_DATA_HOME") == before
