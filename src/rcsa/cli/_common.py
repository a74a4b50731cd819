"""Shared plumbing of the CLI commands: reading JSON, writing results, one-line errors."""

from __future__ import annotations

import sys
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any, TypeVar

import typer

from rcsa.errors import InputError, NotFoundError, RcsaError

if TYPE_CHECKING:
    from rcsa.app.summaries import Table

__all__ = ["DaskOption", "DaskTimeoutOption", "JsonOption", "QuietOption", "WorkersOption", "emit", "command_group", "fail", "is_terminal", "progress_callback",
           "read_json", "run_guarded", "show_tables", "wrote", "write_json", "write_results"]

#: ``--quiet/-q`` of the commands that draw a progress bar.
QuietOption = Annotated[bool, typer.Option("--quiet", "-q", help="No progress bar on stderr.")]
#: ``--json`` of the commands that print a summary table on a terminal.
JsonOption = Annotated[bool, typer.Option("--json", help=(
    "For machines: the result JSON on stdout (or in -o OUT) and no table, even on a terminal. "
    "Without it the JSON still goes to stdout when stdout is not a terminal (a pipe, a file)."))]

#: ``--dask-scheduler``, ``--dask-connect-timeout`` and ``--workers`` of the commands whose work
#: runs in chunks (:func:`rcsa.infra.compute_backends.compute_backend`).
DaskOption = Annotated[str | None, typer.Option(
    "--dask-scheduler", envvar="RCSA_DASK_SCHEDULER",
    help="Compute on this Dask cluster (tcp://HOST:8786; needs pip install 'rcsa[dask]') instead of here.")]
DaskTimeoutOption = Annotated[float, typer.Option(
    "--dask-connect-timeout", envvar="RCSA_DASK_CONNECT_TIMEOUT_S", min=0.1,
    help="Seconds to try to reach the Dask scheduler before giving up.")]
WorkersOption = Annotated[int, typer.Option(
    "--workers", envvar="RCSA_WORKERS", min=0,
    help="Worker processes on this machine when the work has several chunks (0: one per CPU core; 1: in this "
         "process). Ignored with --dask-scheduler.")]

T = TypeVar("T")


def command_group(help: str, **settings: Any) -> typer.Typer:  # noqa: A002 (typer's name)
    """A ``typer.Typer`` as every rcsa command group is made: help as written (no Rich
    markup: ``rcsa[dask]`` stays as it is, option names are never cut), no shell-completion
    options, errors as one line (``run_guarded``), the group's help when called bare."""
    return typer.Typer(help=help, no_args_is_help=True, add_completion=False, pretty_exceptions_enable=False,
                       rich_markup_mode=None, **settings)


def wrote(path: Path | str, what: str) -> None:
    """Say on stderr, in one line, what a command wrote where (stdout stays the result's)."""
    typer.echo(f"wrote {what} to {path}", err=True)


def fail(message: str, code: int = 1) -> typer.Exit:
    """Print ``error: message`` (one line) on stderr and return the exit to raise."""
    typer.echo(f"error: {' '.join(str(message).split())}", err=True)
    return typer.Exit(code)


def read_json(path: Path) -> Any:
    """Parse a JSON file, or fail with a one-line reason."""
    try:
        text = sys.stdin.read() if str(path) == "-" else path.read_text(encoding="utf-8")
    except OSError as exc:
        raise fail(f"cannot read {path}: {exc.strerror or exc}") from None
    # rcsa.app is imported when a command runs, not with the CLI: `rcsa --help` stays fast
    from rcsa.app.inputs import decode_json

    try:  # the service's JSON policy: no NaN/Infinity, numbers within range, nesting bounded
        return decode_json(text, what=str(path))
    except InputError as exc:
        raise fail(f"{path}: {exc}") from None


def write_json(document: Any, out: Path | None, what: str | None = "the result") -> None:
    """Write a JSON document to ``out`` (saying so on stderr, unless ``what`` is None), or to
    stdout when ``out`` is None.

    Indented; numpy arrays (and a Prediction) are written straight to bytes
    (:func:`rcsa.app.results.json_bytes`).
    """
    # rcsa.app is imported when a command runs, not with the CLI: `rcsa --help` stays fast
    from rcsa.app.results import json_bytes

    data = json_bytes(document, indent=True)
    if out is None:
        sys.stdout.buffer.write(data + b"\n")
        sys.stdout.flush()
    else:
        try:
            out.write_bytes(data + b"\n")
        except OSError as exc:
            raise fail(f"cannot write {out}: {exc.strerror or exc}") from None
        if what is not None:
            wrote(out, what)


