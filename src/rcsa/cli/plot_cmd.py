"""``rcsa plot INPUT.json -o OUT.png|svg``: pictures of FRFs and stability lobes.

The input is recognised by its content: a prediction result (``tool_point``), a measurement
in the contract's JSON form (``h``), an assembly (predicted first), a stability-lobes
result (``rcsa lobes`` output: drawn as it is), or a stability-lobes request (solved first).
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from rcsa.cli._common import read_json, run_guarded, wrote
from rcsa.errors import InputError


def register(app: typer.Typer) -> None:
    """Add the ``plot`` command to ``app``."""

    @app.command(short_help="Draw an FRF or a stability lobe diagram (PNG, SVG).")
    def plot(
        source: Annotated[Path, typer.Argument(metavar="RESULT.json", help="Prediction result, measurement, assembly, lobes result or lobes "
                                                              "request (JSON).")],
        out: Annotated[Path, typer.Option("-o", "--out", help="Picture to write: .png or .svg.")],
        layout: Annotated[str, typer.Option(help="FRF layout: full, real_imag or bode.")] = "full",
        store: Annotated[Path | None, typer.Option("--store", help="Measurement store for hybrid assemblies.")] = None,
    ) -> None:
        """Draw an FRF (real/imaginary, magnitude/phase) or a stability lobe diagram."""
        # rcsa.app is imported when the command runs, not with the module: `rcsa --help` stays fast
        from rcsa.app.figures import FRF_LAYOUTS, check_picture_path, document_figure, save_figure
        from rcsa.app.stores import open_store
        doc = read_json(source)

        def draw() -> None:
            check_picture_path(out, "--out")
            if layout not in FRF_LAYOUTS:
                raise InputError("--layout", "must be full, real_imag or bode")
            save_figure(document_figure(doc, layout=layout, store=open_store(store) if store else None), out)

        run_guarded(draw)
        wrote(out, "the picture")
