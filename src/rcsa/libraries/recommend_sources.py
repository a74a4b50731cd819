"""Where the tool-point FRFs of a recommendation come from: a stored sync, or a prediction now.

* **A stored library** (``POST /v1/libraries/{id}:recommend``, ``rcsa library recommend
  --library-id``): the uploaded Fusion file is imported with the settings of the library's
  last sync (spindle, grid, joints, materials, import options) and every tool's result key
  (:func:`rcsa.libraries.results_cache.result_key`) is computed; a tool gets its stored FRF
  only when the key equals the one stored for that tool id. A tool changed since the sync
  (its geometry, holder, …), or not in it, gets no FRF and is reported with the reason
  ("sync the library first") — a preset is never computed from another tool's dynamics.
  The presets themselves do not enter the key, so a file already holding rcsa's presets
  still matches.
* **A prediction** (``rcsa library recommend --spindle`` / ``--measurement``): the library is
  predicted on the spindle (:func:`rcsa.libraries.library_prediction.run_entries`, only the
  receptance ``h`` kept).

With an ``uncertainty`` option (robust presets) every tool with an FRF also gets the ``h`` of
its drawn assemblies (:meth:`rcsa.model.spindle_side.SpindleSide.tool_point_draws`), from the
same settings — the stored sync's, or the ones given — so the pocket can be chosen on the
robust limit. The draws come from the reduced model of the draws (each draw solved exactly
on a few percent of the lines, :mod:`rcsa.model.reduced_draws`; about 10 predictions per 200
draws), or — with ``"solver": "exact"`` — from a full solve per draw, which the limit is
priced for: at most :data:`MAX_DRAWN_LINES` tools × draws × lines per request.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from rcsa.errors import InputError
from rcsa.libraries.fusion import FusionLibrary
from rcsa.libraries.library_prediction import library_request, resolver_of, run_entries
from rcsa.libraries.recommend import Frf, FrfFailure
from rcsa.libraries.sync import LibraryStore, plan_sync, sync_request
from rcsa.measured.hybrid import MeasurementSource
from rcsa.model.batch import parse_batch
from rcsa.model.bounds import MAX_BATCH_COMBINATIONS, MAX_FREQUENCY_LINES
from rcsa.model.contract import MeasuredSpindleSpec, assemble, parse_combination
from rcsa.model.spindle_side import SpindleSide
from rcsa.model.uncertainty import parse_uncertainty
from rcsa.model.wire import complex_from_wire

__all__ = ["MAX_DRAWN_LINES", "FrfSource", "SYNC_SETTINGS", "draw_frfs", "frfs_from_results", "predicted_frfs",
           "stored_frfs"]

#: Largest tools × draws × frequency lines of one robust recommendation (about 20 s of exact
#: solves on the development VM: 0.94 s per 200 draws × 2 000 lines of RA-1; the reduced
#: model of the draws, the default, takes about an eighth of that).
MAX_DRAWN_LINES = 8_000_000

#: The settings of a stored sync that determine its results (passed to ``sync_request``).
SYNC_SETTINGS = ("spindle", "frequency", "joints", "materials", "beam_theory", "shear_coefficient",
                 "natural_frequencies", "options")


@dataclass(frozen=True, slots=True)
class FrfSource:
    """The import entries of a library and the FRF (or the reason for none) of each tool.

    Attributes
    ----------
    entries : list of dict
        One per library item (``id``, ``index``, ``status``, ``reason``/``error``, ``teeth``,
        ``tool_type``, ``description``, ``number``, ``warnings``).
    frfs : dict of str to Frf or str
        Tool id → FRF, or why there is none.
    source : dict
        Where the FRFs come from (``{"kind": "stored", "library_id", "revision"}`` or
        ``{"kind": "predicted", "computed"}``).
    """

    entries: list[dict[str, Any]]
    frfs: dict[str, Frf | str]
    source: dict[str, Any]


def frfs_from_results(results: list[Mapping[str, Any]]) -> dict[str, Frf | str]:
    """Tool id → FRF for the ``ok`` results of a library prediction, else the reason.

    Parameters
    ----------
    results : list of mapping
        Results of :func:`rcsa.libraries.library_prediction.run_entries` or of
        :meth:`rcsa.libraries.sync.LibraryStore.results` (``tool_point.h`` as
        ``{"real", "imag"}``).

    Returns
    -------
    dict of str to Frf or str
    """
    out: dict[str, Frf | str] = {}
    for r in results:
        ident = str(r.get("id"))
        if r.get("status") == "ok" and "tool_point" in r and "h" in r["tool_point"]:
            h = r["tool_point"]["h"]
            out[ident] = Frf(np.asarray(r["frequency_hz"], dtype=float),
                             complex_from_wire(h, f"results[{ident}].tool_point.h", finite=False))
        elif r.get("status") == "error":
            error = r.get("error") or {}
            out[ident] = FrfFailure(f"its tool-point FRF failed: {error.get('field', '')}: {error.get('detail', '')}")
        else:
            out[ident] = str(r.get("reason") or "no tool-point FRF")
    return out


def draw_frfs(frfs: dict[str, Frf | str], batch: Mapping[str, Any], uncertainty: Mapping[str, Any], *,
              store: MeasurementSource | None = None, max_lines: int = MAX_FREQUENCY_LINES) -> None:
    """Add the drawn assemblies' ``h`` to every tool of ``frfs`` that has an FRF (in place).

    Parameters
    ----------
    frfs : dict of str to Frf or str
        Tool id → FRF (replaced by one with ``h_draws``) or the reason for none (kept).
    batch : mapping
        The batch request the FRFs were computed from (spindle, grid, combinations by id).
    uncertainty : mapping
        The ``uncertainty`` option (:func:`rcsa.model.uncertainty.parse_uncertainty`).
    store : MeasurementSource, optional
        Where a measured spindle is looked up.
    max_lines : int
        Largest accepted number of frequency lines.

    Raises
    ------
    InputError
        An invalid option, or more than :data:`MAX_DRAWN_LINES` tools × draws × lines.
    """
    combos, _, common = parse_batch({k: v for k, v in batch.items() if k != "tool_point"}, max_lines=max_lines)
    options = parse_uncertainty(uncertainty, "uncertainty", measured_spindle=isinstance(common.spindle,
                                                                                       MeasuredSpindleSpec),
                                lines=int(common.frequency_hz.size))
    if options is None:
        return
    todo = [c for c in combos if isinstance(frfs.get(str(c.get("id"))), Frf)]
    cost = len(todo) * options.draws * int(common.frequency_hz.size)
    if cost > MAX_DRAWN_LINES:
        raise InputError("uncertainty", f"{len(todo)} tools x {options.draws} draws x {common.frequency_hz.size} "
                                        f"lines = {cost:,} drawn lines; at most {MAX_DRAWN_LINES:,} per "
                                        "recommendation: fewer draws, a coarser grid or fewer tools")
    side = SpindleSide(common, resolver_of(store))
    for combo in todo:
        ident = str(combo["id"])
        frf = frfs[ident]
        assert isinstance(frf, Frf)
        spec = assemble(common, parse_combination(combo, common.materials, ident, extra_fields=("id",)))
        frfs[ident] = Frf(frf.frequency_hz, frf.h, side.tool_point_draws(spec, options).h)


def stored_frfs(libraries: LibraryStore, library_id: str, library: FusionLibrary, *,
                store: MeasurementSource | None = None, max_lines: int = MAX_FREQUENCY_LINES,
                uncertainty: Mapping[str, Any] | None = None) -> FrfSource:
    """The FRFs of a stored library's last sync for the tools of this export (module docstring).

    Raises
    ------
    NotFoundError
        No such library.
    InputError
        The stored settings no longer validate (e.g. the spindle measurement is gone).
    """
    summary = libraries.get(library_id)
    settings = summary.get("settings") or {}
    kwargs = {k: settings[k] for k in SYNC_SETTINGS if settings.get(k) is not None}
    if "spindle" not in kwargs or "frequency" not in kwargs:
        raise InputError("library_id", f"the stored library {library_id!r} has no spindle and grid settings")
    request = sync_request(library_id, library, **kwargs)
    plan = plan_sync(libraries, request, store=store, max_lines=max_lines)
    keys = {str(c["id"]): key for c, key in zip(request["batch"]["combinations"], plan.keys, strict=True)}
    stored = {str(t["id"]): t for t in summary["tools"]}
    results = {str(r["id"]): r for r in libraries.results(library_id, ["h"])["results"]}
    frfs: dict[str, Frf | str] = {}
    for entry in request["entries"]:
        ident = str(entry["id"])
        if entry["status"] != "ok":
            continue
        tool = stored.get(ident)
        if tool is None:
            frfs[ident] = f"not in the stored library {library_id!r}: sync the library first"
        elif tool.get("result_sha256") != keys.get(ident):
            frfs[ident] = (f"changed since the last sync of {library_id!r} (revision {summary['revision']}): "
                           "sync the library first")
        else:
            frfs.update(frfs_from_results([results[ident]]))
    if uncertainty is not None:
        draw_frfs(frfs, request["batch"], uncertainty, store=store, max_lines=max_lines)
    return FrfSource(request["entries"], frfs, {"kind": "stored", "library_id": library_id,
                                                "revision": summary["revision"]})


def predicted_frfs(library: FusionLibrary, *, spindle: Mapping[str, Any], frequency: Mapping[str, Any],
                   store: MeasurementSource | None = None, max_lines: int = MAX_FREQUENCY_LINES,
                   max_combinations: int = MAX_BATCH_COMBINATIONS,
                   progress: Callable[[int, int], None] | None = None,
                   uncertainty: Mapping[str, Any] | None = None, **fields: Any) -> FrfSource:
    """Predict the library's tool-point FRFs on a spindle now (``fields`` as in ``library_request``).

    Raises
    ------
    InputError
        The library or the settings are invalid, or it has more tools than ``max_combinations``.
    """
    fields.setdefault("natural_frequencies", False)  # the lobes need only h
    request = library_request(library, spindle=spindle, frequency=frequency, **fields)
    n = len(request["batch"]["combinations"])
    if n > max_combinations:
        raise InputError("library", f"has {n} tools to predict; at most {max_combinations} per request")
    result = run_entries({**request, "tool_point": ["h"]}, store=store, max_lines=max_lines,
                         max_combinations=max(max_combinations, 1), progress=progress, arrays="numpy")
    frfs = frfs_from_results(result["results"])
    if uncertainty is not None:
        draw_frfs(frfs, request["batch"], uncertainty, store=store, max_lines=max_lines)
    return FrfSource(request["entries"], frfs, {"kind": "predicted", "computed": n})
