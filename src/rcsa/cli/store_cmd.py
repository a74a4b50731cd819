"""``rcsa store import | list | show | delete | check | rebuild``: the measured-spindle FRF store from the shell.

The store is ``--store DIR``, else ``$RCSA_STORE``, else the per-user default
(:func:`rcsa.measured.store.default_store_path`). Output is JSON on stdout (``list`` prints a table
unless ``--json``); a failure prints one line ``error: ...`` on stderr and exits 1. ``check`` and
``rebuild`` print their JSON report and exit 1 when it lists problems.
"""

from __future__ import annotations

import os
from collections.abc import Callable
from pathlib import Path
from typing import Annotated, Any, TypeVar

import typer

from rcsa.cli._common import command_group, fail, write_json
from rcsa.errors import InputError, RcsaError

__all__ = ["store_app"]

T = TypeVar("T")

store_app = command_group("Import, list, show, delete measured spindle FRFs; check and rebuild the store.",
                          short_help="Measured spindle FRFs: import, list, show, delete, check.")

StoreOpt = Annotated[
    Path | None,
    typer.Option(
        "--store", help="Store directory (default: $RCSA_STORE, else ~/.local/share/rcsa/store)."
    ),
]


def _guard(fn: Callable[[], T]) -> T:
    """Run ``fn``; every failure becomes one line on stderr and exit status 1 (no traceback)."""
    try:
        return fn()
    except RcsaError as exc:
        raise fail(str(exc)) from None
    except OSError as exc:
        raise fail(f"{exc.filename or ''} {exc.strerror or exc}".strip()) from None
    except Exception as exc:  # a bug: still one line, unless the user asks for the traceback
        if os.environ.get("RCSA_DEBUG"):
            raise
        raise fail(
            f"internal error ({type(exc).__name__}: {exc}); set RCSA_DEBUG=1 for a traceback"
        ) from None


def _read_bytes(path: Path) -> bytes:
    try:
        return path.read_bytes()
    except FileNotFoundError:
        raise InputError("file", f"{path}: no such file") from None
    except OSError as e:
        raise InputError("file", f"cannot read {path}: {e.strerror or e}") from None


def _artifact_text(text: str | None) -> str | None:
    """``--artifact``: JSON text, or ``@FILE.json`` whose content is the JSON."""
    if not text or not text.startswith("@"):
        return text
    try:
        return Path(text[1:]).read_text(encoding="utf-8")
    except OSError as e:
        raise InputError("artifact", f"give a JSON object or @FILE.json ({e})") from None


