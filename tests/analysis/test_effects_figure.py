"""The effects heat map is readable: no label clipped at any size, percentages without exponents."""

from __future__ import annotations

import math

import numpy as np
import pytest
from matplotlib.text import Text

from rcsa.analysis.effects.mode_features import ModeFeatures
from rcsa.analysis.effects.report import FEATURES, EffectReport
from rcsa.analysis.figures import SAVE_DPI, effects_figure, percent_label, save_figure


def _report(n_modes: int, n_params: int, seed: int = 0) -> EffectReport:
    rng = np.random.default_rng(seed)
    f = np.sort(rng.uniform(200.0, 9000.0, n_modes))
    residue = rng.uniform(1e-6, 1.0, n_modes)
    modes = ModeFeatures(f, residue, f * 1.001, rng.uniform(1e-8, 1e-6, n_modes), rng.uniform(0.01, 0.05, n_modes),
                         np.full((n_modes, 2), 0.02))
    names = tuple(f"spindle_holder.rotational_damping_nms_rad_{j}" if j % 3 == 0 else f"bearings[{j}].stiffness_n_m"
                  for j in range(n_params))
    sens = {q: rng.normal(0.0, 2.0, (n_modes, n_params)) for q in FEATURES}
    return EffectReport((100.0, 10000.0), 1e-3, modes, names, np.ones(n_params), sens)


def _clipped(fig) -> list[str]:
    """Texts that reach outside the figure when it is drawn at the saved resolution."""
    fig.set_dpi(SAVE_DPI)
    renderer = fig.canvas.get_renderer()
    width, height = fig.bbox.width, fig.bbox.height
    out = []
    for text in fig.findobj(Text):
        if not text.get_visible() or not text.get_text():
            continue
        with np.errstate(invalid="ignore"):  # a colorbar's unused tick texts sit at infinity
            box = text.get_window_extent(renderer)
        if all(math.isfinite(v) for v in box.extents) and (
                box.x0 < 0 or box.y0 < 0 or box.x1 > width or box.y1 > height):
            out.append(text.get_text())
    return out


@pytest.mark.parametrize(("n_modes", "n_params"), [(1, 1), (3, 45), (30, 4)])
def test_no_label_is_clipped_at_any_size(n_modes, n_params):
    """One cell, many long parameter names, many modes (the corners of the layout)."""
    fig = effects_figure(_report(n_modes, n_params))
    assert _clipped(fig) == []
    if n_modes == 1:
        assert save_figure(fig, "png")[:4] == b"\x89PNG"


def test_mode_labels_read_as_percentages():
    fig = effects_figure(_report(3, 2))
    labels = [t.get_text() for t in fig.axes[0].get_yticklabels()]
    assert labels[-1].endswith("%)") and all("e+" not in s and "e-" not in s for s in labels), labels


@pytest.mark.parametrize(("fraction", "text"), [(1.0, "100 %"), (0.999, "100 %"), (0.376, "38 %"), (0.1, "10 %"),
                                                (0.0996, "10 %"), (0.025, "2.5 %"), (0.05, "5 %"),
                                                (0.00089, "0.089 %"), (9.8e-5, "< 0.01 %"), (0.0, "0 %"),
                                                (math.nan, "–")])
def test_percent_label(fraction, text):
    assert percent_label(fraction) == text
