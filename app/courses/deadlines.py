"""Due dates: the assignment's, or a student's own extension."""

from __future__ import annotations

from datetime import datetime

from sqlalchemy import bindparam
from sqlmodel import Session, select

from app.models import (
    Assignment,
    Extension,
)


def due_for(db: Session, assignment: Assignment | None, student_id: int) -> datetime | None:
    """The student's due date: their extension, else the assignment's."""
    if assignment is None:
        return None
    extension = db.exec(
        EXTENSION, params={"assignment_id": assignment.id, "student_id": student_id}
    ).first()
    return extension.due_at if extension else assignment.due_at


EXTENSION = select(Extension).where(  # built once (the lab pages' and a submit's)
    Extension.assignment_id == bindparam("assignment_id"),
    Extension.student_id == bindparam("student_id"),
)


def extensions_of(db: Session, assignment: Assignment) -> dict[int, datetime]:
    """``{student_id: due_at}`` for every extension of ``assignment`` (one query)."""
    rows = db.exec(select(Extension).where(Extension.assignment_id == assignment.id)).all()
    return {row.student_id: row.due_at for row in rows}


def set_extension(
    db: Session, assignment: Assignment, student_id: int, due_at: datetime | None
) -> None:
    """Give one student a later due date (None removes the extension)."""
    existing = db.exec(
        select(Extension).where(
            Extension.assignment_id == assignment.id, Extension.student_id == student_id
        )
    ).first()
    if due_at is None:
        if existing is not None:
            db.delete(existing)
        return
    if existing is None:
        existing = Extension(assignment_id=assignment.id, student_id=student_id, due_at=due_at)
    existing.due_at = due_at
    db.add(existing)
