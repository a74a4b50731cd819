"""Write the benchmark tool libraries: ``tests/data/tool-libraries/fusion-single-flute/
single_flute_library.json``, ``.../single_flute_small_library.json`` and
``tests/data/tool-libraries/fusion-multi-flute/multi_flute_library.json``.

25 single-flute ("O-flute") solid carbide flat end mills for aluminium in the Autodesk Fusion
library format, each in the synthetic BT40-ER32 holder of ``fusion-synthetic`` (written for
this project). The dimensions are our own choice and span what single-flute aluminium cutters
are sold as — 2 to 12 mm and 1/8 to 1/2 inch, flute lengths 1.5 to 3 diameters, stickouts from
just past the flutes to 4.5 diameters, shank equal to the cutter (a 3 mm shank under 2 mm) —
but they are not any vendor's catalogue (see tests/data/tool-libraries/SOURCE.md: no licensed vendor library or
catalogue page with single-flute dimensions was available to us).

The second file holds 25 small single-flute O-flute carbide tools for aluminium, Ø1–6 mm with
flute lengths 3–42 mm (standard, long and extra-long flutes, stickout 2–4 mm past the flutes, shank
equal to the cutter, a 3 mm shank under Ø1–2 mm, a 6 mm shank under Ø3–5 mm): the range of the vendor
library of issue 29, whose dimensions are our own choice too.

The third file holds 25 multi-flute solid carbide flat end mills for aluminium (issue 29's "multi-flute
libraries"): 8 two-flute (Ø3–12 mm), 8 three-flute (Ø4–16 mm) and 9 four-flute (Ø6–16 mm), flute lengths
2–4 diameters, stickouts a few millimetres past the flutes, shank equal to the cutter, in the same holder;
the dimensions are our own choice, spanning what such cutters are sold as.

Run: ``.venv/bin/python benchmarks/write_tool_libraries.py`` (deterministic; rewrites the three files).
"""

from __future__ import annotations

import json
from pathlib import Path

OUT = Path(__file__).resolve().parents[1] / "tests" / "data" / "tool-libraries" / "fusion-single-flute" / \
    "single_flute_library.json"
HOLDER_SOURCE = OUT.parents[1] / "fusion-synthetic" / "synthetic_library.json"
OUT_SMALL = OUT.with_name("single_flute_small_library.json")
OUT_MULTI = OUT.parents[1] / "fusion-multi-flute" / "multi_flute_library.json"

# (unit, DC, LCF, LB (stickout), OAL, SFDM) — mm tools in mm, inch tools in inches
TOOLS = [
    ("mm", 2.0, 6.0, 12.0, 50.0, 3.0), ("mm", 3.0, 8.0, 12.0, 50.0, 3.0), ("mm", 3.0, 12.0, 18.0, 60.0, 3.0),
    ("mm", 4.0, 10.0, 16.0, 55.0, 4.0), ("mm", 4.0, 16.0, 22.0, 65.0, 4.0), ("mm", 5.0, 12.0, 18.0, 60.0, 5.0),
    ("mm", 6.0, 12.0, 20.0, 60.0, 6.0), ("mm", 6.0, 18.0, 25.0, 65.0, 6.0), ("mm", 6.0, 22.0, 30.0, 75.0, 6.0),
    ("mm", 8.0, 16.0, 25.0, 65.0, 8.0), ("mm", 8.0, 22.0, 32.0, 75.0, 8.0), ("mm", 8.0, 25.0, 36.0, 80.0, 8.0),
    ("mm", 10.0, 20.0, 30.0, 75.0, 10.0), ("mm", 10.0, 30.0, 42.0, 90.0, 10.0), ("mm", 12.0, 24.0, 36.0, 83.0, 12.0),
    ("mm", 12.0, 35.0, 50.0, 100.0, 12.0),
    ("in", 0.125, 0.375, 0.5, 1.5, 0.125), ("in", 0.125, 0.5, 0.75, 2.0, 0.125),
    ("in", 0.1875, 0.5, 0.75, 2.0, 0.1875), ("in", 0.25, 0.5, 0.875, 2.5, 0.25), ("in", 0.25, 0.75, 1.0, 2.5, 0.25),
    ("in", 0.25, 1.0, 1.25, 3.0, 0.25), ("in", 0.375, 0.875, 1.25, 2.5, 0.375), ("in", 0.375, 1.125, 1.5, 3.0, 0.375),
    ("in", 0.5, 1.25, 1.75, 3.5, 0.5),
]


