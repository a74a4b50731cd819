"""Shared plumbing of the CLI commands: reading JSON, writing results, one-line errors."""

from __future__ import annotations

import sys
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Annotated, Any, TypeVar

import typer

from rcsa.errors import InputError, NotFoundError, RcsaError

__all__ = ["QuietOption", "command_group", "fail", "progress_callback", "read_json", "run_guarded", "wrote",
           "write_json", "write_results"]

#: ``--quiet/-q`` of the commands that draw a progress bar.
QuietOption = Annotated[bool, typer.Option("--quiet", "-q", help="No progress bar on stderr.")]

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
