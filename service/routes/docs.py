"""The API documentation pages, served with no request leaving this service.

FastAPI's own ``/docs`` (Swagger UI) and ``/redoc`` load their JavaScript, style sheet and
icon from public CDNs: on a shop network without internet they stay blank. These routes
serve the same pages with every asset from this service:

* ``GET /docs`` — Swagger UI (try requests out, with the ``X-API-Key`` "Authorize" box);
* ``GET /docs/oauth2-redirect`` — Swagger UI's redirect page (FastAPI's default path);
* ``GET /redoc`` — ReDoc (one page, readable reference);
* ``GET /docs-assets/{name}`` — the assets themselves (and ``GET /favicon.ico``, the icon
  browsers ask every site for).

The assets are the files shipped by the ``fastapi-offline`` package (MIT; Swagger UI 5 and
ReDoc 2 standalone bundles, the same files the CDN serves), read from the installed package
so that a ``pip install -U`` updates them; nothing is vendored into this repository.
Swagger UI's online spec validator (a badge image fetched from validator.swagger.io) is
switched off, and ReDoc is rendered without Google Fonts.
"""

from __future__ import annotations

from importlib.resources import files
from pathlib import Path

from fastapi import APIRouter, Request
from fastapi.openapi.docs import (
    get_redoc_html,
    get_swagger_ui_html,
    get_swagger_ui_oauth2_redirect_html,
)
from starlette.responses import FileResponse, HTMLResponse, Response

from ..errors import ProblemError

__all__ = ["ASSETS_PREFIX", "ASSETS_DIR", "router"]

router = APIRouter()

ASSETS_PREFIX = "/docs-assets"
#: The package's asset folder (a real directory: the package is installed as files).
ASSETS_DIR = Path(str(files("fastapi_offline") / "static"))
#: The served files and their media types (nothing else in that folder is served).
_MEDIA = {"swagger-ui-bundle.js": "text/javascript; charset=utf-8", "swagger-ui.css": "text/css; charset=utf-8",
          "redoc.standalone.js": "text/javascript; charset=utf-8", "favicon.png": "image/png"}
#: Assets change only with the installed package: cache them for a day.
_ASSET_HEADERS = {"Cache-Control": "public, max-age=86400", "X-Content-Type-Options": "nosniff"}
_OPENAPI_URL = "/openapi.json"
_OAUTH2_REDIRECT = "/docs/oauth2-redirect"
#: No spec-validator badge (it is an image from validator.swagger.io); keep the key between reloads.
SWAGGER_PARAMETERS = {"validatorUrl": None, "persistAuthorization": True}


def _root(request: Request) -> str:
    return str(request.scope.get("root_path", "")).rstrip("/")


@router.get("/docs", include_in_schema=False)
def swagger_ui(request: Request) -> HTMLResponse:
    """Swagger UI on this service's OpenAPI document, with local assets."""
    root = _root(request)
    return get_swagger_ui_html(openapi_url=root + _OPENAPI_URL, title=f"{request.app.title} — Swagger UI",
                               oauth2_redirect_url=root + _OAUTH2_REDIRECT,
                               swagger_js_url=f"{root}{ASSETS_PREFIX}/swagger-ui-bundle.js",
                               swagger_css_url=f"{root}{ASSETS_PREFIX}/swagger-ui.css",
                               swagger_favicon_url=f"{root}{ASSETS_PREFIX}/favicon.png",
                               swagger_ui_parameters=SWAGGER_PARAMETERS)


@router.get(_OAUTH2_REDIRECT, include_in_schema=False)
def swagger_ui_redirect() -> HTMLResponse:
    """Swagger UI's OAuth2 redirect page (unused by API keys; FastAPI serves it too)."""
    return get_swagger_ui_oauth2_redirect_html()


@router.get("/redoc", include_in_schema=False)
def redoc(request: Request) -> HTMLResponse:
    """ReDoc on this service's OpenAPI document, with local assets and no web fonts."""
    root = _root(request)
    return get_redoc_html(openapi_url=root + _OPENAPI_URL, title=f"{request.app.title} — ReDoc",
                          redoc_js_url=f"{root}{ASSETS_PREFIX}/redoc.standalone.js",
                          redoc_favicon_url=f"{root}{ASSETS_PREFIX}/favicon.png", with_google_fonts=False)


@router.get(ASSETS_PREFIX + "/{name}", include_in_schema=False)
def asset(name: str) -> Response:
    """One of the documentation pages' assets."""
    if name not in _MEDIA:
        raise ProblemError(404, f"no documentation asset {name!r}; open /docs or /redoc")
    return FileResponse(ASSETS_DIR / name, media_type=_MEDIA[name], headers=_ASSET_HEADERS)


@router.get("/favicon.ico", include_in_schema=False)
def favicon() -> Response:
    """The icon browsers ask for (a PNG, which every browser accepts here)."""
    return asset("favicon.png")
