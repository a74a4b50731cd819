"""Fixtures shared by the whole suite, and how the suite is spread over xdist workers."""

from __future__ import annotations

import os
import shutil
import signal
import sys
import tempfile

import numpy as np
import pytest
from hypothesis import HealthCheck, settings

settings.register_profile("ci", derandomize=True, max_examples=30, deadline=None,
                          suppress_health_check=[HealthCheck.too_slow])
settings.register_profile("dev", max_examples=30, deadline=None)
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "ci"))

#: ``RCSA_*`` variables the suite keeps: where the tests find data, not settings of rcsa.
SUITE_SETTINGS = frozenset({"RCSA_SHARED_DATA"})

_SAVED_ENV = pytest.StashKey[dict[str, str | None]]()
_PRIVATE_XDG = pytest.StashKey[str]()


def pytest_configure(config: pytest.Config) -> None:
    """The suite runs in an environment of its own, whoever starts it.

    ``RCSA_*`` variables of the caller's shell (a store, API keys, limits) are removed — all
    but ``RCSA_SHARED_DATA``, which says where the suite finds the shared research data and
    changes nothing of what rcsa does (``tests/helpers.py``) — and
    ``$XDG_DATA_HOME`` (where the default store lives when ``$RCSA_STORE`` is unset) points
    at a private directory of this process, i.e. of each xdist worker: a test that forgets
    ``tmp_store_path`` can neither write into the user's store nor share one with another
    worker. Tests of the default location set ``XDG_DATA_HOME``/``HOME`` with monkeypatch.
    """
    names = [k for k in os.environ if k.startswith("RCSA_") and k not in SUITE_SETTINGS] + ["XDG_DATA_HOME"]
    config.stash[_SAVED_ENV] = {k: os.environ.get(k) for k in names}
    for k in names:
        os.environ.pop(k, None)
    config.stash[_PRIVATE_XDG] = os.environ["XDG_DATA_HOME"] = tempfile.mkdtemp(prefix="rcsa-test-xdg-")
    if getattr(config.option, "numprocesses", None) and not hasattr(config, "workerinput"):
        # xdist's workers start after this and inherit it: one BLAS thread each, or the
        # workers' OpenBLAS threads fight over the cores (two processes running the FE
        # oracle tests: 216 s wall, 123 s CPU with two threads each; 43 s, 19 s with one)
        for name in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
            os.environ.setdefault(name, "1")


def pytest_unconfigure(config: pytest.Config) -> None:
    saved = config.stash.get(_SAVED_ENV, None)
    if saved is None:
        return
    shutil.rmtree(config.stash[_PRIVATE_XDG], ignore_errors=True)
    for k, v in saved.items():
        if v is None:
            os.environ.pop(k, None)
        else:
            os.environ[k] = v


def pytest_ignore_collect(collection_path, config: pytest.Config) -> bool | None:
    """Under tests/ only test modules are collected (``--doctest-modules`` would otherwise
    import the helpers and scripts beside them, e.g. the crash test's writer process)."""
    if collection_path.suffix == ".py" and not collection_path.name.startswith(("test_", "conftest", "__init__")):
        return True
    return None


@pytest.hookimpl(tryfirst=True)
def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    """Modules with ``slow`` tests run first (the order inside a module is kept).

    Under xdist (``--dist loadfile --no-loadscope-reorder``, pyproject.toml) a test module
    is one unit of work, so a module's shared fixtures (a server, a browser, a computed
    benchmark) are built once, on one worker; putting the slow modules first starts the
    diagnosis benchmark, the crash test and the schemathesis run at once on different
    workers instead of leaving one of them to end the run alone.
    """
    slow = {i.nodeid.split("::", 1)[0] for i in items if i.get_closest_marker("slow")}
    items.sort(key=lambda i: i.nodeid.split("::", 1)[0] not in slow)


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


def _sigpipe_ignored() -> bool:
    """Whether this process ignores SIGPIPE, read from the kernel (``/proc/self/status``), which
    also sees a disposition changed by C code behind the ``signal`` module's back."""
    try:
        with open("/proc/self/status", encoding="ascii") as status:
            for line in status:
                if line.startswith("SigIgn:"):
                    return bool(int(line.split()[1], 16) & (1 << (signal.SIGPIPE - 1)))
    except OSError:
        pass
    return signal.getsignal(signal.SIGPIPE) == signal.SIG_IGN


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_protocol(item: pytest.Item, nextitem: pytest.Item | None):
    """Every test starts with SIGPIPE ignored, as Python starts a process.

    A client socket written after the server closed it (the hostile and slow-client tests do
    that on purpose) raises ``BrokenPipeError`` only while SIGPIPE is ignored; with the default
    disposition the kernel kills the process without a traceback, which under xdist is a
    worker "node down: Not properly terminated" and a run that hangs. Whatever set it back to
    the default during an earlier test is named on stderr, and the disposition restored.
    """
    if hasattr(signal, "SIGPIPE") and not _sigpipe_ignored():
        print(f"conftest: SIGPIPE was not ignored before {item.nodeid}; restored", file=sys.stderr)
        signal.signal(signal.SIGPIPE, signal.SIG_IGN)
    yield
