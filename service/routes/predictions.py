"""``POST /v1/tool-point-frf``: one assembly → its tool-point FRF."""

from __future__ import annotations

from fastapi import APIRouter, Depends
from starlette.requests import Request
from starlette.responses import Response

from rcsa.app.predictions import predict, prediction_document

from ..bodies import require_json
from ..deps import StateDep
from ..jobs import caller, compute
from ..responses import ASYNC_ACCEPTED, body_limit, json_response, problems
from ..routing import ServiceRoute
from ..schemas import PredictionRequest, PredictionResult
from ..security import ReadAccess
from .batches import PreferHeader, ToolPointQuery

router = APIRouter(prefix="/v1", tags=["predictions"], route_class=ServiceRoute)


@router.post("/tool-point-frf", dependencies=[Depends(require_json)], response_model=PredictionResult,
             responses={**problems(401, 413, 415, 422), **ASYNC_ACCEPTED}, openapi_extra=body_limit("prediction"),
             summary="Tool-point FRF of one assembly")
def predict_tool_point(body: PredictionRequest, request: Request, state: StateDep, who: ReadAccess,
                           tool_point: ToolPointQuery = None, prefer: PreferHeader = None) -> Response:
    """Predict the tool-point receptance of a spindle–holder–tool assembly (contract "Assembly").

    The spindle is modelled (segments + bearings) or a stored measurement
    (``{"measurement_id": ...}``, hybrid). Lengths in m, frequencies in Hz; the result gives
    ``h, l, n, p`` in m/N, 1/N, rad/N, rad/(N·m).

    Compute budget (:mod:`rcsa.app.budget`): a request estimated above 20 s or 1 GiB (lines ×
    elements, and exact natural frequencies up to the grid's top) is a 422 saying how to
    shrink it, or send ``Prefer: respond-async`` to run it as a job (202).
    """
    doc = body.model_dump(exclude_unset=True)

    def run() -> Response:
        with state.metrics.timed("predict"):
            result = predict(doc, store=state.reader, max_lines=state.settings.max_frequency_lines)
        state.metrics.computed("predict", 1)
        return json_response(prediction_document(result, tool_point.split(",") if tool_point else None))

    return compute(state, "prediction", doc, prefer=prefer, run=run, owner=caller(who, request))
