"""``rcsa store import | list | show | delete``: the measured-spindle FRF store from the shell.

The store is ``--store DIR``, else ``$RCSA_STORE``, else the per-user default
(:func:`rcsa.store.default_store_path`). Output is JSON on stdout (``list`` prints a table
unless ``--json``); a failure prints one line ``error: ...`` on stderr and exits 1.
"""

from __future__ import annotations

import json
import os
from collections.abc import Callable
from pathlib import Path
from typing import Annotated, Any, TypeVar

import numpy as np
import typer

from ..errors import InputError, RcsaError
from ._common import fail, write_json

__all__ = ["store_app"]

T = TypeVar("T")

store_app = typer.Typer(
    help="Import, list, show and delete measured spindle FRFs.",
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
)

StoreOpt = Annotated[
    Path | None,
    typer.Option(
        "--store", help="Store directory (default: $RCSA_STORE, else ~/.local/share/rcsa/store)."
    ),
]
_FORMATS = ("uff", "csv", "frf", "json", "tap")
_BY_SUFFIX = {
    ".uff": "uff",
    ".unv": "uff",
    ".csv": "csv",
    ".tsv": "csv",
    ".frf": "frf",
    ".json": "json",
}


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


def _open_store(path: Path | None):
    from ..store import MeasurementStore

    return MeasurementStore(path)


def _parse_roles(text: str | None) -> dict[str, tuple[int, int]] | None:
    if not text:
        return None
    roles = {}
    for item in text.split(","):
        name, sep, nodes = item.partition("=")
        rsp, sep2, ref = nodes.partition(":")
        try:
            if not (sep and sep2):
                raise ValueError
            roles[name.strip()] = (int(rsp), int(ref))
        except ValueError:
            raise InputError(
                "roles", f"{item!r}: write NAME=RESPONSE_NODE:REFERENCE_NODE, e.g. h21=2:1"
            ) from None
    return roles


def _parse_points(text: str | None) -> tuple[float, ...] | None:
    if not text:
        return None
    try:
        return tuple(float(x) for x in text.split(","))
    except ValueError:
        raise InputError(
            "points_m", f"{text!r}: write comma-separated metres, e.g. 0,0.025"
        ) from None


def _parse_artifact(text: str | None) -> Any:
    if not text:
        return None
    try:
        raw = Path(text[1:]).read_text(encoding="utf-8") if text.startswith("@") else text
        return json.loads(raw)
    except (OSError, ValueError) as e:
        raise InputError("artifact", f"give a JSON object or @FILE.json ({e})") from None


def _summary(m: Any) -> dict[str, Any]:
    from ..store.schema import frf_unit

    out = {}
    for name, v in m.frfs.items():
        i = int(np.argmax(np.abs(v)))
        out[name] = {
            "units": frf_unit(name),
            "max_magnitude": float(np.abs(v[i])),
            "frequency_at_max_hz": float(m.frequency_hz[i]),
        }
    return out


