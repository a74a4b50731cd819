"""The newcomer's path: ``--help`` of every command readable at 80 columns, and ``--version``.

Help is written as it is (no Rich markup: ``pip install 'rcsa[dask]'`` keeps its ``[dask]``),
every option name is printed whole, flags carry no ``<bool>``, no docstring markup (````x````,
``:func:``) leaks into it, and every line fits the terminal.
"""

from __future__ import annotations

import re

import click
import pytest
import typer
from typer.testing import CliRunner

import rcsa
from rcsa.cli import app

ROOT = typer.main.get_command(app)


def _commands(group: click.Command, path: tuple[str, ...] = ()) -> list[tuple[tuple[str, ...], click.Command]]:
    out = [(path, group)]
    if hasattr(group, "list_commands"):  # a group (typer's own class in typer 0.29)
        for name in group.list_commands(click.Context(group)):
            out += _commands(group.get_command(click.Context(group), name), (*path, name))
    return out


COMMANDS = _commands(ROOT)


def _help(path: tuple[str, ...], columns: int = 80) -> str:
    result = CliRunner().invoke(app, [*path, "--help"], env={"COLUMNS": str(columns)})
    assert result.exit_code == 0, result.output
    return result.output


def test_every_command_is_reached():
    names = {" ".join(p) for p, _ in COMMANDS}
    assert {"predict", "diagnose", "library sync", "library recommend", "store import", "keys create"} <= names
    assert len(names) >= 20


@pytest.mark.parametrize(("path", "command"), COMMANDS, ids=lambda c: " ".join(c) if isinstance(c, tuple) else "")
def test_help_is_readable_at_80_columns(path, command):
    text = _help(path)
    too_long = [line for line in text.splitlines() if len(line) > 80]
    assert not too_long, too_long
    for param in command.params:
        for name in (*param.opts, *param.secondary_opts):
            if name.startswith("-") and name != "--help":
                assert name in text, f"{' '.join(path)}: option {name} is not printed whole"
    assert "<bool>" not in text
    assert not re.search(r"``|:(func|mod|class|data|meth|attr):", text), "docstring markup in the help"
    assert "…" not in text  # nothing is cut short


def test_brackets_in_help_are_printed_not_eaten():
    for path in (("serve",), ("library", "sync"), ("library", "predict")):
        assert "rcsa[dask]" in _help(path).replace("\n", " ").replace("  ", " ")


def test_version_prints_the_package_version():
    result = CliRunner().invoke(app, ["--version"])
    assert result.exit_code == 0 and result.output.strip() == f"rcsa {rcsa.__version__}"
    assert "--version" in _help(())
