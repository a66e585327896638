"""Courses and rosters: create, rename, archive, add, import, reset, remove."""

from __future__ import annotations

import pytest
from sqlmodel import func, select

from app.accounts.security import verify_password
from app.db import read_session
from app.models import Course, Enrollment, Role, User
from tests.factories import (
    create_course,
    credentials_from,
    form_state,
    import_file,
    login,
    make_course,
    make_user,
    post_form,
    section,
)

ROSTER = "学号,姓名,邮箱\n2024001,张三,zhangsan@example.edu\n2024002,李四,\n"


def user_count() -> int:
    with read_session() as db:
        return db.exec(select(func.count()).select_from(User)).one()


def test_create_rename_archive(teacher_client):
    course_id = create_course(teacher_client)
    page = teacher_client.get(f"/courses/{course_id}")
    assert page.status_code == 200 and "Navigation lab" in page.text
    post_form(teacher_client, f"/courses/{course_id}/rename", {"name": "惯导实验"})
    post_form(teacher_client, f"/courses/{course_id}/archive", {"archived": "true"})
    with read_session() as db:
        course = db.get(Course, course_id)
    assert course.name == "惯导实验" and course.archived


def test_empty_course_name_is_refused(teacher_client):
    response = post_form(teacher_client, "/courses", {"name": "   "})
    assert response.status_code == 400  # the dashboard again, the message beside the name
    kept = form_state(response.text, "new-course")
    assert kept.refused == ["name"] and kept.autofocus == "name"
    assert kept.errors == {"name": "Give the course a name."}


def test_import_roster_creates_accounts_with_one_time_passwords(teacher_client, client):
    course_id = create_course(teacher_client)
    response = import_file(teacher_client, course_id, ROSTER.encode("utf-8-sig"))
    assert response.status_code == 200
    assert "张三" in response.text and "李四" in response.text
    passwords = credentials_from(response.text)
    assert set(passwords) == {"2024001", "2024002"}
    with read_session() as db:
        zhang = db.exec(select(User).where(User.username == "2024001")).one()
        enrolled = db.exec(select(func.count()).select_from(Enrollment)).one()
    assert zhang.display_name == "张三" and zhang.email == "zhangsan@example.edu"
    assert zhang.must_change_password and zhang.role == Role.student
    assert verify_password(passwords["2024001"], zhang.password_hash)
    assert enrolled == 2
    # The roster page lists them; nothing shows the passwords again.
    roster_page = teacher_client.get(f"/courses/{course_id}").text
    assert "2024001" in roster_page and passwords["2024001"] not in roster_page


def test_import_gb18030_file_from_excel(teacher_client):
    course_id = create_course(teacher_client)
    response = import_file(teacher_client, course_id, ROSTER.encode("gb18030"))
    assert response.status_code == 200
    with read_session() as db:
        names = set(db.exec(select(User.display_name).where(User.role == "student")).all())
    assert names == {"张三", "李四"}


def test_a_western_excels_roster_keeps_its_accented_names():
    """A roster saved by Excel in a Western locale (Windows-1252): neither UTF-8 nor
    GB18030, read with its names as written, not refused."""
    from app.accounts.roster_csv import parse_roster

    roster = "username,display_name\r\ns101,Zoë Müller\r\ns102,Ana Peña\r\n"
    parsed = parse_roster(roster.encode("cp1252"))
    assert not parsed.problems
    assert [row.display_name for row in parsed.rows] == ["Zoë Müller", "Ana Peña"]


@pytest.mark.parametrize(
    "names",
    [
        ["François Dubois", "Jürgen Weber"],  # "ço", "ür": GB18030 pairs outside GB2312
        ["Hélène Noël", "Ñúñez"],  # "Ñú" is a GB2312 character, "ñe" is not: a tie
        ["Þór"],  # "Þó" is a GB2312 character -- running straight into the small "r"
    ],
)
def test_a_western_roster_that_is_also_gb18030_reads_as_windows_1252(names):
    """Windows-1252 bytes that GB18030 decodes too ("François" as "Fran鏾is") are read as
    written: their Chinese characters would lie outside GB2312, where a Chinese-locale
    Excel's hardly ever are."""
    from app.accounts.roster_csv import parse_roster

    rows = "".join(f"s{k},{name}\r\n" for k, name in enumerate(names))
    parsed = parse_roster(("username,display_name\r\n" + rows).encode("cp1252"))
    assert [row.display_name for row in parsed.rows] == names


@pytest.mark.parametrize(
    "names", [["张三", "王喆"], ["赵喆"], ["Müller", "张三"], ["X轴组", "王小明Wang"]]
)
def test_a_chinese_roster_with_a_rare_character_stays_gb18030(names):
    from app.accounts.roster_csv import parse_roster

    rows = "".join(f"s{k},{name}\n" for k, name in enumerate(names))
    parsed = parse_roster(("学号,姓名\n" + rows).encode("gb18030"))
    assert [row.display_name for row in parsed.rows] == names


def test_student_numbers_in_full_width_forms_are_imported_as_ascii(teacher_client):
    """A registrar's list typed with a Chinese input method in full-width mode."""
    course_id = create_course(teacher_client)
    roster = "学号,姓名\n２０２４００１,张三\n２０２４００２,李四\n"
    response = import_file(teacher_client, course_id, roster.encode("gb18030"))
    assert response.status_code == 200
    with read_session() as db:
        usernames = set(db.exec(select(User.username).where(User.role == "student")).all())
    assert usernames == {"2024001", "2024002"}


