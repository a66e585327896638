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
