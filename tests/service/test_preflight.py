"""The start-up tried once before the workers (``python -m service.preflight``, run by ``rcsa serve``).

A service that cannot start must say so and stop with a non-zero status: uvicorn with several
workers exits 0 when its workers fail at start-up, so a container would look like it ended well.
"""

from __future__ import annotations

import socket
import stat
import subprocess
import sys

import pytest
from service.preflight import StartupError, check

from .conftest import settings_for


def test_a_service_that_can_start_passes(tmp_path):
    check(settings_for(tmp_path / "store"))
    assert (tmp_path / "store").is_dir()


def test_a_bad_setting_is_named(tmp_path, monkeypatch):
    monkeypatch.setenv("RCSA_STORE", str(tmp_path / "store"))
    monkeypatch.setenv("RCSA_MAX_BODY_BYTES", "abc")
    monkeypatch.setenv("RCSA_JOB_WORKERS", "99")
    with pytest.raises(StartupError) as err:
        check()
    assert "RCSA_MAX_BODY_BYTES" in str(err.value) and "RCSA_JOB_WORKERS" in str(err.value)


def test_a_store_that_is_a_file_or_not_writable_stops_the_start(tmp_path):
    (tmp_path / "file").write_text("not a directory")
    with pytest.raises(StartupError, match="store"):
        check(settings_for(tmp_path / "file"))
    locked = tmp_path / "locked"
    locked.mkdir()
    locked.chmod(stat.S_IRUSR | stat.S_IXUSR)
    try:
        if not _can_write(locked):  # root writes anywhere: nothing to test then
            with pytest.raises(StartupError, match="start-up failed"):
                check(settings_for(locked / "store"))
    finally:
        locked.chmod(stat.S_IRWXU)


def _can_write(directory) -> bool:
    try:
        (directory / "probe").write_text("x")
    except OSError:
        return False
    (directory / "probe").unlink()
    return True


def test_an_unreachable_dask_scheduler_stops_the_start(tmp_path):
    pytest.importorskip("distributed")
    with socket.socket() as s:  # bound, never listening: connections are refused
        s.bind(("127.0.0.1", 0))
        address = f"tcp://127.0.0.1:{s.getsockname()[1]}"
        with pytest.raises(StartupError, match=f"cannot reach the Dask scheduler at {address}"):
            check(settings_for(tmp_path / "store", dask_scheduler=address, dask_connect_timeout_s=1))


def test_the_module_exits_1_with_the_reason(tmp_path):
    (tmp_path / "file").write_text("")
    out = subprocess.run([sys.executable, "-m", "service.preflight"], capture_output=True, text=True,
                         env={"RCSA_STORE": str(tmp_path / "file"), "PATH": "/usr/bin:/bin"}, timeout=300)
    assert out.returncode == 1 and "the service cannot start" in out.stderr and str(tmp_path / "file") in out.stderr
