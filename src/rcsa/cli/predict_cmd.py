"""``rcsa predict ASSEMBLY.json [-o OUT.json]``."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from rcsa.cli._common import fail, read_json, run_guarded, write_json, write_results

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
    ) -> None:
        """Predict the tool-point FRF of an assembly (or of every combination of a batch); prints the
        contract's result JSON."""
        # rcsa.app is imported when the command runs, not with the module: `rcsa --help` stays fast
        from rcsa.app.predictions import predict as predict_assembly
        from rcsa.app.predictions import predict_batch
        from rcsa.app.stores import open_store
        doc = read_json(assembly)
        if isinstance(doc, dict) and "combinations" in doc:
            result = run_guarded(lambda: predict_batch(doc, store=open_store(store) if store else None,
                                                       arrays="numpy"))
            write_results(result, out, "batch", "the batch results")
            if result["summary"]["error"]:
                raise typer.Exit(1)
            return
        if out is not None and out.suffix.lower() in (".h5", ".hdf5", ".parquet"):
            raise fail(f"{out}: HDF5 and Parquet results are for batches and libraries; write one assembly's "
                       "result as .json")
        prediction = run_guarded(lambda: predict_assembly(doc, store=open_store(store) if store else None))
        write_json(prediction, out, "the prediction")
