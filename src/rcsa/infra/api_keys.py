"""API keys of the REST service, shared by ``rcsa keys ...`` and the service.

A key is a random secret (``rcsa_`` + 43 URL-safe characters, 256 bits) with a scope:

* ``read`` — predictions, listings, downloads, job status;
* ``write`` — everything ``read`` may do, plus changes to the store (measurement upload
  and delete).

Keys come from two places, both consulted on every request:

* the **key file** ``api-keys.json`` in the store directory, managed with
  ``rcsa keys create --scope write|read`` (prints the secret once), ``rcsa keys list`` and
  ``rcsa keys revoke ID``. It holds only the SHA-256 of each secret (never the secret), is
  written atomically (temporary file + ``os.replace``) under a file lock, with mode 0600;
* the **environment** ``RCSA_API_KEYS="secret1:write,secret2:read"`` (an entry may also give a
  hash instead of a secret: ``sha256:<64 hex>:read``), for containers and tests.

Presented keys are hashed and compared with every known hash by
:func:`hmac.compare_digest` without an early exit, so the time taken does not reveal how
much of a key matched. Secrets are never logged, stored or echoed after creation.
"""

from __future__ import annotations

import builtins
import contextlib
import hashlib
import hmac
import json
import os
import secrets
from collections.abc import Iterable, Iterator
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import filelock

from rcsa.errors import InputError, NotFoundError, StoreError
from rcsa.infra.atomic_files import atomic_write_bytes
from rcsa.infra.clock import utc_now_iso

__all__ = [
    "KEY_FILE",
    "SCOPES",
    "KeyFile",
    "KeyRecord",
    "KeyRing",
    "Principal",
    "hash_key",
    "new_secret",
    "parse_key_list",
]

#: Scopes in increasing order of power; a scope grants every scope before it.
SCOPES = ("read", "write")
#: Name of the key file inside the store directory.
KEY_FILE = "api-keys.json"
_SCHEMA = "rcsa.api-keys"
_PREFIX = "rcsa_"
#: Shortest secret accepted from the environment (a created key has 48 characters).
MIN_SECRET_CHARS = 16


def hash_key(secret: str) -> str:
    """SHA-256 (hex) of a key's secret, the only form in which keys are stored."""
    return hashlib.sha256(secret.encode("utf-8")).hexdigest()


def new_secret() -> str:
    """A fresh random key secret (256 bits), e.g. ``rcsa_3q2...``."""
    return _PREFIX + secrets.token_urlsafe(32)



def _check_scope(scope: object, field: str = "scope") -> str:
    if scope not in SCOPES:
        raise InputError(field, f"must be one of {', '.join(SCOPES)}, got {scope!r}")
    return str(scope)


def grants(scope: str, needed: str) -> bool:
    """Whether a key of ``scope`` may do what needs ``needed``."""
    return SCOPES.index(scope) >= SCOPES.index(needed)


@dataclass(frozen=True, slots=True)
class KeyRecord:
    """One stored key (its hash, never its secret).

    Attributes
    ----------
    id : str
        Public identifier, ``k-`` + 8 hex digits (shown by ``rcsa keys list``, used to revoke).
    scope : {"read", "write"}
    sha256 : str
        SHA-256 of the secret, hex.
    created_utc : str
    label : str
        Free text naming the holder, e.g. ``"fusion add-in, cell 3"``.
    revoked_utc : str or None
        When the key was revoked; a revoked key authenticates nothing.
    """

    id: str
    scope: str
    sha256: str
    created_utc: str
    label: str = ""
    revoked_utc: str | None = None

    def to_dict(self, *, with_hash: bool = True) -> dict[str, Any]:
        """JSON-ready dict; ``with_hash=False`` leaves the hash out (listings)."""
        d = asdict(self)
        if not with_hash:
            d.pop("sha256")
        return d


@dataclass(frozen=True, slots=True)
class Principal:
    """Who made a request: a key id (or ``"anonymous"``) and its scope."""

    key_id: str
    scope: str | None

    def may(self, needed: str) -> bool:
        """Whether this principal holds a scope that grants ``needed``."""
        return self.scope is not None and grants(self.scope, needed)


