"""``rcsa library predict|sync|show|export``: whole Autodesk Fusion tool libraries.

``rcsa library predict LIBRARY --spindle SPINDLE.json | --measurement ID``: tool-point FRFs
of every tool of a Fusion tool library (``.json`` or ``.tools``) on one spindle, computed
here (no service needed), with a progress bar on stderr. The result JSON (one entry per
library item: ``ok``, ``skipped`` with a reason, or ``error``) goes to stdout or ``-o
OUT.json``; the exit status is 1 when any tool errored.

``rcsa library sync LIBRARY --spindle ID-or-SPINDLE.json [--library-id ID]``: keep the
library in the store (:func:`rcsa.app.libraries.prepare_sync`, the same code as ``POST
/v1/libraries/{id}:sync``): only tools whose result is not stored yet are computed; the
added / changed / unchanged / removed summary goes to stderr, the sync report (JSON) to
stdout; exit status 1 when any tool failed. ``rcsa library show ID`` prints a stored
library's summary and per-tool status; ``rcsa library export ID -o FILE.h5|.zip|.json``
writes its results (HDF5, zip of UFF 58 files, or JSON).
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Annotated, Any

import typer

from rcsa.cli._common import fail, read_json, run_guarded, write_json
from rcsa.errors import InputError

__all__ = ["library_app", "register"]

library_app = typer.Typer(help="Tool-point FRFs of whole CAM tool libraries.", no_args_is_help=True,
                          add_completion=False, pretty_exceptions_enable=False)


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


def _options_json(options: str | None) -> dict[str, Any] | None:
    if options is None:
        return None
    try:
        return json.loads(options)
    except ValueError as exc:
        raise InputError("options", f"not valid JSON ({exc})") from None


def _settings(base: dict[str, Any], frequency: str | None, joints: Path | None, store: Any) -> dict[str, Any]:
    """Keyword arguments of :func:`rcsa.app.libraries.prepare_library` from the command's options.

    ``store`` is given when the spindle is a stored measurement named on the command line;
    its lines are then the default grid.
    """
    # rcsa.app is imported when the command runs, not with the module: `rcsa --help` stays fast
    from rcsa.app.libraries import spindle_settings
    return spindle_settings(base, frequency=parse_frequency_option(frequency) if frequency is not None else None,
                            joints=read_json(joints) if joints is not None else None, store=store)


def _progress_bar(quiet: bool) -> Any:
    # rich: only when a command computes (``rcsa --help`` and the other commands do without it)
    from rich.console import Console
    from rich.progress import (
        BarColumn,
        MofNCompleteColumn,
        Progress,
        TextColumn,
        TimeRemainingColumn,
    )

    return Progress(TextColumn("[progress.description]{task.description}"), BarColumn(), MofNCompleteColumn(),
                    TimeRemainingColumn(), transient=True, disable=quiet, console=Console(stderr=True))


FrequencyOption = Annotated[str | None, typer.Option(
    help="START:STOP:STEP in Hz (stop included) or a JSON frequency object. Default: the assembly's, else the "
         "measurement's lines, else 5:5000:1.")]
JointsOption = Annotated[Path | None, typer.Option(
    help="Joints JSON {spindle_holder, holder_tool} for every tool (default: the assembly's, else rigid).")]
ImportOptions = Annotated[str | None, typer.Option(
    help='Import options as JSON, e.g. \'{"holder_segments_per_cone": 6}\'.')]
NaturalFrequenciesOption = Annotated[bool, typer.Option(help="Compute exact natural frequencies.")]
QuietOption = Annotated[bool, typer.Option("--quiet", "-q", help="No progress bar.")]


@library_app.command("predict")
def predict(
    library: Annotated[Path, typer.Argument(help="Fusion tool library: .json, or .tools (zip).")],
    spindle: Annotated[Path | None, typer.Option(help="Spindle JSON (segments + bearings), or an assembly "
                                                      "JSON whose spindle, frequency, joints and materials "
                                                      "are used.")] = None,
    measurement: Annotated[str | None, typer.Option(help="Instead of --spindle: a stored measurement id "
                                                         "(hybrid).")] = None,
    frequency: FrequencyOption = None,
    joints: JointsOption = None,
    options: ImportOptions = None,
    natural_frequencies: NaturalFrequenciesOption = True,
    out: Annotated[Path | None, typer.Option("-o", "--out", help="Write the result here instead of stdout.")] = None,
    store: Annotated[Path | None, typer.Option("--store", help="Measurement store (default: RCSA_STORE or "
                                                               "the per-user store).")] = None,
    quiet: QuietOption = False,
) -> None:
    """Predict the tool-point FRF of every tool in a Fusion library on one spindle."""
    # rcsa.app is imported when the command runs, not with the module: `rcsa --help` stays fast
    from rcsa.app.jobs import Workbench, run_work
    from rcsa.app.libraries import prepare_library
    from rcsa.app.stores import open_store
    if (spindle is None) == (measurement is None):
        raise fail("give exactly one of --spindle SPINDLE.json or --measurement ID")
    base = _spindle_document(spindle) if spindle is not None else {"spindle": {"measurement_id": measurement}}

    def build() -> tuple[Workbench, Any]:
        bench = Workbench(open_store(store) if (store is not None or measurement is not None) else None)
        settings = _settings(base, frequency, joints, bench.store if measurement is not None else None)
        work = prepare_library(bench, library, **settings, natural_frequencies=natural_frequencies,
                               options=_options_json(options))
        if work.check is not None:
            work.check()  # before the progress bar starts
        return bench, work

    bench, work = run_guarded(build)
    with _progress_bar(quiet) as bar:
        task = bar.add_task("tools", total=max(work.size, 1))

        def progress(done: int, total: int) -> None:
            bar.update(task, completed=done, total=max(total, 1))

        result = run_guarded(lambda: run_work(bench, work.kind, work.request, progress=progress)).document
    write_json(result, out)
    s = result["summary"]
    typer.echo(f"{s['ok']} ok, {s['skipped']} skipped, {s['error']} error", err=True)
    if s["error"]:
        for r in result["results"]:
            if r["status"] == "error":
                typer.echo(f"error: {r['id']}: {r['error']['field']}: {r['error']['detail']}", err=True)
        raise typer.Exit(1)


StoreOption = Annotated[Path | None, typer.Option("--store", help="Store directory (default: RCSA_STORE or the "
                                                                   "per-user store).")]


@library_app.command("sync")
def sync(
    library: Annotated[Path, typer.Argument(help="Fusion tool library: .json, or .tools (zip).")],
    spindle: Annotated[str, typer.Option(help="A stored measurement id (m-..., hybrid), or a spindle JSON "
                                              "(segments + bearings) or assembly JSON whose spindle, frequency, "
                                              "joints and materials are used.")],
    library_id: Annotated[str | None, typer.Option("--library-id", help="Id of the stored library (default: the "
                                                                        "file name without suffix).")] = None,
    frequency: FrequencyOption = None,
    joints: JointsOption = None,
    options: ImportOptions = None,
    natural_frequencies: NaturalFrequenciesOption = True,
    out: Annotated[Path | None, typer.Option("-o", "--out", help="Write the sync report here instead of "
                                                                 "stdout.")] = None,
    store: StoreOption = None,
    quiet: QuietOption = False,
) -> None:
    """Keep a Fusion library's tool-point FRFs in the store, computing only new or changed tools."""
    # rcsa.app is imported when the command runs, not with the module: `rcsa --help` stays fast
    from rcsa.app.jobs import Workbench, run_work
    from rcsa.app.libraries import library_id_from_name, prepare_sync
    from rcsa.app.stores import is_measurement_id, open_store
    measurement = spindle if is_measurement_id(spindle) else None
    base = {"spindle": {"measurement_id": measurement}} if measurement else _spindle_document(Path(spindle))
    ident = library_id if library_id is not None else library_id_from_name(library)

    def build() -> tuple[Workbench, Any]:
        st = open_store(store)
        bench = Workbench(st, st.path)
        settings = _settings(base, frequency, joints, st if measurement is not None else None)
        work = prepare_sync(bench, ident, library, **settings, natural_frequencies=natural_frequencies,
                            options=_options_json(options))
        if work.size and work.check is not None:
            work.check()  # before the progress bar starts
        return bench, work

    bench, work = run_guarded(build)
    with _progress_bar(quiet) as bar:
        task = bar.add_task(f"{ident}: computing", total=max(work.size, 1))

        def progress(done: int, total: int) -> None:
            bar.update(task, completed=done, total=max(total, 1))

        report = run_guarded(lambda: run_work(bench, work.kind, work.request, progress=progress,
                                              plan=work.plan)).document
    write_json(report, out)
    c, s = report["counts"], report["summary"]
    typer.echo(f"{ident} revision {report['revision']}: {c['added']} added, {c['changed']} changed, "
               f"{c['unchanged']} unchanged, {c['removed']} removed ({report['computed']} computed, "
               f"{report['from_cache']} from cache; {s['ok']} ok, {s['skipped']} skipped, {s['error']} error)",
               err=True)
    if report["failed"]:
        for f in report["failed"]:
            error = f.get("error") or {}
            typer.echo(f"error: {f['id']}: {error.get('field', '')}: {error.get('detail', '')}", err=True)
        raise typer.Exit(1)


