"""Pictures people look at (PNG or SVG): tool-point FRFs, stability lobes, effect maps, diagnoses.

The CLI (``rcsa plot``, ``--plot`` of ``lobes``/``effects``/``diagnose``) and the REST
service (``POST /v1/plots/...``) both draw through these functions. Figures are matplotlib
:class:`~matplotlib.figure.Figure` objects on the Agg canvas (:mod:`rcsa.analysis.figures`);
matplotlib is imported only when something is drawn.
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Literal

import numpy as np

from rcsa.analysis.effects.sensitivities import effects_report
from rcsa.analysis.figures import effects_figure
from rcsa.analysis.lobes.zoa import LobeResult
from rcsa.analysis.progress import Progress
from rcsa.app.analyses import stability_lobes_answer
from rcsa.app.predictions import predict
from rcsa.app.stores import resolver
from rcsa.app.summaries import unsettled_speeds
from rcsa.errors import InputError
from rcsa.measured.hybrid import MeasurementSource
from rcsa.model.bounds import MAX_FREQUENCY_LINES
from rcsa.model.input_policy import check_count
from rcsa.model.wire import complex_from_wire, number_list

__all__ = [
    "FIGURE_SUFFIXES",
    "FRF_LAYOUTS",
    "Curve",
    "Figure",
    "band_of",
    "check_picture_path",
    "diagnosis_with_figure",
    "document_figure",
    "effects_with_figure",
    "frf_figure",
    "lobes_figure",
    "prediction_figure",
    "robust_lobes_figure",
    "save_figure",
    "tool_point_curve",
]

#: Picture files: PNG or SVG, chosen by the suffix.
FIGURE_SUFFIXES = (".png", ".svg")
#: FRF layouts: real/imaginary and magnitude/phase, real/imaginary only, magnitude/phase only.
FRF_LAYOUTS = ("full", "real_imag", "bode")

#: A matplotlib figure (typed loosely: matplotlib is imported only when drawing).
Figure = Any


@dataclass(frozen=True)
class Curve:
    """A tool-point receptance to draw.

    Attributes
    ----------
    frequency_hz : numpy.ndarray, shape (nfreq,)
    h_m_n : numpy.ndarray, shape (nfreq,), complex
    source : {"frf", "assembly"}
        Where it came from (names the field of an error about it).
    band_m_n : tuple of numpy.ndarray or None
        The p05 and p95 ``|h|`` of an assembly predicted with ``uncertainty``, m/N.
    natural_frequencies_hz : numpy.ndarray or None
        An assembly's natural frequencies, Hz (marked on its picture).
    """

    frequency_hz: np.ndarray
    h_m_n: np.ndarray
    source: Literal["frf", "assembly"]
    band_m_n: tuple[np.ndarray, np.ndarray] | None = None
    natural_frequencies_hz: np.ndarray | None = None


def check_picture_path(path: str | os.PathLike[str], field: str) -> Path:
    """``path`` if it ends in .png or .svg.

    Raises
    ------
    InputError
        Naming ``field`` (the option that gave the path).
    """
    p = Path(path)
    if p.suffix.lower() not in FIGURE_SUFFIXES:
        raise InputError(field, f"the picture must end in .png or .svg, got {p.name!r}")
    return p


def save_figure(figure: Figure, path_or_format: str | os.PathLike[str]) -> bytes | Path:
    """A figure as PNG or SVG bytes (``"png"``/``"svg"``), or written to a .png/.svg path."""
    # matplotlib (~0.3 s to import): only when a picture is asked for
    from rcsa.analysis.figures import save_figure as save

    return save(figure, path_or_format if isinstance(path_or_format, str) else Path(path_or_format))


def frf_figure(frequency_hz: Any, h_m_n: Any, *, layout: str = "full", title: str | None = None,
               labels: list[str] | None = None, band_m_n: tuple[Any, Any] | None = None,
               natural_frequencies_hz: Any = None) -> Figure:
    """Real and imaginary parts, magnitude and phase of receptances (µm/N) against frequency;
    ``band_m_n`` (low, high ``|h|``, m/N) is shaded on the magnitude axes, the
    ``natural_frequencies_hz`` are marked and listed in the title."""
    # matplotlib: only when a picture is asked for
    from rcsa.analysis.figures import frf_figure as draw

    if layout not in FRF_LAYOUTS:
        raise InputError("layout", f"must be one of {', '.join(FRF_LAYOUTS)}, got {layout!r}")
    return draw(frequency_hz, h_m_n, layout=layout, title=title, labels=labels,  # type: ignore[arg-type]
                band_m_n=band_m_n, natural_frequencies_hz=natural_frequencies_hz)


def prediction_figure(result: Mapping[str, Any], *, layout: str = "full", title: str | None = None) -> Figure:
    """The tool-point ``h`` of a prediction result (or a :class:`~rcsa.model.prediction.Prediction`),
    titled, its natural frequencies marked (exact, or modal-fit estimates on a measured
    spindle) and its uncertainty band shaded."""
    tool_point = result.get("tool_point")
    h = tool_point.get("h") if isinstance(tool_point, Mapping) else None
    h = h if isinstance(h, np.ndarray) else complex_from_wire(h, "tool_point.h", finite=False)
    fitted = result.get("natural_frequencies_method") == "modal_fit"
    heading = title or ("Tool-point FRF h (measured spindle)" if fitted else "Tool-point FRF h")
    freqs = result.get("natural_frequencies_hz")
    return frf_figure(result.get("frequency_hz"), h, labels=["tool point h"], layout=layout, title=heading,
                      band_m_n=band_of(result), natural_frequencies_hz=[] if freqs is None else freqs)


def lobes_figure(result: LobeResult, **options: Any) -> Figure:
    """The stability lobe diagram (:func:`rcsa.analysis.figures.lobes_figure`; ``options``:
    ``show_lobes``, ``operating_point`` (rpm, m), ``depth_max_mm``, ``title``)."""
    # matplotlib: only when a picture is asked for
    from rcsa.analysis.figures import lobes_figure as draw

    return draw(result, **options)


def band_of(result: Mapping[str, Any]) -> tuple[np.ndarray, np.ndarray] | None:
    """The p05–p95 ``|h|`` band of a prediction result (``to_dict()``), None without one.

    Raises
    ------
    InputError
        An ``uncertainty`` whose percentiles are not number lists.
    """
    band = result.get("uncertainty")
    if not isinstance(band, Mapping):
        return None
    mag = band.get("h_magnitude_m_n")
    if not isinstance(mag, Mapping):
        raise InputError("uncertainty.h_magnitude_m_n", "must be an object with p05 and p95")
    return (number_list(mag.get("p05"), "uncertainty.h_magnitude_m_n.p05", finite=False),
            number_list(mag.get("p95"), "uncertainty.h_magnitude_m_n.p95", finite=False))


def robust_lobes_figure(result: LobeResult, robust: Mapping[str, Any] | None, **options: Any) -> Figure:
    """:func:`lobes_figure` with what a response says beside the diagram: the robust limit
    (``depth_limit_robust_m`` and ``robust``, :meth:`rcsa.analysis.lobes.robust.RobustLobes.to_dict`)
    drawn dashed, the tool's ``flute_length_m`` (a line; the depth axis stops just above it),
    the ``conditions`` under the title, the speeds whose limit is doubtful hatched
    (:func:`rcsa.app.summaries.unsettled_speeds`) and the ``notes`` written under it."""
    extra = dict(robust or {})
    notes = extra.get("notes")
    flute = extra.get("flute_length_m")
    conditions = extra.get("conditions")
    options = {**options, "notes": [str(n) for n in notes] if isinstance(notes, list) else (),
               "flute_length_m": float(flute) if isinstance(flute, int | float) and not isinstance(flute, bool)
               else None,
               "conditions": conditions if isinstance(conditions, Mapping) else None,
               "doubtful_speeds": unsettled_speeds({**result.to_dict(), **extra})}
    if extra.get("depth_limit_robust_m") is None:
        return lobes_figure(result, **options)
    depth = number_list(extra["depth_limit_robust_m"], "depth_limit_robust_m", finite=False)
    about = extra.get("robust")
    pct = about.get("percentile") if isinstance(about, Mapping) else None
    label = f"robust limit (p{pct:g} of draws)" if isinstance(pct, int | float) else "robust limit"
    return lobes_figure(result, robust_depth_limit_m=depth, robust_label=label, **options)


def tool_point_curve(*, frf: Mapping[str, Any] | None = None, assembly: Mapping[str, Any] | None = None,
                     store: MeasurementSource | None = None, max_lines: int = MAX_FREQUENCY_LINES) -> Curve:
    """The tool-point ``h`` of an inline FRF (``{"frequency_hz", "h": {"real", "imag"}}``), or
    of an assembly predicted first; exactly one of them.

    Raises
    ------
    InputError
        Both or neither given, or the FRF's arrays disagree in length.
    """
    if (frf is None) == (assembly is None):
        raise InputError("frf", "give either frf (an inline FRF) or assembly, exactly one of them")
    if frf is not None:
        if isinstance(frf.get("frequency_hz"), list):
            check_count(len(frf["frequency_hz"]), "frf.frequency_hz", max_lines, "frequency lines")
        f = number_list(frf.get("frequency_hz"), "frf.frequency_hz", finite=False)
        return Curve(f, complex_from_wire(frf.get("h"), "frf.h", f.size, finite=False), "frf")
    result = predict(assembly, store=store, max_lines=max_lines)  # type: ignore[arg-type]
    band = None if result.uncertainty is None else band_of(result.to_dict())
    return Curve(result.frequency_hz, result.tool_point.h, "assembly", band, result.natural_frequencies_hz)


def frf_picture(curve: Curve, *, fmt: str, layout: str = "full", title: str | None = None) -> bytes:
    """A tool-point FRF as PNG or SVG bytes.

    Raises
    ------
    InputError
        Fewer than two lines, or (log-scaled layouts) an ``h`` that is zero everywhere.
    """
    where = curve.source
    if curve.frequency_hz.size < 2:
        raise InputError(f"{where}.frequency_hz" if where == "frf" else f"{where}.frequency",
                         "a figure needs at least 2 frequency lines")
    if layout != "real_imag" and not np.any(np.abs(curve.h_m_n) > 0):
        raise InputError(f"{where}.h" if where == "frf" else where,
                         "h is zero at every line, so its magnitude cannot be drawn on a log scale; "
                         "use layout real_imag")
    heading = title or ("Tool-point FRF h" if curve.source == "assembly" else "FRF h")
    return save_figure(frf_figure(curve.frequency_hz, curve.h_m_n, layout=layout, title=heading,  # type: ignore[return-value]
                                  band_m_n=curve.band_m_n, natural_frequencies_hz=curve.natural_frequencies_hz), fmt)


def lobes_picture(result: LobeResult, *, fmt: str, robust: Mapping[str, Any] | None = None, **options: Any) -> bytes:
    """The stability lobe diagram as PNG or SVG bytes (``options`` as in :func:`lobes_figure`;
    ``robust`` as in :func:`robust_lobes_figure`)."""
    return save_figure(robust_lobes_figure(result, robust, **options), fmt)  # type: ignore[return-value]


def document_figure(doc: object, *, layout: str = "full", store: MeasurementSource | None = None) -> Figure:
    """The figure that fits a JSON document, recognised by its content.

    A prediction result (``tool_point``), a measurement in the contract's JSON form
    (``h`` and ``frequency_hz``), a stability-lobes result (``spindle_speed_rpm`` as a list
    and ``depth_limit_m``), a stability-lobes request (solved first) or an assembly
    (predicted first).
    """
    if not isinstance(doc, dict):
        raise InputError("", "the input must be a JSON object")
    if "tool_point" in doc:
        return prediction_figure(doc, layout=layout)
    if "h" in doc and "frequency_hz" in doc:
        where = ", ".join(str(doc[k]) for k in ("spindle_id", "direction", "plane") if isinstance(doc.get(k), str))
        return frf_figure(doc["frequency_hz"], complex_from_wire(doc["h"], "h", finite=False),
                          labels=["measured h"], layout=layout,
                          title="Measured FRF h" + (f" ({where})" if where else ""))
    if isinstance(doc.get("spindle_speed_rpm"), list) and "depth_limit_m" in doc:
        return robust_lobes_figure(LobeResult.from_dict(doc), doc)  # a stability-lobes result
    if "tangential_coefficient_n_m2" in doc:
        answer = stability_lobes_answer(doc, store=store)
        return robust_lobes_figure(answer.nominal, answer.extras())
    if "tool" in doc and "spindle" in doc:
        return prediction_figure(predict(doc, store=store), layout=layout)
    raise InputError("", "not a prediction result, measurement, assembly, stability-lobes request or "
                         "stability-lobes result")


def effects_with_figure(request: Mapping[str, Any], picture: str | os.PathLike[str] | None = None, *,
                        store: MeasurementSource | None = None, progress: Progress | None = None) -> dict[str, Any]:
    """Effect analysis (:func:`rcsa.app.analyses.effects`), its heat map drawn to ``picture``
    (.png or .svg) when given; ``store`` is where a measured spindle is looked up;
    ``progress(done, total)`` is called at each step."""
    report = effects_report(request, resolver(store), progress)
    if picture is not None:
        save_figure(effects_figure(report), picture)
    return report.to_dict()


def diagnosis_with_figure(request: Mapping[str, Any], picture: str | os.PathLike[str] | None = None, *,
                          store: MeasurementSource | None = None,
                          progress: Progress | None = None) -> dict[str, Any]:
    """Diagnosis (:func:`rcsa.app.analyses.diagnose`), its figure (measured, base and corrected
    FRFs, and the gap map) drawn to ``picture`` (.png or .svg) when given; ``progress(done,
    total)`` is called at each step.

    ``store``: where a measured spindle is looked up (the default store when omitted).

    Raises
    ------
    OSError
        The picture cannot be written (the diagnosis itself succeeded).
    """
    # scipy.stats and scipy.optimize (~0.9 s to import): only when a diagnosis is asked for
    from rcsa.analysis.diagnosis.report import build_response, diagnosis_figure
    from rcsa.analysis.diagnosis.state import analyse

    analysis = analyse(request, resolver(store), progress)
    response = build_response(analysis)
    if picture is not None:
        save_figure(diagnosis_figure(analysis, response), picture)
    return response
