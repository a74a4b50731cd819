"""Command-line interface: ``rcsa predict | serve | store | ...``.

Every command is a thin door onto :mod:`rcsa.app.predictions` (the REST service is the other door).
A failure prints one line ``error: <field>: <rule>`` on stderr and exits with status 1.
"""

from __future__ import annotations

from typing import Annotated

import typer

from rcsa._version import __version__
from rcsa.cli import (
    diagnose_cmd,
    effects_cmd,
    identify_cmd,
    keys_cmd,
    library_cmd,
    lobes_cmd,
    plot_cmd,
    predict_cmd,
    serve_cmd,
)
from rcsa.cli._common import command_group, run_guarded
from rcsa.cli.store_cmd import store_app

__all__ = ["app", "main", "run_guarded"]

app = command_group("Tool-point FRFs of spindle-holder-tool assemblies by exact Timoshenko receptance coupling. "
                    "Every command's input format, with an example file: examples/README.md.", name="rcsa")


def _print_version(value: bool) -> None:
    if value:
        typer.echo(f"rcsa {__version__}")
        raise typer.Exit()


@app.callback()
def _options(
    version: Annotated[bool, typer.Option("--version", help="Print the version of rcsa and exit.",
                                          callback=_print_version, is_eager=True)] = False,
) -> None:
    """Tool-point FRFs of spindle-holder-tool assemblies by exact Timoshenko receptance coupling.

    Every command's input format, with an example file: examples/README.md.
    """


for _module in (predict_cmd, library_cmd, lobes_cmd, plot_cmd, effects_cmd, identify_cmd, diagnose_cmd, serve_cmd,
                keys_cmd):
    _module.register(app)
app.add_typer(store_app, name="store")


def main() -> None:
    """Console-script entry point."""
    app()
