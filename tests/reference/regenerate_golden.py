"""Write the RA-1 golden master, ``tests/data/ra1/golden_prediction.json.gz``, from this code.

    python -m tests.reference.regenerate_golden            # compare only: what would change (exit 1 if anything)
    python -m tests.reference.regenerate_golden --write    # overwrite the file, after printing what changes

The file is the complete result document of ``rcsa.predict(ra1())`` (``to_dict()``: the
frequency grid, the tool-point 2×2 receptance h, l, n, p, the natural frequencies, the peaks,
the static stiffness, the most negative real part) with every number written to 13
significant digits (a relative rounding of at most 5e-14, far below the test's tolerances).
Regenerate it only when a change of the model is intended, and say in the commit why the
numbers moved: ``tests/reference/test_ra1_golden.py`` pins them. Without ``--write`` nothing
is written; with it the differences are printed first, so an overwrite is never silent.
"""

from __future__ import annotations

import gzip
import json
import sys
from pathlib import Path
from typing import Any

GOLDEN = Path(__file__).resolve().parents[1] / "data" / "ra1" / "golden_prediction.json.gz"
DIGITS = 13


def current_document() -> dict[str, Any]:
    """``rcsa.predict(ra1()).to_dict()`` of this code, numbers rounded to :data:`DIGITS` digits."""
    import rcsa
    from rcsa.reference import ra1

    return _rounded(rcsa.predict(ra1()).to_dict())


def _rounded(value: Any) -> Any:
    if isinstance(value, float):
        return float(f"{value:.{DIGITS - 1}e}")
    if isinstance(value, dict):
        return {k: _rounded(v) for k, v in value.items()}
    if isinstance(value, list):
        return [_rounded(v) for v in value]
    return value


def load_golden() -> dict[str, Any]:
    """The stored golden document."""
    with gzip.open(GOLDEN, "rt", encoding="utf-8") as f:
        return json.load(f)


def encode(doc: dict[str, Any]) -> bytes:
    """The file's bytes: canonical JSON, gzip without a timestamp (the same document gives the same bytes)."""
    text = json.dumps(doc, sort_keys=True, separators=(",", ":")) + "\n"
    return gzip.compress(text.encode("utf-8"), compresslevel=9, mtime=0)


def differences(old: dict[str, Any], new: dict[str, Any]) -> list[str]:
    """One line per top-level field (and tool-point entry) whose value differs."""
    lines = []
    for key in sorted(set(old) | set(new)):
        a, b = old.get(key), new.get(key)
        if key == "tool_point" and isinstance(a, dict) and isinstance(b, dict):
            for entry in sorted(set(a) | set(b)):
                if a.get(entry) != b.get(entry):
                    lines.append(f"tool_point.{entry}: {_largest_change(a.get(entry), b.get(entry))}")
        elif a != b:
            lines.append(f"{key}: {str(a)[:100]} -> {str(b)[:100]}")
    return lines


def _largest_change(a: Any, b: Any) -> str:
    try:
        pairs = [(x, y) for part in ("real", "imag") for x, y in zip(a[part], b[part], strict=True)]
        scale = max(abs(x) for x, _ in pairs) or 1.0
        return f"largest change {max(abs(x - y) for x, y in pairs) / scale:.2e} of the peak"
    except (TypeError, KeyError, ValueError):
        return "changed shape"


def main(argv: list[str]) -> int:
    """Compare (and with ``--write`` overwrite) the golden file; the exit status says whether it differed."""
    new = current_document()
    old = load_golden() if GOLDEN.exists() else {}
    changed = differences(old, new)
    for line in changed:
        print(line)
    if not changed:
        print(f"{GOLDEN.name}: unchanged")
        return 0
    if "--write" not in argv:
        print(f"{GOLDEN.name}: {len(changed)} field(s) differ; nothing written (add --write to overwrite)")
        return 1
    GOLDEN.write_bytes(encode(new))
    print(f"{GOLDEN.name}: written ({GOLDEN.stat().st_size} bytes); say in the commit why the numbers moved")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
