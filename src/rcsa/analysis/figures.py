"""Headless figures: tool-point FRFs, stability lobe diagrams and effect-analysis heat maps.

Built on :class:`matplotlib.figure.Figure` with the Agg canvas — ``matplotlib.pyplot``
is never imported, so no global figure registry, no GUI backend and no state shared
between requests (safe in a web service and in threads). SI arrays come in; conversions
to the units people read happen only here: receptance in µm/N, depth of cut in mm,
spindle speed in rpm, phase in degrees.

Examples
--------
>>> import numpy as np
>>> f = np.linspace(100.0, 2000.0, 400)
>>> h = 1.0 / (2e7 * (1 - (f / 800) ** 2 + 0.06j * f / 800))
>>> png = save_figure(frf_figure(f, h, labels=["xx"]), "png")
>>> png[:8] == b"\\x89PNG\\r\\n\\x1a\\n"
True
"""

from __future__ import annotations

import io
import math
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any, Literal

import matplotlib
import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.layout_engine import ConstrainedLayoutEngine
from matplotlib.ticker import MaxNLocator

from rcsa.analysis.effects.report import EffectReport
from rcsa.analysis.lobes.zoa import LobeResult
from rcsa.errors import InputError
from rcsa.physics.receptance import check_frequency_hz

__all__ = ["SAVE_DPI", "FrfLayout", "checked_text", "effects_figure", "freeze_layout", "frf_figure", "lobes_figure",
           "log_frequency_ticks", "new_figure", "percent_label",
           "save_figure"]

FrfLayout = Literal["full", "real_imag", "bode"]

UM_PER_M = 1e6
MM_PER_M = 1e3
_FORMATS = ("png", "svg")
#: Resolution of saved PNGs, dots per inch (the layout is solved at it, :func:`freeze_layout`).
SAVE_DPI = 150


def checked_text(text: str, field: str) -> str:
    """A text for a figure (title, label), refused now if matplotlib could not draw it.

    Text between ``$`` signs is matplotlib mathtext (``$\\omega_n$``); an expression it cannot
    parse would fail only when the figure is drawn. ``\\$`` is a literal dollar sign.

    Raises
    ------
    InputError
        Naming ``field``, with matplotlib's account of the expression.

    Examples
    --------
    >>> checked_text("RA-1, $x_1$", "title")
    'RA-1, $x_1$'
    >>> checked_text("$x^{$", "title")
    Traceback (most recent call last):
    ...
    rcsa.errors.InputError: title: is not a text matplotlib can draw: ...
    """
    dollars = text.count("$") - text.count("\\$")
    if dollars == 0 or dollars % 2:  # matplotlib draws it as plain text
        return text
    from matplotlib.mathtext import MathTextParser

    try:
        MathTextParser("path").parse(text)
    except (ValueError, RecursionError) as exc:
        detail = " ".join(str(exc).split())
        raise InputError(field, f"is not a text matplotlib can draw: {detail[:300]}; write a literal dollar sign "
                                "as \\$") from None
    return text


def new_figure(width_in: float, height_in: float) -> Figure:
    """A headless figure with constrained layout (every figure of the package starts here).

    Parameters
    ----------
    width_in, height_in : float
        Size, inches.

    Returns
    -------
    matplotlib.figure.Figure
        With its Agg canvas attached (no pyplot, no GUI backend).
    """
    fig = Figure(figsize=(width_in, height_in), layout="constrained")
    FigureCanvasAgg(fig)  # attach the headless canvas explicitly
    return fig


def freeze_layout(fig: Figure) -> Figure:
    """Run the constrained layout once and fix it, so every save writes identical files.

    (The layout solver otherwise nudges the axes by ~1e-3 pt on each draw.) Call it last,
    when everything is drawn; returns ``fig``.

    The layout is solved at the resolution PNGs are saved at (:data:`SAVE_DPI`): small text
    is hinted wider at 150 dpi than at the figure's nominal 100 (a 7 pt label by ~5 %), so a
    layout solved at 100 dpi clipped the longest tick labels at the edges of the saved
    picture. At lower resolutions (SVG) text is narrower, so nothing is clipped there either.
    """
    nominal = fig.get_dpi()
    fig.set_dpi(SAVE_DPI)
    fig.draw_without_rendering()
    fig.set_layout_engine("none")
    fig.set_dpi(nominal)
    return fig