@store_app.command("import", short_help="Import a measurement file; print its metadata and id.")
def import_(
    file: Annotated[
        Path, typer.Argument(metavar="FILE", help="File to import (tap: several taps may be given with --tap).")
    ],
    fmt: Annotated[
        str | None,
        typer.Option("--format", help="uff | csv | frf | json | tap (default: from the suffix)."),
    ] = None,
    spindle_id: Annotated[
        str | None, typer.Option("--spindle-id", help="Spindle identifier.")
    ] = None,
    direction: Annotated[
        str | None, typer.Option(help="x | y (UFF: default from the file's response direction).")
    ] = None,
    plane: Annotated[str | None, typer.Option(help="spindle_nose | holder_tip")] = None,
    kind: Annotated[
        str | None,
        typer.Option(help="point_receptance | artifact_frfs | direct_frf (default direct_frf)."),
    ] = None,
    machine: Annotated[str | None, typer.Option(help="Machine name.")] = None,
    notes: Annotated[str | None, typer.Option(help="Free text.")] = None,
    units: Annotated[
        str | None,
        typer.Option(help="FRF unit, e.g. m/N, um/N, in/lbf, m/s^2/N, g/N, dB re 1 m/N."),
    ] = None,
    columns: Annotated[
        str | None,
        typer.Option(
            help="CSV: e.g. f,re,im | f,mag,phase | f,h11.re,h11.im,... (default: from the "
            "file's header); tap: t,force,response."
        ),
    ] = None,
    frequency_unit: Annotated[
        str | None,
        typer.Option(help="CSV frequency unit: Hz | kHz | rad/s (default: the header's, else Hz)."),
    ] = None,
    phase_unit: Annotated[str | None, typer.Option(help="CSV phase unit: deg | rad.")] = None,
    roles: Annotated[
        str | None,
        typer.Option(help="UFF: NAME=RSP_NODE:REF_NODE,... e.g. h11=1:1,h21=2:1,h22=2:2."),
    ] = None,
    scalar_direction: Annotated[
        str | None,
        typer.Option(
            "--scalar-direction",
            help="UFF: direction x | y of scalar FRFs (direction code 0), which the file does not say.",
        ),
    ] = None,
    points_m: Annotated[
        str | None,
        typer.Option(
            "--points-m", help="artifact_frfs: point positions from the tip, m, e.g. 0,0.025."
        ),
    ] = None,
    artifact: Annotated[
        str | None, typer.Option(help="artifact_frfs: artifact JSON object, or @FILE.json.")
    ] = None,
    sensor_mass_kg: Annotated[
        float | None,
        typer.Option("--sensor-mass-kg", help="Remove this accelerometer mass (driving point)."),
    ] = None,
    drop_nonpositive: Annotated[
        bool, typer.Option("--drop-nonpositive", help="Drop rows at f <= 0 Hz instead of refusing.")
    ] = False,
    force_unit: Annotated[str | None, typer.Option(help="tap: force unit, e.g. N.")] = None,
    response_unit: Annotated[
        str | None, typer.Option(help="tap: response unit, e.g. m/s^2, g.")
    ] = None,
    sample_rate_hz: Annotated[
        float | None, typer.Option("--sample-rate-hz", help="tap: sampling rate, Hz.")
    ] = None,
    force_window_s: Annotated[
        float | None, typer.Option("--force-window-s", help="tap: force window width, s.")
    ] = None,
    exponential_tau_s: Annotated[
        float | None,
        typer.Option("--exponential-tau-s", help="tap: exponential window time constant, s."),
    ] = None,
    max_frequency_hz: Annotated[
        float | None, typer.Option("--max-frequency-hz", help="tap: keep f <= this, Hz.")
    ] = None,
    tap: Annotated[
        list[Path] | None,
        typer.Option("--tap", help="tap: further tap files averaged with FILE (H1)."),
    ] = None,
    id_only: Annotated[
        bool, typer.Option("--id-only", help="Print only the new id, for scripts: ID=$(rcsa store import ... --id-only).")
    ] = False,
    store: StoreOpt = None,
) -> None:
    """Import a measurement file and print the new measurement's metadata JSON (with its id)."""
    # rcsa.app is imported when the command runs, not with the module: `rcsa --help` stays fast
    from rcsa.app import measurements as M
    from rcsa.app.stores import open_store

    def run() -> dict[str, Any]:
        metadata = {"spindle_id": spindle_id, "direction": direction, "plane": plane, "kind": kind,
                    "machine": machine, "notes": notes, "points_m": points_m,
                    "artifact": _artifact_text(artifact)}
        options = {"units": units, "columns": columns, "phase_unit": phase_unit, "roles": roles,
                   "scalar_direction": scalar_direction,
                   "sensor_mass_kg": sensor_mass_kg, "force_unit": force_unit,
                   "response_unit": response_unit, "sample_rate_hz": sample_rate_hz,
                   "force_window_s": force_window_s, "exponential_tau_s": exponential_tau_s,
                   "max_frequency_hz": max_frequency_hz}
        form = M.upload_format(file.name, fmt)
        if form not in ("json", "unknown"):  # unknown: the importer says so
            for key in ("spindle_id", "direction", "plane"):
                if metadata[key] is None and not (key == "direction" and form == "uff"):
                    flag = "--" + key.replace("_", "-")
                    raise InputError(key, f"{flag} is required for --format {form}")
        if drop_nonpositive:
            options["drop_nonpositive"] = True
        if form == "csv":
            options["frequency_unit"] = frequency_unit
        m = M.import_measurement(
            _read_bytes(file), file_name=file.name, fmt=fmt, metadata=metadata, options=options,
            extra_taps=[_read_bytes(t) for t in tap or ()],
        )
        return M.store_measurement(open_store(store), m)

    info = _guard(run)
    if id_only:
        typer.echo(info["id"])
    else:
        write_json(info, None)


