"""Infrastructure: domain-free plumbing the layers above share.

Modules: :mod:`.sqlite` (how every SQLite database is opened, and transactions),
:mod:`.clock` (UTC timestamps as the stores write them), :mod:`.atomic_files` (durable
writes), :mod:`.job_queue` (durable background jobs), :mod:`.api_keys` (the service's keys),
:mod:`.compute` (where chunks of work run: this process, or a Dask cluster — optional).
Nothing here knows what a receptance is.
"""
