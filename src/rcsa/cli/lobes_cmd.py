"""``rcsa lobes REQUEST.json [-o OUT.json] [--plot FILE.png|svg]``."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from rcsa.cli._common import (
    DaskOption,
    DaskTimeoutOption,
    JsonOption,
    WorkersOption,
    emit,
    read_json,
    run_guarded,
    wrote,
)


def register(app: typer.Typer) -> None:
    """Add the ``lobes`` command to ``app``."""

    @app.command(short_help="Stability lobes: zero-order or semi-discretization.")
    def lobes(
        request: Annotated[Path, typer.Argument(metavar="REQUEST.json", help="Stability-lobes request JSON (contract format); '-' for stdin.")],
        out: Annotated[Path | None, typer.Option("-o", "--out", help="Write the result here instead of stdout.")] = None,
        plot: Annotated[Path | None, typer.Option("--plot", help="Also draw the lobe diagram (.png or .svg).")] = None,
        store: Annotated[Path | None, typer.Option("--store", help="Measurement store for hybrid assemblies.")] = None,
        as_json: JsonOption = False,
        workers: WorkersOption = 0,
        dask_scheduler: DaskOption = None,
        dask_connect_timeout: DaskTimeoutOption = 10.0,
    ) -> None:
        """Stability lobes from inline FRFs, modal tables or an assembly. "method" auto (the default:
        zero-order only where it is exact, even-toothed slotting; else the semi-discretization, every
        speed checked at two resolutions: "resolved"), zoa or semi_discretization.
        With "uncertainty" (and "robust": {"confidence"}) beside an assembly: depth_limit_robust_m too
        (semi-discretization: from a reduced model of the draws). A stored library's tool
        ("library_tool": {"library_id", "tool_id"}) or a stored measurement's FRF ("frf_x":
        {"measurement_id"}) may stand for the assembly or the FRF.

        The result JSON goes to stdout (or to -o OUT); on a terminal the absolute limit and the
        best pockets are shown as a table instead (--json: the JSON there too).

        A semi-discretization worth more than a few seconds of one core (64 speeds or more; the
        robust limits' reduced model too) is shared by --workers processes (default: one per core)
        or the Dask cluster of --dask-scheduler, in parts of consecutive speeds."""
        # rcsa.app is imported when the command runs, not with the module: `rcsa --help` stays fast
        from rcsa.app.analyses import resolve_lobes_references, stability_lobes_answer
        from rcsa.app.figures import check_picture_path, robust_lobes_figure, save_figure
        from rcsa.app.stores import open_store
        from rcsa.app.summaries import lobes_summary
        from rcsa.infra.compute_backends import compute_backend
        opened = open_store(store) if store else None  # else RCSA_STORE's or the default one, when needed
        doc = run_guarded(lambda: resolve_lobes_references(read_json(request), store=opened))
        backend = run_guarded(lambda: compute_backend(dask_scheduler, connect_timeout_s=dask_connect_timeout,
                                                      workers=workers))
        try:
            answer = run_guarded(lambda: stability_lobes_answer(doc, store=opened, backend=backend))
        finally:
            backend.close()
        if plot is not None:
            run_guarded(lambda: save_figure(robust_lobes_figure(answer.nominal, answer.extras()),
                                            check_picture_path(plot, "--plot")))
            wrote(plot, "the lobe diagram")
        result = answer.to_dict()
        emit(result, out, what="the stability lobes", tables=lambda: lobes_summary(result), as_json=as_json)
