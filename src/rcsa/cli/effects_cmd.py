"""``rcsa effects ASSEMBLY.json [-o OUT.json] [--plot FILE.png|svg] [--store DIR]``."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from rcsa.cli._common import (
    QuietOption,
    progress_callback,
    read_json,
    run_guarded,
    write_json,
    wrote,
)


def register(app: typer.Typer) -> None:
    """Add the ``effects`` command to ``app``."""

    @app.command(short_help="Sensitivities of every mode to bearings, joints and tool.")
    def effects(
        assembly: Annotated[Path, typer.Argument(
            metavar="ASSEMBLY.json",
            help="Assembly JSON (contract format), or {\"assembly\", \"parameters\", \"relative_step\", "
                 "\"band_hz\"}; '-' for stdin.")],
        out: Annotated[Path | None, typer.Option("-o", "--out", help="Write the result here instead of stdout.")] = None,
        plot: Annotated[Path | None, typer.Option("--plot", help="Also draw the sensitivity heat map (.png or .svg).")] = None,
        store: Annotated[Path | None, typer.Option("--store", help="Measurement store for a measured spindle (default: "
                                                                   "RCSA_STORE or the per-user store).")] = None,
        quiet: QuietOption = False,
    ) -> None:
        """Effect analysis: normalised sensitivities of every mode to bearing, joint and tool parameters.

        On a measured spindle ({"measurement_id": ...}) the modes come from a modal fit of the
        hybrid model and bearings are reported as not applicable.
        """
        # rcsa.app is imported when the command runs, not with the module: `rcsa --help` stays fast
        from rcsa.app.figures import check_picture_path, effects_with_figure
        from rcsa.app.stores import open_store
        doc = read_json(assembly)
        picture = None if plot is None else run_guarded(lambda: check_picture_path(plot, "--plot"))
        with progress_callback("effect analysis", quiet) as progress:
            result = run_guarded(lambda: effects_with_figure(doc, picture, store=open_store(store) if store else None,
                                                             progress=progress))
        if picture is not None:
            wrote(picture, "the sensitivity heat map")
        write_json(result, out, "the effect analysis")