@store_app.command("import")
def import_(
    file: Annotated[
        Path, typer.Argument(help="File to import (tap: several taps may be given with --tap).")
    ],
    fmt: Annotated[
        str | None,
        typer.Option("--format", help="uff | csv | frf | json | tap (default: from the suffix)."),
    ] = None,
    spindle_id: Annotated[
        str | None, typer.Option("--spindle-id", help="Spindle identifier.")
    ] = None,
    direction: Annotated[str | None, typer.Option(help="x | y")] = None,
    plane: Annotated[str | None, typer.Option(help="spindle_nose | holder_tip")] = None,
    kind: Annotated[
        str | None,
        typer.Option(help="point_receptance | artifact_frfs | direct_frf (default direct_frf)."),
    ] = None,
    machine: Annotated[str | None, typer.Option(help="Machine name.")] = None,
    notes: Annotated[str | None, typer.Option(help="Free text.")] = None,
    units: Annotated[
        str | None, typer.Option(help="FRF unit, e.g. m/N, um/N, in/lbf, m/s^2/N, g/N.")
    ] = None,
    columns: Annotated[
        str | None,
        typer.Option(
            help="CSV: e.g. f,re,im | f,mag,phase | f,h11.re,h11.im,...; tap: t,force,response."
        ),
    ] = None,
    frequency_unit: Annotated[
        str, typer.Option(help="CSV frequency unit: Hz | kHz | rad/s.")
    ] = "Hz",
    phase_unit: Annotated[str | None, typer.Option(help="CSV phase unit: deg | rad.")] = None,
    roles: Annotated[
        str | None,
        typer.Option(help="UFF: NAME=RSP_NODE:REF_NODE,... e.g. h11=1:1,h21=2:1,h22=2:2."),
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
    store: StoreOpt = None,
) -> None:
    """Import a measurement file and print the new measurement's metadata JSON (with its id)."""

    def run() -> dict[str, Any]:
        from ..importers import read_contract_json, read_csv, read_cutpro, read_tap, read_uff
        from ..store import MeasurementMeta

        form = (fmt or _BY_SUFFIX.get(file.suffix.lower(), "")).lower()
        if form not in _FORMATS:
            raise InputError(
                "format", f"say which format {file.name} is: --format {'|'.join(_FORMATS)}"
            )
        common = {"drop_nonpositive": drop_nonpositive, "sensor_mass_kg": sensor_mass_kg}
        given = {
            "spindle_id": spindle_id, "direction": direction, "plane": plane, "kind": kind, "machine": machine,
            "notes": notes, "points_m": _parse_points(points_m), "artifact": _parse_artifact(artifact),
        }  # fmt: skip
        if form == "json":
            overrides = {k: (list(v) if isinstance(v, tuple) else v) for k, v in given.items()}
            m = read_contract_json(file, overrides=overrides, **common)
        else:
            for key, flag in (
                ("spindle_id", "--spindle-id"),
                ("direction", "--direction"),
                ("plane", "--plane"),
            ):
                if given[key] is None:
                    raise InputError(key, f"{flag} is required for --format {form}")
            given["kind"] = given["kind"] or "direct_frf"
            meta = MeasurementMeta(**{k: v for k, v in given.items() if v is not None})
            if form == "csv":
                m = read_csv(file, meta, units=units, columns=columns or "f,re,im", frequency_unit=frequency_unit,
                             phase_unit=phase_unit, **common)  # fmt: skip
            elif form == "frf":
                m = read_cutpro(file, meta, units=units, **common)
            elif form == "uff":
                m = read_uff(file, meta, roles=_parse_roles(roles), units=units, **common)
            else:
                if drop_nonpositive:
                    raise InputError(
                        "drop_nonpositive",
                        "a tap FFT always drops its 0 Hz bin; leave the flag out",
                    )
                m = read_tap(
                    [file, *(tap or [])], meta, force_unit=force_unit, response_unit=response_unit,
                    columns=columns or "t,force,response", sample_rate_hz=sample_rate_hz,
                    force_window_s=force_window_s, exponential_tau_s=exponential_tau_s,
                    max_frequency_hz=max_frequency_hz, sensor_mass_kg=sensor_mass_kg,
                )  # fmt: skip
        st = _open_store(store)
        return st.info(st.put(m)).to_dict()

    write_json(_guard(run), None)


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
    infos = _guard(
        lambda: _open_store(store).list(
            spindle_id, machine=machine, direction=direction, plane=plane, kind=kind
        )
    )
    if as_json:
        write_json([i.to_dict() for i in infos], None)
        return
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


@store_app.command("show")
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

    def run() -> dict[str, Any]:
        from ..importers import measurement_to_contract

        m = _open_store(store).get(measurement_id)
        out = measurement_to_contract(m, include_data=data)
        out["summary"] = _summary(m)
        return out

    write_json(_guard(run), None)


@store_app.command("delete")
def delete(
    measurement_id: Annotated[str, typer.Argument(metavar="ID", help="Measurement id.")],
    store: StoreOpt = None,
) -> None:
    """Delete a measurement (its id is never reused)."""
    _guard(lambda: _open_store(store).delete(measurement_id))
    write_json({"deleted": measurement_id}, None)
