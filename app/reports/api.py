"""REST API v1: a session's lab report as a PDF."""

from __future__ import annotations

from typing import Annotated, Literal

from fastapi import APIRouter, Query, Request

from app.accounts.api_auth import ReadCaller
from app.lab.api import ReadableSession
from app.reports.pages import AttemptNumber
from app.reports.service import report_response
from app.web.deps import SessionDep
from app.web.errors import API_ERRORS
from app.web.i18n import negotiate

router = APIRouter(prefix="/api/v1", tags=["api"], responses=API_ERRORS)


@router.get(
    "/sessions/{session_id}/report.pdf",
    responses={200: {"content": {"application/pdf": {}}, "description": "the lab report"}},
)
def get_report(
    request: Request,
    session: ReadableSession,
    caller: ReadCaller,
    db: SessionDep,
    attempt: AttemptNumber = None,
    lang: Annotated[Literal["en", "zh-CN"] | None, Query()] = None,
):
    """The lab report as a PDF: submitted attempt ``attempt`` as it was submitted, or
    without it the current data and discussion draft.  In ``lang``, else the language of
    ``Accept-Language``."""
    language = lang or negotiate(request.headers.get("accept-language"))
    return report_response(db, session, attempt, language, caller.user.id)
