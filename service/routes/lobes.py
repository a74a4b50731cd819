"""``POST /v1/stability-lobes``: stability lobes from inline FRFs or an assembly."""

from __future__ import annotations

from typing import Any

from fastapi import APIRouter, Depends
from pydantic import BaseModel
from starlette.requests import Request
from starlette.responses import Response

from rcsa.app import budget
from rcsa.app.analyses import resolve_lobes_references
from rcsa.app.analyses import stability_lobes as lobes

from ..bodies import require_json
from ..deps import StateDep
from ..jobs import caller, compute
from ..responses import ASYNC_ACCEPTED, body_limit, json_response, problems
from ..routing import ServiceRoute
from ..schemas import LobesRequest, LobesResult
from ..security import ReadAccess
from ..state import AppState
from .batches import PreferHeader

router = APIRouter(prefix="/v1", tags=["stability lobes"], route_class=ServiceRoute)


@router.post("/stability-lobes", dependencies=[Depends(require_json)], response_model=LobesResult,
             responses={**problems(401, 413, 415, 422), **ASYNC_ACCEPTED}, openapi_extra=body_limit("lobes"),
             summary="Stability lobes (zero-order or semi-discretization)")
def compute_stability_lobes(body: LobesRequest, request: Request, state: StateDep, who: ReadAccess,
                    prefer: PreferHeader = None) -> Response:
    """Axial depth limit (m) versus spindle speed (rpm), its chatter frequency (Hz) and every
    lobe, from inline tool-point FRFs (``frf_x``, optional ``frf_y``) or an ``assembly``.
    ``"method"``: ``auto`` (the default: zero-order where it is exact, else the resolved
    semi-discretization; zero-order, marked unresolved, where that would not fit an answer given
    at once), ``zoa`` (zero-order, Altintas–Budak) or ``semi_discretization`` (Insperger–Stépán,
    resolving the cut, every speed checked: right at low radial immersion, and it finds the flip lobes).

    By reference instead of re-sending them: ``"library_tool": {"library_id", "tool_id"}`` (a stored
    library's tool: its assembly is rebuilt from the library's last sync; ``teeth`` defaults to
    its flute count), or ``"frf_x": {"measurement_id": ...}`` (a stored measurement's ``h``).

    Under the compute budget (speeds × lines, and the assembly's prediction); ``Prefer:
    respond-async`` runs it as a job."""
    doc = lobes_document(body, state)

    def run() -> Response:
        with state.metrics.timed("lobes"):
            result = lobes(doc, store=state.reader, max_lines=state.settings.max_frequency_lines, within=budget.SYNC)
        return json_response(result)

    return compute(state, "lobes", doc, prefer=prefer, run=run, owner=caller(who, request))


def lobes_document(body: BaseModel, state: AppState, exclude: set[str] | None = None) -> dict[str, Any]:
    """A lobes request's document with its references to stored tools and measurements resolved
    (:func:`rcsa.app.analyses.resolve_lobes_references`; the stability-lobes, lobes-plot and
    lobes-CSV routes)."""
    doc = body.model_dump(exclude_unset=True, exclude=exclude)
    return resolve_lobes_references(doc, store=state.reader, libraries=state.bench.libraries)
