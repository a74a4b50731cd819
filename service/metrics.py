"""Prometheus metrics of the service (``GET /metrics``).

Each app has its own registry (so several apps can live in one process, as in the tests).
With ``PROMETHEUS_MULTIPROC_DIR`` set (it must be set, to an empty directory, before the
worker processes start; ``uvicorn --workers N``), every process writes its values there and
``/metrics`` aggregates all processes with :class:`prometheus_client.multiprocess.MultiProcessCollector`.
"""

from __future__ import annotations

import os
import time
from collections.abc import Iterator
from contextlib import contextmanager

from prometheus_client import (
    CONTENT_TYPE_LATEST,
    CollectorRegistry,
    Counter,
    Histogram,
    generate_latest,
)

__all__ = ["CONTENT_TYPE_LATEST", "Metrics"]

_LATENCY_BUCKETS_S = (0.005, 0.01, 0.02, 0.03, 0.05, 0.075, 0.1, 0.25, 0.5, 1.0, 2.5, 5.0, 10.0, 30.0, 60.0)


class Metrics:
    """The service's counters and histograms."""

    def __init__(self) -> None:
        self.registry = CollectorRegistry(auto_describe=True)
        r = self.registry
        self.requests = Counter("rcsa_http_requests_total", "HTTP requests by route template and status.",
                                ("method", "route", "status"), registry=r)
        self.latency = Histogram("rcsa_http_request_duration_seconds", "Request latency by route template, s.",
                                 ("method", "route"), buckets=_LATENCY_BUCKETS_S, registry=r)
        self.frfs = Counter("rcsa_frfs_computed_total", "Tool-point FRFs computed, by operation.",
                            ("operation",), registry=r)
        self.compute = Histogram("rcsa_compute_seconds", "Time spent in rcsa computations, s.", ("operation",),
                                 buckets=_LATENCY_BUCKETS_S, registry=r)
        self.imports = Counter("rcsa_measurement_imports_total", "Measurements imported, by format.",
                               ("format",), registry=r)
        self.import_failures = Counter("rcsa_measurement_import_failures_total",
                                       "Measurement imports refused, by format.", ("format",), registry=r)
        self.jobs = Counter("rcsa_jobs_finished_total", "Jobs finished, by kind and status.",
                            ("kind", "status"), registry=r)

    @contextmanager
    def timed(self, operation: str) -> Iterator[None]:
        """Time a computation into ``rcsa_compute_seconds``."""
        t0 = time.perf_counter()
        try:
            yield
        finally:
            self.compute.labels(operation).observe(time.perf_counter() - t0)

    def computed(self, operation: str, n: int) -> None:
        """Count ``n`` tool-point FRFs computed by ``operation`` into ``rcsa_frfs_computed_total``."""
        self.frfs.labels(operation).inc(n)

    def exposition(self) -> bytes:
        """The Prometheus text of this process, or of all processes in multi-process mode."""
        if os.environ.get("PROMETHEUS_MULTIPROC_DIR"):
            # needed in multi-process mode only
            from prometheus_client import multiprocess

            registry = CollectorRegistry()
            multiprocess.MultiProcessCollector(registry)
            return generate_latest(registry)
        return generate_latest(self.registry)
