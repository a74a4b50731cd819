"""The examples and every command of the documents work exactly as written.

The documents: the front page ``README.md``, the manual's pages (``docs/*.md``, in the order of
``mkdocs.yml``'s nav) and ``examples/README.md``.

* Every line of every ``bash`` block of the documents is run, in
  order (a line already run is not run again), in a fresh folder (``examples/`` linked in, a
  temporary ``RCSA_STORE``), as a shell would, with a small interpreter:

  - ``.venv/bin/rcsa ...`` through the CLI, in this process (for speed); it must exit 0, write
    its ``-o``/``--out``/``--plot``/``--report`` files, and say so on stderr;
  - ``NAME=$(.venv/bin/rcsa ...)`` keeps the command's output, and ``$NAME`` / ``"$NAME"``
    stand for it in the lines that follow; ``cp A B`` copies;
  - ``curl ...`` is sent to the REST service on the same store (``-H``, ``--data @FILE``,
    ``-F name=value``, ``-F name=@FILE``, ``-o FILE``); it must answer 2xx;
  - ``.venv/bin/python examples/make_examples.py DIR`` through the script's ``write``;
  - ``.venv/bin/python examples/dask_local_cluster.py ...`` in a process of its own (it starts
    a Dask ``LocalCluster``);
  - ``.venv/bin/rcsa serve ...`` is started for real, on a free port, in
    ``test_every_serve_command_starts_a_service`` (it answers ``/readyz``, then is stopped).

  Some lines are not run here, and ``NOT_RUN`` says which and why: installing and the suite
  itself (``.ci/run`` runs exactly the README's line on a fresh machine), the lock's refresh
  from PyPI, the manual's build (``tests/test_docs_site.py`` runs it) and the ``docker`` lines (they need a Docker daemon; ``docker/smoke.sh`` checks
  the image where there is one).
* ``python`` blocks of the documents are executed.
* Every example file is used by a command of ``examples/README.md``.
* ``make_examples.py`` writes the committed files again (numbers equal to rounding).
* Every ``rcsa`` command in a code block of the documents is written as ``.venv/bin/rcsa``
  (runnable after the install line, without activating the venv).
* Every page of the manual is in ``mkdocs.yml``'s nav, so that none is left unrun.
"""

from __future__ import annotations

import importlib.util
import json
import math
import re
import shlex
import shutil
import socket
import subprocess
import sys
import time
import urllib.error
import urllib.request
from pathlib import Path
from typing import Any

import pytest
from typer.testing import CliRunner

from rcsa.cli import app
from tests.helpers import REPO, manual_pages

EXAMPLES = REPO / "examples"
#: The documents whose commands run, in reading order: the front page, the manual, the examples.
DOCUMENTS = (REPO / "README.md", *manual_pages(), EXAMPLES / "README.md")
#: Commands whose progress bar must show (drawn because the env below makes rich interactive).
WITH_PROGRESS = ("effects", "identify", "diagnose")
_ENV = {"TTY_INTERACTIVE": "1", "TTY_COMPATIBLE": "1", "COLUMNS": "100"}
#: Lines the suite does not run, and why (see the module docstring).
NOT_RUN = {"python3 -m venv": "installing: .ci/run does it on a fresh machine",
           ".venv/bin/pip install": "installing: .ci/run does it on a fresh machine",
           ".venv/bin/python -m pytest": "the suite itself: .ci/run runs exactly this line",
           "scripts/update-constraints.sh": "rewrites the lock from PyPI (network), by hand after a dependency change",
           ".venv/bin/mkdocs build": "the manual's build: tests/test_docs_site.py runs it strictly, into a temporary folder",
           "docker ": "needs a Docker daemon: docker/smoke.sh checks the image where there is one"}
_ASSIGN = re.compile(r"^(\w+)=\$\((.*)\)\s*(#.*)?$")


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


def _lines(markdown: Path) -> list[str]:
    """Every command line of the bash blocks (comments and blank lines left out)."""
    return [line for block in _blocks(markdown) for line in block
            if line.strip() and not line.lstrip().startswith("#")]