# (unit, DC, LCF, LB, OAL, SFDM): Ø1–6 mm, flute lengths 3–42 mm
SMALL_TOOLS = [
    ("mm", 1.0, 3.0, 5.0, 38.0, 3.0), ("mm", 1.0, 5.0, 7.0, 38.0, 3.0), ("mm", 1.5, 4.5, 7.0, 38.0, 3.0),
    ("mm", 1.5, 7.5, 10.0, 38.0, 3.0), ("mm", 2.0, 6.0, 9.0, 38.0, 3.0), ("mm", 2.0, 10.0, 13.0, 50.0, 3.0),
    ("mm", 2.0, 14.0, 17.0, 50.0, 3.0), ("mm", 2.5, 8.0, 11.0, 50.0, 3.0), ("mm", 3.0, 8.0, 11.0, 50.0, 6.0),
    ("mm", 3.0, 12.0, 15.0, 50.0, 6.0), ("mm", 3.0, 18.0, 21.0, 60.0, 6.0), ("mm", 3.0, 22.0, 25.0, 64.0, 6.0),
    ("mm", 4.0, 11.0, 14.0, 50.0, 6.0), ("mm", 4.0, 16.0, 19.0, 57.0, 6.0), ("mm", 4.0, 22.0, 26.0, 64.0, 6.0),
    ("mm", 4.0, 28.0, 32.0, 75.0, 6.0), ("mm", 5.0, 13.0, 16.0, 57.0, 6.0), ("mm", 5.0, 20.0, 24.0, 64.0, 6.0),
    ("mm", 5.0, 30.0, 34.0, 75.0, 6.0), ("mm", 6.0, 12.0, 16.0, 57.0, 6.0), ("mm", 6.0, 18.0, 22.0, 64.0, 6.0),
    ("mm", 6.0, 22.0, 26.0, 64.0, 6.0), ("mm", 6.0, 28.0, 32.0, 75.0, 6.0), ("mm", 6.0, 35.0, 39.0, 83.0, 6.0),
    ("mm", 6.0, 42.0, 46.0, 90.0, 6.0),
]


# (flutes, DC, LCF, LB, OAL, SFDM), all mm: 2, 3 and 4 flutes
MULTI_TOOLS = [
    (2, 3.0, 8.0, 12.0, 50.0, 3.0), (2, 4.0, 11.0, 15.0, 50.0, 4.0), (2, 6.0, 13.0, 20.0, 57.0, 6.0),
    (2, 6.0, 25.0, 32.0, 75.0, 6.0), (2, 8.0, 19.0, 26.0, 63.0, 8.0), (2, 10.0, 22.0, 30.0, 72.0, 10.0),
    (2, 12.0, 26.0, 36.0, 83.0, 12.0), (2, 12.0, 45.0, 55.0, 110.0, 12.0),
    (3, 4.0, 11.0, 16.0, 50.0, 4.0), (3, 5.0, 13.0, 18.0, 57.0, 5.0), (3, 6.0, 16.0, 22.0, 57.0, 6.0),
    (3, 8.0, 20.0, 28.0, 63.0, 8.0), (3, 10.0, 25.0, 35.0, 72.0, 10.0), (3, 12.0, 30.0, 42.0, 83.0, 12.0),
    (3, 16.0, 32.0, 45.0, 92.0, 16.0), (3, 16.0, 50.0, 65.0, 120.0, 16.0),
    (4, 6.0, 13.0, 20.0, 57.0, 6.0), (4, 6.0, 24.0, 30.0, 75.0, 6.0), (4, 8.0, 19.0, 26.0, 63.0, 8.0),
    (4, 10.0, 22.0, 32.0, 72.0, 10.0), (4, 10.0, 40.0, 50.0, 100.0, 10.0), (4, 12.0, 26.0, 38.0, 83.0, 12.0),
    (4, 12.0, 38.0, 50.0, 100.0, 12.0), (4, 16.0, 32.0, 45.0, 92.0, 16.0), (4, 16.0, 60.0, 75.0, 150.0, 16.0),
]

_FLUTES = {1: "single flute (O-flute)", 2: "2-flute", 3: "3-flute", 4: "4-flute"}


def _tool(i: int, unit: str, dc: float, lcf: float, lb: float, oal: float, sfdm: float, holder: dict,
          flutes: int = 1) -> dict:
    inch = unit == "in"
    size = f'{dc:g}"' if inch else f"{dc:g}mm"
    geometry = {"CSP": False, "HAND": True, "DC": dc, "NOF": flutes, "OAL": oal, "LCF": lcf, "LB": lb, "SFDM": sfdm,
                "RE": 0, "shoulder-length": lb if sfdm > dc else lcf, "shoulder-diameter": dc,
                "assemblyGaugeLength": round(holder["gaugeLength"] / (25.4 if inch else 1.0) + lb, 6)}
    return {"BMC": "carbide", "GRADE": "Mill Generic",
            "description": f"SYNTH {size} {_FLUTES[flutes]} aluminium end mill, {lb:g}{'in' if inch else 'mm'} "
                           "stickout",
            "guid": f"00000000-0000-4000-8000-{0x500 + i:012x}", "type": "flat end mill",
            "unit": "inches" if inch else "millimeters", "vendor": "Synthetic", "product-id": f"SYNTH-{'SF' if flutes == 1 else 'MF'}-{i + 1:02d}",
            "product-link": "", "geometry": geometry, "holder": holder,
            "post-process": {"break-control": False, "comment": "", "diameter-offset": i + 1, "length-offset": i + 1,
                             "live": True, "manual-tool-change": False, "number": i + 1, "turret": 0}}


def main() -> None:
    holder = json.loads(HOLDER_SOURCE.read_text())["data"][0]["holder"]
    multi = [("mm", *t[1:], t[0]) for t in MULTI_TOOLS]
    for out, table, first in ((OUT, TOOLS, 0), (OUT_SMALL, SMALL_TOOLS, 0x100), (OUT_MULTI, multi, 0x200)):
        out.parent.mkdir(parents=True, exist_ok=True)
        tools = [_tool(first + i, *t[:6], holder=holder, flutes=t[6] if len(t) > 6 else 1)
                 for i, t in enumerate(table)]
        out.write_text(json.dumps({"data": tools, "version": 1}, indent=2) + "\n")
        print(f"{out}: {len(tools)} tools")


if __name__ == "__main__":
    main()
