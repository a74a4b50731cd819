"""`rcsa keys create | list | revoke` on a temporary store."""

from __future__ import annotations

import json

import typer
from typer.testing import CliRunner

from rcsa.cli.keys_cmd import register
from rcsa.infra.api_keys import KeyFile, KeyRing
from rcsa.measured.store import MeasurementStore


def _cli():
    app = typer.Typer()

    @app.callback()
    def main() -> None:
        """Test root."""

    register(app)
    return app


def test_create_list_revoke(tmp_path):
    store = tmp_path / "store"
    runner = CliRunner()
    r = runner.invoke(_cli(), ["keys", "create", "--scope", "write", "--label", "cell 3", "--store", str(store)])
    assert r.exit_code == 0, r.stderr
    secret = r.stdout.strip()
    assert secret.startswith("rcsa_") and "shown only now" in r.stderr
    MeasurementStore(store)  # the key file did not make the directory look foreign
    ring = KeyRing(key_file=KeyFile.in_store(store))
    assert ring.authenticate(secret).scope == "write"
    r = runner.invoke(_cli(), ["keys", "create", "--scope", "read", "--json", "--store", str(store)])
    read = json.loads(r.stdout)
    assert read["scope"] == "read" and read["key"].startswith("rcsa_")
    listed = json.loads(runner.invoke(_cli(), ["keys", "list", "--store", str(store)]).stdout)
    assert [k["label"] for k in listed] == ["cell 3", ""] and all("sha256" not in k for k in listed)
    assert secret not in (store / "api-keys.json").read_text()
    r = runner.invoke(_cli(), ["keys", "revoke", listed[0]["id"], "--store", str(store)])
    assert r.exit_code == 0 and json.loads(r.stdout)["revoked_utc"]
    assert ring.authenticate(secret) is None
    r = runner.invoke(_cli(), ["keys", "revoke", read["key"], "--store", str(store)])
    assert r.exit_code == 0
    r = runner.invoke(_cli(), ["keys", "revoke", "k-00000000", "--store", str(store)])
    assert r.exit_code == 1 and r.stderr.startswith("error: ") and "not found" in r.stderr
    r = runner.invoke(_cli(), ["keys", "create", "--scope", "admin", "--store", str(store)])
    assert r.exit_code == 1 and "scope" in r.stderr
    assert json.loads(runner.invoke(_cli(), ["keys", "list", "--all", "--store", str(store)]).stdout)[0]["revoked_utc"]
