"""Readings that match readings submitted earlier -- another group's replaced attempt,
another of the teacher's assignments (another year) -- found from the copy keys kept
with every submitted attempt, never across teachers."""

from __future__ import annotations

import html

from sqlmodel import select

from app.db import read_session, write_session
from app.lab.copy_index import index_earlier_attempts
from app.models import Assignment, Attempt, CopyKey, LabSession, ReadingArchive, Role
from tests.factories import (
    API,
    browser,
    make_course,
    make_user,
    new_session,
    post_form,
    review,
    save_manual,
    submit,
    token_for,
)
from tests.test_evidence_pages import hand_in, honest_columns
from tests.zip_faults import zip_patched


def shifted(columns: dict, offset: float) -> dict:
    return {k: [round(v + offset, 2) for v in column] for k, column in columns.items()}


def evidence_of(teacher, world, assignment_id=None) -> dict[str, list[dict]]:
    auth = token_for(teacher, "teacher1")
    rows = teacher.get(
        f"{API}/assignments/{assignment_id or world['assignment']}/submissions", headers=auth
    ).json()
    return {row["username"]: row["evidence"] for row in rows}


def earlier(findings: list[dict], part: str = "heading") -> list[dict]:
    return [
        source
        for finding in findings
        if finding["check"] == "copy_earlier" and finding["part"] == part
        for source in finding["sources"]
    ]


def test_a_copy_of_another_groups_replaced_attempt_is_found(world):
    original = honest_columns(11)
    s1, first = hand_in(world, "s1", original, honest_columns(12, 9.8))
    teacher = browser(world, "teacher1")
    assert review(teacher, first, action="return").status_code == 303
    # s1 records heading again and submits: the original readings are no longer current
    assert save_manual(s1, first, "heading", honest_columns(13)).status_code == 200
    submit(s1, first)
    _, second = hand_in(world, "s2", shifted(original, 0.3), honest_columns(14, 9.8))

    found = evidence_of(teacher, world)
    assert earlier(found["s2"]) == [
        {
            "group": "s1",
            "assignment": "Find north",
            "course": "Nav lab 惯导",
            "same": True,
            "attempts": [1],
        }
    ]
    assert not any(f["check"] == "copy" for f in found["s2"])  # not s1's current data
    assert earlier(found["s1"]) == [] and earlier(found["s2"], "latitude") == []

    desk = html.unescape(teacher.get(f"/review/sessions/{second}").text)
    assert "s1, attempt 1 of this assignment (since replaced)" in desk
    chinese = teacher.get(f"/review/sessions/{second}", headers={"Accept-Language": "zh-CN"})
    assert "s1 在本作业中的第 1 次提交" in html.unescape(chinese.text)
    table = teacher.get(f"/courses/{world['course']}/assignments/{world['assignment']}").text
    assert 'data-check="copy_earlier"' in table


def test_another_years_readings_are_found_but_never_another_teachers(world, teacher):
    old = honest_columns(21)
    # last year: the same teacher's other course, where s3 submitted these readings
    s3 = make_user("s3_2025", Role.student)
    last_year = make_course(teacher, "Nav lab 2025", (s3,))
    other_teacher = make_user("teacher2", Role.teacher)
    s4 = make_user("s4", Role.student)
    elsewhere = make_course(other_teacher, "Other lab", (s4,))
    with write_session() as db:
        earlier_assignment = Assignment(
            course_id=last_year,
            title="North 2025",
            latitude_deg=39.93,
            earth_rate_deg_h=15.04,
            allowed_methods="manual",
        )
        foreign = Assignment(
            course_id=elsewhere,
            title="Foreign",
            latitude_deg=39.93,
            earth_rate_deg_h=15.04,
            allowed_methods="manual",
        )
        db.add(earlier_assignment)
        db.add(foreign)
        db.flush()
        ids = earlier_assignment.id, foreign.id
    for username, assignment_id, columns in (
        ("s3_2025", ids[0], old),
        ("s4", ids[1], shifted(honest_columns(31), 1.0)),
    ):
        client = browser(world, username)
        session_id = new_session(client, assignment_id=str(assignment_id))
        assert save_manual(client, session_id, "heading", columns).status_code == 200
        submit(client, session_id)
    # this year: s1 hands in last year's readings, s2 the other teacher's student's
    hand_in(world, "s1", shifted(old, -0.5), honest_columns(22, 9.8))
    hand_in(world, "s2", honest_columns(31), honest_columns(32, 9.8))

    teacher_client = browser(world, "teacher1")
    found = evidence_of(teacher_client, world)
    assert earlier(found["s1"]) == [
        {
            "group": "s3_2025",
            "assignment": "North 2025",
            "course": "Nav lab 2025",
            "same": False,
            "attempts": [1],
        }
    ]
    assert earlier(found["s2"]) == []  # the other teacher's class is not theirs to search
    session_id = next(s.id for s in read_all(LabSession) if s.assignment_id == world["assignment"])
    desk = html.unescape(teacher_client.get(f"/review/sessions/{session_id}").text)
    assert "s3_2025, attempt 1 of “North 2025” in Nav lab 2025" in desk


