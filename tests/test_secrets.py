"""No page or response carries a secret: password hashes, token hashes, GyroLab's LTI
private key (the JWKS publishes only the public half), or (for students) the simulator's
truth before the assignment's rule reveals it."""

from __future__ import annotations

import io
import json
import time

import openpyxl
import pytest
from jwcrypto.jwk import JWK
from sqlmodel import select

from app.db import read_session, write_session
from app.lti.keys import ensure_key
from app.models import ApiToken, Assignment, AuthSession, LabSession, LtiKey, User
from tests.factories import (
    ACCESS,
    browser,
    concrete,
    do_lab,
    pdf_text,
    post_form,
    start,
    submit,
    token_for,
)


def secrets_in_database() -> dict[str, list[str]]:
    with read_session() as db:
        hashes = [u.password_hash for u in db.exec(select(User)).all()]
        hashes += [t.token_hash for t in db.exec(select(ApiToken)).all()]
        hashes += [s.token_hash for s in db.exec(select(AuthSession)).all()]
        for key in db.exec(select(LtiKey)).all():  # the private exponent, as a JWK shows it
            hashes.append(json.loads(JWK.from_pem(key.private_pem.encode()).export())["d"])
        truths = []
        for session in db.exec(select(LabSession)).all():
            truths += [str(session.sim_seed), f"{session.sim_azimuth_deg:.2f}"]
    return {"hashes": hashes, "truths": truths}


def built_class_zip(teacher, world) -> int:  # noqa: F811
    """The class's reports zip, built in the background to the end; its job id."""
    base = f"/courses/{world['course']}/assignments/{world['assignment']}"
    started = post_form(teacher, f"{base}/reports", page=base)
    progress = started.headers["location"]
    deadline = time.monotonic() + 60
    while teacher.get(progress, headers={"Accept": "application/json"}).json()["state"] == (
        "running"
    ):
        assert time.monotonic() < deadline
        time.sleep(0.2)
    return int(progress.rsplit("/", 1)[1])


def readable(name: str, data: bytes) -> str:
    """A download's text as a reader sees it: a PDF's text, every cell of a workbook (its
    XML is compressed inside the zip), anything else decoded."""
    if name.endswith(".pdf"):
        return pdf_text(data)
    if name.endswith(".xlsx"):
        book = openpyxl.load_workbook(io.BytesIO(data), read_only=True)
        return "\n".join(
            str(value)
            for sheet in book.worksheets
            for row in sheet.iter_rows(values_only=True)
            for value in row
            if value is not None
        )
    return data.decode()


@pytest.mark.slow  # every GET route, its PDFs and the class zip rendered
@pytest.mark.one_backend  # what a page shows does not depend on the database: SQLite only
def test_no_response_carries_a_secret(world):  # noqa: F811
    with write_session() as db:
        assignment = db.get(Assignment, world["assignment"])
        assignment.reveal_truth = "never"
        assignment.allowed_methods = "manual,csv,simulator"
        db.add(assignment)
    student = browser(world, "s1")
    session_id = start(student, world)
    with write_session() as db:  # a truth that cannot collide with the handout's numbers
        session = db.get(LabSession, session_id)
        session.sim_azimuth_deg = 277.3141
        db.add(session)
    do_lab(student, session_id)
    submit(student, session_id)
    teacher = browser(world, "teacher1")
    student_api = token_for(student, "s1")
    teacher_api = token_for(teacher, "teacher1")
    ensure_key()
    job_id = built_class_zip(teacher, world)
    board = f"/courses/{world['course']}/assignments/{world['assignment']}/board"
    kept = post_form(teacher, f"{board}/snapshots", page=board)
    snapshot_id = int(kept.headers["location"].rsplit("/", 1)[1])
    secrets = secrets_in_database()
    ids = {
        "course_id": world["course"],
        "assignment_id": world["assignment"],
        "session_id": session_id,
        "student_id": 1,
        "user_id": 1,
        "token_id": 1,
        "part": "heading",
        "position": 1,
        "version": "x",
        "token": "x",
        "link_id": 1,
        "platform_id": 1,
        "job_id": job_id,
        "snapshot_id": snapshot_id,
        "archive_id": 1,
    }
    checked = 0
    for route in ACCESS:
        method, path = concrete(route, ids)
        if method != "GET":
            continue
        for client, headers, is_student in (
            (student, student_api, True),
            (teacher, teacher_api, False),
        ):
            response = client.get(path, headers=headers if path.startswith("/api/") else {})
            body = response.content.decode("utf-8", errors="replace")
            if path.endswith((".pdf", ".xlsx")) and response.status_code == 200:
                body = readable(path, response.content)  # the text, not compressed streams
            if path.endswith((".zip", "/download")):
                import zipfile

                if response.status_code == 200:
                    archive = zipfile.ZipFile(io.BytesIO(response.content))
                    members = [(n, archive.read(n)) for n in archive.namelist()]
                    body = "".join(readable(n, data) for n, data in members)
            for secret in secrets["hashes"]:
                assert secret not in body, (route, "hash")
            assert "$argon2" not in body, route
            if is_student:
                for truth in secrets["truths"]:
                    assert truth not in body, (route, "truth")
            checked += 1
    assert checked >= 40
    # the truth does reach the teacher (the review page), so the check above can fail
    review = teacher.get(f"/review/sessions/{session_id}").text
    assert any(truth in review for truth in secrets["truths"]) or "True azimuth" in review
    assert json.loads(student.get(f"/lab/sessions/{session_id}/results.json").text)
