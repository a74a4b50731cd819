"""Diagnoses, joint identifications and effect analyses: thin doors onto ``rcsa.app.analyses``.

Each route passes the JSON body to ``rcsa.app.analyses.diagnose`` / ``identify`` / ``effects``;
identifications and effect analyses also get the service's measurement store (measured spindles).
"""

from __future__ import annotations

from typing import Annotated, Any

from fastapi import APIRouter, Body, Depends
from starlette.responses import Response

from rcsa.app import analyses

from ..bodies import require_json
from ..deps import StateDep
from ..responses import json_response, problems
from ..security import ReadAccess

router = APIRouter(prefix="/v1", tags=["analyses"])

_OPERATIONS = {
    "diagnose": ("/diagnoses", "Sim-to-real gap diagnosis (contract \"Diagnosis\")"),
    "identify": ("/identifications", "Joint identification (contract \"Joint identification\")"),
    "effects": ("/effects", "Sensitivities of each mode to the model's parameters"),
}
_Request = Annotated[dict[str, Any], Body(description="The request document (see the contract).")]


#: Operations that read measured spindles from the service's store.
_WITH_STORE = {"identify", "effects"}


def _call(name: str, body: dict[str, Any], state: Any) -> Any:
    kwargs = {"store": state.reader} if name in _WITH_STORE else {}
    with state.metrics.timed(name):
        return getattr(analyses, name)(body, **kwargs)


def _route(name: str, path: str, summary: str) -> None:
    def endpoint(state: StateDep, _: ReadAccess,
                 body: _Request) -> Response:
        return json_response(_call(name, body, state))

    endpoint.__name__ = f"post_{name}"
    endpoint.__doc__ = f"{summary}: the body goes to ``rcsa.app.analyses.{name}``."
    router.add_api_route(path, endpoint, methods=["POST"], summary=summary, dependencies=[Depends(require_json)],
                         responses={200: {"description": "The analysis result (see the contract)."},
                                    **problems(401, 413, 415, 422)})


for _name, (_path, _summary) in _OPERATIONS.items():
    _route(_name, _path, _summary)
