"""Data evidence where the teacher works: the class table's badges, the grading desk's
sentences, the API and the class CSV -- and never on the student's pages (issue 35,
item 1)."""

from __future__ import annotations

import csv
import html
import io

import numpy as np
from sqlmodel import select

from app.db import read_session
from app.models import EvidenceNote
from tests.factories import (
    API,
    HEADING,
    VERTICAL,
    browser,
    do_lab,
    post_form,
    save_manual,
    set_assignment,
    start,
    submit,
    token_for,
)


def honest_columns(seed: int, mean: float = 11.0) -> dict[int, list[float]]:
    """12 readings a position as the teaching FOG shows them: whole 0.1 °/h steps."""
    rng = np.random.default_rng(seed)
    means = (mean, 0.3, -mean, -0.3)
    return {
        k + 1: [round(float(v), 1) for v in np.round(rng.normal(m, 0.1, 12) / 0.1) * 0.1]
        for k, m in enumerate(means)
    }


def hand_in(world, name: str, heading, vertical):
    student = browser(world, name)
    session_id = start(student, world)
    assert save_manual(student, session_id, "heading", heading).status_code == 200
    assert save_manual(student, session_id, "latitude", vertical).status_code == 200
    submit(student, session_id)
    return student, session_id


def test_the_teacher_sees_the_evidence_and_the_student_does_not(world):
    # s1 types the handout's tables; s2 copies s1 with an offset; s3 types honest readings
    s1, first = hand_in(world, "s1", HEADING, VERTICAL)
    shifted = {k: [round(v + 0.2, 2) for v in column] for k, column in HEADING.items()}
    hand_in(world, "s2", shifted, VERTICAL)
    s3, third = hand_in(world, "s3", honest_columns(1), honest_columns(2, 9.8))

    teacher = browser(world, "teacher1")
    page = teacher.get(f"/courses/{world['course']}/assignments/{world['assignment']}").text
    assert 'data-check="handout"' in page and 'data-check="copy"' in page
    assert "A: handout&#39;s data" in page or "A: handout's data" in html.unescape(page)

    auth = token_for(teacher, "teacher1")
    rows = {
        row["username"]: row
        for row in teacher.get(
            f"{API}/assignments/{world['assignment']}/submissions", headers=auth
        ).json()
    }
    checks = {
        name: {(f["part"], f["check"]) for f in row["evidence"]} for name, row in rows.items()
    }
    assert ("heading", "handout") in checks["s1"] and ("heading", "copy") in checks["s1"]
    assert ("heading", "copy") in checks["s2"] and ("heading", "handout") in checks["s2"]
    copy = next(
        f for f in rows["s2"]["evidence"] if f["check"] == "copy" and f["part"] == "heading"
    )
    assert copy["others"] == ["s1"]
    assert checks["s3"] == set()  # honest readings on the gyro's steps: nothing
    # the handout's readings sit between the simulated teaching FOG's 0.1 °/h steps
    assert ("heading", "off_grid") in checks["s1"]

    desk = html.unescape(teacher.get(f"/review/sessions/{first}").text)
    assert "Data evidence" in desk
    assert "Part A: readings match the handout's example table (A1, A2, A3, A4)" in desk
    assert "Nothing unusual" in html.unescape(teacher.get(f"/review/sessions/{third}").text)
    chinese = teacher.get(f"/review/sessions/{first}", headers={"Accept-Language": "zh-CN"})
    assert "数据证据" in chinese.text and "讲义示例表" in chinese.text

    exported = teacher.get(
        f"/courses/{world['course']}/assignments/{world['assignment']}/export.csv"
    ).content.decode("utf-8-sig")
    header, *body = list(csv.reader(io.StringIO(exported)))
    column = header.index("Data evidence")
    assert any("handout's example table" in line[column] for line in body)

    for student, session_id in ((s1, first), (s3, third)):  # students never see it
        own = html.unescape(student.get(f"/lab/sessions/{session_id}").text)
        assert "Data evidence" not in own and "handout's example table" not in own
        assert "data-check" not in own


