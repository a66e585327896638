"""Current data loaded in bulk: the same arrays as take by take, and a dashboard whose query
count does not grow with the class (it used to re-read and re-solve every student)."""

from __future__ import annotations

import numpy as np
from sqlalchemy import event
from sqlmodel import select

from app.db import get_engine, read_session, write_session
from app.lab.recent_samples import RECENT
from app.lab.results import current_data
from app.lab.samples import CHUNK_SAMPLES
from app.lab.store import load_samples, store_take
from app.lab.take_appends import append_samples
from app.models import Assignment, Enrollment, LabSession, Role, Take
from app.review.service import class_rows
from tests.factories import make_course, make_user


def add_session(owner_id: int, assignment_id: int | None, seed: int) -> int:
    """A session with both parts recorded; heading 1 twice (the first take superseded) and
    one position longer than a chunk, with times."""
    rng = np.random.default_rng(seed)
    with write_session() as db:
        session = LabSession(
            owner_id=owner_id, assignment_id=assignment_id, title="t", latitude_deg=40.0
        )
        db.add(session)
        db.flush()
        for part in ("heading", "latitude"):
            for position in range(1, 5):
                size = CHUNK_SAMPLES + 17 if (part, position) == ("latitude", 2) else 12
                times = np.arange(size) * 0.1 if position == 3 else None
                store_take(
                    db,
                    session,
                    part=part,
                    position=position,
                    angle_deg=90.0 * position,
                    values=rng.normal(10.0, 0.1, size),
                    times=times,
                    source="api",
                )
        store_take(
            db,
            session,
            part="heading",
            position=1,
            angle_deg=0.0,
            values=rng.normal(11.0, 0.1, 15),
            times=None,
            source="api",
        )
        return session.id


def test_bulk_loading_gives_the_same_arrays_as_take_by_take(app, monkeypatch):
    from app.lab import results

    monkeypatch.setattr(results, "TAKES_PER_READ", 5)  # several statements, takes split
    student = make_user("s", Role.student)
    ids = [add_session(student.id, None, seed) for seed in range(3)]
    RECENT.clear()  # read from the database, not from what this process just wrote
    with read_session() as db:
        takes = db.exec(
            select(Take).where(Take.session_id.in_(ids), Take.superseded_at.is_(None))
        ).all()
        assert len(takes) == 24
        bulk = {item.take.id: item for item in results.iter_takes_data(db, takes)}
        assert sorted(bulk) == sorted(take.id for take in takes)
        for take in takes:
            item = bulk[take.id]
            values, times = load_samples(db, take)
            assert item.take is take
            np.testing.assert_array_equal(item.values, values[take.trim_start :])
            assert (item.times is None) == (times is None)
            if times is not None:
                np.testing.assert_array_equal(item.times, times)
        by_position = {(t.session_id, t.part, t.position): bulk[t.id] for t in takes}
        assert by_position[(ids[0], "heading", 1)].values.size == 15  # the newer take
        assert by_position[(ids[0], "latitude", 2)].values.size == CHUNK_SAMPLES + 17
        session = db.get(LabSession, ids[1])
        for part, positions in current_data(db, session).items():
            for position, item in positions.items():
                np.testing.assert_array_equal(
                    item.values, by_position[(ids[1], part, position)].values
                )


def count_queries(run) -> int:
    statements: list[str] = []

    def count(_conn, _cursor, statement, *_args) -> None:
        statements.append(statement)

    engine = get_engine()
    event.listen(engine, "before_cursor_execute", count)
    try:
        run()
    finally:
        event.remove(engine, "before_cursor_execute", count)
    return len(statements)


def test_dashboard_queries_do_not_grow_with_the_class(app):
    teacher = make_user("t", Role.teacher)
    course_id = make_course(teacher, "Big class")
    with write_session() as db:
        assignment = Assignment(
            course_id=course_id, title="A", latitude_deg=40.0, earth_rate_deg_h=15.04
        )
        db.add(assignment)
        db.flush()
        assignment_id = assignment.id

    def enrol(count: int, start: int) -> None:
        for i in range(start, start + count):
            student = make_user(f"s{i:02d}", Role.student)
            with write_session() as db:
                db.add(Enrollment(course_id=course_id, student_id=student.id))
            add_session(student.id, assignment_id, seed=i)

    def dashboard() -> list:
        with read_session() as db:
            return class_rows(db, db.get(Assignment, assignment_id))

    enrol(2, 0)
    small = count_queries(dashboard)
    enrol(6, 2)
    large = count_queries(dashboard)
    rows = dashboard()
    assert len(rows) == 8
    assert large == small
    # identical data shows up as duplicates (the fingerprints are still computed)
    assert all(row.duplicate_of == [] for row in rows)


def test_just_written_samples_are_not_read_back_and_equal_what_the_database_holds(app):
    student = make_user("s", Role.student)
    session_id = add_session(student.id, None, seed=4)
    reads: list[str] = []

    def count(_conn, _cursor, statement, *_args) -> None:
        reads.append(statement)

    with read_session() as db:
        session = db.get(LabSession, session_id)
        event.listen(get_engine(), "before_cursor_execute", count)
        try:
            held = current_data(db, session)
        finally:
            event.remove(get_engine(), "before_cursor_execute", count)
        assert not any("sample_chunk" in statement.lower() for statement in reads)
        RECENT.clear()
        read = current_data(db, session)
    assert held.keys() == read.keys() == {"heading", "latitude"}
    for part in held:
        assert list(held[part]) == list(read[part]) == [1, 2, 3, 4]
        for position, item in held[part].items():
            again = read[part][position]
            assert item.take.id == again.take.id
            np.testing.assert_array_equal(item.values, again.values)
            assert (item.times is None) == (again.times is None)
            assert (item.mean, item.std) == (again.mean, again.std)
            assert not item.values.flags.writeable  # shared between requests


def test_a_rolled_back_or_appended_take_is_read_from_the_database(app):
    student = make_user("s", Role.student)
    session_id = add_session(student.id, None, seed=5)
    RECENT.clear()
    with write_session() as db:
        session = db.get(LabSession, session_id)
        store_take(
            db,
            session,
            part="heading",
            position=2,
            angle_deg=0.0,
            values=np.full(12, 99.0),
            times=None,
            source="api",
        )
        db.rollback()
    with read_session() as db:
        session = db.get(LabSession, session_id)
        take = db.exec(
            select(Take).where(
                Take.session_id == session_id,
                Take.part == "heading",
                Take.position == 2,
                Take.superseded_at.is_(None),
            )
        ).one()
        assert RECENT.get(take) is None
        assert current_data(db, session)["heading"][2].values.max() < 20.0
    with write_session() as db:
        session = db.get(LabSession, session_id)
        take, added = append_samples(
            db,
            session,
            part="heading",
            position=2,
            angle_deg=0.0,
            values=np.full(3, 12.5),
            times=None,
        )
        assert added == 3
    with read_session() as db:
        session = db.get(LabSession, session_id)
        item = current_data(db, session)["heading"][2]
        assert item.values.size == 15 and item.values[-1] == 12.5
