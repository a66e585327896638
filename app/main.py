"""The ASGI application: ``create_app()`` wires middleware, static files, routers, errors."""

from __future__ import annotations

import logging
import time
from contextlib import asynccontextmanager
from pathlib import Path

import plotly
from fastapi import FastAPI, Request
from fastapi.exceptions import RequestValidationError
from fastapi.responses import FileResponse, HTMLResponse, JSONResponse
from fastapi.staticfiles import StaticFiles
from sqlalchemy.exc import DBAPIError
from starlette.exceptions import HTTPException as StarletteHTTPException
from swagger_ui_bundle import swagger_ui_path

from app import __version__
from app.accounts import admin_pages, token_pages
from app.accounts import pages as account_pages
from app.config import get_settings
from app.courses import assignment_pages, join_pages
from app.courses import pages as course_pages
from app.db import UnstorableText, database_busy, get_engine, storage_unavailable
from app.explore import pages as explore_pages
from app.lab import api, stream
from app.lab import pages as lab_pages
from app.paths import STATIC_DIR
from app.review import pages as review_pages
from app.web import home
from app.web.deps import CsrfFailed, Forbidden, LoginRequired, PasswordChangeRequired, reload_login
from app.web.headers import SecurityHeaders
from app.web.i18n import translate
from app.web.render import redirect, render, request_language

log = logging.getLogger("gyrolab")
STORAGE_LOG_INTERVAL_S = 600.0
_storage_logged_at = [-STORAGE_LOG_INTERVAL_S]


def report_storage_fault(error: DBAPIError) -> None:
    """Log a read-only or full database once, not once per request (again every ten
    minutes while it lasts)."""
    now = time.monotonic()
    if now - _storage_logged_at[0] >= STORAGE_LOG_INTERVAL_S:
        _storage_logged_at[0] = now
        log.error("the database cannot be written; answering 503 until it can: %s", error.orig)


API_DESCRIPTION = """REST API of GyroLab, the FOG north-finding teaching lab.

Authenticate with `Authorization: Bearer <token>`: a personal access token (page *API
tokens*; scopes `read` and `upload`) or a one-hour token from `POST /api/v1/auth/token`.
Rates are °/h unless a unit is given; angles are degrees.  Errors are
`{"detail": "..."}` with a 4xx status.  Limits: request bodies up to 32 MiB, at most
1,000,000 samples per position, 600 requests per minute per token.
"""
SWAGGER_PAGE = """<!doctype html>
<html lang="en"><head><meta charset="utf-8"><title>GyroLab API</title>
<link rel="icon" href="/static/favicon.svg" type="image/svg+xml">
<link rel="stylesheet" href="/vendor/swagger-ui/swagger-ui.css"></head>
<body data-schema="/docs/openapi.json"><div id="swagger-ui"></div>
<script src="/vendor/swagger-ui/swagger-ui-bundle.js"></script>
<script src="/vendor/swagger-ui/swagger-ui-standalone-preset.js"></script>
<script src="/static/js/swagger-init.js"></script></body></html>
"""
PLOTLY_JS = Path(plotly.__file__).parent / "package_data" / "plotly.min.js"
PLOTLY_URL = f"/vendor/plotly-{plotly.__version__}.min.js"


def _wants_json(request: Request) -> bool:
    """API paths, fetch() calls sending JSON, and clients asking for JSON get JSON errors."""
    return (
        request.url.path.startswith("/api/")
        or "application/json" in request.headers.get("accept", "")
        or request.headers.get("content-type", "").startswith("application/json")
    )


def _error_page(request: Request, status: int, key: str):
    if _wants_json(request):
        return JSONResponse({"detail": key}, status_code=status)
    return render(request, "error.html", {"status": status, "message_key": key}, status)


