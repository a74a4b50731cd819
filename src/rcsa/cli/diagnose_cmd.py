"""``rcsa diagnose REQUEST.json [-o OUT.json] [--plot PNG]``."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from rcsa.cli._common import (
    JsonOption,
    QuietOption,
    emit,
    fail,
    progress_callback,
    read_json,
    run_guarded,
    wrote,
)
from rcsa.cli.predict_cmd import StoreOption


def register(app: typer.Typer) -> None:
    """Add the ``diagnose`` command to ``app``."""

    @app.command(short_help="Where tap tests and model part, and which effect explains it.")
    def diagnose(
        request: Annotated[Path, typer.Argument(metavar="REQUEST.json", help="Diagnosis request JSON (contract format, SI units); '-' for stdin.")],
        out: Annotated[Path | None, typer.Option("-o", "--out", help="Write the result here instead of stdout.")] = None,
        plot: Annotated[Path | None, typer.Option("--plot", help="Also draw measured/base/corrected FRFs and the "
                                                                  "gap map to this .png or .svg file.")] = None,
        store: StoreOption = None,
        quiet: QuietOption = False,
        as_json: JsonOption = False,
    ) -> None:
        """Where model and measurement part, which unmodelled effect explains it, and how far the gap shrinks.

        The base model's spindle may be a stored measurement ({"measurement_id": ...}), looked
        up in the store. The response JSON goes to stdout (or to -o OUT); on a terminal the
        verdict and the shrink are shown as a table instead (--json: the JSON there too).
        """
        # rcsa.app is imported when the command runs, not with the module: `rcsa --help` stays fast
        from rcsa.app.figures import FIGURE_SUFFIXES, diagnosis_with_figure
        from rcsa.app.stores import open_store
        from rcsa.app.summaries import diagnosis_summary
        if plot is not None and plot.suffix.lower() not in FIGURE_SUFFIXES:
            raise fail(f"--plot: the file must end in .png or .svg, got {plot.name!r}")
        doc = read_json(request)
        try:
            with progress_callback("diagnosis", quiet) as progress:
                response = run_guarded(lambda: diagnosis_with_figure(
                    doc, plot, store=open_store(store) if store else None, progress=progress))
        except OSError as exc:
            raise fail(f"cannot write {plot}: {exc.strerror or exc}") from None
        if plot is not None:
            wrote(plot, "the diagnosis picture (FRFs and gap map)")
        emit(response, out, what="the diagnosis", tables=lambda: diagnosis_summary(response), as_json=as_json)
