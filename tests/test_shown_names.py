"""A name with bidirectional controls would reorder what is shown after it -- "\\u202e"
before a class table's username shows "student1" as "1tneduts".  Names lose them wherever
an account is made or named: a roster, a form, a sign-in provider."""

from __future__ import annotations

import pytest
from sqlmodel import select

from app.accounts.roster_csv import parse_roster, person_problems
from app.accounts.sso import account_for
from app.core.text_files import shown_name
from app.db import read_session, write_session
from app.models import Role, User
from tests.factories import make_user

RLO = "\u202e"


@pytest.mark.parametrize(
    ("typed", "shown"),
    [
        (f"{RLO}evil", "evil"),
        ("\u2067عربي\u2069 Li", "عربي Li"),  # an isolate around Arabic: the letters stay
        (" 张三 ", "张三"),
        ("Zoë\u200dx", "Zoë\u200dx"),  # a joiner some scripts need stays
    ],
)
def test_shown_names_lose_only_bidirectional_controls(typed, shown):
    assert shown_name(typed) == shown


def test_a_roster_and_a_form_store_names_without_them(app):
    parsed = parse_roster(f"学号,姓名\n2024001,{RLO}张三\n".encode())
    assert [row.display_name for row in parsed.rows] == ["张三"]
    assert "display_name" in person_problems("2024002", f"{RLO}\u2066")  # nothing left
    user = make_user("2024003", name=f"{RLO}Wang")
    assert user.display_name == "Wang"


def test_a_sign_in_providers_name_loses_them(app):
    claims = {"iss": "https://idp.example", "sub": "s-1", "name": f"{RLO}Mallory"}
    with write_session() as db:
        account_for(db, claims, Role.student)
    with read_session() as db:
        names = db.exec(select(User.display_name).where(User.role == "student")).all()
    assert names == ["Mallory"]


def test_titles_lose_them_too(teacher_client):
    """A course's, an assignment's, a session's and an LMS course's title are shown beside
    other text on every page and export: they lose the controls as names do."""
    from app.courses.assignment_form import AssignmentForm
    from app.lti.provisioning import context_of
    from app.models import Course
    from tests.factories import post_form

    made = post_form(teacher_client, "/courses", {"name": f"{RLO}Physics 2"}, page="/")
    assert made.status_code == 303, made.text
    course_id = int(made.headers["location"].rsplit("/", 1)[1])
    renamed = post_form(
        teacher_client,
        f"/courses/{course_id}/rename",
        {"name": f"Optics{RLO}"},
        page=f"/courses/{course_id}",
    )
    assert renamed.status_code == 303, renamed.text
    refused = post_form(teacher_client, "/courses", {"name": RLO}, page="/")
    assert refused.status_code == 400  # nothing but a control: no name at all
    form = AssignmentForm.model_validate({"title": f"\u2066Lab 1{RLO}", "latitude_deg": 40})
    assert form.title == "Lab 1"
    body = {"https://purl.imsglobal.org/spec/lti/claim/context": {"id": "c1", "title": f"{RLO}Geo"}}
    assert context_of(None, body) == ("c1", "Geo")
    with read_session() as db:
        assert [c.name for c in db.exec(select(Course)).all()] == ["Optics"]


def test_a_session_title_loses_them(student_client):
    from app.models import LabSession
    from tests.factories import new_session

    session_id = new_session(student_client, title=f"{RLO}Bench 3")
    with read_session() as db:
        assert db.get(LabSession, session_id).title == "Bench 3"