def log_frequency_ticks(ax: Any, f_min_hz: float, f_max_hz: float) -> list[float]:
    """Label a logarithmic frequency axis with plain numbers that never collide.

    Matplotlib labels a log axis that spans less than a decade with its minor ticks
    ("2×10², 3×10², …"), which overlap at small sizes. Here the labelled ticks are the
    1–2–5 numbers inside the band (1–2–3–5 when fewer than three fall in it), written as
    plain numbers (``200``, ``500``, ``1000``); minor ticks stay, unlabelled.

    Parameters
    ----------
    ax : matplotlib.axes.Axes
        With a logarithmic x axis.
    f_min_hz, f_max_hz : float
        The band drawn, Hz.

    Returns
    -------
    list of float
        The labelled ticks, Hz.

    Examples
    --------
    >>> fig = new_figure(3, 2)
    >>> ax = fig.add_subplot()
    >>> ax.set_xscale("log")
    >>> log_frequency_ticks(ax, 200.0, 3000.0)
    [200.0, 500.0, 1000.0, 2000.0]
    >>> log_frequency_ticks(ax, 300.0, 800.0)
    [300.0, 500.0]
    """
    from matplotlib.ticker import FixedLocator, FuncFormatter, NullFormatter

    ticks: list[float] = []
    for mantissas in ((1.0, 2.0, 5.0), (1.0, 2.0, 3.0, 5.0), (1.0, 1.5, 2.0, 3.0, 4.0, 5.0, 7.0)):
        decades = range(math.floor(math.log10(f_min_hz)), math.ceil(math.log10(f_max_hz)) + 1)
        ticks = [m * 10.0**d for d in decades for m in mantissas if f_min_hz * (1 - 1e-9) <= m * 10.0**d
                 <= f_max_hz * (1 + 1e-9)]
        if len(ticks) >= 2:
            break
    ax.xaxis.set_major_locator(FixedLocator(ticks))
    ax.xaxis.set_major_formatter(FuncFormatter(lambda x, _: f"{x:g}"))
    ax.xaxis.set_minor_formatter(NullFormatter())
    return ticks


def percent_label(fraction: float) -> str:
    """A fraction as a readable percentage: ``"100 %"``, ``"38 %"``, ``"2.5 %"``, ``"0.089 %"``.

    Two significant digits below 10 %, whole percents above, and ``"< 0.01 %"`` for anything
    smaller (never an exponent such as ``1e+02``); ``"–"`` when it is not a number.

    Examples
    --------
    >>> [percent_label(x) for x in (1.0, 0.376, 0.025, 0.00089, 1e-7)]
    ['100 %', '38 %', '2.5 %', '0.089 %', '< 0.01 %']
    """
    value = 100.0 * float(fraction)
    if not math.isfinite(value):
        return "–"
    if abs(value) >= 9.95:
        return f"{value:.0f} %"
    if abs(value) < 0.01:
        return "0 %" if value == 0 else "< 0.01 %"
    return f"{float(f'{value:.2g}'):g} %"


def _frf_columns(frequency_hz: object, frf_m_n: object) -> tuple[np.ndarray, np.ndarray]:
    f = check_frequency_hz(frequency_hz)
    h = np.asarray(frf_m_n, dtype=complex)
    if h.ndim == 1:
        h = h[:, None]
    if h.ndim != 2 or h.shape[0] != f.size:
        raise InputError(
            "frf_m_n", f"expected shape ({f.size},) or ({f.size}, ncurves), got {h.shape}"
        )
    if not np.all(np.isfinite(h)):
        raise InputError("frf_m_n", "contains NaN or infinite values")
    return f, h


