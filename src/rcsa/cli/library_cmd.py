"""``rcsa library predict LIBRARY --spindle SPINDLE.json | --measurement ID``.

Tool-point FRFs of every tool of an Autodesk Fusion tool library (``.json`` or ``.tools``)
on one spindle, computed here (no service needed), with a progress bar on stderr. The result
JSON (one entry per library item: ``ok``, ``skipped`` with a reason, or ``error``) goes to
stdout or ``-o OUT.json``; the exit status is 1 when any tool errored.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Annotated, Any

import typer

from ..errors import InputError
from ._common import fail, read_json, run_guarded, write_json

__all__ = ["library_app", "register"]

library_app = typer.Typer(help="Tool-point FRFs of whole CAM tool libraries.", no_args_is_help=True,
                          add_completion=False, pretty_exceptions_enable=False)

_DEFAULT_GRID = {"start_hz": 5.0, "stop_hz": 5000.0, "step_hz": 1.0}


def parse_frequency_option(text: str) -> dict[str, Any]:
    """``START:STOP:STEP`` (Hz, stop included) or a JSON frequency object."""
    text = text.strip()
    if text.startswith("{"):
        try:
            doc = json.loads(text)
        except ValueError as exc:
            raise InputError("frequency", f"not valid JSON ({exc})") from None
        return doc
    parts = text.split(":")
    try:
        if len(parts) != 3:
            raise ValueError
        start, stop, step = (float(p) for p in parts)
    except ValueError:
        raise InputError("frequency", f"{text!r}: write START:STOP:STEP in Hz, e.g. 5:5000:1, or a JSON "
                                      'object {"values_hz": [...]}') from None
    return {"start_hz": start, "stop_hz": stop, "step_hz": step}


def _spindle_document(path: Path) -> dict[str, Any]:
    """A spindle JSON, or an assembly JSON whose spindle (and grid, joints, materials) are used."""
    doc = read_json(path)
    if not isinstance(doc, dict):
        raise fail(f"{path}: expected a JSON object (a spindle or an assembly)")
    if "spindle" in doc:
        return doc
    return {"spindle": doc}


@library_app.command("predict")
def predict(
    library: Annotated[Path, typer.Argument(help="Fusion tool library: .json, or .tools (zip).")],
    spindle: Annotated[Path | None, typer.Option(help="Spindle JSON (segments + bearings), or an assembly "
                                                      "JSON whose spindle, frequency, joints and materials "
                                                      "are used.")] = None,
    measurement: Annotated[str | None, typer.Option(help="Instead of --spindle: a stored measurement id "
                                                         "(hybrid).")] = None,
    frequency: Annotated[str | None, typer.Option(help="START:STOP:STEP in Hz (stop included) or a JSON "
                                                       "frequency object. Default: the assembly's, else the "
                                                       "measurement's lines, else 5:5000:1.")] = None,
    joints: Annotated[Path | None, typer.Option(help="Joints JSON {spindle_holder, holder_tool} for every "
                                                     "tool (default: the assembly's, else rigid).")] = None,
    options: Annotated[str | None, typer.Option(help="Import options as JSON, e.g. "
                                                     '\'{"holder_segments_per_cone": 6}\'.')] = None,
    natural_frequencies: Annotated[bool, typer.Option(help="Compute exact natural frequencies.")] = True,
    out: Annotated[Path | None, typer.Option("-o", "--out", help="Write the result here instead of stdout.")] = None,
    store: Annotated[Path | None, typer.Option("--store", help="Measurement store (default: RCSA_STORE or "
                                                               "the per-user store).")] = None,
    quiet: Annotated[bool, typer.Option("--quiet", "-q", help="No progress bar.")] = False,
) -> None:
    """Predict the tool-point FRF of every tool in a Fusion library on one spindle."""
    from rich.console import Console
    from rich.progress import (
        BarColumn,
        MofNCompleteColumn,
        Progress,
        TextColumn,
        TimeRemainingColumn,
    )

    from .. import library_api

    if (spindle is None) == (measurement is None):
        raise fail("give exactly one of --spindle SPINDLE.json or --measurement ID")
    base = _spindle_document(spindle) if spindle is not None else {"spindle": {"measurement_id": measurement}}

    def build() -> tuple[dict[str, Any], Any]:
        from ..store import MeasurementStore

        st = MeasurementStore(store) if (store is not None or measurement is not None) else None
        if frequency is not None:
            grid = parse_frequency_option(frequency)
        elif "frequency" in base:
            grid = base["frequency"]
        elif measurement is not None:
            grid = {"values_hz": st.get(measurement).frequency_hz.tolist()}
        else:
            grid = dict(_DEFAULT_GRID)
        if options is not None:
            try:
                opts = json.loads(options)
            except ValueError as exc:
                raise InputError("options", f"not valid JSON ({exc})") from None
        else:
            opts = None
        request = library_api.library_request(
            library, spindle=base["spindle"], frequency=grid,
            joints=read_json(joints) if joints is not None else base.get("joints"),
            materials=base.get("materials"), beam_theory=base.get("beam_theory"),
            shear_coefficient=base.get("shear_coefficient"), natural_frequencies=natural_frequencies,
            options=opts)
        library_api.check_common(request["batch"], store=st)
        return request, st

    request, st = run_guarded(build)
    with Progress(TextColumn("[progress.description]{task.description}"), BarColumn(), MofNCompleteColumn(),
                  TimeRemainingColumn(), transient=True, disable=quiet,
                  console=Console(stderr=True)) as bar:
        task = bar.add_task("tools", total=max(len(request["batch"]["combinations"]), 1))

        def progress(done: int, total: int) -> None:
            bar.update(task, completed=done, total=max(total, 1))

        result = run_guarded(lambda: library_api.run_library_request(request, store=st, progress=progress,
                                                                     arrays="numpy"))
    write_json(result, out)
    s = result["summary"]
    typer.echo(f"{s['ok']} ok, {s['skipped']} skipped, {s['error']} error", err=True)
    if s["error"]:
        for r in result["results"]:
            if r["status"] == "error":
                typer.echo(f"error: {r['id']}: {r['error']['field']}: {r['error']['detail']}", err=True)
        raise typer.Exit(1)


def register(app: typer.Typer) -> None:
    """Add ``rcsa library ...`` to ``app``."""
    app.add_typer(library_app, name="library", help="Tool-point FRFs of whole CAM tool libraries.")