def test_attempts_from_before_the_index_are_indexed_at_start(world):
    hand_in(world, "s1", honest_columns(41), honest_columns(42, 9.8))
    with read_session() as db:
        kept = sorted((k.part, k.key) for k in db.exec(select(CopyKey)).all())
    assert {part for part, _ in kept} == {"heading", "latitude"}
    with write_session() as db:  # as a database from before the index looks
        for key in db.exec(select(CopyKey)).all():
            db.delete(key)
        for attempt in db.exec(select(Attempt)).all():
            attempt.copy_indexed = False
            db.add(attempt)
    assert index_earlier_attempts() == 1
    assert index_earlier_attempts() == 0
    with read_session() as db:
        assert sorted((k.part, k.key) for k in db.exec(select(CopyKey)).all()) == kept


def test_only_readings_the_students_recorded_have_keys():
    from types import SimpleNamespace

    import numpy as np

    from app.lab.copy_index import part_keys
    from app.lab.results import PositionData

    def position(source, seed):
        values = np.round(np.random.default_rng(seed).normal(11, 0.1, 12), 1)
        return PositionData.of(SimpleNamespace(source=source, trim_start=0), values, None)

    typed = {k: position("manual", k) for k in (1, 2, 3, 4)}
    simulated = {k: position("simulator", k) for k in (1, 2, 3, 4)}
    mixed = {1: position("manual", 1), 2: position("manual", 2), 3: position("simulator", 3)}
    keys = part_keys({"heading": typed, "latitude": simulated})
    assert list(keys) == ["heading"] and keys["heading"][0].startswith("o")
    assert part_keys({"heading": mixed}) == {}  # two positions of its own: no evidence


def test_the_samples_read_for_keys_are_only_those_that_can_have_keys():
    from types import SimpleNamespace

    from app.lab.copy_index import keyable_takes

    def take(part, position, source):
        return SimpleNamespace(part=part, position=position, source=source)

    typed = [take("heading", k, "manual") for k in (1, 2, 3, 4)]
    simulated = [take("latitude", k, "simulator") for k in (1, 2, 3, 4)]
    mixed = [take("latitude", 1, "csv"), take("latitude", 2, "csv")] + simulated[2:]
    assert keyable_takes(typed + simulated) == typed
    assert keyable_takes(simulated) == []  # a streamed session: nothing is read
    assert keyable_takes(mixed) == []  # two positions of its own
    assert keyable_takes(typed[:3] + mixed) == typed[:3]


def read_all(model):
    with read_session() as db:
        return list(db.exec(select(model)).all())


# --- readings of earlier years, uploaded ----------------------------------------------------


def other_teachers_class(world) -> tuple:
    """teacher2's course with s4 and an assignment: another university, say."""
    teacher2 = make_user("teacher2", Role.teacher)
    course = make_course(teacher2, "Elsewhere", (make_user("s4", Role.student),))
    with write_session() as db:
        assignment = Assignment(
            course_id=course,
            title="North",
            latitude_deg=39.93,
            earth_rate_deg_h=15.04,
            allowed_methods="manual",
        )
        db.add(assignment)
        db.flush()
        return course, assignment.id


def upload(client, name: str, content: bytes):
    return post_form(
        client, "/review/archives", files={"readings": (name, content)}, page="/review/archives"
    )


def shown(client) -> str:
    return html.unescape(client.get("/review/archives").text)


