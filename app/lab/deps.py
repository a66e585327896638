"""The lab's objects as dependencies: a route's signature says whose session it reaches
and which way of recording it needs."""

from __future__ import annotations

from typing import Annotated

from fastapi import Depends

from app.accounts.deps import CurrentUser
from app.lab.service import own_session, require_method
from app.models import InputMethod, LabSession
from app.web.deps import ObjectId, SessionDep


def owned_session(session_id: ObjectId, user: CurrentUser, db: SessionDep) -> LabSession:
    """The logged-in user's own session (404 for anyone else's)."""
    return own_session(db, user, session_id)


OwnedSession = Annotated[LabSession, Depends(owned_session)]


def recordable(method: InputMethod):
    """A dependency: the user's own session, when its assignment allows ``method``."""

    def dependency(session: OwnedSession, db: SessionDep) -> LabSession:
        require_method(db, session, method)
        return session

    return dependency


ManualSession = Annotated[LabSession, Depends(recordable(InputMethod.manual))]
SimulatorSession = Annotated[LabSession, Depends(recordable(InputMethod.simulator))]
