"""API-key authentication: ``X-API-Key`` with scopes ``read`` and ``write``.

* Writes (measurement upload and delete) need a ``write`` key: without a key ``401``, with a
  ``read`` key ``403``; either way before the request body is looked at, so nothing changes.
* Reads and computations are open to anonymous callers while ``RCSA_ANONYMOUS_READ`` is
  true (the default); otherwise they need a ``read`` (or ``write``) key.
* A key that is sent but unknown or revoked is always ``401`` (a misconfigured client should
  learn it at once, not fall back to anonymous).

Keys are looked up in :class:`rcsa.app.keys.KeyRing` (environment + the store's hashed key
file), compared in constant time.
"""

from __future__ import annotations

from typing import Annotated

from fastapi import Depends, Security
from fastapi.dependencies.models import Dependant
from fastapi.security import APIKeyHeader

from rcsa.infra.api_keys import Principal

from .deps import StateDep
from .errors import ProblemError

__all__ = ["ReadAccess", "WriteAccess", "access_of", "api_key_header", "principal", "require_read", "require_write"]

api_key_header = APIKeyHeader(
    name="X-API-Key", auto_error=False, scheme_name="APIKey",
    description="API key (scope read or write). Create one on the server with "
                "`rcsa keys create --scope write`; writes always need a write key.")

_CHALLENGE = {"WWW-Authenticate": 'APIKey realm="rcsa", header="X-API-Key"'}
ANONYMOUS = Principal("anonymous", None)


def principal(state: StateDep, key: Annotated[str | None, Security(api_key_header)] = None) -> Principal:
    """Who is calling: the key's principal, or anonymous when no key was sent."""
    if not key:
        return ANONYMOUS
    found = state.keys.authenticate(key)
    if found is None:
        raise ProblemError(401, "the X-API-Key is not valid (unknown or revoked); check the key, or ask the "
                                "operator for a new one (rcsa keys create)", headers=_CHALLENGE)
    return found


def require_read(state: StateDep, who: Annotated[Principal, Depends(principal)]) -> Principal:
    """Allow reads and computations (anonymous ones only with RCSA_ANONYMOUS_READ)."""
    if who.scope is None and not state.settings.anonymous_read:
        raise ProblemError(401, "this service needs an API key for every request: send X-API-Key with a "
                                "read or write key", headers=_CHALLENGE)
    return who


def require_write(who: Annotated[Principal, Depends(principal)]) -> Principal:
    """Allow changes to the store (write keys only)."""
    if who.scope is None:
        raise ProblemError(401, "changing the store needs an API key with scope write in the X-API-Key "
                                "header; the operator creates one with `rcsa keys create --scope write`",
                           headers=_CHALLENGE)
    if not who.may("write"):
        raise ProblemError(403, f"the API key {who.key_id} has scope {who.scope}; changing the store needs "
                                "a key with scope write")
    return who


ReadAccess = Annotated[Principal, Depends(require_read)]
WriteAccess = Annotated[Principal, Depends(require_write)]


def access_of(dependant: Dependant) -> str | None:
    """``"write"``, ``"read"`` or None: the strictest access among a route's dependencies.

    The one rule both the request checks (``service/routing.py``) and the OpenAPI document
    (``service/openapi_doc.py``) read a route's access by.
    """
    found: set[str] = set()
    todo = [dependant]
    while todo:
        dep = todo.pop()
        if dep.call is require_write:
            found.add("write")
        elif dep.call is require_read:
            found.add("read")
        todo.extend(dep.dependencies)
    return "write" if "write" in found else ("read" if found else None)
