"""Who may read a job (``JobStore.get(..., access=)``) and the page of one's jobs (``JobStore.page``)."""

from __future__ import annotations

import pytest

from rcsa.errors import NotFoundError
from rcsa.infra.job_queue import JobStore


def test_a_job_exists_only_for_its_access_identity(tmp_path):
    jobs = JobStore(tmp_path / "jobs")
    mine = jobs.submit("batch", {"n": 1}, owner="anonymous@10.0.0.1", access="token:aa")
    legacy = jobs.submit("batch", {"n": 2}, owner="k-1")  # before jobs had an access identity
    assert jobs.get(mine.id, access="token:aa").id == mine.id
    assert jobs.get(mine.id).access == "token:aa"  # the runners and the operator see every job
    for other in ("token:bb", "key:k-1", ""):
        with pytest.raises(NotFoundError):
            jobs.get(mine.id, access=other)
        with pytest.raises(NotFoundError):
            jobs.request(mine.id, access=other)
    with pytest.raises(NotFoundError):
        jobs.get(legacy.id, access="key:k-1")  # no identity recorded: nobody's
    # a retried submission reuses an unfinished job of the same access only
    assert jobs.submit("batch", {"n": 1}, owner="anonymous@10.0.0.1", access="token:aa",
                       reuse_unfinished=True).id == mine.id
    assert jobs.submit("batch", {"n": 1}, owner="anonymous@10.0.0.1", access="token:cc",
                       reuse_unfinished=True).id != mine.id


def test_the_page_of_ones_jobs_is_newest_first_and_nobody_elses(tmp_path):
    jobs = JobStore(tmp_path / "jobs")
    ids = [jobs.submit("batch", {"n": i}, access="key:k-1").id for i in range(5)]
    jobs.submit("batch", {"other": True}, access="key:k-2")
    seen, cursor = [], None
    for _ in range(10):
        page, cursor = jobs.page("key:k-1", limit=2, cursor=cursor)
        seen += [j.id for j in page]
        if cursor is None:
            break
    assert seen == ids[::-1]
    assert jobs.page("key:k-3") == ([], None)
