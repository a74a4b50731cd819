"""How far a semi-discretization pocket is followed, and what it costs (issue 29: presets on the CLI's grid).

Below the speeds the branch and bound screened, a preset's pocket is followed by single-depth
checks whose cost grows as 1/n (``rcsa.analysis.lobes.tool_pockets``). The recommendation
follows it at most ``POCKET_FOLLOWED_SPAN`` (2) times slower or faster than the preset's speed
and says where it is open. The baseline, in the same process, is the same recommendation
followed without a bound (the span made 100: the whole speed range).

Case: the multi-flute library (``tests/data/tool-libraries/fusion-multi-flute``) on RA-1's
spindle and joints with the example assembly's own grid (``examples/ra1.json``: 5–10 000 Hz at
1 Hz, what ``rcsa library recommend --spindle examples/ra1.json`` uses), aluminium 7075,
a_e/D 0.5, down milling, the default ``auto``, in one process. Timed: its three-flute Ø4 mm tool
alone (its pocket reaches the bottom of the range) and the whole library; each configuration
once after a warm-up run of the same tool (imports and caches filled). Also compared: the
presets themselves (speed and stepdown must not depend on the bound).

Run: ``.venv/bin/python benchmarks/bench_pocket_extent.py``; writes
``benchmarks/results/pocket_extent.json``.
"""

from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")  # before numpy is imported

import json  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from benchmarks import record  # noqa: E402

from rcsa.analysis.lobes import tool_pockets  # noqa: E402
from rcsa.app.jobs import Workbench  # noqa: E402
from rcsa.app.presets import recommend_predicted  # noqa: E402

LIBRARY = ROOT / "tests" / "data" / "tool-libraries" / "fusion-multi-flute" / "multi_flute_library.json"
TOOL_INDEX = 8  # the three-flute Ø4 mm tool, 16 mm stickout
OPTIONS = {"material": "aluminium-7075", "max_rpm": 24000, "milling": "down", "radial_immersion": 0.5,
           "method": "auto"}


def _recommend(items: list[dict]) -> tuple[dict, float]:
    ra1 = json.loads((ROOT / "examples" / "ra1.json").read_text())
    data = json.dumps({"data": items, "version": 1}).encode()
    c0 = time.process_time()
    report = recommend_predicted(Workbench(None), data, OPTIONS, file_name="library.json", spindle=ra1["spindle"],
                                 frequency=ra1["frequency"], joints=ra1["joints"]).report
    return report, time.process_time() - c0


def _presets(report: dict) -> list[tuple]:
    return [(t["id"], t.get("spindle_speed_rpm"), t.get("stepdown_m")) for t in report["tools"]]


def main() -> None:
    load = record.load_average()
    items = json.loads(LIBRARY.read_text())["data"]
    _recommend([items[TOOL_INDEX]])  # warm-up: imports, the spindle's caches
    out: dict = {"library": str(LIBRARY.relative_to(ROOT)), "tool": items[TOOL_INDEX]["guid"], "options": OPTIONS}
    reports = {}
    for name, span in (("bounded", tool_pockets.POCKET_FOLLOWED_SPAN), ("whole_range", 100.0)):
        tool_pockets.POCKET_FOLLOWED_SPAN = span  # the baseline: followed over the whole speed range
        tool, tool_s = _recommend([items[TOOL_INDEX]])
        library, library_s = _recommend(items)
        reports[name] = library
        out[name] = {"span": span, "tool_cpu_s": tool_s, "library_cpu_s": library_s,
                     "tool_pocket": tool["tools"][0]["pocket"],
                     "open_pockets": sum(bool(t.get("pocket", {}).get("low_open") or t.get("pocket", {}).get("high_open"))
                                         for t in library["tools"] if t["status"] == "written")}
        print(f"{name:12s} (span {span:g}): the tool {tool_s:.2f} s CPU, pocket "
              f"{tool['tools'][0]['pocket']['low_rpm']:.0f}-{tool['tools'][0]['pocket']['high_rpm']:.0f} rpm; "
              f"the library ({len(items)} tools) {library_s:.2f} s CPU, {out[name]['open_pockets']} pockets open",
              flush=True)
    tool_pockets.POCKET_FOLLOWED_SPAN = out["bounded"]["span"]
    out["tool_ratio"] = out["whole_range"]["tool_cpu_s"] / out["bounded"]["tool_cpu_s"]
    out["library_ratio"] = out["whole_range"]["library_cpu_s"] / out["bounded"]["library_cpu_s"]
    out["same_presets"] = _presets(reports["bounded"]) == _presets(reports["whole_range"])
    print(f"followed within 2x: the tool {out['tool_ratio']:.1f}x, the library {out['library_ratio']:.2f}x faster; "
          f"same presets: {out['same_presets']}")
    record.write("pocket_extent", out, load_start=load)


if __name__ == "__main__":
    main()
