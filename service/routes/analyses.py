"""Diagnoses, joint identifications and effect analyses: thin doors onto ``rcsa.app.analyses``.

Each route passes the JSON body to ``rcsa.app.analyses.diagnose`` / ``identify`` / ``effects``;
identifications and effect analyses also get the service's measurement store (measured spindles).
"""

from __future__ import annotations

from typing import Annotated, Any

from fastapi import APIRouter, Body, Depends
from starlette.requests import Request
from starlette.responses import Response

from rcsa.app import analyses

from ..bodies import require_json
from ..deps import StateDep
from ..jobs import caller, compute
from ..responses import ASYNC_ACCEPTED, body_limit, json_response, problems
from ..routing import ServiceRoute
from ..security import ReadAccess
from .batches import PreferHeader

router = APIRouter(prefix="/v1", tags=["analyses"], route_class=ServiceRoute)

_OPERATIONS = {
    "diagnose": ("/diagnoses", "diagnosis", "Sim-to-real gap diagnosis (contract \"Diagnosis\")"),
    "identify": ("/identifications", "identification", "Joint identification (contract \"Joint identification\")"),
    "effects": ("/effects", "effects", "Sensitivities of each mode to the model's parameters"),
}
_Request = Annotated[dict[str, Any], Body(description="The request document (see the contract).")]


#: Operations that read measured spindles from the service's store.
_WITH_STORE = {"identify", "effects"}


def _call(name: str, body: dict[str, Any], state: Any) -> Any:
    kwargs = {"store": state.reader} if name in _WITH_STORE else {}
    with state.metrics.timed(name):
        return getattr(analyses, name)(body, **kwargs)


def _route(name: str, path: str, operation: str, summary: str) -> None:
    def endpoint(request: Request, state: StateDep, who: ReadAccess, body: _Request,
                 prefer: PreferHeader = None) -> Response:
        return compute(state, operation, body, prefer=prefer, run=lambda: json_response(_call(name, body, state)),
                       owner=caller(who, request))

    endpoint.__name__ = f"post_{name}"
    endpoint.__doc__ = (f"{summary}: the body goes to ``rcsa.app.analyses.{name}``.\n\nUnder the compute budget "
                        f"(:mod:`rcsa.app.budget`, operation ``{operation}``): above 20 s or 1 GiB estimated, a 422 "
                        "says how to shrink it; ``Prefer: respond-async`` runs it as a job (202).")
    router.add_api_route(path, endpoint, methods=["POST"], summary=summary, dependencies=[Depends(require_json)],
                         responses={200: {"description": "The analysis result (see the contract)."},
                                    **problems(401, 413, 415, 422), **ASYNC_ACCEPTED},
                         openapi_extra=body_limit(operation))


for _name, (_path, _operation, _summary) in _OPERATIONS.items():
    _route(_name, _path, _operation, _summary)
