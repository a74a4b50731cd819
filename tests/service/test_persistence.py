"""Persistence plumbing shared by the stores: one SQLite setup, one clock, one answer-or-queue path."""

from __future__ import annotations

import re
import sqlite3
from contextlib import closing

import pytest
from service.idempotency import IdempotencyStore

from rcsa.app.jobs import JOB_KINDS, Work, Workbench, answer_or_queue, job_handlers, job_store
from rcsa.app.stores import library_store, open_store
from rcsa.infra.api_keys import KeyFile
from rcsa.infra.clock import utc_iso
from rcsa.infra.sqlite import connect as connect_sqlite
from rcsa.infra.sqlite import transaction
from rcsa.measured.store.catalogue import Catalogue

MICROSECONDS = re.compile(r"^\d{4}-\d\d-\d\dT\d\d:\d\d:\d\d\.\d{6}Z$")
SECONDS = re.compile(r"^\d{4}-\d\d-\d\dT\d\d:\d\d:\d\dZ$")
FULL, NORMAL = 2, 1  # PRAGMA synchronous


def _synchronous(con: sqlite3.Connection) -> int:
    with closing(con):
        assert con.execute("PRAGMA journal_mode").fetchone()[0] == "wal"
        return con.execute("PRAGMA synchronous").fetchone()[0]


def test_each_database_syncs_as_its_data_needs(tmp_path):
    store = open_store(tmp_path / "store")
    assert _synchronous(job_store(store.path)._connect()) == FULL  # acknowledged jobs
    assert _synchronous(library_store(store.path)._connect()) == FULL  # reported revisions
    assert _synchronous(IdempotencyStore(tmp_path / "idem", retention_s=60)._connect()) == FULL  # kept answers
    assert _synchronous(Catalogue(tmp_path / "index.sqlite")._connect()) == NORMAL  # a rebuildable cache


def test_a_transaction_commits_or_rolls_back_as_a_whole(tmp_path):
    db = tmp_path / "t.sqlite"
    with closing(connect_sqlite(db, synchronous="NORMAL", schema="CREATE TABLE IF NOT EXISTS t (x INTEGER)")) as con:
        with transaction(con):
            con.execute("INSERT INTO t VALUES (1)")
        with pytest.raises(RuntimeError), transaction(con):
            con.execute("INSERT INTO t VALUES (2)")
            raise RuntimeError("half-way")
        assert not con.in_transaction
        assert [r[0] for r in con.execute("SELECT x FROM t")] == [1]
    with pytest.raises(ValueError, match="synchronous"):
        connect_sqlite(db, synchronous="OFF")  # type: ignore[arg-type]


def test_timestamps_keep_each_store_s_format(tmp_path):
    jobs = job_store(tmp_path)
    job = jobs.submit("batch", {"x": 1})
    assert MICROSECONDS.match(job.created_utc)  # compared as strings when purging: fixed width
    record, _ = KeyFile.in_store(tmp_path).create("read", "test")
    assert SECONDS.match(record.created_utc)
    assert utc_iso(1.5) == "1970-01-01T00:00:01.500000Z" and utc_iso(1.5, timespec="seconds") == "1970-01-01T00:00:01Z"


def test_a_retried_submission_reuses_the_unfinished_job_only(tmp_path):
    jobs = job_store(tmp_path / "a")
    first = jobs.submit("batch", {"b": 1, "a": [1, 2]})
    assert jobs.submit("batch", {"a": [1, 2], "b": 1}, reuse_unfinished=True).id == first.id  # same canonical request
    assert jobs.submit("batch", {"a": [1, 2], "b": 1}).id != first.id  # not asked to reuse
    assert jobs.submit("library", {"a": [1, 2], "b": 1}, reuse_unfinished=True).id != first.id  # another kind

    done = job_store(tmp_path / "b")
    job = done.submit("batch", {"a": 1})
    assert done.claim("runner").id == job.id
    done.succeed(job.id, "runner", b"{}")
    assert done.submit("batch", {"a": 1}, reuse_unfinished=True).id != job.id  # a finished job is not reused


def test_one_decision_and_one_handler_for_every_kind(tmp_path):
    jobs = job_store(tmp_path)
    bench = Workbench(None, tmp_path)
    assert set(job_handlers(bench)) == set(JOB_KINDS) == {"batch", "library", "library-sync"}
    big = Work("batch", {"entries": [], "batch": {}}, size=51)
    assert answer_or_queue(bench, jobs, big, respond_async=False, async_threshold=50).status == "queued"
    asked = Work("library-sync", {"x": 1}, size=0)
    assert asked.should_queue(respond_async=True, async_threshold=50)
    empty_library = Work("library", {"x": 1}, size=0)  # nothing to wait for: answered at once
    assert not empty_library.should_queue(respond_async=True, async_threshold=50)
    checked = []
    guarded = Work("batch", {"y": 1}, size=1, check=lambda: checked.append(True))
    answer_or_queue(bench, jobs, guarded, respond_async=True, async_threshold=50)
    assert checked == [True]  # a queued request is checked before it is queued
