"""Diagnoses, joint identifications and effect analyses: thin doors onto ``rcsa.app.analyses``.

Each route validates the body against its schema (:class:`service.schemas.DiagnosisRequest`,
:class:`~service.schemas.IdentificationRequest`, :data:`~service.schemas.EffectsRequest`:
types and the library's bounds, published in the OpenAPI) and passes it, as sent, to
``rcsa.app.analyses.diagnose`` / ``identify`` / ``effects``, which check every rule between
fields and name the field as the schema does. All three also get the service's measurement
store (measured spindles are looked up there).
"""

from __future__ import annotations

from typing import Any

from fastapi import APIRouter, Depends
from pydantic import BaseModel
from starlette.requests import Request
from starlette.responses import Response

from rcsa.app import analyses

from ..bodies import require_json
from ..deps import StateDep
from ..jobs import caller, compute
from ..responses import ASYNC_ACCEPTED, body_limit, json_response, problems
from ..routing import ServiceRoute
from ..schemas import (
    DiagnosisRequest,
    DiagnosisResult,
    EffectsRequest,
    EffectsResult,
    IdentificationRequest,
    IdentificationResult,
)
from ..security import ReadAccess
from .batches import PreferHeader

router = APIRouter(prefix="/v1", tags=["analyses"], route_class=ServiceRoute)

#: Operations that read measured spindles from the service's store.
_WITH_STORE = {"diagnose", "identify", "effects"}
_ERRORS = {**problems(401, 413, 415, 422), **ASYNC_ACCEPTED}


def _call(name: str, doc: dict[str, Any], state: Any) -> Any:
    kwargs = {"store": state.reader} if name in _WITH_STORE else {}
    with state.metrics.timed(name):
        return getattr(analyses, name)(doc, **kwargs)


def _answer(name: str, operation: str, body: BaseModel, request: Request, state: Any, who: Any,
            prefer: str | None) -> Response:
    """``name`` computed under the compute budget of ``operation`` (:func:`service.jobs.compute`):
    now, or as the caller's job with ``Prefer: respond-async``."""
    doc = body.model_dump(exclude_unset=True)
    return compute(state, operation, doc, prefer=prefer, run=lambda: json_response(_call(name, doc, state)),
                   owner=caller(who, request))


@router.post("/diagnoses", dependencies=[Depends(require_json)], response_model=DiagnosisResult,
             responses=_ERRORS, openapi_extra=body_limit("diagnosis"),
             summary="Sim-to-real gap diagnosis (contract \"Diagnosis\")")
def diagnose(body: DiagnosisRequest, request: Request, state: StateDep, who: ReadAccess,
                  prefer: PreferHeader = None) -> Response:
    """Where a base model and tap tests of it part, which unmodelled effect explains it
    (``verdict``), and each measurement's FRF once that effect is added (``corrected_h``).

    Under the compute budget (:mod:`rcsa.app.budget`): above 20 s or 1 GiB estimated, a 422
    says how to shrink it; ``Prefer: respond-async`` runs it as a job (202)."""
    return _answer("diagnose", "diagnosis", body, request, state, who, prefer)


@router.post("/identifications", dependencies=[Depends(require_json)], response_model=IdentificationResult,
             responses=_ERRORS, openapi_extra=body_limit("identification"),
             summary="Joint identification (contract \"Joint identification\")")
def identify_joints(body: IdentificationRequest, request: Request, state: StateDep, who: ReadAccess,
                  prefer: PreferHeader = None) -> Response:
    """The joints' translational stiffness and damping from measured tool-point FRFs;
    ``status`` is ``identified`` or ``not_identifiable`` (with a ``detail``).

    Under the compute budget; ``Prefer: respond-async`` runs it as a job (202)."""
    return _answer("identify", "identification", body, request, state, who, prefer)


@router.post("/effects", dependencies=[Depends(require_json)], response_model=EffectsResult,
             responses=_ERRORS, openapi_extra=body_limit("effects"),
             summary="Sensitivities of each mode to the model's parameters")
def analyse_effects(body: EffectsRequest, request: Request, state: StateDep, who: ReadAccess,
                 prefer: PreferHeader = None) -> Response:
    """Normalised sensitivities d ln(feature) / d ln(parameter) of every mode in a band to
    bearing, joint and tool parameters (on a measured spindle: modal-fit modes, bearings not
    applicable).

    Under the compute budget; ``Prefer: respond-async`` runs it as a job (202)."""
    return _answer("effects", "effects", body, request, state, who, prefer)
