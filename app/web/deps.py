"""FastAPI dependencies every layer shares: the database session, settings, the form and
ids (who the caller is: ``app.accounts.deps``)."""

from __future__ import annotations

import re
from collections.abc import Iterator
from typing import Annotated

from fastapi import Depends, Path, Request
from sqlalchemy import inspect
from sqlmodel import Session
from starlette.datastructures import FormData

from app.config import Settings, get_settings
from app.db import (
    get_engine,
    read_session,
    reader,
    row_writer,
    writer,
)
from app.models import AuthSession, User

SAFE_METHODS = {"GET", "HEAD", "OPTIONS"}


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


async def read_form(request: Request) -> FormData:
    """The request's form (parsed once; Starlette keeps it on the request).

    Reading the body is the only async step: route handlers and dependencies that touch the
    database are plain ``def`` so that FastAPI runs them on its thread pool -- a database
    call in an ``async def`` would stop the event loop, and with it every other request and
    stream of this worker, while it waits for the write lock."""
    return await request.form()


FormDep = Annotated[FormData, Depends(read_form)]


MAX_ID = 2**31 - 1  # PostgreSQL's INTEGER ids: larger ids cannot exist, so they answer 422
ObjectId = Annotated[int, Path(ge=1, le=MAX_ID)]
