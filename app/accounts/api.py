"""REST API v1, accounts: a log-in token, who am I, and a teacher's password reset."""

from __future__ import annotations

from typing import Annotated

from fastapi import APIRouter, Form, Request

from app.accounts.api_auth import BEARER, AnyCaller, UploadCaller
from app.accounts.schemas import MeOut, NewPasswordOut, TokenOut
from app.accounts.security import log_in
from app.accounts.service import may_reset_password, reset_password, teaches_student
from app.accounts.tokens import LOGIN_TOKEN_LIFETIME, new_token
from app.core.exceptions import UserError
from app.models import Role, User
from app.web.deps import ObjectId, RowWriteSession, SessionDep, SettingsDep
from app.web.errors import API_ERRORS

router = APIRouter(prefix="/api/v1", responses=API_ERRORS)


@router.post(
    "/auth/token",
    response_model=TokenOut,
    tags=["api: auth"],
    dependencies=[RowWriteSession],
)
def login_for_token(
    request: Request,
    db: SessionDep,
    settings: SettingsDep,
    username: Annotated[str, Form(min_length=1, max_length=200)],
    password: Annotated[str, Form(min_length=1, max_length=1000)],
):
    """OAuth2 password flow: a one-hour bearer token (read and upload), throttled like the
    log-in page."""
    address = request.client.host if request.client else "unknown"
    outcome = log_in(db, username, password, address, settings)
    if outcome.problem == "throttled":
        raise UserError(
            "api.login_throttled",
            status=429,
            headers={"Retry-After": str(outcome.retry_after)},
        )
    if outcome.problem == "busy":
        raise UserError("api.login_busy", status=503, headers={"Retry-After": "1"})
    if outcome.user is None:
        raise UserError("api.bad_login", status=401, headers=BEARER)
    user = outcome.user
    if user.must_change_password:
        db.commit()
        raise UserError("api.change_password_first", status=403)
    raw, _ = new_token(db, user, kind="login", lifetime=LOGIN_TOKEN_LIFETIME)
    db.commit()
    return TokenOut(access_token=raw, expires_in=int(LOGIN_TOKEN_LIFETIME.total_seconds()))


@router.get("/me", response_model=MeOut, tags=["api"])
def me(caller: AnyCaller):
    """Who the token or session belongs to."""
    user = caller.user
    return MeOut(
        id=user.id,
        username=user.username,
        display_name=user.display_name,
        role=user.role,
        language=user.language,
    )


@router.post(
    "/users/{user_id}/reset-password", response_model=NewPasswordOut, tags=["api: teachers"]
)
def reset_user_password(user_id: ObjectId, caller: UploadCaller, db: SessionDep):
    """Teachers and administrators: a new one-time password; every session and token of
    that user ends.  A teacher may reset only a student their own roster created and that
    no other teacher's course holds (anyone else: an administrator)."""
    if caller.user.role not in (Role.teacher, Role.admin):
        raise UserError("api.teachers_or_admins_only", status=403)
    user = db.get(User, user_id)
    if user is None or (
        caller.user.role == Role.teacher and not teaches_student(db, caller.user, user)
    ):
        raise UserError("api.no_such_user", status=404)
    if not may_reset_password(db, caller.user, user):
        raise UserError("api.reset_not_yours", status=403)
    password = reset_password(db, user)
    db.commit()
    return NewPasswordOut(username=user.username, initial_password=password)
