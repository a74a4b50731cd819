"""Command-line interface: ``rcsa predict | serve | store | ...``.

Every command is a thin door onto :mod:`rcsa.app.predictions` (the REST service is the other door).
A failure prints one line ``error: <field>: <rule>`` on stderr and exits with status 1.
"""

from __future__ import annotations

import typer

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
from rcsa.cli._common import run_guarded
from rcsa.cli.store_cmd import store_app

__all__ = ["app", "main", "run_guarded"]

app = typer.Typer(
    name="rcsa",
    help="Tool-point FRFs of spindle-holder-tool assemblies by exact Timoshenko receptance coupling.",
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
)
for _module in (predict_cmd, library_cmd, lobes_cmd, plot_cmd, effects_cmd, identify_cmd, diagnose_cmd, serve_cmd,
                keys_cmd):
    _module.register(app)
app.add_typer(store_app, name="store", help="Import, list, show, delete measured spindle FRFs; check and rebuild "
                                           "the store.")


def main() -> None:
    """Console-script entry point."""
    app()
