"""Reading request bodies that may be JSON or a multipart form (uploads).

Such routes read the body themselves (after authentication, so a refused write never
touches it) and validate the JSON variant with the same pydantic models and the same 422
problems as ordinary routes.
"""

from __future__ import annotations

from collections.abc import Iterable
from typing import Any, TypeVar

from fastapi import Request
from fastapi.exceptions import RequestValidationError
from pydantic import BaseModel, ValidationError
from starlette.datastructures import FormData, UploadFile

from rcsa.app.inputs import decode_json
from rcsa.errors import InputError, MalformedInput

from .errors import ProblemError, malformed_body
from .routing import ServiceRequest, is_json_media

__all__ = ["check_form_fields", "form_json", "form_text", "form_uploads", "json_document", "read_body", "read_upload",
           "require_json", "validate_json"]

M = TypeVar("M", bound=BaseModel)

_MAX_FORM_FIELDS = 200
_MAX_FORM_FILES = 64


async def read_body(request: Request) -> tuple[str, Any]:
    """``("json", document)`` (decoded under the JSON policy) or ``("form", FormData)`` by
    Content-Type; 415 otherwise."""
    ctype = request.headers.get("content-type", "")
    media = ctype.split(";")[0].strip().lower()
    if is_json_media(media):
        return "json", await json_document(request)
    if media == "multipart/form-data":
        form = await request.form(max_files=_MAX_FORM_FILES, max_fields=_MAX_FORM_FIELDS)
        return "form", form
    raise ProblemError(415, f"Content-Type {media or '(none)'} is not accepted here: send application/json, or "
                            "multipart/form-data with the file and the metadata as form fields")


async def json_document(request: Request) -> Any:
    """The request's JSON body under the JSON policy (:func:`rcsa.app.inputs.decode_json`),
    decoded once per request."""
    if isinstance(request, ServiceRequest):
        return await request.document()  # counted, decoded (and cached) under the policy
    try:
        return decode_json(await request.body())
    except MalformedInput as exc:
        raise malformed_body(exc) from None


def validate_json(model: type[M], data: bytes | Any) -> M:
    """Validate a JSON body (bytes, decoded under the JSON policy, or the decoded
    document); errors become the usual 422 problem."""
    doc = decode_json(data) if isinstance(data, bytes | bytearray) else data
    try:
        return model.model_validate(doc)
    except ValidationError as exc:
        raise RequestValidationError([{**e, "loc": ("body", *e["loc"])} for e in exc.errors()]) from None


async def read_upload(item: Any, field: str, limit_bytes: int) -> tuple[bytes, str]:
    """The bytes and file name of an uploaded file field (413 above ``limit_bytes``)."""
    if not isinstance(item, UploadFile):
        raise InputError(field, "must be a file (multipart part with a filename)")
    data = await item.read(limit_bytes + 1)
    if len(data) > limit_bytes:
        raise ProblemError(413, f"{field}: the file {item.filename!r} exceeds the upload limit of {limit_bytes} "
                                "bytes (RCSA_MAX_UPLOAD_BYTES)", errors=[{"field": field, "detail": "too large"}])
    return data, item.filename or ""


def check_form_fields(form: FormData, allowed: Iterable[str]) -> None:
    """Refuse a form field the route does not know (422 naming it and listing the allowed ones)."""
    names = list(allowed)
    unknown = sorted(set(form.keys()) - set(names))
    if unknown:
        raise InputError(unknown[0], f"unknown form field (allowed: {', '.join(names)})")


async def form_uploads(form: FormData, name: str, limit_bytes: int, *, least: int = 1, most: int | None = 1,
                       what: str = "file") -> list[tuple[bytes, str, str | None]]:
    """The files of a form field: ``(bytes, file name, media type)`` each (413 above ``limit_bytes``).

    Parameters
    ----------
    form : FormData
    name : str
        The field.
    limit_bytes : int
        Largest file.
    least, most : int
        How many files the field must have (``most`` None: any number).
    what : str
        What the files are, for the message (e.g. ``"library file (.json or .tools)"``).
    """
    items = form.getlist(name)
    if len(items) < least or (most is not None and len(items) > most):
        count = ("exactly one" if least == most == 1 else f"at most {most}" if not least else
                 f"at least {least}" if most is None else f"{least} to {most}")
        raise InputError(name, f"send {count} {what}" if items or not least else
                         f"is required: the {what} as a multipart part")
    out = []
    for item in items:
        data, file_name = await read_upload(item, name, limit_bytes)
        out.append((data, file_name, getattr(item, "content_type", None)))
    return out


def form_json(form: FormData, name: str) -> Any:
    """A form field holding JSON, decoded under the JSON policy (None when absent or empty)."""
    text = form_text(form, name)
    if text is None or text == "":
        return None
    return decode_json(text, path=name, what=f"form field {name}")


def form_text(form: FormData, name: str) -> str | None:
    """A text form field (None when absent); a file where text belongs is a 422."""
    values = form.getlist(name)
    if not values:
        return None
    if len(values) > 1:
        raise InputError(name, "is given more than once")
    if not isinstance(values[0], str):
        raise InputError(name, "must be a text field, not a file")
    return values[0]


def require_json(request: Request) -> None:
    """Dependency of JSON-body routes: any other Content-Type is a 415 problem."""
    media = request.headers.get("content-type", "").split(";")[0].strip().lower()
    if is_json_media(media):
        return
    if not media and request.headers.get("content-length", "0") == "0" and "transfer-encoding" not in request.headers:
        return  # no body at all: validation says what is required
    raise ProblemError(415, f"Content-Type {media or '(none)'} is not accepted here: send the body as "
                            "application/json")
