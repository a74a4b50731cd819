"""Service settings, from ``RCSA_*`` environment variables (pydantic-settings).

Every setting has a default that works on a fresh machine; the store is ``RCSA_STORE`` or
the per-user default (:func:`rcsa.measured.store.default_store_path`), created on first use.
"""

from __future__ import annotations

from pathlib import Path

from pydantic import Field, SecretStr
from pydantic_settings import BaseSettings, SettingsConfigDict

from rcsa.app.bounds import MAX_BATCH_COMBINATIONS

__all__ = ["Settings"]

MIB = 1024 * 1024


class Settings(BaseSettings):
    """Configuration of one service instance (all processes of a deployment share it)."""

    model_config = SettingsConfigDict(env_prefix="RCSA_", extra="ignore", env_ignore_empty=True,
                                      frozen=True)

    store: Path | None = Field(None, description="Store directory (env RCSA_STORE); default: the "
                                                 "per-user store ~/.local/share/rcsa/store.")
    api_keys: SecretStr = Field(SecretStr(""), description='Keys accepted besides the key file: '
                                '"SECRET:write,SECRET:read" or "sha256:HEX:read" entries (env RCSA_API_KEYS).')
    anonymous_read: bool = Field(True, description="Allow reads and computations without a key.")
    max_body_bytes: int = Field(64 * MIB, ge=1024, description="Largest request body, bytes (413 above).")
    max_upload_bytes: int = Field(64 * MIB, ge=1024, description="Largest uploaded file, bytes (413 above).")
    max_frequency_lines: int = Field(20_000, ge=1, description="Most frequency lines per request.")
    max_batch_combinations: int = Field(MAX_BATCH_COMBINATIONS, ge=1, le=MAX_BATCH_COMBINATIONS,
                                        description="Most combinations per batch request (at most "
                                                    f"{MAX_BATCH_COMBINATIONS}, the schema's bound).")
    async_batch_threshold: int = Field(50, ge=0, description="Batches and libraries with more "
                                       "combinations than this run as jobs (202 Accepted).")
    sync_time_limit_s: float = Field(120.0, ge=0, description="An answer given at once (a POST that computes "
                                     "without storing anything) stops at this many seconds with a 503 problem; send "
                                     "Prefer: respond-async for longer work (0: no limit).")
    job_workers: int = Field(1, ge=0, le=8, description="Job runner threads per process (0: this "
                             "process runs no jobs, another one must).")
    job_poll_s: float = Field(1.0, gt=0, description="How often an idle job runner looks for work, s.")
    job_heartbeat_s: float = Field(2.0, gt=0, description="Heartbeat period of a running job, s.")
    job_stale_s: float = Field(60.0, gt=0, description="A running job without heartbeat for this long "
                               "is resumed by another runner, s.")
    job_max_attempts: int = Field(3, ge=1, description="Interrupted runs after which a job fails.")
    job_retention_s: float = Field(7 * 86400.0, gt=0, description="Finished jobs older than this are "
                                   "purged at startup, s.")
    job_time_limit_s: float = Field(3600.0, gt=0, description="A job running longer than this is failed "
                                    "(\"Job time limit exceeded\"), s.")
    job_results_max_bytes: int = Field(20 * 1024**3, ge=0, description="Disk budget of the kept job results: "
                                       "beyond it the oldest results are deleted (their jobs say when), bytes; "
                                       "0: no budget.")
    job_max_unfinished_per_caller: int = Field(10, ge=1, description="Queued or running jobs one caller (API key, "
                                               "or anonymous client address) may have; more answer 429.")
    job_max_running_per_caller: int = Field(1, ge=0, description="Jobs of one caller running at once, all "
                                            "anonymous callers counting as one (0: no cap; queued jobs are claimed "
                                            "round-robin across callers either way).")
    dask_scheduler: str | None = Field(None, description="Dask scheduler address (tcp://host:8786): jobs compute "
                                       "on that cluster (pip install 'rcsa[dask]'); unset, in this process.")
    dask_connect_timeout_s: float = Field(10.0, gt=0, description="How long to try to reach the Dask scheduler "
                                          "at start-up (and when reconnecting), s.")
    dask_retries: int = Field(3, ge=0, description="Retries of a chunk that fails on a Dask worker.")
    retry_after_s: int = Field(1, ge=1, description="Retry-After sent with 202 and job status, s.")
    seed_demo: bool = Field(True, description="Seed an empty store once with the demo-ra1 measurement.")
    measurement_cache: int = Field(32, ge=0, description="Measurements kept in memory per process.")
    gzip_min_bytes: int = Field(4096, ge=0, description="Smallest response body gzip-compressed, bytes.")
    gzip_level: int = Field(1, ge=1, le=9, description="gzip level (1 is fastest; numeric JSON gains "
                            "little from higher levels).")
    access_log: bool = Field(True, description="One log line per request, with its request id.")
    header_timeout_s: float = Field(10.0, gt=0, description="A connection must send the whole head of a request "
                                    "(request line and headers) within this many seconds of its first byte (or of "
                                    "being opened), or it is closed, s (slow-header clients; rcsa serve and the "
                                    "image use the service's HTTP protocol, service.http).")
    body_timeout_s: float = Field(10.0, gt=0, description="Longest pause while a request body arrives, and the "
                                  "grace before body_min_rate_bytes_s counts; a body that stalls or trickles is "
                                  "answered 408 and the connection closed, s.")
    body_min_rate_bytes_s: float = Field(4096.0, gt=0, description="Average rate a request body must keep "
                                         "arriving at after the first body_timeout_s, bytes/s.")