@store_app.command("list")
def list_(
    spindle_id: Annotated[
        str | None, typer.Option("--spindle-id", help="Only this spindle.")
    ] = None,
    direction: Annotated[str | None, typer.Option(help="Only x or y.")] = None,
    plane: Annotated[str | None, typer.Option(help="Only this plane.")] = None,
    kind: Annotated[str | None, typer.Option(help="Only this kind.")] = None,
    machine: Annotated[str | None, typer.Option(help="Only this machine.")] = None,
    as_json: Annotated[
        bool, typer.Option("--json", help="Print a JSON array instead of a table.")
    ] = False,
    store: StoreOpt = None,
) -> None:
    """List stored measurements (metadata only), oldest first."""
    # rcsa.app is imported when the command runs, not with the module: `rcsa --help` stays fast
    from rcsa.app.stores import open_store
    infos = _guard(
        lambda: open_store(store).list(
            spindle_id, machine=machine, direction=direction, plane=plane, kind=kind
        )
    )
    if as_json:
        write_json([i.to_dict() for i in infos], None)
        return
    # rich: only for the table (``--json`` and the other commands do without it)
    from rich.console import Console
    from rich.table import Table

    table = Table(
        "id",
        "spindle",
        "machine",
        "dir",
        "plane",
        "kind",
        "points",
        "f range (Hz)",
        "created (UTC)",
        "source",
    )
    for i in infos:
        m = i.meta
        table.add_row(
            i.id, m.spindle_id, m.machine, m.direction, m.plane, m.kind, str(i.n_frequencies),
            f"{i.frequency_min_hz:g}-{i.frequency_max_hz:g}", (i.created_utc or "")[:19], i.provenance.source_file,
        )  # fmt: skip
    Console(width=200).print(table)


@store_app.command("show", short_help="A measurement's metadata and the peak of each FRF.")
def show(
    measurement_id: Annotated[
        str, typer.Argument(metavar="ID", help="Measurement id, e.g. m-0123456789ab.")
    ],
    data: Annotated[
        bool, typer.Option("--data", help="Include the arrays (contract JSON form).")
    ] = False,
    store: StoreOpt = None,
) -> None:
    """Print a measurement's metadata and a summary (peak of each FRF) as JSON."""
    # rcsa.app is imported when the command runs, not with the module: `rcsa --help` stays fast
    from rcsa.app import measurements as M
    from rcsa.app.stores import open_store

    def run() -> dict[str, Any]:
        return M.measurement_document(open_store(store), measurement_id, include_data=data)

    write_json(_guard(run), None)


@store_app.command("delete")
def delete(
    measurement_id: Annotated[str, typer.Argument(metavar="ID", help="Measurement id.")],
    store: StoreOpt = None,
) -> None:
    """Delete a measurement (its id is never reused)."""
    # rcsa.app is imported when the command runs, not with the module: `rcsa --help` stays fast
    from rcsa.app import measurements as M
    from rcsa.app.stores import open_store
    write_json(_guard(lambda: M.delete_measurement(open_store(store), measurement_id)), None)


@store_app.command("check", short_help="Verify every measurement file and the catalogue.")
def check(store: StoreOpt = None) -> None:
    """Verify every measurement file (schema, checksums, readability, id) and the catalogue;
    print a JSON report; exit 1 when it lists problems. Changes nothing."""
    # rcsa.app is imported when the command runs, not with the module: `rcsa --help` stays fast
    from rcsa.app import measurements as M
    from rcsa.app.stores import open_store
    report = _guard(lambda: M.check_store(open_store(store)))
    write_json(report, None)
    if not report["ok"]:
        raise typer.Exit(1)


@store_app.command("rebuild", short_help="Make the catalogue again from the measurement files.")
def rebuild(store: StoreOpt = None) -> None:
    """Make the catalogue (index.sqlite) again from the measurement files; print a JSON
    report; exit 1 when some files cannot be read (listed as damaged, left out)."""
    # rcsa.app is imported when the command runs, not with the module: `rcsa --help` stays fast
    from rcsa.app import measurements as M
    from rcsa.app.stores import open_store
    report = _guard(lambda: M.rebuild_catalogue(open_store(store)))
    write_json(report, None)
    if not report["ok"]:
        raise typer.Exit(1)
