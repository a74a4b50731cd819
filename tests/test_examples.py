"""The examples and the READMEs' commands work exactly as written.

* Every ``bash`` block of ``README.md`` and ``examples/README.md`` that uses ``examples/`` is
  run line by line, in order (a line already run is not run again), in a fresh folder (``examples/`` linked in, a temporary
  ``RCSA_STORE``): ``.venv/bin/rcsa ...`` through the CLI (in this process, for speed),
  ``.venv/bin/python examples/make_examples.py DIR`` through the script's ``write``.
  ``rcsa serve`` and ``curl`` lines are not run here (``tests/service/test_examples_api.py``
  sends every example to its REST endpoint). Each command must exit 0 and write its ``-o``
  and ``--plot`` files; the analyses must have drawn their progress bar.
* Every example file is used by a command of ``examples/README.md``.
* ``make_examples.py`` writes the committed files again (numbers equal to rounding).
* Every ``rcsa`` command in a README code block is written as ``.venv/bin/rcsa`` (runnable
  after the install line, without activating the venv).
"""

from __future__ import annotations

import importlib.util
import json
import math
import re
import shlex
from pathlib import Path
from typing import Any

import pytest
from typer.testing import CliRunner

from rcsa.cli import app
from tests.helpers import REPO

EXAMPLES = REPO / "examples"
READMES = (REPO / "README.md", EXAMPLES / "README.md")
#: Commands whose progress bar must show (drawn because the env below makes rich interactive).
WITH_PROGRESS = ("effects", "identify", "diagnose")
_ENV = {"TTY_INTERACTIVE": "1", "TTY_COMPATIBLE": "1", "COLUMNS": "100"}


def _blocks(markdown: Path, language: str = "bash") -> list[list[str]]:
    """The logical lines (backslash continuations joined) of each ``language`` code block."""
    blocks, current, inside = [], None, False
    for line in markdown.read_text(encoding="utf-8").splitlines():
        if line.startswith("```"):
            if inside:
                blocks.append(current)
                inside = False
            elif line.strip() == f"```{language}":
                current, inside = [], True
            continue
        if inside:
            if current and current[-1].endswith("\\"):
                current[-1] = current[-1][:-1] + " " + line.strip()
            else:
                current.append(line)
    return blocks


def _example_commands(markdown: Path) -> list[list[str]]:
    """The commands of the bash blocks that use examples/ (rcsa and the example script)."""
    out = []
    for block in _blocks(markdown):
        if not any("examples/" in line for line in block):
            continue
        for line in block:
            words = shlex.split(line, comments=True)
            if not words or words[0] not in (".venv/bin/rcsa", ".venv/bin/python") or "serve" in words[:2]:
                continue
            out.append(words)
    return out


def _load_script() -> Any:
    spec = importlib.util.spec_from_file_location("make_examples", EXAMPLES / "make_examples.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _run(words: list[str], runner: CliRunner) -> None:
    if words[0] == ".venv/bin/python":
        assert words[1] == "examples/make_examples.py", words
        _load_script().write(Path(words[2]))
        return
    args = words[1:]
    result = runner.invoke(app, args, env=_ENV)
    assert result.exit_code == 0, (words, result.stderr, result.stdout[-2000:])
    for flag in ("-o", "--plot", "--out"):
        if flag in args:
            written = Path(args[args.index(flag) + 1])
            assert written.is_file() and written.stat().st_size > 100, (words, written)
    if args[0] in WITH_PROGRESS:
        counts = re.findall(r"(\d+)/(\d+)", result.stderr)
        assert any(a == b and int(a) > 1 for a, b in counts), (words, result.stderr[-500:])
    if args[:2] == ["store", "import"]:
        assert json.loads(result.stdout)["id"].startswith("m-")


@pytest.fixture
def scratch(tmp_path, monkeypatch) -> Path:
    """An empty working folder with examples/ linked in and its own store."""
    (tmp_path / "examples").symlink_to(EXAMPLES)
    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv("RCSA_STORE", str(tmp_path / "store"))
    monkeypatch.setenv("MPLCONFIGDIR", str(tmp_path / "mpl"))
    return tmp_path


@pytest.mark.slow
def test_every_example_command_runs_as_written(scratch):
    runner = CliRunner()
    ran = []
    for readme in READMES:
        commands = _example_commands(readme)
        assert commands, readme
        for words in commands:
            if words not in ran:  # the top README repeats some of examples/README.md's lines
                _run(words, runner)
                ran.append(words)
    used = {Path(w).name for words in ran for w in words if w.startswith("examples/")}
    committed = {p.name for p in EXAMPLES.iterdir() if p.suffix in (".json", ".csv", ".py")}
    assert committed - used == {"batch.json"}, committed - used  # a batch has no CLI command (REST test)
    # the analyses said what they found
    diagnosis = json.loads((scratch / "diagnosis-result.json").read_text())
    assert diagnosis["verdict"]["effect"] == "holder_tool_joint", diagnosis["verdict"]
    identification = json.loads((scratch / "identification-result.json").read_text())
    assert identification["status"] == "identified"
    assert identification["joints"]["holder_tool"]["stiffness_n_m"] == pytest.approx(5.7e6, rel=0.05)
    assert "lobe-0" in (scratch / "lobes.svg").read_text()
    # make_examples.py wrote the committed files again
    for name in ("diagnosis.json", "identification.json", "measurement.json", "lobes-frf.json", "lobes-assembly.json",
                 "batch.json", "effects.json"):
        _assert_same(json.loads((scratch / "regenerated-examples" / name).read_text()),
                     json.loads((EXAMPLES / name).read_text()), name)
    regenerated = (scratch / "regenerated-examples" / "measurement.csv").read_text().splitlines()
    committed_csv = (EXAMPLES / "measurement.csv").read_text().splitlines()
    assert regenerated[0] == committed_csv[0] and len(regenerated) == len(committed_csv)


def _assert_same(a: Any, b: Any, where: str) -> None:
    """Equal documents; numbers to 1e-6 relative (BLAS rounding differs between machines)."""
    if isinstance(a, dict):
        assert isinstance(b, dict) and a.keys() == b.keys(), where
        for k in a:
            _assert_same(a[k], b[k], f"{where}.{k}")
    elif isinstance(a, list):
        assert isinstance(b, list) and len(a) == len(b), where
        for i, (x, y) in enumerate(zip(a, b, strict=True)):
            _assert_same(x, y, f"{where}[{i}]")
    elif isinstance(a, float) or isinstance(b, float):
        assert math.isclose(a, b, rel_tol=1e-6, abs_tol=1e-15), (where, a, b)
    else:
        assert a == b, (where, a, b)


def test_readme_rcsa_commands_are_runnable_as_written():
    for readme in READMES:
        for language in ("bash", "console"):
            for block in _blocks(readme, language):
                for line in block:
                    text = line.removeprefix("$ ").strip()
                    assert not re.match(r"rcsa\s", text), f"{readme.name}: write .venv/bin/rcsa: {line!r}"
