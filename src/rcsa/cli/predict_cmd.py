"""``rcsa predict ASSEMBLY.json [-o OUT.json]``."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from rcsa.cli._common import JsonOption, emit, fail, read_json, run_guarded

StoreOption = Annotated[Path | None, typer.Option("--store", help="Measurement store (default: RCSA_STORE or the per-user store).")]


def register(app: typer.Typer) -> None:
    """Add the ``predict`` command to ``app``."""

    @app.command(short_help="Tool-point FRF of one assembly (contract JSON).")
    def predict(
        assembly: Annotated[Path, typer.Argument(metavar="ASSEMBLY.json", help=(
            "Assembly JSON (contract format, SI units), or a batch {spindle, frequency, combinations}; "
            "'-' for stdin."))],
        out: Annotated[Path | None, typer.Option("-o", "--out", help=(
            "Write the result here instead of stdout: OUT.json, or for a batch also OUT.h5 (HDF5) or "
            "OUT.parquet (needs rcsa[parquet])."))] = None,
        store: StoreOption = None,
        as_json: JsonOption = False,
    ) -> None:
        """Predict the tool-point FRF of an assembly (or of every combination of a batch).

        The contract's result JSON goes to stdout (or to -o OUT). On a terminal a short summary
        is shown instead (natural frequencies, static stiffness, the most negative real part of
        h); --json prints the JSON there too."""
        # rcsa.app is imported when the command runs, not with the module: `rcsa --help` stays fast
        from rcsa.app.predictions import predict as predict_assembly
        from rcsa.app.predictions import predict_batch
        from rcsa.app.stores import open_store
        from rcsa.app.summaries import batch_summary, prediction_summary
        doc = read_json(assembly)
        if isinstance(doc, dict) and "combinations" in doc:
            result = run_guarded(lambda: predict_batch(doc, store=open_store(store) if store else None,
                                                       arrays="numpy"))
            emit(result, out, what="the batch results", tables=lambda: batch_summary(result), as_json=as_json,
                   kind="batch")
            if result["summary"]["error"]:
                raise typer.Exit(1)
            return
        if out is not None and out.suffix.lower() in (".h5", ".hdf5", ".parquet"):
            raise fail(f"{out}: HDF5 and Parquet results are for batches and libraries; write one assembly's "
                       "result as .json")
        prediction = run_guarded(lambda: predict_assembly(doc, store=open_store(store) if store else None))
        emit(prediction, out, what="the prediction", tables=lambda: prediction_summary(prediction),
               as_json=as_json)
