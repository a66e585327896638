"""The student's own discussion for the lab report: a draft on the session, frozen with
each attempt when it is submitted."""

from __future__ import annotations

import unicodedata

from sqlmodel import Session

from app.core.exceptions import UserError
from app.lab.store import check_editable, reopen
from app.models import DISCUSSION_MAX, LabSession


def clean_text(text: str) -> str:
    """Line endings as ``\\n``; control characters other than newline and tab dropped (a
    PDF or a spreadsheet has no use for them); surrounding blank space trimmed."""
    text = text.replace("\r\n", "\n").replace("\r", "\n")
    kept = (ch for ch in text if ch in "\n\t" or not unicodedata.category(ch).startswith("C"))
    return "".join(kept).strip()


def save_discussion(db: Session, session: LabSession, text: str) -> None:
    """Keep the discussion draft (added, not committed).  Like any edit, refused while the
    work awaits review or after grading, and it starts the next attempt after a return."""
    check_editable(session)
    cleaned = clean_text(text)
    if len(cleaned) > DISCUSSION_MAX:
        raise UserError(
            "report.discussion_too_long",
            limit=DISCUSSION_MAX,
        )
    if cleaned == session.discussion:
        return
    session.discussion = cleaned
    reopen(session)
    db.add(session)