def _load_script() -> Any:
    spec = importlib.util.spec_from_file_location("make_examples", EXAMPLES / "make_examples.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


class Shell:
    """Runs README lines as a shell would, the commands in this process."""

    def __init__(self, client: Any) -> None:
        self.runner = CliRunner()
        self.client = client
        self.variables: dict[str, str] = {}
        self.ran: list[list[str]] = []
        self.skipped: list[str] = []
        self.serve: list[list[str]] = []

    def expand(self, line: str) -> str:
        for name, value in self.variables.items():
            line = line.replace("${" + name + "}", value).replace("$" + name, value)
        return line

    def run(self, line: str) -> None:
        if " && " in line:  # a chain: each command in turn (an assertion stops it, as && would)
            for part in line.split(" && "):
                self.run(part.strip())
            return
        for prefix, why in NOT_RUN.items():
            if line.startswith(prefix):
                self.skipped.append(f"{line[:40]}...: {why}")
                return
        assigned = _ASSIGN.match(line)
        if assigned:
            words = shlex.split(self.expand(assigned.group(2)))
            self.ran.append(words)
            self.variables[assigned.group(1)] = self.rcsa(words).stdout.strip()
            return
        words = shlex.split(self.expand(line), comments=True)
        if words in self.ran:
            return
        self.ran.append(words)
        if words[0] == "cp":
            shutil.copy(words[1], words[2])
        elif words[0] == "curl":
            self.curl(words[1:])
        elif words[:2] == [".venv/bin/python", "examples/make_examples.py"]:
            _load_script().write(Path(words[2]))
        elif words[:2] == [".venv/bin/python", "examples/dask_local_cluster.py"]:
            # a real process: it starts a LocalCluster of worker processes
            subprocess.run([sys.executable, *words[1:]], check=True, timeout=600)
        elif words[:2] == [".venv/bin/rcsa", "serve"]:
            self.serve.append(words)
        else:
            assert words[0] == ".venv/bin/rcsa", f"not a command the READMEs may use: {line!r}"
            self.rcsa(words)

    def rcsa(self, words: list[str]) -> Any:
        assert words[0] == ".venv/bin/rcsa", words
        args = words[1:]
        result = self.runner.invoke(app, args, env=_ENV)
        assert result.exit_code == 0, (words, result.stderr, result.stdout[-2000:])
        for flag in ("-o", "--out", "--plot", "--report"):
            if flag in args:
                written = Path(args[args.index(flag) + 1])
                assert written.is_file() and written.stat().st_size > 100, (words, written)
                assert str(written) in result.stderr, (words, "says nothing of", written, result.stderr[-300:])
        if args and args[0] in WITH_PROGRESS:
            counts = re.findall(r"(\d+)/(\d+)", result.stderr)
            assert any(a == b and int(a) > 1 for a, b in counts), (words, result.stderr[-500:])
        if args[:2] == ["store", "import"] and "--id-only" not in args:
            assert json.loads(result.stdout)["id"].startswith("m-")
        return result

    def curl(self, args: list[str]) -> None:
        headers: dict[str, str] = {}
        files: list[tuple[str, Any]] = []
        body: bytes | None = None
        out = url = None
        i = 0
        while i < len(args):
            a = args[i]
            if a == "-s":
                i += 1
                continue
            if a in ("-H", "--data", "-d", "-F", "-o"):
                value = args[i + 1]
                if a == "-H":
                    name, _, v = value.partition(":")
                    headers[name.strip()] = v.strip()
                elif a in ("--data", "-d"):
                    body = Path(value[1:]).read_bytes() if value.startswith("@") else value.encode()
                elif a == "-F":
                    name, _, v = value.partition("=")
                    files.append((name, (Path(v[1:]).name, Path(v[1:]).read_bytes()) if v.startswith("@")
                                  else (None, v)))
                else:
                    out = value
                i += 2
                continue
            assert a.startswith("http://127.0.0.1:8000/"), f"curl: cannot read {a!r}"
            url = a.removeprefix("http://127.0.0.1:8000")
            i += 1
        assert url is not None, args
        if files:
            r = self.client.post(url, headers=headers, files=files)
        elif body is not None:
            r = self.client.post(url, headers=headers, content=body)
        else:
            r = self.client.get(url, headers=headers)
        assert 200 <= r.status_code < 300, (args, r.status_code, r.text[:1000])
        if out is not None:
            Path(out).write_bytes(r.content)


@pytest.fixture
def scratch(tmp_path, monkeypatch) -> Path:
    """An empty working folder with examples/ linked in and its own store."""
    (tmp_path / "examples").symlink_to(EXAMPLES)
    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv("RCSA_STORE", str(tmp_path / "store"))
    monkeypatch.setenv("MPLCONFIGDIR", str(tmp_path / "mpl"))
    return tmp_path


@pytest.fixture
def shell(scratch):
    from tests.service.conftest import TestClient, create_app, settings_for

    with TestClient(create_app(settings_for(scratch / "store", api_keys=""))) as client:
        yield Shell(client)


@pytest.mark.slow
def test_every_command_of_the_documents_runs_as_written(scratch, shell):
    for document in DOCUMENTS:
        for line in _lines(document):
            shell.run(line)
    assert _lines(REPO / "README.md") and _lines(EXAMPLES / "README.md")
    # only installing, the suite itself (both .ci/run's), the lock's refresh and docker are not run here
    assert shell.skipped and all(any(s.endswith(why) for why in NOT_RUN.values()) for s in shell.skipped)
    assert shell.serve, "no rcsa serve line found"
    used = {Path(w).name for words in shell.ran for w in words if "examples/" in w}
    used |= {w.split("@examples/")[1] for words in shell.ran for w in words if "@examples/" in w}
    committed = {p.name for p in EXAMPLES.iterdir() if p.suffix in (".json", ".csv", ".py") or p.is_dir()}
    assert committed <= used, committed - used
    # the analyses said what they found
    diagnosis = json.loads((scratch / "diagnosis-result.json").read_text())
    assert diagnosis["verdict"]["effect"] == "holder_tool_joint", diagnosis["verdict"]
    identification = json.loads((scratch / "identification-result.json").read_text())
    assert identification["status"] == "identified"
    assert identification["joints"]["holder_tool"]["stiffness_n_m"] == pytest.approx(5.7e6, rel=0.05)
    assert "lobe-0" in (scratch / "lobes.svg").read_text()
    band = json.loads((scratch / "ra1-band.json").read_text())["uncertainty"]
    assert band["draws"] == 50 and set(band["h_magnitude_m_n"]) >= {"p05", "p50", "p95"}
    robust = json.loads((scratch / "lobes-robust-result.json").read_text())
    assert "depth_limit_robust_m" in robust
    sdm = json.loads((scratch / "lobes-sdm-result.json").read_text())
    assert {lobe["kind"] for lobe in sdm["lobes"]} >= {"hopf"}
    sdm_report = json.loads((scratch / "presets-sdm-report.json").read_text())
    assert {t["lobe_method"] for t in sdm_report["tools"] if t["status"] == "written"} == {"semi_discretization"}
    dask_sync = json.loads((scratch / "library-dask.json").read_text())
    assert dask_sync["summary"]["ok"] == 2, dask_sync["summary"]
    presets = json.loads((scratch / "shop.json").read_text())
    assert "rcsa" in json.dumps(presets)  # presets written in place
    # make_examples.py wrote the committed files again
    for name in ("diagnosis.json", "identification.json", "measurement.json", "lobes-frf.json", "lobes-assembly.json",
                 "batch.json", "effects.json", "ra1-uncertainty.json", "lobes-robust.json", "lobes-sdm.json"):
        _assert_same(json.loads((scratch / "regenerated-examples" / name).read_text()),
                     json.loads((EXAMPLES / name).read_text()), name)
    regenerated = (scratch / "regenerated-examples" / "measurement.csv").read_text().splitlines()
    committed_csv = (EXAMPLES / "measurement.csv").read_text().splitlines()
    assert regenerated[0] == committed_csv[0] and len(regenerated) == len(committed_csv)


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


@pytest.mark.slow
def test_every_serve_command_starts_a_service(scratch):
    commands = [shlex.split(part, comments=True) for document in DOCUMENTS for line in _lines(document)
                for part in line.split(" && ") if part.strip().startswith(".venv/bin/rcsa serve")]
    assert len(commands) >= 2, commands
    for words in commands:
        args = list(words[1:])
        port = _free_port()
        if "--port" in args:
            args[args.index("--port") + 1] = str(port)
        else:
            args += ["--port", str(port)]
        if "--host" in args:  # listen where the test can reach it, whatever the README binds to
            args[args.index("--host") + 1] = "127.0.0.1"
        proc = subprocess.Popen([sys.executable, "-c", "from rcsa.cli import main; main()", *args],
                                stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
        try:
            ready = False
            for _ in range(600):  # attempts, not seconds: start-up is slow on a loaded machine
                try:
                    with urllib.request.urlopen(f"http://127.0.0.1:{port}/readyz", timeout=10) as r:
                        ready = r.status == 200
                        break
                except (urllib.error.URLError, ConnectionError, TimeoutError):
                    if proc.poll() is not None:
                        break
                    time.sleep(0.1)
            assert ready, (words, proc.poll(), proc.stderr.read().decode()[-2000:] if proc.poll() is not None else "")
        finally:
            proc.terminate()
            proc.wait(timeout=60)
            proc.stderr.close()


def test_the_python_blocks_of_the_documents_run(scratch):
    # the files the README's reading snippet opens, made as its text says (rcsa predict BATCH.json -o ...)
    for out in ("out.h5", "out.parquet"):
        result = CliRunner().invoke(app, ["predict", "examples/batch.json", "-o", out])
        assert result.exit_code == 0, result.stderr
    for document in DOCUMENTS:
        for block in _blocks(document, "python"):
            exec(compile("\n".join(block), f"{document.name} python block", "exec"), {})  # noqa: S102


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


def test_rcsa_commands_of_the_documents_are_runnable_as_written():
    for document in DOCUMENTS:
        for language in ("bash", "console"):
            for block in _blocks(document, language):
                for line in block:
                    text = line.removeprefix("$ ").strip()
                    assert not re.match(r"rcsa\s", text), f"{document.name}: write .venv/bin/rcsa: {line!r}"


def test_every_page_of_the_manual_is_read():
    """A page left out of mkdocs.yml's nav would be neither built into the site's menu nor run here."""
    pages = {p.name for p in (REPO / "docs").glob("*.md")}
    assert pages == {p.name for p in manual_pages()}, pages ^ {p.name for p in manual_pages()}
    assert all(p.is_file() for p in manual_pages())
