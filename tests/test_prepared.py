"""``app.prepared``: a statement compiled once and run on the driver gives exactly the rows
SQLAlchemy gives, commits what it writes, keeps one snapshot when asked, and raises the
driver's errors as SQLAlchemy's (so "database is locked" still answers 503)."""

from __future__ import annotations

from datetime import UTC, datetime, timedelta

import pytest
from sqlalchemy import bindparam, column, select, table
from sqlalchemy.exc import DBAPIError
from sqlmodel import Session

from app.accounts.rate_leases import lease_parameters, lease_update
from app.db import get_engine, write_session
from app.models import ApiToken, Assignment, Course, LabSession, User, utcnow
from app.prepared import Prepared, driver_transaction


def seed() -> tuple[int, int]:
    """A teacher, a course, an assignment with a due date, a session with a boolean set."""
    with write_session() as db:
        teacher = User(username="t", display_name="Tē", role="teacher", password_hash="x")
        db.add(teacher)
        db.flush()
        course = Course(name="Gyro", teacher_id=teacher.id)
        db.add(course)
        db.flush()
        assignment = Assignment(
            course_id=course.id,
            title="Lab",
            latitude_deg=39.93,
            earth_rate_deg_h=15.041,
            due_at=datetime(2026, 12, 1, 9, 30, 15, 123456, tzinfo=UTC),
        )
        db.add(assignment)
        db.flush()
        session = LabSession(
            owner_id=teacher.id,
            assignment_id=assignment.id,
            title="s",
            latitude_deg=-33.5,
            earth_rate_deg_h=15.0,
            symmetric_order=True,
        )
        db.add(session)
        db.flush()
        return session.id, teacher.id


SESSION_AND_ASSIGNMENT = (
    select(LabSession, Assignment.due_at, Assignment.true_heading_deg, Assignment.latitude_deg)
    .join(Assignment, Assignment.id == LabSession.assignment_id)
    .where(LabSession.id == bindparam("session_id"), LabSession.title != "literal")
)


def test_rows_equal_sqlalchemys_value_for_value(test_database):
    session_id, _ = seed()
    statement = select(*SESSION_AND_ASSIGNMENT.selected_columns).select_from(
        LabSession.__table__.join(Assignment.__table__)
    )
    statement = statement.where(LabSession.id == bindparam("session_id"))
    with get_engine().connect() as connection:
        expected = connection.execute(statement, {"session_id": session_id}).all()
    got = Prepared(statement).rows(get_engine(), session_id=session_id)
    assert [tuple(row) for row in got] == [tuple(row) for row in expected]
    assert [type(v) for v in got[0]] == [type(v) for v in expected[0]]
    row = got[0]
    assert row.symmetric_order is True and row.due_at == datetime(
        2026, 12, 1, 9, 30, 15, 123456, tzinfo=UTC
    )
    assert row.true_heading_deg is None and row[-1] == 39.93
    assert Prepared(statement).rows(get_engine(), session_id=session_id + 99) == []


def test_a_statements_own_literals_are_bound(test_database):
    session_id, _ = seed()
    statement = select(LabSession.id).where(
        LabSession.id == bindparam("session_id"), LabSession.title == "s"
    )
    assert Prepared(statement).first(get_engine(), session_id=session_id) == (session_id,)
    other = select(LabSession.id).where(
        LabSession.id == bindparam("session_id"), LabSession.title == "not it"
    )
    assert Prepared(other).first(get_engine(), session_id=session_id) is None


def test_an_update_returning_is_committed_on_its_own(test_database):
    _, user_id = seed()
    with write_session() as db:
        token = ApiToken(
            user_id=user_id,
            kind="personal",
            name="t",
            token_hash="h" * 64,
            prefix="gl_h",
            scopes="read",
        )
        db.add(token)
        db.flush()
        token_id = token.id
    lease = Prepared(lease_update(ApiToken))
    now = utcnow()
    assert lease.first(get_engine(), **lease_parameters(token_id, 5, now)) == (now, 5)
    assert lease.first(get_engine(), **lease_parameters(token_id, 3, now)) == (now, 8)
    later = now + timedelta(minutes=2)  # a new window
    assert lease.first(get_engine(), **lease_parameters(token_id, 1, later)) == (later, 1)
    with Session(get_engine()) as db:  # committed: another connection sees it
        assert db.get(ApiToken, token_id).window_count == 1


def test_a_snapshot_transaction_sees_one_state(test_database):
    session_id, _ = seed()
    latitude = Prepared(
        select(LabSession.latitude_deg).where(LabSession.id == bindparam("session_id"))
    )
    with driver_transaction(get_engine(), snapshot=True) as transaction:
        before = transaction.first(latitude, session_id=session_id)
        with write_session() as db:  # another writer commits meanwhile
            db.get(LabSession, session_id).latitude_deg = 12.0
        assert transaction.first(latitude, session_id=session_id) == before == (-33.5,)
    assert latitude.first(get_engine(), session_id=session_id) == (12.0,)


def test_driver_errors_are_sqlalchemys(test_database):
    missing = table("no_such_table", column("id"))
    with pytest.raises(DBAPIError, match="no_such_table"):
        Prepared(select(missing.c.id)).rows(get_engine())
    # and the connection went back to the pool usable
    assert Prepared(select(User.id).where(User.id == -1)).rows(get_engine()) == []


def test_in_lists_are_refused(test_database):
    statement = select(User.id).where(User.id.in_(bindparam("ids", expanding=True)))
    with pytest.raises(ValueError, match="expanding"):
        Prepared(statement).rows(get_engine(), ids=[1, 2])