def frf_figure(
    frequency_hz: object,
    frf_m_n: object,
    *,
    labels: Sequence[str] | None = None,
    layout: FrfLayout = "full",
    title: str | None = None,
    band_m_n: tuple[object, object] | None = None,
    natural_frequencies_hz: object | None = None,
) -> Figure:
    """Figure of one or more receptances, shown in µm/N.

    Parameters
    ----------
    frequency_hz : array_like, shape (nfreq,)
        Frequency grid, Hz (linear axis).
    frf_m_n : array_like, shape (nfreq,) or (nfreq, ncurves)
        Complex receptances, m/N (frequency first; one column per curve).
    labels : sequence of str, optional
        One legend entry per curve.
    layout : {"full", "real_imag", "bode"}
        ``"real_imag"``: real and imaginary parts (the tap-test view whose negative real
        minimum drives stability); ``"bode"``: magnitude (log y) and phase (deg);
        ``"full"`` (default): both, as a 2 × 2 grid.
    title : str, optional
    band_m_n : (array_like, array_like), optional
        Lower and upper ``|h|`` of an uncertainty band (e.g. p05 and p95), m/N, on the same
        grid: shaded on the magnitude axes (``gid`` ``"band"``).
    natural_frequencies_hz : array_like of float, optional
        Natural frequencies to mark, Hz: a dotted vertical line on every axes (``gid``
        ``"natural-frequency"``, after the curves) and the values in the figure's title.

    Returns
    -------
    matplotlib.figure.Figure
        Each axes carries ``gid`` ``"real"``, ``"imag"``, ``"mag"`` or ``"phase"`` and
        holds one line per curve, in input order, then the natural frequencies' lines.
    """
    f, h = _frf_columns(frequency_hz, frf_m_n)
    if labels is not None and len(labels) != h.shape[1]:
        raise InputError("labels", f"expected {h.shape[1]} labels, got {len(labels)}")
    if layout not in ("full", "real_imag", "bode"):
        raise InputError("layout", f"must be 'full', 'real_imag' or 'bode', got {layout!r}")
    h_um = h * UM_PER_M
    panels = {
        "real": ("Real (µm/N)", h_um.real, "linear"),
        "imag": ("Imaginary (µm/N)", h_um.imag, "linear"),
        "mag": ("Magnitude (µm/N)", np.abs(h_um), "log"),
        "phase": ("Phase (deg)", np.degrees(np.angle(h)), "linear"),
    }
    names = {
        "real_imag": ["real", "imag"],
        "bode": ["mag", "phase"],
        "full": ["real", "imag", "mag", "phase"],
    }[layout]
    fig = new_figure(10.0 if layout == "full" else 6.4, 6.0)
    axes = fig.subplots(2, 2 if layout == "full" else 1, sharex=True, squeeze=False).T.ravel()
    for ax, name in zip(axes, names, strict=True):
        ylabel, data, scale = panels[name]
        for c in range(h.shape[1]):
            ax.plot(f, data[:, c], lw=1.2, label=None if labels is None else labels[c])
        if name == "mag" and band_m_n is not None:
            low, high = (np.asarray(b, dtype=float) * UM_PER_M for b in band_m_n)
            ax.fill_between(f, low, high, color="tab:blue", alpha=0.2, lw=0, gid="band", label="p05–p95")
        ax.set_ylabel(ylabel)
        ax.set_yscale(scale)
        ax.set_gid(name)
        ax.grid(True, which="both", alpha=0.3)
        if name == "phase":
            ax.set_yticks(np.arange(-180, 181, 90))
    given = () if natural_frequencies_hz is None else np.asarray(natural_frequencies_hz, dtype=float).ravel()
    marked = [float(x) for x in given if f[0] <= x <= f[-1]]
    for ax in axes:
        for x in marked:
            ax.axvline(x, color="0.45", lw=0.7, ls=":", gid="natural-frequency")
    for ax in axes[1::2]:
        ax.set_xlabel("Frequency (Hz)")
    axes[0].set_xlim(f[0], f[-1])
    if labels is not None:
        axes[0].legend(loc="best", fontsize="small")
    heading = checked_text(title, "title") if title else "Receptance"
    if natural_frequencies_hz is not None:
        listed = ", ".join(f"{x:.0f}" for x in marked[:8]) + (", …" if len(marked) > 8 else "")
        heading += f"\nnatural frequencies (dotted): {listed} Hz" if marked else "\nno natural frequency in the band"
    fig.suptitle(heading, fontsize="medium")
    return freeze_layout(fig)