def test_typed_parts_are_checked_from_the_sessions_current_data(world):
    from app.db import read_session
    from app.lab.results import current_data
    from app.models import Assignment, LabSession
    from app.review.evidence import session_evidence

    student = browser(world, "s1")
    session_id = start(student, world)
    do_lab(student, session_id)
    with read_session() as db:
        session = db.get(LabSession, session_id)
        assignment = db.get(Assignment, world["assignment"])
        evidence = session_evidence(assignment, session, current_data(db, session))
    assert evidence.recorded == {"heading", "latitude"}  # typed: both parts checked
    assert {f["check"] for f in evidence.findings} >= {"handout", "off_grid"}


def test_a_finding_is_marked_seen_with_a_note_and_stays(world):
    s1, first = hand_in(world, "s1", HEADING, VERTICAL)
    teacher = browser(world, "teacher1")
    page = f"/review/sessions/{first}"
    note = "Asked them: they typed the handout to try the grid. 已沟通。"
    response = post_form(
        teacher,
        f"{page}/evidence",
        {"check": "handout", "part": "heading", "note": note},
        page=page,
    )
    assert response.status_code == 303
    desk = html.unescape(teacher.get(page).text)
    assert note in desk and "Seen by Teacher One" in desk
    assert 'data-check="handout" data-part="heading" class="seen"' in desk
    dashboard = teacher.get(f"/courses/{world['course']}/assignments/{world['assignment']}").text
    assert 'class="badge evidence seen" data-check="handout"' in dashboard
    auth = token_for(teacher, "teacher1")
    rows = teacher.get(f"{API}/assignments/{world['assignment']}/submissions", headers=auth)
    (handout_finding,) = [
        f for f in rows.json()[0]["evidence"] if f["check"] == "handout" and f["part"] == "heading"
    ]
    assert handout_finding["seen"]["note"] == note  # the finding stays, marked

    # marking again replaces the note; nonsense is refused with a message, nothing stored
    post_form(
        teacher, f"{page}/evidence", {"check": "handout", "part": "heading", "note": ""}, page=page
    )
    assert note not in html.unescape(teacher.get(page).text)
    for check in ("nope", "smooth"):  # not a check; a check this session has no finding of
        bad = post_form(teacher, f"{page}/evidence", {"check": check, "part": "heading"}, page=page)
        assert bad.status_code == 303
        assert "There is no such finding" in html.unescape(teacher.get(page).text)
    with read_session() as db:
        marks = db.exec(select(EvidenceNote).where(EvidenceNote.session_id == first)).all()
        assert [(m.check, m.part) for m in marks] == [("handout", "heading")]
    long = post_form(
        teacher,
        f"{page}/evidence",
        {"check": "handout", "part": "heading", "note": "x" * 2001},
        page=page,
    )
    assert long.status_code == 303
    assert "longer than 2000 characters" in html.unescape(teacher.get(page).text)

    # a student cannot mark anything, not even on their own session
    refused = post_form(s1, f"{page}/evidence", {"check": "handout", "part": "heading"}, page="/")
    assert refused.status_code in (403, 404)


