"""``rcsa library predict|sync|show|export|recommend``: whole CAM tool libraries (Autodesk Fusion, FreeCAD).

LIBRARY is a Fusion library (``.json`` or ``.tools``) or a FreeCAD one: a toolbit ``.fctb``, a
library ``.fctl`` (its toolbits next to it or in ``../Bit``), a folder or a zip of toolbits;
its holder is the one ``.fcholder`` in the folder or zip, or ``--holder H.fcholder``, and
FreeCAD stores no stickout: ``--options '{"stickout_m": 0.04}'`` (or per toolbit id).

``rcsa library predict LIBRARY --spindle SPINDLE.json | --measurement ID``: tool-point FRFs
of every tool of the library on one spindle, computed
here (no service needed), with a progress bar on stderr. The result JSON (one entry per
library item: ``ok``, ``skipped`` with a reason, or ``error``) goes to stdout or ``-o
OUT.json`` (``-o OUT.h5`` or ``OUT.parquet``: the same as HDF5 or Parquet); the exit status is
1 when any tool errored.

``rcsa library sync LIBRARY --spindle ID-or-SPINDLE.json [--library-id ID]``: keep the
library in the store (:func:`rcsa.app.libraries.prepare_sync`, the same code as ``POST
/v1/libraries/{id}:sync``): only tools whose result is not stored yet are computed; the
added / changed / unchanged / removed summary goes to stderr, the sync report (JSON) to
stdout (``-o OUT.json``: there; ``-o OUT.h5|.parquet``: the synced results written there, the
report to stdout); exit status 1 when any tool failed. ``--dask-scheduler tcp://HOST:8786`` (or
``RCSA_DASK_SCHEDULER``) computes on that Dask cluster instead of here; the results are
written here, the same bytes either way. ``rcsa library show ID`` prints a stored
library's summary and per-tool status; ``rcsa library export ID -o FILE.h5|.parquet|.zip|.json``
writes its results (HDF5, Parquet, zip of UFF 58 files, or JSON).

``rcsa library recommend LIBRARY --material M --max-rpm N (--spindle S | --measurement ID |
--library-id ID) (-o OUT | --in-place)``: chatter-safe presets (:mod:`rcsa.app.presets`). Per
milling tool, the best stable pocket of its stability lobes (tool-point FRF predicted now on
the spindle, or stored by a sync of ``--library-id``) is written into the Fusion library as a
preset named ``rcsa chatter-safe: <material>`` (re-running replaces it; nothing else in the
file changes). The report (JSON) goes to stdout or ``--report``; a one-line summary per tool
to stderr; exit status 1 when a tool failed.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any

import typer

from rcsa.cli._common import (
    DaskOption,
    DaskTimeoutOption,
    QuietOption,
    WorkersOption,
    command_group,
    fail,
    read_json,
    run_guarded,
    write_json,
    write_results,
    wrote,
)
from rcsa.errors import InputError

if TYPE_CHECKING:
    from rcsa.app.jobs import Workbench
    from rcsa.app.presets import PresetFile

__all__ = ["library_app", "register"]

library_app = command_group("Tool-point FRFs of whole CAM tool libraries (Autodesk Fusion, FreeCAD): predict them, "
                            "keep them in the store, export them, write chatter-safe presets.",
                            short_help="Tool-point FRFs and presets of whole CAM tool libraries.")


def written_preset_line(tool: dict[str, Any]) -> str:
    """The line the recommendation prints for a written preset (a report's tool entry): speed, stepdown,
    the limit it comes from and the pocket, saying where the pocket was followed no further.

    >>> written_preset_line({"id": "t1", "spindle_speed_rpm": 23930, "depth_limit_m": 5.6e-4, "safety_factor": 1.25,
    ...     "stepdown": {"value": 0.448, "unit": "millimeters"},
    ...     "pocket": {"low_rpm": 11965.0, "high_rpm": 24720.0, "low_open": True, "high_open": False}})
    't1: 23930 rpm, stepdown 0.448 millimeters (limit 0.56 mm / 1.25, pocket 11965-24720 rpm, followed no further below)'
    """
    sd, pocket = tool["stepdown"], tool["pocket"]
    open_ends = [end for end, key in (("below", "low_open"), ("above", "high_open")) if pocket.get(key)]
    return (f"{tool['id']}: {tool['spindle_speed_rpm']} rpm, stepdown {sd['value']:g} {sd['unit']} "
            f"(limit {tool['depth_limit_m'] * 1e3:.3g} mm / {tool['safety_factor']:g}, pocket "
            f"{pocket['low_rpm']:.0f}-{pocket['high_rpm']:.0f} rpm"
            + (f", followed no further {' and '.join(open_ends)}" if open_ends else "") + ")")


def parse_frequency_option(text: str) -> dict[str, Any]:
    """``START:STOP:STEP`` (Hz, stop included) or a JSON frequency object."""
    # rcsa.app is imported when the command runs, not with the module: `rcsa --help` stays fast
    from rcsa.app.inputs import decode_json
    text = text.strip()
    if text.startswith("{"):
        doc: dict[str, Any] = decode_json(text, path="frequency", what="--frequency")
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


def _wrote_to(out: Path | None, what: str) -> str:
    """``"wrote <what> to <out>: "`` when a result went to a file, for a command's summary line."""
    return "" if out is None else f"wrote {what} to {out}: "


def _spindle_document(path: Path) -> dict[str, Any]:
    """A spindle JSON, or an assembly JSON whose spindle (and grid, joints, materials) are used."""
    doc = read_json(path)
    if not isinstance(doc, dict):
        raise fail(f"{path}: expected a JSON object (a spindle or an assembly)")
    if "spindle" in doc:
        return doc
    return {"spindle": doc}


def _options_json(options: str | None) -> dict[str, Any] | None:
    # rcsa.app is imported when the command runs, not with the module: `rcsa --help` stays fast
    from rcsa.app.inputs import decode_json
    if options is None:
        return None
    doc: dict[str, Any] | None = decode_json(options, path="options", what="--options")
    return doc


def _uncertainty_json(option: str | None) -> dict[str, Any] | None:
    from rcsa.app.inputs import decode_json  # when the command runs (`rcsa --help` stays fast)
    if option is None:
        return None
    doc: dict[str, Any] | None = decode_json(option, path="uncertainty", what="--uncertainty")
    return doc


def _settings(base: dict[str, Any], frequency: str | None, joints: Path | None, store: Any,
              holder_tool: str | None = None) -> dict[str, Any]:
    """Keyword arguments of :func:`rcsa.app.libraries.prepare_library` from the command's options.

    ``store`` is given when the spindle is a stored measurement named on the command line;
    its lines are then the default grid. ``holder_tool`` is a clamping model name or a JSON
    ``joints.holder_tool`` object for every tool.
    """
    # rcsa.app is imported when the command runs, not with the module: `rcsa --help` stays fast
    from rcsa.app.inputs import decode_json
    from rcsa.app.libraries import spindle_settings
    ht: Any = holder_tool
    if holder_tool is not None and holder_tool.lstrip().startswith("{"):
        ht = decode_json(holder_tool, path="holder_tool", what="--holder-tool")
    return spindle_settings(base, frequency=parse_frequency_option(frequency) if frequency is not None else None,
                            joints=read_json(joints) if joints is not None else None, holder_tool=ht, store=store)


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
HolderToolOption = Annotated[str | None, typer.Option(
    "--holder-tool", help="Every tool's holder-tool clamping: bonded, point, or a JSON joints.holder_tool object, "
                          "e.g. '{\"model\": \"contact\", \"interface_stiffness_n_m3\": 5e13}' (replaces the "
                          "joints' own).")]
ImportOptions = Annotated[str | None, typer.Option(
    help='Import options as JSON, e.g. \'{"holder_segments_per_cone": 6}\'.')]
NaturalFrequenciesOption = Annotated[bool, typer.Option(help="Compute exact natural frequencies.")]
UncertaintyOption = Annotated[str | None, typer.Option(
    help='Every tool\'s uncertainty band as JSON, e.g. \'{"draws": 200, "seed": 1}\' (p05/p50/p95 of |h|).')]
LibraryArgument = Annotated[Path, typer.Argument(metavar="LIBRARY", help="Fusion tool library (.json, .tools) or FreeCAD toolbits "
                                                      "(.fctb, .fctl, a folder or a zip of them).")]
HolderOption = Annotated[Path | None, typer.Option(help="FreeCAD holder (.fcholder) for the toolbits, when the "
                                                       "library has none.")]


@library_app.command("predict", short_help="Tool-point FRFs of every tool of a library, now.")
def predict(
    library: LibraryArgument,
    spindle: Annotated[Path | None, typer.Option(help="Spindle JSON (segments + bearings), or an assembly "
                                                      "JSON whose spindle, frequency, joints and materials "
                                                      "are used.")] = None,
    measurement: Annotated[str | None, typer.Option(help="Instead of --spindle: a stored measurement id "
                                                         "(hybrid).")] = None,
    frequency: FrequencyOption = None,
    joints: JointsOption = None,
    holder_tool: HolderToolOption = None,
    options: ImportOptions = None,
    natural_frequencies: NaturalFrequenciesOption = True,
    uncertainty: UncertaintyOption = None,
    out: Annotated[Path | None, typer.Option("-o", "--out", help=(
        "Write the result here instead of stdout: OUT.json, OUT.h5 (HDF5) or OUT.parquet (needs "
        "rcsa[parquet])."))] = None,
    store: Annotated[Path | None, typer.Option("--store", help="Measurement store (default: RCSA_STORE or "
                                                               "the per-user store).")] = None,
    quiet: QuietOption = False,
    dask_scheduler: DaskOption = None,
    dask_connect_timeout: DaskTimeoutOption = 10.0,
    workers: WorkersOption = 0,
    holder: HolderOption = None,
) -> None:
    """Predict the tool-point FRF of every tool in a Fusion or FreeCAD library on one spindle."""
    # rcsa.app is imported when the command runs, not with the module: `rcsa --help` stays fast
    from rcsa.app.jobs import Workbench, run_work
    from rcsa.app.libraries import prepare_library
    from rcsa.app.stores import open_store
    from rcsa.infra.compute_backends import compute_backend
    if (spindle is None) == (measurement is None):
        raise fail("give exactly one of --spindle SPINDLE.json or --measurement ID")
    base = _spindle_document(spindle) if spindle is not None else {"spindle": {"measurement_id": measurement}}

    def build() -> tuple[Workbench, Any]:
        bench = Workbench(open_store(store) if (store is not None or measurement is not None) else None)
        settings = _settings(base, frequency, joints, bench.store if measurement is not None else None, holder_tool)
        work = prepare_library(bench, library, holder=holder, **settings,
                               natural_frequencies=natural_frequencies, options=_options_json(options),
                               uncertainty=_uncertainty_json(uncertainty))
        if work.check is not None:
            work.check()  # before the progress bar starts
        return bench, work

    if out is not None:
        from rcsa.app.results import format_of_suffix, require_format
        run_guarded(lambda: require_format(format_of_suffix(out)))  # before computing anything
    bench, work = run_guarded(build)
    backend = run_guarded(lambda: compute_backend(dask_scheduler, connect_timeout_s=dask_connect_timeout,
                                                  workers=workers))
    with _progress_bar(quiet) as bar:
        task = bar.add_task("tools", total=max(work.size, 1))

        def progress(done: int, total: int) -> None:
            bar.update(task, completed=done, total=max(total, 1))

        try:
            result = run_guarded(lambda: run_work(bench, work.kind, work.request, progress=progress,
                                                  backend=backend)).document
        finally:
            backend.close()
    write_results(result, out, "library", None)  # the summary line below says where
    s = result["summary"]
    typer.echo(f"{_wrote_to(out, 'the library results')}{s['ok']} ok, {s['skipped']} skipped, {s['error']} error",
               err=True)
    if s["error"]:
        for r in result["results"]:
            if r["status"] == "error":
                typer.echo(f"error: {r['id']}: {r['error']['field']}: {r['error']['detail']}", err=True)
        raise typer.Exit(1)


StoreOption = Annotated[Path | None, typer.Option("--store", help="Store directory (default: RCSA_STORE or the "
                                                                   "per-user store).")]


@library_app.command("sync", short_help="Keep a library's FRFs in the store; compute only changes.")
def sync(
    library: LibraryArgument,
    spindle: Annotated[str, typer.Option(help="A stored measurement id (m-..., hybrid), or a spindle JSON "
                                              "(segments + bearings) or assembly JSON whose spindle, frequency, "
                                              "joints and materials are used.")],
    library_id: Annotated[str | None, typer.Option("--library-id", help="Id of the stored library (default: the "
                                                                        "file name without suffix).")] = None,
    frequency: FrequencyOption = None,
    joints: JointsOption = None,
    holder_tool: HolderToolOption = None,
    options: ImportOptions = None,
    natural_frequencies: NaturalFrequenciesOption = True,
    uncertainty: UncertaintyOption = None,
    out: Annotated[Path | None, typer.Option("-o", "--out", help=(
        "OUT.json: write the sync report here instead of stdout. OUT.h5 or OUT.parquet: write the synced "
        "library's results there (as rcsa library export does) and the report to stdout."))] = None,
    store: StoreOption = None,
    quiet: QuietOption = False,
    dask_scheduler: DaskOption = None,
    dask_connect_timeout: DaskTimeoutOption = 10.0,
    workers: WorkersOption = 0,
    holder: HolderOption = None,
) -> None:
    """Keep a library's tool-point FRFs in the store, computing only new or changed tools."""
    # rcsa.app is imported when the command runs, not with the module: `rcsa --help` stays fast
    from rcsa.app.jobs import Workbench, run_work
    from rcsa.app.libraries import prepare_sync
    from rcsa.app.stores import open_store, spindle_reference
    from rcsa.infra.compute_backends import compute_backend
    stored = spindle_reference(spindle)
    measurement = spindle if stored is not None else None
    base = stored if stored is not None else _spindle_document(Path(spindle))

    def build() -> tuple[Workbench, Any]:
        st = open_store(store)
        bench = Workbench(st, st.path)
        settings = _settings(base, frequency, joints, st if measurement is not None else None, holder_tool)
        work = prepare_sync(bench, library_id, library, holder=holder, **settings,
                            natural_frequencies=natural_frequencies, options=_options_json(options),
                            uncertainty=_uncertainty_json(uncertainty))
        if work.size and work.check is not None:
            work.check()  # before the progress bar starts
        return bench, work

    binary = out if out is not None and out.suffix.lower() != ".json" else None
    if binary is not None:
        from rcsa.app.results import format_of_suffix, require_format
        run_guarded(lambda: require_format(format_of_suffix(binary, allowed=("hdf5", "parquet"))))
    bench, work = run_guarded(build)
    ident = work.request["library_id"]
    backend = run_guarded(lambda: compute_backend(dask_scheduler if work.size else None,
                                                  connect_timeout_s=dask_connect_timeout, workers=workers))
    with _progress_bar(quiet) as bar:
        task = bar.add_task(f"{ident}: computing", total=max(work.size, 1))

        def progress(done: int, total: int) -> None:
            bar.update(task, completed=done, total=max(total, 1))

        try:
            report = run_guarded(lambda: run_work(bench, work.kind, work.request, progress=progress,
                                                  plan=work.plan, backend=backend)).document
        finally:
            backend.close()
    if binary is not None:
        from rcsa.app.libraries import write_export
        from rcsa.app.stores import library_store
        try:
            run_guarded(lambda: write_export(library_store(store), ident, binary))
        except OSError as exc:
            raise fail(f"cannot write {out}: {exc.strerror or exc}") from None
    write_json(report, None if binary is not None else out, None)  # the summary line below says where
    c, s = report["counts"], report["summary"]
    written = _wrote_to(out, "the library results" if binary else "the sync report")
    typer.echo(f"{written}{ident} revision {report['revision']}: {c['added']} added, {c['changed']} changed, "
               f"{c['unchanged']} unchanged, {c['removed']} removed ({report['computed']} computed, "
               f"{report['from_cache']} from cache; {s['ok']} ok, {s['skipped']} skipped, {s['error']} error)",
               err=True)
    if report["failed"]:
        for f in report["failed"]:
            error = f.get("error") or {}
            typer.echo(f"error: {f['id']}: {error.get('field', '')}: {error.get('detail', '')}", err=True)
        raise typer.Exit(1)


@library_app.command("show", short_help="A stored library's summary and every tool's status.")
def show(
    library_id: Annotated[str, typer.Argument(metavar="LIBRARY_ID", help="Id of a stored library.")],
    store: StoreOption = None,
    out: Annotated[Path | None, typer.Option("-o", "--out", help="Write here instead of stdout.")] = None,
) -> None:
    """Print a stored library's summary and every tool's status (JSON)."""
    # rcsa.app is imported when the command runs, not with the module: `rcsa --help` stays fast
    from rcsa.app.stores import library_store
    write_json(run_guarded(lambda: library_store(store).get(library_id)), out, "the library summary")


@library_app.command("export", short_help="Write a stored library's results: HDF5, Parquet, UFF zip, JSON.")
def export(
    library_id: Annotated[str, typer.Argument(metavar="LIBRARY_ID", help="Id of a stored library.")],
    out: Annotated[Path, typer.Option("-o", "--out", help="FILE.h5 (HDF5), FILE.parquet (needs rcsa[parquet]), "
                                                          "FILE.zip (one UFF 58 file per tool) or FILE.json.")],
    store: StoreOption = None,
) -> None:
    """Write a stored library's results to a file; the format follows its suffix."""
    # rcsa.app is imported when the command runs, not with the module: `rcsa --help` stays fast
    from rcsa.app.libraries import EXPORT_FORMATS, write_export
    from rcsa.app.stores import library_store
    if out.suffix.lower() not in EXPORT_FORMATS:
        raise fail(f"{out}: the file name must end in {', '.join(EXPORT_FORMATS)}")
    try:
        export = run_guarded(lambda: write_export(library_store(store), library_id, out))
    except OSError as exc:
        raise fail(f"cannot write {out}: {exc.strerror or exc}") from None
    ok = export.ok
    wrote(out, f"{ok} tool{'s' if ok != 1 else ''} of {library_id} revision {export.revision}")


@library_app.command("recommend", short_help="Write chatter-safe presets into a Fusion library.")
def recommend(
    library: Annotated[Path, typer.Argument(metavar="LIBRARY", help="Autodesk Fusion tool library (.json or .tools).")],
    material: Annotated[str, typer.Option(help="Workpiece material: a table entry (aluminium-7075, aluminium-6082, "
                                               "carbon-steel, ...; see docs/presets.md) or your own name with "
                                               "--tangential-coefficient-n-m2 and --radial-ratio.")],
    max_rpm: Annotated[float, typer.Option(help="The machine's highest spindle speed, rpm.")],
    spindle: Annotated[Path | None, typer.Option(help="Predict the FRFs now on this spindle JSON (or assembly JSON "
                                                      "whose spindle, frequency, joints and materials are used).")
                       ] = None,
    measurement: Annotated[str | None, typer.Option(help="Predict the FRFs now on this stored measurement "
                                                         "(hybrid).")] = None,
    library_id: Annotated[str | None, typer.Option("--library-id", help="Use the FRFs stored by the last sync of "
                                                                        "this library id.")] = None,
    out: Annotated[Path | None, typer.Option("-o", "--out", help="Write the library with the presets here.")] = None,
    in_place: Annotated[bool, typer.Option("--in-place", help="Write the presets into LIBRARY itself.")] = False,
    report: Annotated[Path | None, typer.Option(help="Write the report here instead of stdout.")] = None,
    min_rpm: Annotated[float, typer.Option(help="The machine's lowest spindle speed to consider, rpm.")] = 1000.0,
    tangential_coefficient_n_m2: Annotated[float | None, typer.Option(
        help="Kt (K_tc of the linear edge-force model), N/m²; with --radial-ratio, instead of the table's.")] = None,
    radial_ratio: Annotated[float | None, typer.Option(help="Kr = K_rc / K_tc.")] = None,
    radial_immersion: Annotated[float, typer.Option(help="Radial depth of cut / diameter, a_e/D.")] = 0.5,
    milling: Annotated[str, typer.Option(help="down or up.")] = "down",
    safety_factor: Annotated[float, typer.Option(help="Stepdown = depth limit / this (>= 1).")] = 1.25,
    speed_tolerance: Annotated[float, typer.Option(help="Relative speed window that must stay stable (0.03 = "
                                                        "±3 %).")] = 0.03,
    max_surface_speed: Annotated[float | None, typer.Option(help="Surface-speed limit v_c, m/min (default: the "
                                                                 "table's, carbide tools only).")] = None,
    feed_per_tooth_mm: Annotated[float | None, typer.Option(help="Feed per tooth for the preset's feeds, mm "
                                                                 "(default: f_z of the tool's own preset).")] = None,
    method: Annotated[str, typer.Option(help="Lobe method: auto (zoa only where it is exact, even-toothed "
                                             "slotting; else semi_discretization), zoa or semi_discretization.")
                      ] = "auto",
    uncertainty: UncertaintyOption = None,
    confidence: Annotated[float | None, typer.Option(help="With --uncertainty: choose the pocket on the robust "
                                                          "depth limit at this confidence (default 0.95).")] = None,
    frequency: FrequencyOption = None,
    joints: JointsOption = None,
    holder_tool: HolderToolOption = None,
    options: ImportOptions = None,
    store: StoreOption = None,
    quiet: QuietOption = False,
    dask_scheduler: DaskOption = None,
    dask_connect_timeout: DaskTimeoutOption = 10.0,
    workers: WorkersOption = 0,
) -> None:
    """Write chatter-safe presets (spindle speed and stepdown in a stable pocket) into a Fusion library."""
    # rcsa.app is imported when the command runs, not with the module: `rcsa --help` stays fast
    from rcsa.app.jobs import Workbench
    from rcsa.app.presets import (
        check_recommendation,
        recommend_predicted,
        recommend_stored,
        write_preset_file,
    )
    from rcsa.app.stores import open_store
    from rcsa.infra.compute_backends import compute_backend
    if sum(x is not None for x in (spindle, measurement, library_id)) != 1:
        raise fail("give exactly one of --spindle SPINDLE.json, --measurement ID or --library-id ID")
    if (out is None) == (not in_place):
        raise fail("give exactly one of -o OUT (a new file) or --in-place (write into LIBRARY)")
    target = library if in_place else out
    settings = {"material": material, "max_rpm": max_rpm, "min_rpm": min_rpm,
                "tangential_coefficient_n_m2": tangential_coefficient_n_m2, "radial_ratio": radial_ratio,
                "radial_immersion": radial_immersion, "milling": milling, "safety_factor": safety_factor,
                "speed_tolerance": speed_tolerance, "max_surface_speed_m_min": max_surface_speed,
                "feed_per_tooth_m": None if feed_per_tooth_mm is None else feed_per_tooth_mm * 1e-3, "method": method,
                "uncertainty": _uncertainty_json(uncertainty), "confidence": confidence}
    settings = {k: v for k, v in settings.items() if v is not None}
    try:
        data = library.read_bytes()
    except OSError as exc:
        raise fail(f"cannot read {library}: {exc.strerror or exc}") from None
    run_guarded(lambda: check_recommendation(data, settings, file_name=library.name))  # before any progress bar

    backend = run_guarded(lambda: compute_backend(dask_scheduler, connect_timeout_s=dask_connect_timeout,
                                                  workers=workers))

    def stored() -> PresetFile:
        st = open_store(store)
        return recommend_stored(Workbench(st, st.path, backend=backend), str(library_id), data, settings,
                                file_name=library.name)

    def predicted() -> PresetFile:
        base = _spindle_document(spindle) if spindle is not None else {"spindle": {"measurement_id": measurement}}
        bench = Workbench(open_store(store) if (store is not None or measurement is not None) else None,
                          backend=backend)
        fields = _settings(base, frequency, joints, bench.store if measurement is not None else None, holder_tool)
        with _progress_bar(quiet) as bar:
            task = bar.add_task("tools", total=1)

            def progress(done: int, total: int) -> None:
                bar.update(task, completed=done, total=max(total, 1))

            return recommend_predicted(bench, data, settings, file_name=library.name, progress=progress,
                                       import_options=_options_json(options), **fields)

    try:
        result = run_guarded(stored if library_id is not None else predicted)
    finally:
        backend.close()
    try:
        write_preset_file(result, target)  # type: ignore[arg-type]
    except OSError as exc:
        raise fail(f"cannot write {target}: {exc.strerror or exc}") from None
    write_json(result.report, report, "the recommendation report")
    for t in result.report["tools"]:
        if t["status"] == "written":
            typer.echo(written_preset_line(t), err=True)
        else:
            typer.echo(f"{t['id']}: {t['status']}: {t['reason']}", err=True)
    s = result.report["summary"]
    typer.echo(f"{target}: {s['written']} preset{'s' if s['written'] != 1 else ''} written, {s['skipped']} "
               f"skipped, {s['failed']} failed", err=True)
    if s["failed"]:
        raise typer.Exit(1)


def register(app: typer.Typer) -> None:
    """Add ``rcsa library ...`` to ``app``."""
    app.add_typer(library_app, name="library")