def lobes_figure(
    result: LobeResult,
    *,
    show_lobes: bool = True,
    operating_point: tuple[float, float] | None = None,
    depth_max_mm: float | None = None,
    title: str | None = None,
    robust_depth_limit_m: object | None = None,
    robust_label: str = "robust limit",
    flute_length_m: float | None = None,
    notes: Sequence[str] = (),
    conditions: Mapping[str, Any] | None = None,
    doubtful_speeds: Mapping[str, np.ndarray] | None = None,
) -> Figure:
    """Stability lobe diagram: axial depth limit (mm) against spindle speed (rpm).

    Parameters
    ----------
    result : LobeResult
        From :func:`rcsa.analysis.lobes.zoa.stability_lobes`.
    show_lobes : bool
        Draw every lobe as a thin line under the envelope.
    operating_point : (float, float), optional
        Current ``(spindle_speed_rpm, depth_m)``, e.g. from a CAM preset; drawn as a
        marker, green if below the envelope (stable) and red otherwise.
    depth_max_mm : float, optional
        Upper y limit, mm. Default: the envelope's maximum, capped at 8 × the absolute
        limit so that the pockets stay readable.
    title : str, optional
    robust_depth_limit_m : array_like, shape (nspeed,), optional
        A robust depth limit per speed (:mod:`rcsa.analysis.lobes.robust`), m; drawn dashed
        (``gid`` ``"robust"``) with ``robust_label``.
    robust_label : str
    flute_length_m : float, optional
        The tool's flute length, m: drawn as a line (``gid`` ``"flute-length"``); no stepdown
        exceeds it, so the depth axis stops just above it when the limits go higher.
    notes : sequence of str
        Caveats of the diagram (under-resolved speeds, an FRF grid too coarse for the
        lobes), written under the axes.
    conditions : mapping, optional
        How the diagram was made (:func:`rcsa.app.analyses.cutting_conditions`: teeth, radial
        immersion, milling, cutting coefficients, method, FRF source): written under the title.
        Without it the method is told by the result's type and the FRF source by
        ``result.same_frf_in_y``.
    doubtful_speeds : mapping of str to numpy.ndarray, optional
        Boolean masks over the speeds whose limit is not to be trusted as drawn, by reason
        (:func:`rcsa.app.summaries.unsettled_speeds`): each reason's speeds are hatched grey
        (``gid`` ``"doubtful-<reason>"``) and named in the legend.

    Returns
    -------
    matplotlib.figure.Figure
        One axes. Its lines carry ``gid`` ``"lobe-<k>"`` for the lobes and ``"envelope"``
        for the lower envelope; the stable region under the envelope is shaded. The legend
        stands outside the axes, under them (``ax.get_legend()``).
    """
    fig = new_figure(8.0, 4.8)
    ax = fig.add_subplot()
    speed = result.spindle_speed_rpm
    env_mm = result.depth_limit_m * MM_PER_M
    if show_lobes:
        for lobe in result.lobes:
            if lobe.spindle_speed_rpm.size:
                ax.plot(
                    lobe.spindle_speed_rpm,
                    lobe.depth_limit_m * MM_PER_M,
                    color="0.6",
                    lw=0.8,
                    gid=f"lobe-{lobe.index}",
                )
    covered = np.isfinite(env_mm)
    # a semi-discretization speed without a limit is stable up to its search depth (not unsettled)
    stable_to = getattr(result, "depth_search_max_m", None)
    shade_mm = np.where(covered, env_mm, stable_to * MM_PER_M if stable_to is not None else 0.0)
    shaded = covered | (stable_to is not None)
    ax.fill_between(
        speed,
        0.0,
        np.where(shaded, shade_mm, 0.0),
        where=shaded,
        color="tab:green",
        alpha=0.15,
        lw=0,
        label="stable",
    )
    ax.plot(speed, env_mm, color="tab:blue", lw=2.0, gid="envelope", label="stability limit")
    if robust_depth_limit_m is not None:
        robust_mm = np.asarray(robust_depth_limit_m, dtype=float) * MM_PER_M
        ax.plot(speed, robust_mm, color="tab:orange", lw=1.5, ls="--", gid="robust", label=robust_label)
    min_mm = result.min_depth_limit_m * MM_PER_M
    ax.axhline(min_mm, color="tab:red", lw=0.8, ls="--", label=f"absolute limit {min_mm:.3g} mm")
    if operating_point is not None:
        n_op, b_op = (float(v) for v in operating_point)
        limit = (
            np.interp(n_op, speed[covered], result.depth_limit_m[covered])
            if covered.any()
            else np.nan
        )
        stable = bool(b_op < limit)
        ax.plot(
            [n_op],
            [b_op * MM_PER_M],
            marker="o",
            ms=8,
            ls="none",
            gid="operating-point",
            color="tab:green" if stable else "tab:red",
            label="operating point",
        )
    top = depth_max_mm
    if top is None:
        finite_max = float(np.nanmax(env_mm)) if covered.any() else min_mm
        top = 1.1 * min(finite_max, 8.0 * min_mm) if np.isfinite(min_mm) else 1.1 * finite_max
    if flute_length_m is not None and np.isfinite(flute_length_m):
        flute_mm = flute_length_m * MM_PER_M
        ax.axhline(flute_mm, color="0.3", lw=1.0, ls=":", gid="flute-length",
                   label=f"flute length {flute_mm:.3g} mm (no deeper stepdown)")
        if depth_max_mm is None and covered.any() and float(np.nanmax(env_mm)) > flute_mm:
            top = 1.15 * flute_mm  # deeper limits than the flute cannot be used
    for k, (why, mask) in enumerate((doubtful_speeds or {}).items()):
        hatch = ("////", "\\\\", "xx")[k % 3]
        for i, (lo, hi) in enumerate(_speed_runs(speed, np.asarray(mask, dtype=bool))):
            ax.axvspan(lo, hi, facecolor="0.85", edgecolor="0.55", hatch=hatch, lw=0, alpha=0.6, zorder=0.5,
                       gid=f"doubtful-{why}", label=None if i else _DOUBTFUL.get(why, why))
    ax.set_xlim(speed[0], speed[-1])
    ax.set_ylim(0.0, top)
    ax.set_xlabel("Spindle speed (rpm)")
    ax.set_ylabel("Axial depth of cut limit (mm)")
    ax.grid(True, alpha=0.3)
    ax.xaxis.set_major_locator(MaxNLocator(nbins=7))
    # under the axes (below the speed label), never over the low-speed lobes
    ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.16), ncols=3, fontsize="small")
    fig.suptitle(checked_text(title, "title") if title else "Stability lobes", fontsize="medium")
    ax.set_title(_lobes_conditions(result, conditions), fontsize="small")
    if notes:
        import textwrap  # noqa: PLC0415 (only for diagrams with notes)

        text = "\n".join(textwrap.fill("• " + checked_text(n, "notes"), 150) for n in notes)
        share = min(0.05 + 0.025 * text.count("\n"), 0.3)  # of the height, under the axes
        fig.text(0.01, 0.005, text, fontsize=6.5, va="bottom", ha="left", gid="notes", color="tab:red")
        engine = fig.get_layout_engine()
        assert isinstance(engine, ConstrainedLayoutEngine)  # every figure starts constrained (figure())
        engine.set(rect=(0.0, share, 1.0, 1.0 - share))
    return freeze_layout(fig)


