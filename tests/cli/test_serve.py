"""``rcsa serve`` refuses to start, with exit status 1 and the reason, when the service cannot start."""

from __future__ import annotations

from typer.testing import CliRunner

from rcsa.cli import app


def test_serve_with_an_unusable_store_exits_1_before_starting_uvicorn(tmp_path):
    (tmp_path / "file").write_text("")
    r = CliRunner().invoke(app, ["serve", "--workers", "2", "--port", "1"], env={"RCSA_STORE": str(tmp_path / "file")})
    assert r.exit_code == 1, r.output
