"""A library sync and a library prediction on a Dask cluster started here (needs ``rcsa[dask]``).

Starts a ``distributed.LocalCluster`` of two worker processes on this machine and runs the
same commands as ``.venv/bin/rcsa library sync|predict ... --dask-scheduler tcp://...``: each
chunk of tools is a task on a worker, the results come back to this process, which alone
writes the store. On a real cluster, start ``dask scheduler`` and ``dask worker
tcp://HOST:8786`` on the machines (the same rcsa version everywhere) and give that address
instead (or ``RCSA_DASK_SCHEDULER``).

Run: ``.venv/bin/python examples/dask_local_cluster.py examples/fusion-library.json
examples/ra1.json`` (the store: ``RCSA_STORE`` or the per-user one).
"""

from __future__ import annotations

import sys

import dask
from distributed import LocalCluster

from rcsa.cli import app
from rcsa.infra.compute_backends import DASK_WORKER_ENVIRON


def main(library: str, spindle: str) -> None:
    """Sync ``library`` on ``spindle`` and predict it again, both on a local two-worker cluster."""
    # the workers keep freed memory up to 128 MiB (Dask's default of 64 KiB costs the SDM ~1.6x)
    dask.config.set({"distributed.nanny.pre-spawn-environ": DASK_WORKER_ENVIRON})
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as cluster:
        address = cluster.scheduler_address
        sys.stderr.write(f"Dask scheduler at {address}\n")
        common = ["--spindle", spindle, "--frequency", "100:5000:5", "--dask-scheduler", address, "--quiet"]
        for args in (["library", "sync", library, "--library-id", "dask-example", *common],
                     ["library", "predict", library, *common, "-o", "library-dask.json"]):
            app(args, standalone_mode=False)


if __name__ == "__main__":
    if len(sys.argv) != 3:
        sys.exit("usage: dask_local_cluster.py LIBRARY SPINDLE.json")
    main(sys.argv[1], sys.argv[2])