#: What the hatched speeds of a lobe diagram mean, by the reason :func:`rcsa.app.summaries.unsettled_speeds` gives.
_DOUBTFUL = {
    "under-resolved": "under-resolved: < 8 SDM steps per chatter cycle",
    "unresolved": "unresolved: two SDM resolutions differ > 1 %",
    "coarse grid": "coarse grid: lobes drawn as straight chords",
}


def _speed_runs(speed: np.ndarray, mask: np.ndarray) -> list[tuple[float, float]]:
    """The speed intervals of the contiguous runs of ``mask``, each reaching halfway to the
    unflagged neighbours (a single flagged speed still gets a visible band)."""
    if mask.size != speed.size or not mask.any():
        return []
    edges = np.concatenate([[speed[0]], 0.5 * (speed[1:] + speed[:-1]), [speed[-1]]])
    change = np.flatnonzero(np.diff(np.concatenate([[0], mask.astype(np.int8), [0]])))
    return [(float(edges[a]), float(edges[b])) for a, b in zip(change[::2], change[1::2], strict=True)]


def _lobes_conditions(result: LobeResult, conditions: Mapping[str, Any] | None) -> str:
    """The line under a lobe diagram's title: cutting conditions, method and where the FRF
    came from (only what is known is said)."""
    c = dict(conditions or {})
    method = c.get("method") or ("semi_discretization" if hasattr(result, "steps_per_period") else "zoa")
    steps = c.get("steps_per_period", getattr(result, "steps_per_period", None))
    cutting = ""
    if "teeth" in c:
        cutting = (f"{c['teeth']} teeth · a_e/D = {float(c['radial_immersion']):g} · {c['milling']} milling · "
                   f"K_t = {float(c['tangential_coefficient_n_m2']) / 1e6:g} N/mm² · "
                   f"K_r/K_t = {float(c['radial_ratio']):g}\n")
    scheme = getattr(result, "scheme", None)
    resolving = "steps resolving the cut, checked per speed" if scheme == "cut_window" else \
        "steps resolving the period, checked per speed"
    fixed = c.get("steps_per_period") is not None
    how = ("semi-discretization (" + (f"{steps} steps/period" if fixed else resolving) + ")"
           if method == "semi_discretization" else "zero-order (Altintas–Budak)")
    frf = {"assembly": "FRF: the assembly's predicted tool point, in x and y (symmetric tool)",
           "x_only": "FRF: only x given, Φyy = Φxx assumed", "x_and_y": "FRF: x and y given",
           "modal_table_x_only": "modal table of x, the same in y", "modal_table_x_and_y": "modal tables of x and y"}.get(
        str(c.get("frf")), "FRF: Φyy = Φxx (the x FRF used in y)" if result.same_frf_in_y else "FRF: x and y given")
    return checked_text(f"{cutting}{how} · {frf}", "conditions")


