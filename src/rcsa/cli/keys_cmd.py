"""``rcsa keys create | list | revoke``: API keys of the REST service.

Keys live as SHA-256 hashes in ``api-keys.json`` inside the store directory (``--store``,
else ``$RCSA_STORE``, else the per-user store), so every service process on that store
accepts them at once, without a restart. ``create`` prints the secret once; it is not
stored anywhere and cannot be shown again.
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from rcsa.cli._common import command_group, run_guarded, write_json

__all__ = ["keys_app", "register"]

keys_app = command_group("Create, list and revoke API keys of the REST service.")

StoreOpt = Annotated[Path | None, typer.Option("--store", help="Store directory (default: $RCSA_STORE, else "
                                                                "~/.local/share/rcsa/store).")]


@keys_app.command("create")
def create(
    scope: Annotated[str, typer.Option(help="read (predictions, listings) or write (also upload and delete).")],
    label: Annotated[str, typer.Option(help="Who or what holds the key, e.g. 'fusion add-in cell 3'.")] = "",
    as_json: Annotated[bool, typer.Option("--json", help="Print a JSON object instead of text.")] = False,
    store: StoreOpt = None,
) -> None:
    """Create a key and print its secret once (only its hash is kept)."""
    # rcsa.app is imported when the command runs, not with the module: `rcsa --help` stays fast
    from rcsa.app.keys import key_file
    record, secret = run_guarded(lambda: key_file(store).create(scope, label))
    if as_json:
        write_json({**record.to_dict(with_hash=False), "key": secret}, None)
        return
    typer.echo(secret)
    typer.echo(f"created {record.id} (scope {record.scope}); the key above is shown only now: store it safely "
               "and send it as the X-API-Key header", err=True)


@keys_app.command("list", short_help="List keys as JSON (never their secrets).")
def list_(
    include_revoked: Annotated[bool, typer.Option("--all", help="Also list revoked keys.")] = False,
    store: StoreOpt = None,
) -> None:
    """List keys (ids, scopes, labels, dates; never secrets) as JSON."""
    # rcsa.app is imported when the command runs, not with the module: `rcsa --help` stays fast
    from rcsa.app.keys import key_file
    records = run_guarded(lambda: key_file(store).list(include_revoked=include_revoked))
    write_json([r.to_dict(with_hash=False) for r in records], None)


@keys_app.command("revoke", short_help="Revoke a key; it is refused from the next request on.")
def revoke(
    key: Annotated[str, typer.Argument(metavar="KEY", help="Key id (k-...) from `rcsa keys list`, or the key itself.")],
    store: StoreOpt = None,
) -> None:
    """Revoke a key; services on this store refuse it from the next request on."""
    # rcsa.app is imported when the command runs, not with the module: `rcsa --help` stays fast
    from rcsa.app.keys import key_file
    record = run_guarded(lambda: key_file(store).revoke(key))
    write_json(record.to_dict(with_hash=False), None)


def register(app: typer.Typer) -> None:
    """Add ``rcsa keys ...`` to ``app``."""
    app.add_typer(keys_app, name="keys")
