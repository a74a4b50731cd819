"""``rcsa lobes REQUEST.json [-o OUT.json] [--plot FILE.png|svg]``."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from rcsa.cli._common import read_json, run_guarded, write_json


def register(app: typer.Typer) -> None:
    """Add the ``lobes`` command to ``app``."""

    @app.command()
    def lobes(
        request: Annotated[Path, typer.Argument(help="Stability-lobes request JSON (contract format); '-' for stdin.")],
        out: Annotated[Path | None, typer.Option("-o", "--out", help="Write the result here instead of stdout.")] = None,
        plot: Annotated[Path | None, typer.Option("--plot", help="Also draw the lobe diagram (.png or .svg).")] = None,
        store: Annotated[Path | None, typer.Option("--store", help="Measurement store for hybrid assemblies.")] = None,
    ) -> None:
        """Stability lobes (Altintas–Budak zero-order) from inline FRFs or an assembly."""
        from rcsa import app
        from rcsa.measured.store import MeasurementStore

        doc = read_json(request)
        result = run_guarded(lambda: app.stability_lobes_result(doc, store=MeasurementStore(store) if store else None))
        if plot is not None:
            from rcsa.analysis.figures import lobes_figure, save_figure

            run_guarded(lambda: save_figure(lobes_figure(result), _plot_path(plot)))
        write_json(result.to_dict(), out)


def _plot_path(path: Path) -> Path:
    from rcsa.errors import InputError

    if path.suffix.lower() not in (".png", ".svg"):
        raise InputError("--plot", f"the picture must end in .png or .svg, got {path.name!r}")
    return path