def effects_figure(report: EffectReport, features: Sequence[str] = ("frequency_hz", "peak_magnitude_m_n",
                                                                      "damping_ratio")) -> Any:
    """Heat map of the sensitivities, modes × parameters, one panel per feature.

    Uses :class:`matplotlib.figure.Figure` with the Agg canvas (never pyplot).

    Returns
    -------
    matplotlib.figure.Figure
        Save it with :func:`rcsa.analysis.figures.save_figure`.

    Raises
    ------
    InputError
        When the report holds no mode or no parameter.
    """
    from matplotlib.colors import TwoSlopeNorm

    nm, npar = report.frequency_hz.size, len(report.parameters)
    if nm == 0 or npar == 0:
        raise InputError("band_hz", "the report has no mode (or no parameter) to draw")
    fig = new_figure(max(6.0, 0.5 * npar + 2.5), 2.2 + len(features) * max(1.6, 0.3 * nm + 0.8))
    axes = fig.subplots(len(features), 1, squeeze=False, sharex=True)[:, 0]
    part = report.tip_participation
    ylabels = [f"{f:.0f} Hz ({percent_label(p)})" for f, p in zip(report.frequency_hz, part, strict=True)]
    titles = {"frequency_hz": "natural frequency", "peak_magnitude_m_n": "peak |h|",
              "damping_ratio": "damping ratio", "peak_frequency_hz": "peak frequency"}
    cmap = matplotlib.colormaps["RdBu_r"].with_extremes(bad="0.85")
    for ax, q in zip(axes, features, strict=True):
        s = np.asarray(report.sensitivity[q], dtype=float)
        lim = float(np.nanmax(np.abs(s))) if np.any(np.isfinite(s)) else 1.0
        lim = lim if lim > 0 else 1.0
        image = ax.imshow(np.ma.masked_invalid(s), aspect="auto", cmap=cmap,
                          norm=TwoSlopeNorm(0.0, -lim, lim), interpolation="nearest")
        for (i, j), v in np.ndenumerate(s):
            if math.isfinite(v) and abs(v) >= 0.01 * lim:
                ax.text(j, i, f"{v:.2g}", ha="center", va="center", fontsize=6)
        ax.set_yticks(range(nm), ylabels, fontsize=7)
        ax.set_title(f"d ln({titles.get(q, q)}) / d ln(parameter)", fontsize=9)
        fig.colorbar(image, ax=ax, shrink=0.9)
    axes[-1].set_xticks(range(npar), report.parameters, rotation=60, ha="right", fontsize=7)
    axes[0].text(0.0, 1.12, "modes: natural frequency (tip participation); grey: no peak at the tool point",
                 transform=axes[0].transAxes, fontsize=7)
    return freeze_layout(fig)


def save_figure(fig: Figure, path_or_format: str | Path, *, dpi: int = SAVE_DPI) -> bytes | Path:
    """Write a figure as PNG or SVG.

    Parameters
    ----------
    fig : matplotlib.figure.Figure
    path_or_format : str or pathlib.Path
        ``"png"`` or ``"svg"`` (case-insensitive): return the file's bytes. Anything else
        is a path whose suffix (``.png``/``.svg``) selects the format; the file is written.
    dpi : int
        Resolution of PNG output.

    Returns
    -------
    bytes or pathlib.Path
        The bytes, or the path written.
    """
    as_bytes = isinstance(path_or_format, str) and path_or_format.lower() in _FORMATS
    if as_bytes:
        fmt = str(path_or_format).lower()
    else:
        path = Path(path_or_format)
        fmt = path.suffix.lower().lstrip(".")
        if fmt not in _FORMATS:
            raise InputError("path", f"suffix must be .png or .svg, got {path.suffix!r}")
    buf = io.BytesIO()
    # Reproducible files: no timestamp, fixed SVG id salt (temporary, restored on exit).
    metadata = {"Date": None} if fmt == "svg" else {"Software": None}
    with matplotlib.rc_context({"svg.hashsalt": "rcsa", "svg.fonttype": "path"}):
        fig.savefig(buf, format=fmt, dpi=dpi, metadata=metadata)
    data = buf.getvalue()
    if as_bytes:
        return data
    path.write_bytes(data)
    return path
