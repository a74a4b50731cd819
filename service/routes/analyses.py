"""Diagnoses, joint identifications and effect analyses: thin doors onto ``rcsa.app.analyses``.

Each route validates the body against its schema (:class:`service.schemas.DiagnosisRequest`,
:class:`~service.schemas.IdentificationRequest`, :data:`~service.schemas.EffectsRequest`:
types and the library's bounds, published in the OpenAPI) and passes it, as sent, to
``rcsa.app.analyses.diagnose`` / ``identify`` / ``effects``, which check every rule between
fields and name the field as the schema does. Identifications and effect analyses also get
the service's measurement store (measured spindles).
"""

from __future__ import annotations

from typing import Any

from fastapi import APIRouter, Depends
from pydantic import BaseModel
from starlette.responses import Response

from rcsa.app import analyses

from ..bodies import require_json
from ..deps import StateDep
from ..responses import json_response, problems
from ..schemas import (
    DiagnosisRequest,
    DiagnosisResult,
    EffectsRequest,
    EffectsResult,
    IdentificationRequest,
    IdentificationResult,
)
from ..security import ReadAccess

router = APIRouter(prefix="/v1", tags=["analyses"])

#: Operations that read measured spindles from the service's store.
_WITH_STORE = {"identify", "effects"}
_ERRORS = problems(401, 413, 415, 422)


def _call(name: str, body: BaseModel, state: Any) -> Any:
    kwargs = {"store": state.reader} if name in _WITH_STORE else {}
    with state.metrics.timed(name):
        return getattr(analyses, name)(body.model_dump(exclude_unset=True), **kwargs)


@router.post("/diagnoses", dependencies=[Depends(require_json)], response_model=DiagnosisResult,
             responses=_ERRORS, summary="Sim-to-real gap diagnosis (contract \"Diagnosis\")")
def post_diagnose(body: DiagnosisRequest, state: StateDep, _: ReadAccess) -> Response:
    """Where a base model and tap tests of it part, which unmodelled effect explains it
    (``verdict``), and each measurement's FRF once that effect is added (``corrected_h``)."""
    return json_response(_call("diagnose", body, state))


@router.post("/identifications", dependencies=[Depends(require_json)], response_model=IdentificationResult,
             responses=_ERRORS, summary="Joint identification (contract \"Joint identification\")")
def post_identify(body: IdentificationRequest, state: StateDep, _: ReadAccess) -> Response:
    """The joints' translational stiffness and damping from measured tool-point FRFs;
    ``status`` is ``identified`` or ``not_identifiable`` (with a ``detail``)."""
    return json_response(_call("identify", body, state))


@router.post("/effects", dependencies=[Depends(require_json)], response_model=EffectsResult,
             responses=_ERRORS, summary="Sensitivities of each mode to the model's parameters")
def post_effects(body: EffectsRequest, state: StateDep, _: ReadAccess) -> Response:
    """Normalised sensitivities d ln(feature) / d ln(parameter) of every mode in a band to
    bearing, joint and tool parameters (on a measured spindle: modal-fit modes, bearings not
    applicable)."""
    return json_response(_call("effects", body, state))
