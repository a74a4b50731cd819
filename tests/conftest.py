"""Fixtures shared by the whole suite."""

from __future__ import annotations

import os

import numpy as np
import pytest
from hypothesis import HealthCheck, settings

settings.register_profile("ci", derandomize=True, max_examples=30, deadline=None,
                          suppress_health_check=[HealthCheck.too_slow])
settings.register_profile("dev", max_examples=30, deadline=None)
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "ci"))


def pytest_ignore_collect(collection_path, config: pytest.Config) -> bool | None:
    """Under tests/ only test modules are collected (``--doctest-modules`` would otherwise
    import the helpers and scripts beside them, e.g. the crash test's writer process)."""
    if collection_path.suffix == ".py" and not collection_path.name.startswith(("test_", "conftest", "__init__")):
        return True
    return None


@pytest.fixture
def rng() -> np.random.Generator:
    """A seeded generator: tests never use global randomness."""
    return np.random.default_rng(1234)


@pytest.fixture
def tmp_store_path(tmp_path, monkeypatch):
    """An empty store directory, also set as RCSA_STORE for code that uses the default."""
    path = tmp_path / "store"
    monkeypatch.setenv("RCSA_STORE", str(path))
    return path