def test_a_copy_of_an_uploaded_class_zip_is_found(world):
    original = honest_columns(51)
    hand_in(world, "s1", original, honest_columns(52, 9.8))
    teacher1 = browser(world, "teacher1")
    exported = teacher1.get(
        f"/courses/{world['course']}/assignments/{world['assignment']}/export.zip"
    ).content
    _, assignment_id = other_teachers_class(world)
    teacher2 = browser(world, "teacher2")
    assert "Nothing uploaded yet" in shown(teacher2)
    assert upload(teacher2, "lab 2025.zip", exported).status_code == 303
    page = shown(teacher2)
    assert "lab 2025.zip: the readings of 1 attempt are kept" in page
    assert "lab 2025.zip" in page.split('id="archives"')[1]
    s4 = browser(world, "s4")
    session_id = new_session(s4, assignment_id=str(assignment_id))
    assert save_manual(s4, session_id, "heading", shifted(original, 0.7)).status_code == 200
    submit(s4, session_id)

    rows = teacher2.get(
        f"{API}/assignments/{assignment_id}/submissions", headers=token_for(teacher2, "teacher2")
    ).json()
    assert earlier(rows[0]["evidence"]) == [
        {"group": "s1", "attempts": [1], "archive": "lab 2025.zip"}
    ]
    desk = html.unescape(teacher2.get(f"/review/sessions/{session_id}").text)
    assert "s1, attempt 1 in the uploaded readings “lab 2025.zip”" in desk
    # teacher1's own class is never matched against teacher2's upload
    assert earlier(evidence_of(teacher1, world)["s1"]) == []

    with read_session() as db:
        archive_id = db.exec(select(ReadingArchive.id)).one()
    page = "/review/archives"
    assert post_form(teacher1, f"{page}/{archive_id}/delete", page=page).status_code == 404
    assert post_form(teacher2, f"{page}/{archive_id}/delete", page=page).status_code == 303
    with read_session() as db:
        assert db.exec(select(CopyKey).where(CopyKey.archive_id.is_not(None))).all() == []
    rows = teacher2.get(
        f"{API}/assignments/{assignment_id}/submissions", headers=token_for(teacher2, "teacher2")
    ).json()
    assert earlier(rows[0]["evidence"]) == []


def test_one_readings_csv_is_an_archive_too(world):
    student, session_id = hand_in(world, "s1", honest_columns(61), honest_columns(62, 9.8))
    readings = student.get(f"/lab/sessions/{session_id}/export.csv").content
    other_teachers_class(world)
    teacher2 = browser(world, "teacher2")
    assert upload(teacher2, "group7.csv", readings).status_code == 303
    assert "group7.csv: the readings of 1 attempt are kept" in shown(teacher2)
    with read_session() as db:
        labels = {
            (k.label, k.attempt, k.part) for k in db.exec(select(CopyKey)).all() if k.archive_id
        }
    assert labels == {("group7", None, "heading"), ("group7", None, "latitude")}


def teacher1_export(world) -> bytes:
    """teacher1's class zip of the assignment, as the dashboard exports it."""
    teacher1 = browser(world, "teacher1")
    return teacher1.get(
        f"/courses/{world['course']}/assignments/{world['assignment']}/export.zip"
    ).content