def write_results(document: Any, out: Path | None, kind: str, what: str | None = "the result") -> None:
    """Write a batch or library result to ``out`` in the form its suffix names (``.json``,
    ``.h5``/``.hdf5``, ``.parquet``), or as JSON to stdout when ``out`` is None; say so on
    stderr (``what``; None when the caller's own summary line says it)."""
    if out is None or out.suffix.lower() == ".json":
        write_json(document, out, what)
        return
    from rcsa.app.results import write_result  # when a command runs: `rcsa --help` stays fast

    try:
        run_guarded(lambda: write_result(document, out, kind))
    except OSError as exc:
        raise fail(f"cannot write {out}: {exc.strerror or exc}") from None
    if what is not None:
        wrote(out, what)


def is_terminal(stream: Any) -> bool:
    """Whether ``stream`` is an interactive terminal (where a person reads a table)."""
    try:
        return bool(stream.isatty())
    except (AttributeError, ValueError):  # no isatty, or closed
        return False


def show_tables(tables: list[Table], stream: Any) -> None:
    """Draw :class:`rcsa.app.summaries.Table` s as rich tables on ``stream``."""
    # rich: only when a command has something to show (``rcsa --help`` stays fast)
    from rich.console import Console
    from rich.table import Table as RichTable

    console = Console(file=stream, highlight=False, soft_wrap=False)
    for table in tables:
        drawn = RichTable(title=table.title, caption=table.caption or None, title_justify="left",
                          caption_justify="left", show_header=any(table.columns), min_width=len(table.title) + 4)
        for i, column in enumerate(table.columns):
            drawn.add_column(column, justify="left" if i == 0 else "right", overflow="fold")
        for row in table.rows:
            drawn.add_row(*row)
        console.print(drawn)


def emit(document: Any, out: Path | None, *, what: str, tables: Callable[[], list[Table]], as_json: bool,
           kind: str | None = None) -> None:
    """Write a result for machines and show its summary to a person.

    The JSON goes to ``out`` when given (as :func:`write_results`, ``kind`` naming a batch's
    binary forms), else to stdout when ``as_json`` (``--json``) or when stdout is not a
    terminal — so a pipe or a redirect always gets the JSON, as the contract's CLI says. The
    summary ``tables()`` go to the terminal: stdout when it is one and the JSON is not going
    there, else stderr when that is one; never with ``as_json``. On a terminal without ``-o``
    or ``--json`` only the table is printed, and a line on stderr says how to get the JSON.
    """
    to_stdout = out is None and (as_json or not is_terminal(sys.stdout))
    if out is not None and kind is not None:
        write_results(document, out, kind, what)
    elif out is not None:
        write_json(document, out, what)
    elif to_stdout:
        write_json(document, None)
    if as_json:
        return
    screen = sys.stdout if is_terminal(sys.stdout) and not to_stdout else \
        sys.stderr if is_terminal(sys.stderr) else None
    if screen is not None:
        show_tables(tables(), screen)
    if out is None and not to_stdout:
        typer.echo(f"({what} as JSON: add --json, or -o OUT.json)", err=True)


def run_guarded(fn: Callable[[], T]) -> T:
    """Run ``fn`` and turn library errors into a one-line message and exit status 1."""
    try:
        return fn()
    except InputError as exc:
        raise fail(str(exc)) from None
    except NotFoundError as exc:
        raise fail(str(exc)) from None
    except RcsaError as exc:
        raise fail(str(exc)) from None


@contextmanager
def progress_callback(description: str, quiet: bool = False) -> Iterator[Callable[[int, int], None]]:
    """A ``progress(done, total)`` callback that drives a rich progress bar on stderr.

    The bar is transient (it disappears when done) and drawn only on a terminal; with
    ``quiet`` the callback does nothing. Results go to stdout, so they stay clean.
    """
    # rich: only when a command computes (``rcsa --help`` and the other commands do without it)
    from rich.console import Console
    from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn

    with Progress(TextColumn("[progress.description]{task.description}"), BarColumn(), MofNCompleteColumn(),
                  TimeElapsedColumn(), transient=True, disable=quiet, console=Console(stderr=True)) as bar:
        task = bar.add_task(description, total=None)

        def progress(done: int, total: int) -> None:
            bar.update(task, completed=done, total=max(total, 1))

        yield progress
