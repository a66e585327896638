"""Who is calling the REST API, and what they may do: the caller as a dependency.

``Authorization: Bearer <token>`` (a personal access token with scopes, or a one-hour
log-in token), else the browser's session cookie with the CSRF token in ``X-CSRF-Token``
for changes.  Both count against the same per-minute rate.  A route's signature says who
may call it: ``ReadCaller``, ``UploadCaller``, ``TeacherCaller``, ``TeacherUploadCaller``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Annotated

from fastapi import Depends, Request

from app.accounts.deps import load_login
from app.accounts.tokens import check_token, count_cookie_request
from app.core.exceptions import UserError
from app.db import statement_session
from app.models import Role, User
from app.web.deps import SAFE_METHODS, SessionDep, SettingsDep
from app.web.signing import tokens_match

BEARER = {"WWW-Authenticate": "Bearer"}


@dataclass
class Caller:
    user: User
    scopes: set[str]
    via: str  # token | cookie


def api_caller(request: Request, db: SessionDep, settings: SettingsDep) -> Caller:
    header = request.headers.get("authorization", "")
    if header.lower().startswith("bearer "):
        return _token_caller(header[7:].strip(), db, settings.api_rate_per_minute)
    user = load_login(request, db, settings)
    if user is None:
        raise UserError("api.not_authenticated", status=401, headers=BEARER)
    if request.method not in SAFE_METHODS and not tokens_match(
        request.state.auth.csrf_token, request.headers.get("x-csrf-token")
    ):
        raise UserError("api.csrf_header", status=403)
    if user.must_change_password:
        raise UserError("api.change_password_first", status=403)
    with statement_session() as counter_db:  # the same per-minute rate as a token
        wait = count_cookie_request(counter_db, request.state.auth, settings.api_rate_per_minute)
    if wait:
        raise UserError("api.rate_session", status=429, headers={"Retry-After": str(wait)})
    return Caller(user, {"read", "upload"}, "cookie")


def _token_caller(raw: str, db, rate_per_minute: int) -> Caller:
    # Not a serialised writer: the token and its owner are read, and the rate's lease (a
    # database write once per few requests) is one atomic UPDATE (see check_token); the
    # user is handed to the request's session like a cookie login (deps.load_login), so
    # the write lock is taken by the handler alone.
    with statement_session() as counter_db:
        check = check_token(counter_db, raw, rate_per_minute)
    if check.problem == "invalid" or check.user is None:
        raise UserError("api.bad_token", status=401, headers=BEARER)
    if check.problem == "rate":
        raise UserError(
            "api.rate_token", status=429, headers={"Retry-After": str(check.retry_after)}
        )
    if check.user.must_change_password:
        raise UserError("api.change_password_first", status=403)
    return Caller(db.merge(check.user, load=False), check.scopes, "token")


def require_scope(caller: Caller, scope: str, *, teacher: bool = False) -> Caller:
    """The caller, who must hold ``scope`` (and be a teacher if asked)."""
    if scope not in caller.scopes:
        raise UserError("api.scope_missing", status=403, scope=scope)
    if teacher and caller.user.role != Role.teacher:
        raise UserError("api.teachers_only", status=403)
    return caller


def scoped(scope: str, *, teacher: bool = False):
    """A dependency: the caller, who must hold ``scope`` (and be a teacher if asked)."""

    async def dependency(caller: Annotated[Caller, Depends(api_caller)]) -> Caller:
        # async: a check without I/O needs no trip to the thread pool
        return require_scope(caller, scope, teacher=teacher)

    return dependency


AnyCaller = Annotated[Caller, Depends(api_caller)]
ReadCaller = Annotated[Caller, Depends(scoped("read"))]
UploadCaller = Annotated[Caller, Depends(scoped("upload"))]
TeacherCaller = Annotated[Caller, Depends(scoped("read", teacher=True))]
TeacherUploadCaller = Annotated[Caller, Depends(scoped("upload", teacher=True))]
