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

from distributed import LocalCluster

from rcsa.cli import app


def main(library: str, spindle: str) -> None:
    """Sync ``library`` on ``spindle`` and predict it again, both on a local two-worker cluster."""
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as cluster:
        address = cluster.scheduler_address
        print(f"Dask scheduler at {address}", file=sys.stderr)
        common = ["--spindle", spindle, "--frequency", "100:5000:5", "--dask-scheduler", address, "--quiet"]
        for args in (["library", "sync", library, "--library-id", "dask-example", *common],
                     ["library", "predict", library, *common, "-o", "library-dask.json"]):
            app(args, standalone_mode=False)


if __name__ == "__main__":
    if len(sys.argv) != 3:
        sys.exit("usage: dask_local_cluster.py LIBRARY SPINDLE.json")
    main(sys.argv[1], sys.argv[2])
