"""Start-up stays light: ``import rcsa`` and ``rcsa --help`` load none of the heavy libraries.

Checked by what is in ``sys.modules`` of a fresh interpreter (not by timing: the figures
are in the manual's benchmark table, from ``benchmarks/bench_engine.py``).
"""

from __future__ import annotations

import json
import subprocess
import sys

import pytest

#: Loaded only by the commands and functions that need them.
HEAVY = ("scipy.signal", "matplotlib", "h5py", "fastapi")


def _loaded_after(code: str) -> dict[str, object]:
    probe = (f"import json, sys\n{code}\n"
             f"print(json.dumps({{'heavy': sorted({{m for m in sys.modules for h in {HEAVY!r} "
             f"if m == h or m.startswith(h + '.')}}), 'numpy': 'numpy' in sys.modules}}))")
    out = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, check=True)
    result: dict[str, object] = json.loads(out.stdout.strip().splitlines()[-1])
    return result


def test_import_rcsa_loads_no_heavy_library():
    loaded = _loaded_after("import rcsa")
    assert loaded == {"heavy": [], "numpy": False}


@pytest.mark.parametrize("argv", [["--help"], ["predict", "--help"], ["library", "--help"], ["store", "--help"]])
def test_building_the_cli_and_its_help_load_no_heavy_library(argv):
    code = ("import contextlib, io, typer\n"
            "from rcsa.cli import app\n"
            "typer.main.get_command(app)\n"
            "with contextlib.redirect_stdout(io.StringIO()), contextlib.suppress(SystemExit):\n"
            f"    app({argv!r})")
    loaded = _loaded_after(code)
    assert loaded["heavy"] == []


def test_the_api_is_there_on_first_use():
    import rcsa

    assert set(rcsa.__all__) <= set(dir(rcsa))
    assert callable(rcsa.predict) and callable(rcsa.diagnose) and rcsa.Receptance.__name__ == "Receptance"
    with pytest.raises(AttributeError, match="no attribute 'nothing'"):
        rcsa.nothing  # noqa: B018
