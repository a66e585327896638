"""Demo data: created once on an empty database, usable at once."""

from __future__ import annotations

from sqlmodel import func, select

from app.accounts.security import verify_password
from app.cli.demo import create_demo_data, database_is_empty
from app.db import read_session, write_session
from app.models import Assignment, Course, Enrollment, User


def test_demo_data(var_dir):
    from app.migrate import upgrade_to_head

    upgrade_to_head()
    with write_session() as db:
        assert database_is_empty(db)
        credentials = create_demo_data(db)
    with read_session() as db:
        assert not database_is_empty(db)
        users = {u.username: u for u in db.exec(select(User)).all()}
        assert db.exec(select(func.count()).select_from(Enrollment)).one() == 3
        assert db.exec(select(Course)).one().teacher_id == users["teacher"].id
        assert db.exec(select(Assignment)).one().methods == ["manual", "csv", "simulator"]
    assert [row[1] for row in credentials] == ["teacher", "student1", "student2", "student3"]
    for _role, username, password in credentials:
        assert verify_password(password, users[username].password_hash)
        assert not users[username].must_change_password
