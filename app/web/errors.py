"""Every error the app answers with, rendered in one place.

A :class:`~app.core.exceptions.UserError` (message key, params, HTTP status) becomes JSON
``{"detail": <message>, "key": <key>}`` under ``/api`` and for ``fetch()`` calls, else the
error page -- in the reader's language either way (saved choice, ``lang`` cookie or
``Accept-Language``).  The framework's own errors (404 routes, 405, 413 bodies, 422
validation) and database faults (busy, read-only, full) are answered the same way.
"""

from __future__ import annotations

import logging
import time
from typing import Any
from urllib.parse import quote

from fastapi import FastAPI, Request
from fastapi.exceptions import RequestValidationError
from fastapi.responses import JSONResponse, Response
from pydantic import BaseModel, Field
from sqlalchemy.exc import DBAPIError
from starlette.exceptions import HTTPException as StarletteHTTPException

from app.core.exceptions import UserError
from app.db import UnstorableText, database_busy, get_engine, storage_unavailable
from app.web.deps import LoginRequired, PasswordChangeRequired, reload_login
from app.web.i18n import translate
from app.web.render import redirect, render, request_language
from app.web.validation_errors import localised_details

log = logging.getLogger("gyrolab")
STORAGE_LOG_INTERVAL_S = 600.0
_storage_logged_at = [-STORAGE_LOG_INTERVAL_S]
HTTP_STATUS_KEYS = {
    400: "error.bad_request",
    401: "error.not_authenticated",
    403: "error.forbidden",
    404: "error.not_found",
    405: "error.method",
    413: "error.too_large",
}


def wants_json(request: Request) -> bool:
    """API paths, fetch() calls sending JSON, and clients asking for JSON get JSON errors."""
    return (
        request.url.path.startswith("/api/")
        or "application/json" in request.headers.get("accept", "")
        or request.headers.get("content-type", "").startswith("application/json")
    )


def message_for(error: UserError, language: str) -> str:
    """The error in the reader's language, from the catalogue (the one source of its words)."""
    return translate(error.key, language, **error.params)


def error_response(request: Request, error: UserError) -> Response:
    """The one rendering of a user-facing error: JSON or the error page."""
    message = message_for(error, request_language(request))
    if wants_json(request):
        return JSONResponse(
            {"detail": message, "key": error.key},
            status_code=error.status,
            headers=error.headers or None,
        )
    response = render(
        request, "error.html", {"status": error.status, "message": message}, error.status
    )
    response.headers.update(error.headers)
    return response


def report_storage_fault(error: DBAPIError) -> None:
    """Log a read-only or full database once, not once per request (again every ten
    minutes while it lasts)."""
    now = time.monotonic()
    if now - _storage_logged_at[0] >= STORAGE_LOG_INTERVAL_S:
        _storage_logged_at[0] = now
        log.error("the database cannot be written; answering 503 until it can: %s", error.orig)


def register_error_handlers(app: FastAPI) -> None:
    @app.exception_handler(UserError)
    def _user_error(request: Request, exc: UserError):
        return error_response(request, exc)

    @app.exception_handler(LoginRequired)
    async def _login_required(request: Request, _exc: LoginRequired):
        if wants_json(request):
            return error_response(
                request,
                UserError(
                    "error.not_authenticated", status=401, headers={"WWW-Authenticate": "Bearer"}
                ),
            )
        target = request.url.path + ("?" + request.url.query if request.url.query else "")
        return redirect(f"/login?next={quote(target)}")

    @app.exception_handler(PasswordChangeRequired)
    async def _password_change(request: Request, _exc: PasswordChangeRequired):
        if wants_json(request):
            return error_response(request, UserError("error.password_change", status=403))
        return redirect("/account/password")

    @app.exception_handler(StarletteHTTPException)
    async def _http(request: Request, exc: StarletteHTTPException):
        key = HTTP_STATUS_KEYS.get(exc.status_code, "error.generic")
        return error_response(
            request, UserError(key, status=exc.status_code, headers=dict(exc.headers or {}))
        )

    @app.exception_handler(UnstorableText)
    def _nul_text(request: Request, _exc: UnstorableText):
        # The failed flush rolled the request's session back and expired its objects.
        reload_login(request)
        return error_response(request, UserError("error.nul_text"))

    @app.exception_handler(DBAPIError)
    def _database_error(request: Request, exc: DBAPIError):
        if database_busy(exc):  # nothing was written: the request's transaction rolled back
            log.warning("database busy: %s %s", request.method, request.url.path)
            reload_login(request)
            return error_response(
                request, UserError("error.busy", status=503, headers={"Retry-After": "2"})
            )
        if not storage_unavailable(exc):
            raise exc
        report_storage_fault(exc)
        get_engine().dispose()  # connections opened read-only stay so: start afresh
        reload_login(request)
        return error_response(
            request, UserError("error.storage", status=503, headers={"Retry-After": "30"})
        )

    @app.exception_handler(RequestValidationError)
    async def _invalid(request: Request, exc: RequestValidationError):
        if wants_json(request):
            details = localised_details(exc.errors(), request_language(request))
            return JSONResponse({"detail": details}, status_code=422)
        return error_response(request, UserError("error.bad_request"))


class ErrorOut(BaseModel):
    detail: str | list = Field(
        description="what is wrong, in the reader's words (for 422 a list of the fields' "
        "problems, each with its `loc`, `type` and `msg`)"
    )
    key: str | None = Field(default=None, description="the message's key (not for 422)")


API_ERRORS: dict[int | str, dict[str, Any]] = {
    400: {"description": "Bad input (the message says what is wrong)", "model": ErrorOut},
    401: {"description": "Not authenticated", "model": ErrorOut},
    403: {
        "description": "Not allowed (role, token scope, CSRF or assignment rules)",
        "model": ErrorOut,
    },
    404: {"description": "No such object, or not yours", "model": ErrorOut},
    413: {"description": "Request body too large", "model": ErrorOut},
    422: {"description": "Wrong types or missing fields", "model": ErrorOut},
    429: {"description": "Too many requests", "model": ErrorOut},
}
