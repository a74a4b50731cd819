"""``rcsa identify REQUEST.json [-o OUT.json] [--store DIR]``."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from rcsa.cli._common import QuietOption, progress_callback, read_json, run_guarded, write_json


def register(app: typer.Typer) -> None:
    """Add the ``identify`` command to ``app``."""

    @app.command(short_help="Joint stiffness and damping from measured tool points.")
    def identify(
        request: Annotated[Path, typer.Argument(
            metavar="REQUEST.json",
            help="Identification request JSON: {\"assembly\", \"measurements\"} (contract format); '-' for stdin.")],
        out: Annotated[Path | None, typer.Option("-o", "--out", help="Write the result here instead of stdout.")] = None,
        store: Annotated[Path | None, typer.Option("--store", help="Measurement store for a measured spindle (default: "
                                                                   "RCSA_STORE or the per-user store).")] = None,
        quiet: QuietOption = False,
    ) -> None:
        """Identify the joints' translational stiffness and damping from measured tool-point FRFs.

        Prints the result JSON; its status is "identified" or "not_identifiable" (with a
        detail), and both exit 0: only a malformed request fails. The assembly's spindle may
        be a stored measurement ({"measurement_id": ...}).
        """
        # rcsa.app is imported when the command runs, not with the module: `rcsa --help` stays fast
        from rcsa.app.analyses import identify as identify_joints
        from rcsa.app.stores import open_store
        doc = read_json(request)
        with progress_callback("joint identification", quiet) as progress:
            result = run_guarded(lambda: identify_joints(doc, store=open_store(store) if store else None,
                                                         progress=progress))
        write_json(result, out, "the identification")
