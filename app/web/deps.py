"""FastAPI dependencies every layer shares: the database session, settings, the form and
ids (who the caller is: ``app.accounts.deps``)."""

from __future__ import annotations

from collections.abc import AsyncIterator
from enum import Enum
from typing import Annotated

from fastapi import Depends, Path, Request
from sqlalchemy import inspect
from sqlmodel import Session
from starlette.concurrency import run_in_threadpool
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


class Locking(Enum):
    """How a route's state-changing request holds the database (declared on the route)."""

    exclusive = "exclusive"  # serialised with every other writer (db.writer): the default
    rows = "rows"  # locks the rows it checks (db.row_writer): RowWriteSession
    none = "none"  # a POST that only reads (a body, but nothing stored): ReadOnlySession


async def row_writes() -> None:
    """Marker of :data:`RowWriteSession` (does nothing; no trip to the thread pool)."""


async def reads_only() -> None:
    """Marker of :data:`ReadOnlySession` (does nothing; no trip to the thread pool)."""


RowWriteSession = Depends(row_writes)
"""On a route (``dependencies=[RowWriteSession]``) or a router: its writes lock only the
rows they check.  Writes to one lab session (recording, trimming, submitting, leaving a
group) reach it through ``lab.service.own_session``, which locks its row and its owner's;
starting a session locks the student's row (``lab.sessions.start_session``); a log-in locks
its account and address names (``accounts.security.log_in``); a log-out revokes its own
session row.  On PostgreSQL such writes run side by side; on SQLite they are serialised."""
ReadOnlySession = Depends(reads_only)
"""On a POST that stores nothing: it reads in a snapshot, takes no write lock and no
write slot (``web.admission``)."""
_MARKERS = {row_writes: Locking.rows, reads_only: Locking.none}


def lockings_declared(route: object) -> list[Locking]:
    """The lockings a route declares by :data:`RowWriteSession` or :data:`ReadOnlySession`
    among its (or its router's) dependencies (``app.routes`` allows at most one)."""
    return [
        _MARKERS[depends.dependency]
        for depends in getattr(route, "dependencies", ())
        if depends.dependency in _MARKERS
    ]


def declared_locking(route: object) -> Locking:
    """A route's declared locking; :attr:`Locking.exclusive` when it declares none."""
    declared = lockings_declared(route)
    return declared[0] if declared else Locking.exclusive


async def get_db(request: Request) -> AsyncIterator[Session]:
    """One session per request: reads (GET, HEAD, OPTIONS, and POSTs declared
    :data:`ReadOnlySession`) in a snapshot; writes take the write lock (db.writer), or
    lock their rows on routes declared :data:`RowWriteSession` (db.row_writer).

    Made on the event loop, not in a trip to the thread pool: making it touches no
    database.  Closing it ends what the request left open (nothing after a commit, a
    read's snapshot, a failed write's rollback): on the loop for SQLite, where that takes
    microseconds; in the thread pool for PostgreSQL, where it is a round trip to a server
    that may be on another host."""
    engine = get_engine()
    locking = declared_locking(request.scope.get("route"))
    if request.method in SAFE_METHODS or locking is Locking.none:
        bind = reader(engine)
    elif locking is Locking.rows:
        bind = row_writer(engine)
    else:
        bind = writer(engine)
    session = Session(bind, expire_on_commit=False)
    try:
        yield session
    finally:
        if engine.dialect.name == "sqlite":
            session.close()
        else:
            await run_in_threadpool(session.close)


SessionDep = Annotated[Session, Depends(get_db)]


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