def create_app(*, migrate_on_start: bool = True) -> FastAPI:
    @asynccontextmanager
    async def lifespan(_app: FastAPI):
        if migrate_on_start:
            from app.migrate import upgrade_to_head

            upgrade_to_head()
        yield

    app = FastAPI(
        title="GyroLab",
        version=__version__,
        description=API_DESCRIPTION,
        lifespan=lifespan,
        docs_url=None,
        redoc_url=None,
        max_body_size=get_settings().max_body_bytes,
    )
    app.add_middleware(SecurityHeaders)
    app.mount("/static", StaticFiles(directory=str(STATIC_DIR)), name="static")
    app.mount("/vendor/swagger-ui", StaticFiles(directory=swagger_ui_path), name="swagger-ui")

    @app.get("/docs", include_in_schema=False)
    def api_docs() -> HTMLResponse:
        """The API reference: Swagger UI from the installed swagger-ui-bundle, started by a
        script file of ours (no inline script, so the CSP holds here too)."""
        return HTMLResponse(SWAGGER_PAGE)

    @app.get("/docs/openapi.json", include_in_schema=False)
    def docs_schema() -> dict:
        """The schema labelled 3.0 for the packaged Swagger UI 4, which predates OpenAPI 3.1
        (the real schema, 3.1, is /openapi.json)."""
        return {**app.openapi(), "openapi": "3.0.3"}

    @app.get(PLOTLY_URL, include_in_schema=False)
    def plotly_js() -> FileResponse:
        """plotly.js straight from the installed plotly package, cached for a year."""
        return FileResponse(
            PLOTLY_JS,
            media_type="text/javascript",
            headers={"Cache-Control": "public, max-age=31536000, immutable"},
        )

    app.state.plotly_url = PLOTLY_URL

    @app.exception_handler(LoginRequired)
    async def _login_required(request: Request, _exc: LoginRequired):
        if _wants_json(request):
            return JSONResponse({"detail": "Not authenticated"}, status_code=401)
        target = request.url.path
        if request.url.query:
            target += "?" + request.url.query
        from urllib.parse import quote

        return redirect(f"/login?next={quote(target)}")

    @app.exception_handler(PasswordChangeRequired)
    async def _password_change(request: Request, _exc: PasswordChangeRequired):
        if _wants_json(request):
            return JSONResponse({"detail": "Password change required"}, status_code=403)
        return redirect("/account/password")

    @app.exception_handler(Forbidden)
    async def _forbidden(request: Request, _exc: Forbidden):
        return _error_page(request, 403, "error.forbidden")

    @app.exception_handler(CsrfFailed)
    async def _csrf(request: Request, _exc: CsrfFailed):
        return _error_page(request, 403, "error.csrf")

    @app.exception_handler(StarletteHTTPException)
    async def _http(request: Request, exc: StarletteHTTPException):
        if _wants_json(request):
            return JSONResponse(
                {"detail": exc.detail}, status_code=exc.status_code, headers=exc.headers
            )
        key = {404: "error.not_found", 405: "error.method", 413: "error.too_large"}.get(
            exc.status_code, "error.generic"
        )
        return render(
            request, "error.html", {"status": exc.status_code, "message_key": key}, exc.status_code
        )

    @app.exception_handler(UnstorableText)
    def _nul_text(request: Request, _exc: UnstorableText):
        # The failed flush rolled the request's session back and expired its objects.
        reload_login(request)
        return _error_page(request, 400, "error.nul_text")

    @app.exception_handler(DBAPIError)
    def _database_error(request: Request, exc: DBAPIError):
        if database_busy(exc):  # nothing was written: the request's transaction rolled back
            log.warning("database busy: %s %s", request.method, request.url.path)
            reload_login(request)
            if _wants_json(request):
                return JSONResponse(
                    {"detail": translate("error.busy", request_language(request))},
                    status_code=503,
                    headers={"Retry-After": "2"},
                )
            response = _error_page(request, 503, "error.busy")
            response.headers["Retry-After"] = "2"
            return response
        if not storage_unavailable(exc):
            raise exc
        report_storage_fault(exc)
        get_engine().dispose()  # connections opened read-only stay so: start afresh
        reload_login(request)
        if _wants_json(request):
            language = request_language(request)
            return JSONResponse(
                {"detail": translate("error.storage", language)},
                status_code=503,
                headers={"Retry-After": "30"},
            )
        response = _error_page(request, 503, "error.storage")
        response.headers["Retry-After"] = "30"
        return response

    @app.exception_handler(RequestValidationError)
    async def _invalid(request: Request, exc: RequestValidationError):
        if _wants_json(request):
            return JSONResponse({"detail": jsonable_errors(exc)}, status_code=422)
        return render(
            request, "error.html", {"status": 400, "message_key": "error.bad_request"}, 400
        )

    app.include_router(account_pages.router)
    app.include_router(home.router)
    app.include_router(course_pages.router)
    app.include_router(join_pages.router)
    app.include_router(admin_pages.router)
    app.include_router(assignment_pages.router)
    app.include_router(lab_pages.router)
    app.include_router(review_pages.router)
    app.include_router(stream.router)
    app.include_router(token_pages.router)
    app.include_router(explore_pages.router)
    app.include_router(api.router)
    return app


def jsonable_errors(exc: RequestValidationError) -> list[dict]:
    return [
        {"loc": list(err.get("loc", ())), "msg": err.get("msg", ""), "type": err.get("type", "")}
        for err in exc.errors()
    ]


app = create_app()