class KeyFile:
    """The hashed key file of a store directory.

    Parameters
    ----------
    path : str or os.PathLike
        The file (normally ``<store>/api-keys.json``); its directory must exist for writes.
    """

    def __init__(self, path: str | os.PathLike[str]) -> None:
        self.path = Path(path)
        self._lock_path = self.path.with_name("." + self.path.name + ".lock")

    @classmethod
    def in_store(cls, store_path: str | os.PathLike[str]) -> KeyFile:
        """The key file of the store at ``store_path``."""
        return cls(Path(store_path) / KEY_FILE)

    def records(self) -> builtins.list[KeyRecord]:
        """Every record in the file (revoked ones too); ``[]`` when there is no file."""
        try:
            text = self.path.read_text(encoding="utf-8")
        except FileNotFoundError:
            return []
        except OSError as e:
            raise StoreError(f"cannot read the key file {self.path}: {e.strerror or e}") from None
        try:
            doc = json.loads(text)
            if doc.get("schema") != _SCHEMA:
                raise ValueError(f"schema {doc.get('schema')!r} is not {_SCHEMA!r}")
            return [KeyRecord(**r) for r in doc["keys"]]
        except (ValueError, TypeError, KeyError, AttributeError) as e:
            raise StoreError(f"the key file {self.path} is damaged ({e}); restore it or "
                             "remove it and create new keys") from None

    def _write(self, records: Iterable[KeyRecord]) -> None:
        doc = {"schema": _SCHEMA, "schema_version": 1, "keys": [r.to_dict() for r in records]}
        try:
            atomic_write_bytes(self.path, (json.dumps(doc, indent=1) + "\n").encode(), mode=0o600)
        except OSError as e:
            raise StoreError(f"cannot write the key file {self.path}: {e.strerror or e}") from None

    @contextlib.contextmanager
    def _locked(self) -> Iterator[None]:
        try:
            self.path.parent.mkdir(parents=True, exist_ok=True)
            with filelock.FileLock(str(self._lock_path), timeout=30):
                yield
        except filelock.Timeout:
            raise StoreError(f"the key file {self.path} is locked by another process; try again") from None

    def create(self, scope: str, label: str = "") -> tuple[KeyRecord, str]:
        """Add a new key; return its record and its secret (shown once, never stored).

        Parameters
        ----------
        scope : {"read", "write"}
        label : str
            Who or what holds the key.
        """
        scope = _check_scope(scope)
        if not isinstance(label, str) or len(label) > 200 or any(ord(c) < 32 for c in label):
            raise InputError("label", "must be printable text of at most 200 characters")
        secret = new_secret()
        with self._locked():
            records = self.records()
            known = {r.id for r in records}
            key_id = "k-" + secrets.token_hex(4)
            while key_id in known:  # pragma: no cover - 2**32 ids
                key_id = "k-" + secrets.token_hex(4)
            record = KeyRecord(key_id, scope, hash_key(secret), utc_now_iso(timespec="seconds"), label)
            self._write([*records, record])
        return record, secret

    def list(self, *, include_revoked: bool = False) -> builtins.list[KeyRecord]:
        """Records, oldest first; revoked ones only when asked."""
        return [r for r in self.records() if include_revoked or r.revoked_utc is None]

    def revoke(self, key: str) -> KeyRecord:
        """Revoke a key given by its id (``k-…``) or by its secret; return the record.

        Raises
        ------
        NotFoundError
            No live key has that id or secret.
        """
        digest = hash_key(key)
        with self._locked():
            records = self.records()
            for i, r in enumerate(records):
                if r.revoked_utc is None and (r.id == key or hmac.compare_digest(r.sha256, digest)):
                    records[i] = KeyRecord(r.id, r.scope, r.sha256, r.created_utc, r.label, utc_now_iso(timespec="seconds"))
                    self._write(records)
                    return records[i]
        raise NotFoundError("API key", key if key.startswith("k-") else "(secret)")


def parse_key_list(text: str) -> list[tuple[str, str, str]]:
    """Parse ``"secret1:write,secret2:read,sha256:<hex>:read"``.

    Returns
    -------
    list of (id, scope, sha256)
        ``id`` is ``env-`` + the first 8 hex digits of the hash (never the secret).

    Raises
    ------
    InputError
        Field ``RCSA_API_KEYS``: an entry without a valid scope, or a secret shorter than
        :data:`MIN_SECRET_CHARS`.
    """
    out = []
    for raw in (text or "").split(","):
        item = raw.strip()
        if not item:
            continue
        secret, sep, scope = item.rpartition(":")
        if not sep or scope not in SCOPES:
            raise InputError("RCSA_API_KEYS", "write entries as SECRET:SCOPE (scope read or write), "
                                              "separated by commas")
        if secret.startswith("sha256:"):
            digest = secret[len("sha256:"):].lower()
            if len(digest) != 64 or any(c not in "0123456789abcdef" for c in digest):
                raise InputError("RCSA_API_KEYS", "a sha256:HASH entry needs 64 hex digits")
        else:
            if len(secret) < MIN_SECRET_CHARS:
                raise InputError("RCSA_API_KEYS", f"a key must have at least {MIN_SECRET_CHARS} "
                                                  "characters (rcsa keys create makes good ones)")
            digest = hash_key(secret)
        out.append((f"env-{digest[:8]}", scope, digest))
    return out


class KeyRing:
    """All keys a service accepts: from the environment and from the store's key file.

    The key file is re-read when it changes (size, mtime or inode), so ``rcsa keys create``
    and ``revoke`` take effect without a restart, in every worker process.

    Parameters
    ----------
    static : list of (id, scope, sha256)
        From :func:`parse_key_list`.
    key_file : KeyFile or None
    """

    def __init__(self, static: Iterable[tuple[str, str, str]] = (), key_file: KeyFile | None = None) -> None:
        self._static = [(i, _check_scope(s), h) for i, s, h in static]
        self._file = key_file
        self._stamp: tuple[int, int, int] | None = None
        self._from_file: list[tuple[str, str, str]] = []

    def _file_keys(self) -> list[tuple[str, str, str]]:
        if self._file is None:
            return []
        try:
            st = os.stat(self._file.path)
        except FileNotFoundError:
            self._stamp, self._from_file = None, []
            return []
        stamp = (st.st_mtime_ns, st.st_size, st.st_ino)
        if stamp != self._stamp:
            records = self._file.records()
            self._from_file = [(r.id, r.scope, r.sha256) for r in records if r.revoked_utc is None]
            self._stamp = stamp
        return self._from_file

    @property
    def configured(self) -> bool:
        """Whether any key exists at all."""
        return bool(self._static or self._file_keys())

    def authenticate(self, presented: str | None) -> Principal | None:
        """The principal a presented key belongs to, or None (no key, or an unknown key).

        Every known hash is compared, in constant time each, whatever matches first.
        """
        if not presented:
            return None
        digest = hash_key(presented)
        found: tuple[str, str] | None = None
        for key_id, scope, stored in [*self._static, *self._file_keys()]:
            if hmac.compare_digest(stored, digest) and found is None:
                found = (key_id, scope)
        return Principal(*found) if found else None
