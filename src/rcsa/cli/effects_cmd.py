"""``rcsa effects ASSEMBLY.json [-o OUT.json] [--plot FILE.png|svg]``."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from rcsa.cli._common import read_json, run_guarded, write_json


def register(app: typer.Typer) -> None:
    """Add the ``effects`` command to ``app``."""

    @app.command()
    def effects(
        assembly: Annotated[Path, typer.Argument(
            help="Assembly JSON (contract format), or {\"assembly\", \"parameters\", \"relative_step\", "
                 "\"band_hz\"}; '-' for stdin.")],
        out: Annotated[Path | None, typer.Option("-o", "--out", help="Write the result here instead of stdout.")] = None,
        plot: Annotated[Path | None, typer.Option("--plot", help="Also draw the sensitivity heat map (.png or .svg).")] = None,
    ) -> None:
        """Effect analysis: normalised sensitivities of every mode to bearing, joint and tool parameters."""
        from rcsa.analysis.sensitivity import effects_figure, effects_report

        doc = read_json(assembly)
        report = run_guarded(lambda: effects_report(doc))
        if plot is not None:
            from rcsa.analysis.figures import save_figure

            run_guarded(lambda: save_figure(effects_figure(report), _plot_path(plot)))
        write_json(report.to_dict(), out)


def _plot_path(path: Path) -> Path:
    from rcsa.errors import InputError

    if path.suffix.lower() not in (".png", ".svg"):
        raise InputError("--plot", f"the picture must end in .png or .svg, got {path.name!r}")
    return path