def test_bad_uploads_are_refused_and_nothing_is_kept(world, monkeypatch):
    import io
    import zipfile

    from app.review import archives

    monkeypatch.setattr(archives, "MAX_UNPACKED", 2**20)  # 1 MB: a small zip bomb will do
    other_teachers_class(world)
    teacher2 = browser(world, "teacher2")
    bomb = io.BytesIO()
    with zipfile.ZipFile(bomb, "w", zipfile.ZIP_DEFLATED) as archive:
        archive.writestr("a/attempt-1.csv", b"part,position,value\n" + b"0" * (3 * 2**20))
    cases = [
        ("empty.csv", b"", "Choose a file to upload."),
        ("broken.zip", b"PK\x03\x04 not really", "This is not a zip file that can be read."),
        ("latin.csv", "part,position,value\nheading,1,1\n\xe9".encode("latin-1"), "is not UTF-8"),
        ("nothing.csv", b"a,b,c\n1,2,3\n", "No readings recorded by students"),
        ("bomb.zip", bomb.getvalue(), "The readings unpack to more than 1 MB."),
        (
            "sim.csv",
            b"part,position,source,value\n"
            + b"".join(
                f"heading,{k},simulator,{v}\n".encode() for k in (1, 2, 3, 4) for v in range(12)
            ),
            "No readings recorded by students",
        ),
    ]
    # what the zip module cannot open or read: was a 500 (NotImplementedError, RuntimeError)
    student, session_id = hand_in(world, "s1", honest_columns(73), honest_columns(74, 9.8))
    exported = teacher1_export(world)
    cases += [
        ("new.zip", zip_patched(exported, version=85), "This is not a zip file that can be read."),
        ("locked.zip", zip_patched(exported, encrypted=True), "protected by a password"),
        ("7z.zip", zip_patched(exported, method=9), "such as Deflate64"),
    ]
    for name, content, message in cases:
        refused = upload(teacher2, name, content)
        assert refused.status_code == 400, name
        assert 'id="error-readings"' in refused.text, name  # beside the file field
        assert message in html.unescape(refused.text), name
    hostile = "<script>alert(1)</script>=cmd|x.csv"
    readings = student.get(f"/lab/sessions/{session_id}/export.csv").content
    assert upload(teacher2, hostile, readings).status_code == 303
    raw = teacher2.get("/review/archives").text
    assert "<script>alert(1)" not in raw and "&lt;script&gt;" in raw
    with read_session() as db:
        assert len(db.exec(select(ReadingArchive)).all()) == 1
    zh = teacher2.get("/review/archives", headers={"Accept-Language": "zh-CN"}).text
    assert "往届读数" in zh and "上传读数" in zh


def test_earlier_readings_through_the_api(world):
    """The same upload as the page's, by a script with a teacher's token: listed, matched,
    refused with JSON in both languages, and deleted only by its owner."""
    original = honest_columns(81)
    student, session_id = hand_in(world, "s1", original, honest_columns(82, 9.8))
    readings = student.get(f"/lab/sessions/{session_id}/export.csv").content
    _, assignment_id = other_teachers_class(world)
    teacher2 = browser(world, "teacher2")
    auth = token_for(teacher2, "teacher2")
    assert teacher2.get(f"{API}/archives", headers=auth).json() == []

    made = teacher2.post(
        f"{API}/archives", files={"readings": ("2025 group 3.csv", readings)}, headers=auth
    )
    assert made.status_code == 201, made.text
    kept = made.json()
    assert (kept["name"], kept["groups"]) == ("2025 group 3.csv", 1)
    assert [a["id"] for a in teacher2.get(f"{API}/archives", headers=auth).json()] == [kept["id"]]
    s4 = browser(world, "s4")
    copied = new_session(s4, assignment_id=str(assignment_id))
    assert save_manual(s4, copied, "heading", shifted(original, -0.4)).status_code == 200
    submit(s4, copied)
    rows = teacher2.get(f"{API}/assignments/{assignment_id}/submissions", headers=auth).json()
    assert earlier(rows[0]["evidence"]) == [
        {"group": "2025 group 3", "attempts": [], "archive": "2025 group 3.csv"}
    ]

    for files, message_en, message_zh in (
        (None, "Choose a file to upload.", "请选择"),
        ({"readings": ("x.csv", b"a,b\n1,2\n")}, "No readings recorded by students", "没有"),
    ):
        for language, message in (("en", message_en), ("zh-CN", message_zh)):
            refused = teacher2.post(
                f"{API}/archives", files=files, headers={**auth, "Accept-Language": language}
            )
            assert refused.status_code == 400, refused.text
            assert message in refused.json()["detail"]
    assert len(teacher2.get(f"{API}/archives", headers=auth).json()) == 1

    teacher1 = browser(world, "teacher1")
    other = token_for(teacher1, "teacher1")
    assert teacher1.delete(f"{API}/archives/{kept['id']}", headers=other).status_code == 404
    assert teacher1.get(f"{API}/archives", headers=other).json() == []
    assert teacher2.delete(f"{API}/archives/{kept['id']}", headers=auth).status_code == 204
    assert teacher2.delete(f"{API}/archives/{kept['id']}", headers=auth).status_code == 404
    with read_session() as db:
        assert db.exec(select(CopyKey).where(CopyKey.archive_id.is_not(None))).all() == []
    # a cookie caller needs the CSRF header for the change, as on every API route
    assert (
        teacher2.post(f"{API}/archives", files={"readings": ("y.csv", readings)}).status_code == 403
    )
