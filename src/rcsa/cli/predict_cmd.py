"""``rcsa predict ASSEMBLY.json [-o OUT.json]``."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from rcsa.cli._common import read_json, run_guarded, write_json

StoreOption = Annotated[Path | None, typer.Option("--store", help="Measurement store (default: RCSA_STORE or the per-user store).")]


def register(app: typer.Typer) -> None:
    """Add the ``predict`` command to ``app``."""

    @app.command(short_help="Tool-point FRF of one assembly (contract JSON).")
    def predict(
        assembly: Annotated[Path, typer.Argument(metavar="ASSEMBLY.json", help="Assembly JSON (contract format, SI units); '-' for stdin.")],
        out: Annotated[Path | None, typer.Option("-o", "--out", help="Write the result here instead of stdout.")] = None,
        store: StoreOption = None,
    ) -> None:
        """Predict the tool-point FRF of an assembly; prints the contract's result JSON."""
        # rcsa.app is imported when the command runs, not with the module: `rcsa --help` stays fast
        from rcsa.app.predictions import predict as predict_assembly
        from rcsa.app.stores import open_store
        doc = read_json(assembly)
        result = run_guarded(lambda: predict_assembly(doc, store=open_store(store) if store else None))
        write_json(result.to_dict(), out, "the prediction")
