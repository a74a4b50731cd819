"""``rcsa plot INPUT.json -o OUT.png|svg``: pictures of FRFs and stability lobes.

The input is recognised by its content: a prediction result (``tool_point``), a measurement
in the contract's JSON form (``h``), an assembly (predicted first), or a stability-lobes
request (solved first).
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Any

import numpy as np
import typer

from rcsa.cli._common import read_json, run_guarded


def _complex(doc: Any, field: str) -> np.ndarray:
    from rcsa.errors import InputError

    try:
        return np.asarray(doc["real"], dtype=float) + 1j * np.asarray(doc["imag"], dtype=float)
    except (KeyError, TypeError, ValueError):
        raise InputError(field, "must be {\"real\": [...], \"imag\": [...]}") from None


def figure_for(doc: Any, layout: str, store: Any) -> Any:
    """The figure that fits the document (see the module docstring)."""
    from rcsa import app
    from rcsa.analysis.figures import frf_figure, lobes_figure
    from rcsa.errors import InputError

    if not isinstance(doc, dict):
        raise InputError("", "the input must be a JSON object")
    if "tool_point" in doc:
        return frf_figure(doc["frequency_hz"], _complex(doc["tool_point"].get("h"), "tool_point.h"),
                          labels=["tool point h"], layout=layout)
    if "h" in doc and "frequency_hz" in doc:
        return frf_figure(doc["frequency_hz"], _complex(doc["h"], "h"), labels=["measured h"], layout=layout)
    if "tangential_coefficient_n_m2" in doc:
        return lobes_figure(app.stability_lobes_result(doc, store=store))
    if "tool" in doc and "spindle" in doc:
        result = app.predict(doc, store=store)
        return frf_figure(result.frequency_hz, result.tool_point.h, labels=["tool point h"], layout=layout)
    raise InputError("", "not a prediction result, measurement, assembly or stability-lobes request")


def register(app: typer.Typer) -> None:
    """Add the ``plot`` command to ``app``."""

    @app.command()
    def plot(
        source: Annotated[Path, typer.Argument(help="Prediction result, measurement, assembly or lobes request (JSON).")],
        out: Annotated[Path, typer.Option("-o", "--out", help="Picture to write: .png or .svg.")],
        layout: Annotated[str, typer.Option(help="FRF layout: full, real_imag or bode.")] = "full",
        store: Annotated[Path | None, typer.Option("--store", help="Measurement store for hybrid assemblies.")] = None,
    ) -> None:
        """Draw an FRF (real/imaginary, magnitude/phase) or a stability lobe diagram."""
        from rcsa.analysis.figures import save_figure
        from rcsa.errors import InputError
        from rcsa.measured.store import MeasurementStore

        doc = read_json(source)

        def draw() -> None:
            if out.suffix.lower() not in (".png", ".svg"):
                raise InputError("--out", f"the picture must end in .png or .svg, got {out.name!r}")
            if layout not in ("full", "real_imag", "bode"):
                raise InputError("--layout", "must be full, real_imag or bode")
            save_figure(figure_for(doc, layout, MeasurementStore(store) if store else None), out)

        run_guarded(draw)
