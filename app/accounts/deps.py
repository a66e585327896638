"""Who the caller is: the session cookie resolved to a user once per request, role checks
and the CSRF check of every cookie-authenticated change."""

from __future__ import annotations

from datetime import timedelta
from typing import Annotated

from fastapi import Depends, Request
from sqlalchemy import bindparam, update
from sqlalchemy.exc import DBAPIError
from sqlmodel import Session, select
from starlette.concurrency import run_in_threadpool

from app.accounts.security import session_is_live
from app.config import Settings
from app.core.exceptions import UserError
from app.db import read_session, statement_session, storage_unavailable
from app.models import AuthSession, Role, User, utcnow
from app.web.deps import (
    SAFE_METHODS,
    LoginRequired,
    PasswordChangeRequired,
    SessionDep,
    SettingsDep,
    read_form,
)
from app.web.render import SESSION_COOKIE, csrf_cookie_name
from app.web.signing import token_digest, tokens_match

TOUCH_INTERVAL = timedelta(seconds=60)
# Pages a user who must change their password may still reach.
PASSWORD_CHANGE_PATHS = {"/account/password", "/logout", "/lang"}


def load_login(request: Request, db: Session, settings: Settings) -> User | None:
    """Resolve the session cookie to a user once per request (cached on request.state)."""
    if getattr(request.state, "auth_loaded", False):
        return request.state.user
    request.state.auth_loaded = True
    request.state.user = None
    request.state.auth = None
    if request.method in SAFE_METHODS:
        return _resolve_login(request, db, settings)
    # A write request: look the login up without the write lock, then hand the rows to the
    # request's session without SQL, so that the lock is taken by the handler's first
    # query, in the handler's own thread.  (Dependencies and the handler run on different
    # trips to the thread pool; a write transaction held across that gap could wait for a
    # free thread while every pool thread waits for its lock -- seen in the load test.)
    with read_session() as lookup:
        user = _resolve_login(request, lookup, settings)
    if user is not None:
        request.state.user = user = db.merge(user, load=False)
        request.state.auth = db.merge(request.state.auth, load=False)
    return user


# One statement, one round trip: every request of a class passes here (on PostgreSQL each
# statement costs the worker ≈ 90 µs of its interpreter).  Built once with a bound
# parameter: building the select and its cache key per request cost ≈ 170 µs of the
# ≈ 260 µs a lookup took (bench/README.md, fourteenth part).
SESSION_AND_USER = (
    select(AuthSession, User)
    .join(User, User.id == AuthSession.user_id)
    .where(AuthSession.token_hash == bindparam("digest"))
)


def login_for_cookie(
    db: Session, token: str | None, settings: Settings
) -> tuple[User, AuthSession] | None:
    """The user and live log-in session of a session cookie (pages, API and WebSocket)."""
    if not token:
        return None
    found = db.exec(SESSION_AND_USER, params={"digest": token_digest(token)}).first()
    if found is None:
        return None
    record, user = found
    return (user, record) if session_is_live(record, settings) else None


def _resolve_login(request: Request, db: Session, settings: Settings) -> User | None:
    found = login_for_cookie(db, request.cookies.get(SESSION_COOKIE), settings)
    if found is None:
        return None
    user, record = found
    if utcnow() - record.last_seen_at > TOUCH_INTERVAL:
        # End this read first: a request never holds one pooled connection while it waits
        # for another (a full pool would otherwise stall until its timeout).
        db.commit()
        _touch(record.id)
    request.state.user = user
    request.state.auth = record
    return user


def _touch(session_id: int) -> None:
    """Extend the idle timer: one atomic UPDATE of its row, in no serialised transaction
    (skipped while the database cannot be written: reading pages goes on)."""
    try:
        with statement_session() as db:
            db.exec(
                update(AuthSession)
                .where(AuthSession.id == session_id)
                .values(last_seen_at=utcnow())
            )
            db.commit()
    except DBAPIError as error:
        if not storage_unavailable(error):
            raise


async def given_csrf_token(request: Request) -> str | None:
    """The CSRF token sent: the ``X-CSRF-Token`` header or the form's ``csrf_token``."""
    given = request.headers.get("x-csrf-token")
    if given is None and request.method not in SAFE_METHODS:
        content_type = request.headers.get("content-type", "")
        if content_type.startswith(("application/x-www-form-urlencoded", "multipart/form-data")):
            value = (await read_form(request)).get("csrf_token")
            given = value if isinstance(value, str) else None
    return given


def csrf_protect(
    request: Request,
    db: SessionDep,
    settings: SettingsDep,
    given: Annotated[str | None, Depends(given_csrf_token)],
) -> None:
    """Check the CSRF token of every state-changing cookie-authenticated (or anonymous) form.

    Logged in: the token stored with the server-side session.  Not logged in (login form):
    a double-submit cookie.
    """
    if request.method in SAFE_METHODS:
        return
    user = load_login(request, db, settings)
    expected = (
        request.state.auth.csrf_token if user else request.cookies.get(csrf_cookie_name(request))
    )
    if not tokens_match(expected, given):
        raise UserError("error.csrf", status=403)


def login_loaded(request: Request) -> bool:
    """Whether this request's caller has been looked up already (no query needed)."""
    return getattr(request.state, "auth_loaded", False)


def checked_login(request: Request, user: User | None, role: Role | None = None) -> User:
    """The caller, who must be logged in (else the log-in page), have changed a password
    they were told to change (else that page), and have ``role`` when one is given."""
    if user is None:
        raise LoginRequired()
    if user.must_change_password and request.url.path not in PASSWORD_CHANGE_PATHS:
        raise PasswordChangeRequired()
    if role is not None and user.role != role:
        raise UserError("error.forbidden", status=403)
    return user


def required_login(
    request: Request, db: Session, settings: Settings, role: Role | None = None
) -> User:
    """:func:`checked_login` of the caller, looked up if need be: for a dependency that
    loads the route's objects, so that finding the caller and loading them take one trip
    to the thread pool (each trip costs a worker ≈ 0.1 ms of CPU; bench/README.md,
    fifteenth part)."""
    return checked_login(request, load_login(request, db, settings), role)


async def optional_user(request: Request, db: SessionDep, settings: SettingsDep) -> User | None:
    if login_loaded(request):
        return request.state.user
    return await run_in_threadpool(load_login, request, db, settings)


async def _user_with_role(
    request: Request, db: Session, settings: Settings, role: Role | None
) -> User:
    """The checked caller: without a trip to the thread pool once looked up (by the CSRF
    check, or by a dependency that loaded the route's objects)."""
    if login_loaded(request):
        return checked_login(request, request.state.user, role)
    return await run_in_threadpool(required_login, request, db, settings, role)


async def current_user(request: Request, db: SessionDep, settings: SettingsDep) -> User:
    return await _user_with_role(request, db, settings, None)


async def teacher_user(request: Request, db: SessionDep, settings: SettingsDep) -> User:
    return await _user_with_role(request, db, settings, Role.teacher)


async def student_user(request: Request, db: SessionDep, settings: SettingsDep) -> User:
    return await _user_with_role(request, db, settings, Role.student)


async def admin_user(request: Request, db: SessionDep, settings: SettingsDep) -> User:
    return await _user_with_role(request, db, settings, Role.admin)


CurrentUser = Annotated[User, Depends(current_user)]
OptionalUser = Annotated[User | None, Depends(optional_user)]
TeacherUser = Annotated[User, Depends(teacher_user)]
AdminUser = Annotated[User, Depends(admin_user)]
StudentUser = Annotated[User, Depends(student_user)]
CsrfProtected = Depends(csrf_protect)
