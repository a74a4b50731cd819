"""Infrastructure: domain-free plumbing the layers above share.

Modules: :mod:`.sqlite` (how every SQLite database is opened, and transactions),
:mod:`.clock` (UTC timestamps as the stores write them), :mod:`.atomic_files` (durable
writes), :mod:`.job_queue` (durable background jobs), :mod:`.api_keys` (the service's keys),
:mod:`.compute_backends` (where chunks of work run: ``LocalBackend`` in this process, ``ProcessBackend`` in worker processes of this machine,
``DaskBackend`` on a Dask cluster — optional). Nothing here knows what a receptance is.
"""
