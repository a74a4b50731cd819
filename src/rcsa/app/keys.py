"""API keys of the REST service as ``rcsa keys ...`` and the service see them.

Keys live as SHA-256 hashes in the store directory's key file (managed by
``rcsa keys create | list | revoke``) and, for containers and tests, in ``RCSA_API_KEYS``;
see :mod:`rcsa.infra.api_keys` for the format and the constant-time check.
"""

from __future__ import annotations

import os

from rcsa.infra.api_keys import KeyFile, KeyRing, parse_key_list
from rcsa.measured.store import MeasurementStore

__all__ = ["key_file", "key_ring"]


def key_file(store_path: str | os.PathLike[str] | None = None) -> KeyFile:
    """The key file of the store at ``store_path`` (the default store when None).

    The store is opened first (created with its marker if new), so a mistyped path never
    leaves a stray key file in a directory that is not a store.
    """
    return KeyFile.in_store(MeasurementStore(store_path).path)


def key_ring(store_path: str | os.PathLike[str], configured: str = "") -> KeyRing:
    """Every key a service on the store at ``store_path`` accepts.

    Parameters
    ----------
    store_path : path
        The (open) store directory, whose key file is read on every check.
    configured : str
        Keys given to the process: ``"SECRET:write,SECRET:read"`` or ``"sha256:HEX:read"``
        entries (``RCSA_API_KEYS``).

    Raises
    ------
    ValueError
        ``configured`` is malformed.
    """
    return KeyRing(parse_key_list(configured), KeyFile.in_store(store_path))
