"""Readings that match readings submitted earlier: another group's earlier attempt in this
assignment (since replaced), a group of another of the teacher's assignments (another
year, another section), or a group of an earlier year's readings the teacher uploaded
(``app/review/archives.py``).  Matching is by the offset-free copy keys kept for every
submitted attempt (``app/lab/copy_index.py``), never beyond the teacher's own courses."""

from __future__ import annotations

from collections.abc import Iterable

from sqlalchemy import bindparam
from sqlmodel import Session, col, select

from app.lab.partners import group_names
from app.models import (
    Assignment,
    Attempt,
    CopyKey,
    Course,
    LabSession,
    ReadingArchive,
    User,
)

IN_CHUNK = 500  # keys per IN (…) list

# Built once (building a select with its joins cost more than running it); the keys are an
# expanding parameter, run through Core: no ORM row processing.
ELSEWHERE_HITS = (
    select(
        CopyKey.key,
        CopyKey.part,
        Attempt.number,
        LabSession.id,
        User.username,
        Assignment.title,
        Course.name,
    )
    .join(Attempt, Attempt.id == CopyKey.attempt_id)
    .join(LabSession, LabSession.id == Attempt.session_id)
    .join(Assignment, Assignment.id == LabSession.assignment_id)
    .join(Course, Course.id == Assignment.course_id)
    .join(User, User.id == LabSession.owner_id)
    .where(
        col(CopyKey.key).in_(bindparam("keys", expanding=True)),
        Course.teacher_id == bindparam("teacher_id"),
        Assignment.id != bindparam("assignment_id"),
    )
)
ARCHIVE_HITS = (
    select(CopyKey.key, CopyKey.part, CopyKey.label, CopyKey.attempt, ReadingArchive.name)
    .join(ReadingArchive, ReadingArchive.id == CopyKey.archive_id)
    .where(
        col(CopyKey.key).in_(bindparam("keys", expanding=True)),
        ReadingArchive.teacher_id == bindparam("teacher_id"),
    )
)
SAME_ASSIGNMENT_KEYS = (
    select(CopyKey.key, CopyKey.part, Attempt.number, LabSession.id, User.username)
    .join(Attempt, Attempt.id == CopyKey.attempt_id)
    .join(LabSession, LabSession.id == Attempt.session_id)
    .join(User, User.id == LabSession.owner_id)
    .where(LabSession.assignment_id == bindparam("assignment_id"))
)


def _chunks(items: list, size: int = IN_CHUNK) -> Iterable[list]:
    for start in range(0, len(items), size):
        yield items[start : start + size]


def earlier_copies(db: Session, assignment: Assignment, rows) -> dict[int, dict[str, list[dict]]]:
    """session id → part → the earlier sources its current readings match.

    A source is ``{"group", "attempts", "assignment", "course", "same"}`` for an attempt
    in the teacher's courses (``same``: this assignment) or ``{"group", "attempts",
    "archive"}`` for an uploaded archive.  Not a source: the session itself, and a
    session of this assignment whose current readings match too (that is the ``copy``
    finding already).

    So an attempt of this assignment is a source only where its key is no longer in its
    own session's current readings (since replaced): this assignment's keys are read
    whole (every group's submitted keys match themselves, and are dropped before anything
    else is done with them), the other places' only for the keys wanted."""
    current: dict[tuple[int, str], set[str]] = {}
    wanted: set[str] = set()
    for row in rows:
        if row.session is None or row.data_evidence is None:
            continue
        for part, keys in row.data_evidence.keys.items():
            current[(row.session.id, part)] = set(keys)
            wanted.update(keys)
    if not wanted:
        return {}
    course = db.get(Course, assignment.course_id)
    connection = db.connection()
    by_key: dict[tuple[str, str], list[tuple]] = {}
    here = {"assignment": assignment.title, "course": course.name, "same": True}
    for key, part, number, session_id, owner in connection.execute(
        SAME_ASSIGNMENT_KEYS, {"assignment_id": assignment.id}
    ).all():
        if key in wanted and key not in current.get((session_id, part), ()):
            by_key.setdefault((part, key), []).append(("s", session_id, owner, number, here))
    where = {"teacher_id": course.teacher_id, "assignment_id": assignment.id}
    for chunk in _chunks(sorted(wanted)):
        for key, part, number, session_id, owner, title, name in connection.execute(
            ELSEWHERE_HITS, {**where, "keys": chunk}
        ).all():
            place = {"assignment": title, "course": name, "same": False}
            by_key.setdefault((part, key), []).append(("s", session_id, owner, number, place))
        for key, part, label, number, name in connection.execute(
            ARCHIVE_HITS, {"teacher_id": course.teacher_id, "keys": chunk}
        ).all():
            by_key.setdefault((part, key), []).append(("a", name, label, number, {"archive": name}))
    if not by_key:
        return {}
    sessions = {hit[1] for hits in by_key.values() for hit in hits if hit[0] == "s"}
    groups = group_names(db, sorted(sessions))
    found: dict[int, dict[str, list[dict]]] = {}
    for (session_id, part), keys in current.items():
        sources: dict[tuple, dict] = {}
        for key in keys:
            for kind, where_, name, number, place in by_key.get((part, key), []):
                if kind == "s" and where_ == session_id:
                    continue
                group = "+".join(groups[where_]) if kind == "s" and where_ in groups else name
                source = sources.setdefault(
                    (kind, where_, name), {"group": group, **place, "attempts": []}
                )
                if number is not None and number not in source["attempts"]:
                    source["attempts"].append(number)
        if sources:
            listed = sorted(sources.values(), key=lambda s: (not s.get("same"), s["group"]))
            for source in listed:
                source["attempts"].sort()
            found.setdefault(session_id, {})[part] = listed
    return found