def test_invalid_roster_creates_nothing_and_reports_each_row(teacher_client):
    course_id = create_course(teacher_client)
    before = user_count()
    bad = (
        "学号,姓名,邮箱\n2024001,张三,\nbad name!,李四,\n2024003,,\n2024001,重复,\n"
        "2024005,赵六,not-mail\n"
    )
    response = import_file(teacher_client, course_id, bad.encode())
    assert response.status_code == 400
    text = response.text
    for line in ("Line 3", "Line 4", "Line 5", "Line 6"):
        assert line in text
    assert "already appears on line 2" in text
    assert user_count() == before


def test_student_numbers_a_spreadsheet_saved_as_numbers_are_refused_with_the_reason(
    teacher_client,
):
    """A numeric column saved as "2024001.0" or shortened to "2.024001E+06" is not the
    student number: nothing is created, and the teacher is told to save it as text."""
    course_id = create_course(teacher_client)
    before = user_count()
    roster = "学号,姓名\n2024001.0,张三\n2.024002E+06,李四\n2024003,王五\n"
    response = import_file(teacher_client, course_id, roster.encode())
    assert response.status_code == 400
    for value, line in (("2024001.0", 2), ("2.024002E+06", 3)):
        assert f"Line {line}" in response.text
        assert f"“{value}” is a student number as a spreadsheet saved" in response.text
    assert user_count() == before


def test_roster_rejects_teacher_usernames(teacher_client):
    course_id = create_course(teacher_client)
    before = user_count()
    response = import_file(teacher_client, course_id, b"username,name\nteacher1,Me\n2024009,X\n")
    assert response.status_code == 400 and "teacher account" in response.text
    assert user_count() == before


def test_roster_edge_files(teacher_client):
    course_id = create_course(teacher_client)
    assert import_file(teacher_client, course_id, b"").status_code == 400
    assert "empty" in import_file(teacher_client, course_id, b"\n\n").text
    assert import_file(teacher_client, course_id, b"\xff\xfe\x00\x00garbage\x81").status_code == 400
    big = b"u,n\n" + b"x" * 1_100_000
    assert "larger than" in import_file(teacher_client, course_id, big).text


def test_import_without_header_and_existing_student(teacher_client):
    make_user("2024100", Role.student)
    course_id = create_course(teacher_client)
    response = import_file(teacher_client, course_id, "2024100,Old\n2024101,新同学\n".encode())
    assert response.status_code == 200
    assert set(credentials_from(response.text)) == {"2024101"}
    # someone else's account: listed with the course code to join by, never enrolled
    assert "2024100" in section(response.text, "needs-code")
    with read_session() as db:
        old = db.exec(select(User).where(User.username == "2024100")).one()
        assert db.exec(select(Enrollment).where(Enrollment.student_id == old.id)).first() is None


def test_add_student_by_hand_and_reset_and_remove(teacher_client, client):
    course_id = create_course(teacher_client)
    response = post_form(
        teacher_client,
        f"/courses/{course_id}/students",
        {"username": "s42", "display_name": "王五", "email": ""},
        page=f"/courses/{course_id}",
    )
    assert response.status_code == 200
    first = credentials_from(response.text)["s42"]
    with read_session() as db:
        student = db.exec(select(User).where(User.username == "s42")).one()
    response = post_form(
        teacher_client,
        f"/courses/{course_id}/students/{student.id}/reset-password",
        page=f"/courses/{course_id}",
    )
    second = credentials_from(response.text)["s42"]
    assert first != second
    with read_session() as db:
        assert verify_password(second, db.get(User, student.id).password_hash)
    response = post_form(
        teacher_client,
        f"/courses/{course_id}/students/{student.id}/remove",
        page=f"/courses/{course_id}",
    )
    assert response.status_code == 303
    with read_session() as db:
        assert db.get(User, student.id) is not None  # the account (and its work) stays
        assert (
            db.exec(select(Enrollment).where(Enrollment.student_id == student.id)).first() is None
        )


def test_add_student_validation(teacher_client):
    course_id = create_course(teacher_client)
    response = post_form(
        teacher_client,
        f"/courses/{course_id}/students",
        {"username": "bad name", "display_name": "X"},
        page=f"/courses/{course_id}",
    )
    assert response.status_code == 400 and "not a valid username" in response.text
    response = post_form(
        teacher_client,
        f"/courses/{course_id}/students",
        {"username": "teacher1", "display_name": "X"},
        page=f"/courses/{course_id}",
    )
    assert response.status_code == 400 and "teacher account" in response.text


def test_student_sees_their_courses(client, teacher):
    student = make_user("s1", Role.student)
    other = make_user("s2", Role.student)
    make_course(teacher, "Mine 我的课", (student,))
    make_course(teacher, "Not mine", (other,))
    login(client, "s1")
    page = client.get("/").text
    assert "Mine 我的课" in page and "Not mine" not in page


def test_imported_student_must_change_password(teacher_client, app):
    from fastapi.testclient import TestClient

    course_id = create_course(teacher_client)
    response = import_file(teacher_client, course_id, ROSTER.encode())
    password = credentials_from(response.text)["2024002"]
    with TestClient(app, follow_redirects=False) as browser:
        assert login(browser, "2024002", password).headers["location"] == "/account/password"
        assert browser.get(f"/courses/{course_id}").headers["location"] == "/account/password"


def test_a_list_of_existing_accounts_is_not_called_new_accounts(teacher_client):
    make_user("2024300", Role.student)
    course_id = create_course(teacher_client)
    response = import_file(teacher_client, course_id, b"2024300,Old\n")
    assert response.status_code == 200
    assert "<h1>Class list added</h1>" in response.text
    assert "New student accounts" not in response.text and 'id="credentials"' not in response.text
    fresh = import_file(teacher_client, course_id, "2024301,新同学\n".encode())
    assert "<h1>New student accounts</h1>" in fresh.text