def test_readings_sent_with_times_at_another_step_are_shown_to_the_teacher(world):
    from app.core.presets import PRESETS

    set_assignment(world, allowed_methods="manual,csv,simulator,api")
    student = browser(world, "s3")
    session_id = start(student, world)
    auth = token_for(student, "s3")
    interval = 1.0 / PRESETS["teaching-fog"].sample_rate_hz
    for part, columns in (("heading", honest_columns(3)), ("latitude", honest_columns(4, 9.8))):
        for k, column in columns.items():
            times = [1000.0 * k + i * interval / 10 for i in range(len(column))]  # 10× too fast
            reply = student.put(
                f"{API}/sessions/{session_id}/{part}/positions/{k}",
                json={"samples": column, "times_s": times},
                headers=auth,
            )
            assert reply.status_code == 200, reply.text
    teacher = browser(world, "teacher1")
    desk = html.unescape(teacher.get(f"/review/sessions/{session_id}").text)
    step = f"{interval / 10:.4g}"
    assert f"Part A: the readings are {step} s apart, but this station's gyro gives one" in desk
    assert f"every {interval:.4g} s" in desk
    chinese = html.unescape(
        teacher.get(f"/review/sessions/{session_id}", headers={"Accept-Language": "zh-CN"}).text
    )
    assert f"读数间隔为 {step} 秒" in chinese
    dashboard = teacher.get(f"/courses/{world['course']}/assignments/{world['assignment']}").text
    assert 'data-check="time_step"' in dashboard
    own = html.unescape(student.get(f"/lab/sessions/{session_id}").text)
    assert "s apart" not in own and "data-check" not in own


def test_each_finding_has_its_chart_beside_the_gyros(world):
    import json
    import re

    set_assignment(world, simulator_preset="navigation-fog")  # σ ≈ 0.38 °/h, a fine grid
    rng = np.random.default_rng(5)
    means = (11.0, 0.3, -11.0, -0.3)
    # typed to 0.01 °/h, but every reading ends in 0 or 5: a preferred last digit
    heading = {
        k + 1: [round(float(v), 2) for v in np.round(rng.normal(m, 0.38, 12) / 0.05) * 0.05]
        for k, m in enumerate(means)
    }
    student, session_id = hand_in(world, "s1", heading, honest_columns(6, 9.8))
    teacher = browser(world, "teacher1")
    auth = token_for(teacher, "teacher1")
    rows = teacher.get(f"{API}/assignments/{world['assignment']}/submissions", headers=auth)
    row = rows.json()[0]
    digits = next(f for f in row["evidence"] if f["check"] == "digits")
    assert digits["part"] == "heading" and sum(digits["counts"][d] for d in (0, 5)) == 48

    page = teacher.get(f"/review/sessions/{session_id}").text
    assert 'data-figure="evidence-heading"' in page
    assert 'data-figure="evidence-digits-heading"' in page
    figures = json.loads(
        html.unescape(re.search(r'id="evidence-figures">(.*?)</script>', page, re.S).group(1))
    )
    bars = figures["evidence-digits-heading"]["data"][0]["y"]
    assert bars == digits["counts"]  # the chart shows the numbers the finding used
    beside = figures["evidence-heading"]["data"]
    group = [t for t in beside if t["xaxis"] == "x"]
    gyro = [t for t in beside if t["xaxis"] == "x2"]
    assert [len(t["y"]) for t in group] == [len(t["y"]) for t in gyro] == [12, 12, 12, 12]
    assert all(abs(sum(t["y"])) < 1e-4 for t in group)  # about each position's mean (5 d.p.)
    text = html.unescape(page)
    labels = [a["text"] for a in figures["evidence-heading"]["layout"]["annotations"]]
    assert labels == ["This group", "The station's gyro (a draw of its model)"]
    assert "readings the station's gyro makes at the same counts" in text
    zh = html.unescape(
        teacher.get(f"/review/sessions/{session_id}", headers={"Accept-Language": "zh-CN"}).text
    )
    assert "读数与实验台陀螺的对照" in zh and "各末位数字出现的次数" in zh
    again = teacher.get(f"/review/sessions/{session_id}").text  # one draw per session
    assert re.search(r'id="evidence-figures">(.*?)</script>', again, re.S).group(1) == re.search(
        r'id="evidence-figures">(.*?)</script>', page, re.S
    ).group(1)
    own = student.get(f"/lab/sessions/{session_id}").text
    assert "evidence-figures" not in own and "evidence-heading" not in own
