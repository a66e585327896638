"""FastAPI dependencies: database session, current user, role checks and CSRF."""

from __future__ import annotations

import re
from collections.abc import Iterator
from datetime import timedelta
from typing import Annotated

from fastapi import Depends, Path, Request
from sqlalchemy import inspect, update
from sqlalchemy.exc import DBAPIError
from sqlmodel import Session, select
from starlette.datastructures import FormData

from app.accounts.security import session_is_live, token_digest, tokens_match
from app.config import Settings, get_settings
from app.core.exceptions import UserError
from app.db import (
    get_engine,
    read_session,
    reader,
    row_writer,
    statement_session,
    storage_unavailable,
    writer,
)
from app.models import AuthSession, Role, User, utcnow
from app.web.render import SESSION_COOKIE, csrf_cookie_name

SAFE_METHODS = {"GET", "HEAD", "OPTIONS"}
TOUCH_INTERVAL = timedelta(seconds=60)
# Pages a user who must change their password may still reach.
PASSWORD_CHANGE_PATHS = {"/account/password", "/logout", "/lang"}


class LoginRequired(Exception):
    """No valid session: HTML routes redirect to the login page."""


class PasswordChangeRequired(Exception):
    """The user must choose a new password before anything else."""


# Row writers (db.row_writer): writes to one lab session (recording, trimming, submitting,
# leaving a group) reach it through ``lab.service.own_session``, which locks its row and
# its owner's; starting a session locks the student's row (``lab.sessions.start_session``);
# a log-in locks its account and address names (``accounts.security.log_in``); a log-out
# revokes its own session row.  Every other write is exclusive.
ROW_WRITE_PATH = re.compile(r"/(lab|api/v1)/sessions(/\d+/.*)?|/login|/logout|/api/v1/auth/token")


def get_db(request: Request) -> Iterator[Session]:
    """One session per request; writes (POST, PUT, ...) take the write lock (db.writer),
    or on one lab session's routes lock that session's rows (db.row_writer)."""
    engine = get_engine()
    if request.method in SAFE_METHODS:
        bind = reader(engine)
    elif ROW_WRITE_PATH.fullmatch(request.url.path):
        bind = row_writer(engine)
    else:
        bind = writer(engine)
    with Session(bind, expire_on_commit=False) as session:
        yield session


def get_read_db() -> Iterator[Session]:
    """For a POST that only reads (it carries a body, but stores nothing): no write lock."""
    with Session(reader(get_engine()), expire_on_commit=False) as session:
        yield session


SessionDep = Annotated[Session, Depends(get_db)]
ReadOnlySessionDep = Annotated[Session, Depends(get_read_db)]


async def settings_now() -> Settings:
    """The settings, as a dependency that needs no trip to the thread pool."""
    return get_settings()


SettingsDep = Annotated[Settings, Depends(settings_now)]


def reload_login(request: Request) -> None:
    """Give the request's user and login session fresh rows after its session rolled back
    (a failed flush expires every object it had loaded)."""
    with read_session() as db:
        for name, table in (("user", User), ("auth", AuthSession)):
            row = getattr(request.state, name, None)
            if row is not None:
                identity = inspect(row).identity
                setattr(request.state, name, db.get(table, identity[0]) if identity else None)


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


def login_for_cookie(
    db: Session, token: str | None, settings: Settings
) -> tuple[User, AuthSession] | None:
    """The user and live log-in session of a session cookie (pages, API and WebSocket)."""
    if not token:
        return None
    record = db.exec(
        select(AuthSession).where(AuthSession.token_hash == token_digest(token))
    ).first()
    if record is None or not session_is_live(record, settings):
        return None
    user = db.get(User, record.user_id)
    return None if user is None else (user, record)


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


async def read_form(request: Request) -> FormData:
    """The request's form (parsed once; Starlette keeps it on the request).

    Reading the body is the only async step: route handlers and dependencies that touch the
    database are plain ``def`` so that FastAPI runs them on its thread pool -- a database
    call in an ``async def`` would stop the event loop, and with it every other request and
    stream of this worker, while it waits for the write lock."""
    return await request.form()


FormDep = Annotated[FormData, Depends(read_form)]


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


def optional_user(request: Request, db: SessionDep, settings: SettingsDep) -> User | None:
    return load_login(request, db, settings)


def current_user(request: Request, db: SessionDep, settings: SettingsDep) -> User:
    user = load_login(request, db, settings)
    if user is None:
        raise LoginRequired()
    if user.must_change_password and request.url.path not in PASSWORD_CHANGE_PATHS:
        raise PasswordChangeRequired()
    return user


CurrentUser = Annotated[User, Depends(current_user)]
OptionalUser = Annotated[User | None, Depends(optional_user)]


def teacher_user(user: CurrentUser) -> User:
    if user.role != Role.teacher:
        raise UserError("error.forbidden", status=403)
    return user


def student_user(user: CurrentUser) -> User:
    if user.role != Role.student:
        raise UserError("error.forbidden", status=403)
    return user


def admin_user(user: CurrentUser) -> User:
    if user.role != Role.admin:
        raise UserError("error.forbidden", status=403)
    return user


TeacherUser = Annotated[User, Depends(teacher_user)]
AdminUser = Annotated[User, Depends(admin_user)]
StudentUser = Annotated[User, Depends(student_user)]
CsrfProtected = Depends(csrf_protect)

MAX_ID = 2**31 - 1  # PostgreSQL's INTEGER ids: larger ids cannot exist, so they answer 422
ObjectId = Annotated[int, Path(ge=1, le=MAX_ID)]
