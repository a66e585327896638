"""The lab's objects as dependencies: a route's signature says whose session it reaches.

Routes that read get the session (:data:`OwnedSession`).  Routes that change one get its
id, checked in a read snapshot (:data:`OwnSessionId`: anyone else's is a 404 before the
request's body is even looked at), and read it again in their handler
(``lab.service.own_session`` / ``recordable_session``): dependencies and the handler run
on separate trips to the thread pool, and the write lock a dependency's query took would be
held across the gap (tests/test_locking.py holds every row-writing route to this)."""

from __future__ import annotations

from typing import Annotated

from fastapi import Depends, Request

from app.accounts.deps import CurrentUser, required_login
from app.db import read_session
from app.lab.service import own_session
from app.models import LabSession
from app.web.deps import ObjectId, SessionDep, SettingsDep


def owned_session(
    request: Request, session_id: ObjectId, db: SessionDep, settings: SettingsDep
) -> LabSession:
    """The logged-in user's own session (404 for anyone else's), the user found in the
    same trip to the thread pool."""
    return own_session(db, required_login(request, db, settings), session_id)


OwnedSession = Annotated[LabSession, Depends(owned_session)]


def own_session_id(session_id: ObjectId, user: CurrentUser) -> int:
    """The id of the logged-in user's own session (404 for anyone else's), checked without
    the write lock (the user, found by the CSRF check before, costs no trip to the thread
    pool: ``accounts.deps.current_user``)."""
    with read_session() as db:
        own_session(db, user, session_id)
    return session_id


OwnSessionId = Annotated[int, Depends(own_session_id)]