@library_app.command("show")
def show(
    library_id: Annotated[str, typer.Argument(help="Id of a stored library.")],
    store: StoreOption = None,
    out: Annotated[Path | None, typer.Option("-o", "--out", help="Write here instead of stdout.")] = None,
) -> None:
    """Print a stored library's summary and every tool's status (JSON)."""
    # rcsa.app is imported when the command runs, not with the module: `rcsa --help` stays fast
    from rcsa.app.stores import library_store
    write_json(run_guarded(lambda: library_store(store).get(library_id)), out)


@library_app.command("export")
def export(
    library_id: Annotated[str, typer.Argument(help="Id of a stored library.")],
    out: Annotated[Path, typer.Option("-o", "--out", help="FILE.h5 (HDF5), FILE.zip (one UFF 58 file per tool) "
                                                          "or FILE.json.")],
    store: StoreOption = None,
) -> None:
    """Write a stored library's results to a file; the format follows its suffix."""
    # rcsa.app is imported when the command runs, not with the module: `rcsa --help` stays fast
    from rcsa.app.libraries import EXPORT_FORMATS, write_export
    from rcsa.app.stores import library_store
    if out.suffix.lower() not in EXPORT_FORMATS:
        raise fail(f"{out}: the file name must end in .h5, .hdf5, .zip or .json")
    try:
        export = run_guarded(lambda: write_export(library_store(store), library_id, out))
    except OSError as exc:
        raise fail(f"cannot write {out}: {exc.strerror or exc}") from None
    ok = export.ok
    typer.echo(f"{out}: {ok} tool{'s' if ok != 1 else ''} of {library_id} revision {export.revision}", err=True)


def register(app: typer.Typer) -> None:
    """Add ``rcsa library ...`` to ``app``."""
    app.add_typer(library_app, name="library", help="Tool-point FRFs of whole CAM tool libraries.")
