"""The figure of ``benchmarks/results/default_lobes.json``: default lobes against converged limits.

One panel per case of ``benchmarks/bench_default_lobes.py`` (each speed's depth limit over the
converged limit of the collocation oracle, on a log axis): the default answer (``auto``: the
resolved semi-discretization, every mode) beside the last release's two defaults (zero-order;
semi-discretization with 40 steps over the period and 3 modes a direction). The band the issue
asks of a default (−10 % … +5 %) is shaded; a speed its answer did not mark resolved is drawn
hollow; a speed where it found no limit at all (stable to its search depth, where the converged
cut chatters) is a cross at the top edge. Nothing is computed here: the figure shows what the
JSON holds, and the PNG carries the SHA-256 of the JSON it was drawn from (its ``Source``
text field), so ``tests/test_figures_rendered.py`` fails when the figures change and the
picture was not drawn again.

Run: ``.venv/bin/python benchmarks/plot_default_lobes.py [OUT.png]`` (default
``docs/default_lobes.png``).
"""

from __future__ import annotations

import hashlib
import json
import math
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "benchmarks" / "results" / "default_lobes.json"
OUT = ROOT / "docs" / "default_lobes.png"
#: Where a speed without any limit is drawn (the axis' top edge), ratio.
NO_LIMIT_AT = 80.0

#: How each variant of the benchmark is drawn: label, colour, marker.
STYLE = {
    "default": ("default now (auto: resolved SDM, every mode)", "tab:blue", "o"),
    "old_default_zoa": ("last release's default (zero-order)", "tab:orange", "s"),
    "old_sdm_defaults": ("last release's SDM defaults (40 steps, 3 modes)", "tab:red", "^"),
}
TITLES = {
    "single_flute_down": "1 flute, a/D 0.05, down",
    "single_flute_up": "1 flute, a/D 0.05, up",
    "ji2024_35mm": "five-mode table, x ≠ y",
    "strong_high_mode": "strong high mode",
    "four_flutes_up": "4 flutes, up milling",
}


def source_digest(data: bytes) -> str:
    """What the PNG's ``Source`` field holds for the JSON ``data``: ``sha256:<hex>``."""
    return "sha256:" + hashlib.sha256(data).hexdigest()


def draw(data: bytes, out: Path) -> Path:
    """Draw the figures of one ``default_lobes`` record (its JSON bytes) into ``out`` (PNG); returns ``out``."""
    record = json.loads(data)
    figures = record["figures"]
    low, high = figures["band"]
    cases = [c for c in TITLES if c in figures["cases"]] + sorted(set(figures["cases"]) - set(TITLES))
    fig, axes = plt.subplots(1, len(cases), figsize=(3.2 * len(cases), 3.6), sharey=True)
    for ax, name in zip(axes, cases, strict=True):
        case = figures["cases"][name]
        speeds = case["speeds"]
        ax.axhspan(1.0 + low, 1.0 + high, color="tab:green", alpha=0.15, lw=0)
        ax.axhline(1.0, color="k", lw=0.8)
        for variant, (label, colour, marker) in STYLE.items():
            entry = case[variant]
            ratio, resolved = entry["ratio"], entry["resolved"]
            ax.plot(speeds, ratio, color=colour, lw=0.8, alpha=0.6)
            found = [r is not None and math.isfinite(r) for r in ratio]
            for filled in (True, False):
                pick = [i for i, ok in enumerate(resolved) if ok is filled and found[i]]
                ax.scatter([speeds[i] for i in pick], [ratio[i] for i in pick], color=colour if filled else "none",
                           edgecolors=colour, marker=marker, s=22, label=label if filled else None, zorder=3)
            none = [i for i, f in enumerate(found) if not f]
            ax.scatter([speeds[i] for i in none], [NO_LIMIT_AT] * len(none), color=colour, marker="x", s=30, zorder=3)
        ax.set_yscale("log")
        ax.set_ylim(0.1, 1.3 * NO_LIMIT_AT)
        ax.set_title(TITLES.get(name, name), fontsize=9)
        ax.set_xlabel("spindle speed, rpm", fontsize=8)
        ax.tick_params(labelsize=7)
    axes[0].set_ylabel("depth limit / converged limit", fontsize=8)
    handles, labels = axes[0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="lower center", ncol=3, fontsize=8, frameon=False)
    fig.suptitle(f"Default stability lobes against converged limits (shaded: {low:+.0%} … {high:+.0%}; "
                 f"hollow: not marked resolved; x at the top: no limit found) — {record.get('commit', '?')}, "
                 f"{record.get('written_utc', '?')}",
                 fontsize=9)
    fig.tight_layout(rect=(0, 0.08, 1, 0.95))
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=110, metadata={"Source": source_digest(data)})
    plt.close(fig)
    return out


def main() -> None:
    out = Path(sys.argv[1]) if len(sys.argv) > 1 else OUT
    print(f"wrote {draw(RESULTS.read_bytes(), out)}")


if __name__ == "__main__":
    main()
