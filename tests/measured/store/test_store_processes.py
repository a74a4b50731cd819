"""Several processes on one store: writers killed with SIGKILL at random moments, and
concurrent writers with a concurrent reader.

Each writer (``_writer.py``) logs ``put <id> <seed>`` only after ``put`` returned, so every
logged id must read back bit-exact, whatever happened afterwards.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import h5py
import numpy as np
import pytest

import rcsa
from rcsa.errors import NotFoundError
from rcsa.measured.store import MeasurementStore
from rcsa.measured.store.hdf5io import read_measurement_file

from ._factory import assert_same_data, make_measurement

WRITER = Path(__file__).with_name("_writer.py")
pytestmark = pytest.mark.skipif(os.name != "posix", reason="SIGKILL and flock semantics are POSIX")


def _env() -> dict[str, str]:
    src = str(Path(rcsa.__file__).resolve().parents[1])
    return {**os.environ, "PYTHONPATH": os.pathsep.join([src, os.environ.get("PYTHONPATH", "")])}


def _start(store: Path, log: Path, seed0: int, count: int, delete_every: int) -> subprocess.Popen:
    return subprocess.Popen(
        [
            sys.executable,
            str(WRITER),
            str(store),
            str(log),
            str(seed0),
            str(count),
            str(delete_every),
        ],
        env=_env(),
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
    )


def _read_logs(logs: list[Path]) -> tuple[dict[str, int], set[str], set[str]]:
    """``(put id -> seed, ids whose delete returned, ids whose delete may be in flight)``."""
    put, deleted, deleting = {}, set(), set()
    for log in logs:
        if not log.exists():
            continue
        for line in log.read_text().splitlines():
            parts = line.split()
            if parts[:1] == ["put"]:
                put[parts[1]] = int(parts[2])
            elif parts[:1] == ["deleting"]:
                deleting.add(parts[1])
            elif parts[:1] == ["del"]:
                deleted.add(parts[1])
    return put, deleted, deleting - deleted


def _wait_ready(log: Path, proc: subprocess.Popen, timeout_s: float = 300.0) -> None:
    end = time.monotonic() + timeout_s
    while time.monotonic() < end:
        if log.exists() and log.read_text().startswith("ready"):
            return
        if proc.poll() is not None:
            raise AssertionError(f"writer exited early: {proc.stderr.read().decode()}")
        time.sleep(0.01)
    raise AssertionError("writer did not start")


def _wait_puts(log: Path, proc: subprocess.Popen, count: int) -> None:
    """Until the writer has logged ``count`` committed puts (pytest-timeout guards a hang)."""
    while log.read_text().count("\nput ") < count:
        if proc.poll() is not None:
            raise AssertionError(f"writer exited early: {proc.stderr.read().decode()}")
        time.sleep(0.005)


@pytest.mark.slow
def test_writers_killed_at_random_moments_lose_nothing_committed(tmp_path):
    store_dir = tmp_path / "store"
    MeasurementStore(store_dir)
    rng = np.random.default_rng(20240611)
    logs: list[Path] = []
    stale_seen = 0
    rounds, writers = 10, 3
    for r in range(rounds):
        procs = []
        for w in range(writers):
            log = tmp_path / f"log-{r}-{w}.txt"
            logs.append(log)
            procs.append(
                (
                    _start(
                        store_dir,
                        log,
                        seed0=1_000_000 * r + 10_000 * w,
                        count=10_000,
                        delete_every=4,
                    ),
                    log,
                )
            )
        for p, log in procs:
            _wait_ready(log, p)
        # kill each writer at its own random moment: once it has committed a few measurements
        # (counted in its log, so a loaded machine only makes the round slower), then 0-130 ms on
        for p, log in procs:
            _wait_puts(log, p, int(rng.integers(2, 6)))
            time.sleep(rng.uniform(0.0, 0.4 / writers))
            p.send_signal(signal.SIGKILL)
        for p, _ in procs:
            p.wait(timeout=30)
            assert p.returncode == -signal.SIGKILL, p.stderr.read().decode()
            p.stderr.close()
        stale_seen += len(os.listdir(store_dir / "tmp"))  # evidence of kills in mid-write
        # between rounds the store stays fully usable by a fresh process
        assert MeasurementStore(store_dir).check() == []

    store = MeasurementStore(store_dir)
    put, deleted, in_flight = _read_logs(logs)
    assert len(put) > 50, "the writers should have committed many measurements"
    files = {p.stem for p in (store_dir / "measurements").glob("*.h5")}
    # every committed and not-deleted measurement reads back bit-exact
    for mid, seed in put.items():
        if mid in deleted:
            assert mid not in files
            with pytest.raises(NotFoundError):
                store.get(mid)
        elif mid in in_flight and mid not in files:
            continue  # killed inside delete(): gone or intact are both fine
        else:
            assert_same_data(store.get(mid), make_measurement(seed))
    # no file in the store fails to open, with h5py directly or through the store
    for path in (store_dir / "measurements").iterdir():
        with h5py.File(path, "r") as f:
            assert f.attrs["schema"] == "rcsa.measurement"
        read_measurement_file(path)
    assert store.check() == []
    listed = {i.id for i in store.list()}
    assert listed == files
    # committed-but-unlogged puts (killed between put() and the log line) may exist; nothing else
    assert set(put) - deleted - in_flight <= listed
    store.put(make_measurement(1))
    assert os.listdir(store_dir / "tmp") == []  # stale temporaries cleaned by the next writer
    unlogged = files - set(put)
    print(
        f"\ncrash test: {rounds * writers} writers killed, {len(put)} puts and {len(deleted)} deletes "
        f"committed, {len(in_flight)} deletes killed in flight, {len(unlogged)} puts committed but killed "
        f"before logging, {len(files)} files, {stale_seen} stale temporaries left by mid-write kills"
    )


@pytest.mark.slow
def test_concurrent_writers_and_a_reader_lose_nothing(tmp_path):
    store_dir = tmp_path / "store"
    store = MeasurementStore(store_dir)
    n = 40
    logs = [tmp_path / "a.txt", tmp_path / "b.txt"]
    procs = [
        _start(store_dir, log, seed0=100_000 * k, count=n, delete_every=0)
        for k, log in enumerate(logs)
    ]
    reads = 0
    while any(p.poll() is None for p in procs):
        for info in store.list():  # a reader never sees a half-written measurement
            assert store.get(info.id).id == info.id
            reads += 1
    for p in procs:
        assert p.returncode == 0, p.stderr.read().decode()
        p.stderr.close()
    put, _, _ = _read_logs(logs)
    assert len(put) == 2 * n
    assert {i.id for i in store.list()} == set(put)
    for mid, seed in put.items():
        assert_same_data(store.get(mid), make_measurement(seed))
    print(f"\nconcurrency test: {2 * n} puts from 2 processes, {reads} concurrent reads")
