"""Lab reports: the PDF a student hands in and a teacher reads -- the handout's numbers,
an attempt exactly as submitted, the review once given, long records attached, the class
zip, and the discussion the student writes for it."""

from __future__ import annotations

import csv
import io
import time
import zipfile

import pytest
from pypdf import PdfReader
from sqlmodel import select

from app.db import read_session
from app.models import LabSession, ReportJob, User
from tests.factories import (
    API,
    HEADING,
    VERTICAL,
    browser,
    do_lab,
    new_api_session,
    pdf_text,
    post_form,
    review,
    save_manual,
    start,
    submit,
    token_for,
)
from tests.test_partners import allow_groups, code_of, join

pytestmark = pytest.mark.slow  # PDF rendering (WeasyPrint, matplotlib)


def report(client, session_id: int, attempt: int | None = None, language: str = "en"):
    query = f"?attempt={attempt}" if attempt is not None else ""
    response = client.get(
        f"/lab/sessions/{session_id}/report.pdf{query}", headers={"Accept-Language": language}
    )
    assert response.status_code == 200, response.text[:300]
    assert response.headers["content-type"] == "application/pdf"
    assert response.content.startswith(b"%PDF-")
    return response


def write_discussion(client, session_id: int, text: str):
    page = f"/lab/sessions/{session_id}"
    return post_form(client, f"{page}/discussion", {"discussion": text}, page=page)


def flat(text: str) -> str:
    """PDF text with line breaks and runs of spaces made single spaces."""
    return " ".join(text.split())


@pytest.mark.one_backend  # PDF rendering; the report routes run on PostgreSQL in test_secrets
def test_the_handout_report_holds_the_pages_numbers_in_both_languages(world):
    student = browser(world, "s1")
    session_id = start(student, world)
    do_lab(student, session_id)
    write_discussion(student, session_id, "The bias cancels in ω1 − ω3.\n\n误差主要来自读数噪声。")
    submit(student, session_id)
    results = student.get(f"/lab/sessions/{session_id}/results.json").json()
    azimuth = f"{results['heading']['azimuth_deg']:.2f}"
    latitude = f"{results['latitude']['latitude_deg']:.2f}"
    rate = f"{results['latitude']['earth_rate_deg_h']:.3f}"
    assert (azimuth, latitude, rate) == ("10.75", "40.73", "15.133")  # the handout's
    page = student.get(f"/lab/sessions/{session_id}").text
    assert f"{azimuth}°" in page and f"{latitude}°" in page and rate in page

    english = report(student, session_id, attempt=1)
    assert "attempt-1.pdf" in english.headers["content-disposition"]
    reader = PdfReader(io.BytesIO(english.content))
    assert len(reader.pages) >= 4
    assert reader.metadata.title.startswith("Lab report")
    text = flat(pdf_text(english.content))
    for heading in ("Apparatus and method", "Readings", "Calculation", "Results", "Figures"):
        assert heading in text
    assert "Data quality" in text and "Discussion" in text
    assert f"{azimuth}°" in text and f"{latitude}°" in text and f"{rate} °/h" in text
    assert "A1 = atan2(y, x) = 10.75°" in text  # the worked steps, as on the page
    assert "10.740" in text and "-11.870" in text  # every reading (10 per position)
    assert "Submitted attempt 1" in text and "学生1 (s1)" in text
    assert "The bias cancels in ω1 − ω3." in text and "误差主要来自读数噪声。" in text
    assert "Figure 4." in text  # readings and fit, per part
    for part in ("heading", "latitude"):  # each part's bias with its 1σ, as on the page
        bias, sigma = results[part]["bias_deg_h"], results[part]["bias_sigma_deg_h"]
        assert f"{bias:.3f} ± {sigma:.3f} °/h" in page
        assert f"{bias:.3f} °/h {sigma:.3f} °/h" in text
    # both parts assume white noise: the footnote is printed once, for both
    assert text.count("Uncertainties assume white noise") == 1

    chinese = flat(pdf_text(report(student, session_id, attempt=1, language="zh-CN").content))
    assert "实验报告" in chinese and "计算过程" in chinese and "第 1 次提交" in chinese
    assert f"{azimuth}°" in chinese and f"{latitude}°" in chinese


@pytest.mark.one_backend  # seven PDFs; the attempt's takes are the exports' (both backends)
def test_an_attempts_report_never_changes_and_the_review_appears_once_given(world):
    student = browser(world, "s1")
    teacher = browser(world, "teacher1")
    session_id = start(student, world)
    do_lab(student, session_id)
    write_discussion(student, session_id, "First thoughts.")
    submit(student, session_id)
    review(
        teacher,
        session_id,
        feedback="Check the sign of θ.",
        **{"comment-latitude-2": "Let the table settle."},
        action="return",
    )
    returned = flat(pdf_text(report(student, session_id, 1).content))
    assert "Check the sign of θ." in returned and "Let the table settle." in returned
    assert "Grade" not in returned  # no grade before release

    # the student revises: new latitude readings and a new discussion
    shifted = {k: [v + 0.5 for v in values] for k, values in VERTICAL.items()}
    assert save_manual(student, session_id, "latitude", shifted).status_code == 200
    write_discussion(student, session_id, "Second thoughts.")
    current = flat(pdf_text(report(student, session_id).content))
    assert "Second thoughts." in current and "Current data, not submitted" in current
    first = flat(pdf_text(report(student, session_id, 1).content))
    assert "First thoughts." in first and "Second thoughts." not in first
    assert "11.100" in first and "11.600" not in first  # attempt 1's own readings
    assert "11.600" in current

    submit(student, session_id)
    review(teacher, session_id, feedback="Well done.", points="88", action="release")
    second = flat(pdf_text(report(student, session_id, 2).content))
    assert "Well done." in second and "88 / 100" in second and "Second thoughts." in second
    # graded work can no longer change: its plain download is the graded attempt's report
    graded = report(student, session_id)
    assert "attempt-2.pdf" in graded.headers["content-disposition"]
    text = flat(pdf_text(graded.content))
    assert "Submitted attempt 2" in text and "Current data" not in text
    assert "Well done." in text and "88 / 100" in text


@pytest.mark.one_backend  # the layout of a long record; its queries are the ones above
def test_long_records_are_summarised_and_attached_as_csv(client, student):
    auth = token_for(client, "student1")
    session_id = new_api_session(client, auth)
    for position in range(1, 5):
        values = [HEADING[position][i % 10] for i in range(120)]
        upload = {"samples": values, "times_s": [position * 100 + i * 0.1 for i in range(120)]}
        response = client.put(
            f"{API}/sessions/{session_id}/heading/positions/{position}", json=upload, headers=auth
        )
        assert response.status_code == 200, response.text
    response = client.get(f"{API}/sessions/{session_id}/report.pdf?lang=zh-CN", headers=auth)
    assert response.status_code == 200 and response.content.startswith(b"%PDF-")
    reader = PdfReader(io.BytesIO(response.content))
    (name,) = reader.attachments
    assert name == f"gyrolab-session-{session_id}-current-readings.csv"
    rows = [r for r in csv.reader(io.StringIO(reader.attachments[name][0].decode("utf-8-sig")))]
    data = [r for r in rows if r and not r[0].startswith("#")]
    assert data[0] == ["part", "position", "angle_deg", "source", "time_s", "value"]
    assert len(data) == 1 + 4 * 120
    text = flat("\n".join(page.extract_text() for page in reader.pages))
    assert "实验报告" in text and name in text  # in Chinese, naming the attachment
    assert "全部所用读数" not in text  # no 120-row table printed


@pytest.mark.one_backend  # the layout of a long record; its queries are the ones above
def test_readings_beyond_the_attach_limit_are_not_attached_and_the_report_says_where(
    client, student, monkeypatch
):
    """A logger's million readings per position made a 29 MB PDF in 18 s: beyond
    ``ATTACH_LIMIT`` readings (here lowered to 400) none are attached, and the report says
    so and where every one is, in both languages; the readings figure is drawn from each
    bucket's lowest and highest reading, as the page's chart."""
    from app.lab.charts import MAX_POINTS
    from app.reports import content

    monkeypatch.setattr(content, "ATTACH_LIMIT", 400)
    auth = token_for(client, "student1")
    session_id = new_api_session(client, auth)
    count = 3 * MAX_POINTS
    for position in range(1, 5):
        values = [HEADING[position][i % 10] + 0.001 * (i % 7) for i in range(count)]
        upload = {"samples": values, "times_s": [position * 1e4 + i * 0.1 for i in range(count)]}
        response = client.put(
            f"{API}/sessions/{session_id}/heading/positions/{position}", json=upload, headers=auth
        )
        assert response.status_code == 200, response.text
    said = {
        "en": f"(up to {count} readings per position, {4 * count} in all): the table above "
        "summarises them. So many readings are not attached to this PDF; every one of them "
        "is in the session's CSV (“Export CSV” on its page).",
        "zh-CN": f"（每个位置最多 {count} 个读数，共 {4 * count} 个）：上表为汇总。读数太多，"
        "未附在本 PDF 中；全部读数见本次实验的 CSV（实验页面上的“导出 CSV”）。",
    }
    for language, sentence in said.items():
        response = client.get(
            f"{API}/sessions/{session_id}/report.pdf?lang={language}", headers=auth
        )
        assert response.status_code == 200 and response.content.startswith(b"%PDF-")
        reader = PdfReader(io.BytesIO(response.content))
        assert not reader.attachments
        text = flat("".join(page.extract_text() for page in reader.pages))
        assert flat(sentence).replace(" ", "") in text.replace(" ", "")
    # the figure: each position drawn through at most MAX_POINTS points, not 6000
    from app.lab.results import session_results
    from app.reports import figures

    drawn = []

    def counted(times, values, limit=MAX_POINTS):
        kept = downsample(times, values, limit)
        drawn.append((values.size, kept[1].size))
        return kept

    downsample = figures.downsample
    monkeypatch.setattr(figures, "downsample", counted)
    with read_session() as db:
        outcome = session_results(db, db.get(LabSession, session_id))["heading"]
    assert figures.readings_svg(outcome, lambda key, **_: key).startswith("<svg")
    assert len(drawn) == 4 and all(
        n == count and MAX_POINTS // 2 < kept <= MAX_POINTS for n, kept in drawn
    )


@pytest.mark.one_backend  # refused before any report is built
@pytest.mark.parametrize("query", ["?attempt=7", "?attempt=0", "?attempt=x", "?attempt=1e400"])
def test_a_missing_or_bad_attempt_is_a_clear_4xx(student_client, query):
    session_id = start_practice(student_client)
    response = student_client.get(
        f"/lab/sessions/{session_id}/report.pdf{query}", headers={"Accept": "application/json"}
    )
    assert response.status_code in (404, 422)
    assert response.json()["detail"]


def start_practice(client) -> int:
    page = post_form(client, "/lab/sessions", {"station": "handout"}, page="/lab")
    return int(page.headers["location"].rsplit("/", 1)[1])


@pytest.mark.one_backend  # PDF rendering; the class rows are the dashboard's (both backends)
def test_the_class_zip_holds_each_submitted_students_latest_report(world):
    allow_groups(world)
    for username in ("s1", "s2"):
        student = browser(world, username)
        session_id = start(student, world)
        if username == "s2":  # s3 is s2's lab partner: one report, named after both
            assert join(browser(world, "s3"), code_of(session_id)).status_code == 303
        do_lab(student, session_id)
        submit(student, session_id)
    teacher = browser(world, "teacher1")
    base = f"/courses/{world['course']}/assignments/{world['assignment']}"
    started = post_form(teacher, f"{base}/reports", page=base)
    assert started.status_code == 303
    progress = started.headers["location"]
    assert 'id="zip-job"' in teacher.get(progress).text
    again = post_form(teacher, f"{base}/reports", page=base)  # joins the build under way
    assert again.headers["location"] == progress
    deadline = time.monotonic() + 60
    while (job := teacher.get(progress, headers={"Accept": "application/json"}).json())[
        "state"
    ] == "running":
        assert time.monotonic() < deadline, job
        time.sleep(0.2)
    assert job == {"state": "done", "done": 2, "total": 2}
    page = teacher.get(progress)
    assert "Ready: 2 reports in one zip." in page.text and f"{progress}/download" in page.text
    response = teacher.get(f"{progress}/download")
    assert response.status_code == 200
    assert response.headers["content-type"] == "application/zip"
    archive = zipfile.ZipFile(io.BytesIO(response.content))
    assert sorted(archive.namelist()) == ["s1_attempt-1.pdf", "s2+s3_attempt-1.pdf"]
    shared = pdf_text(archive.read("s2+s3_attempt-1.pdf"))
    assert "学生2 (s2)" in shared and "学生3 (s3)" in shared
    # the teacher's copy of one student's report, from the review desk
    review_page = teacher.get(f"/review/sessions/{session_id}").text
    assert f"/review/sessions/{session_id}/report.pdf?attempt=1" in review_page
    copy = teacher.get(f"/review/sessions/{session_id}/report.pdf?attempt=1")
    assert copy.status_code == 200 and "学生2 (s2)" in pdf_text(copy.content)


def test_the_discussion_is_kept_cleaned_and_frozen_while_under_review(world):
    student = browser(world, "s1")
    session_id = start(student, world)
    hostile = "<script>alert(1)</script>\x00\x07 =1+1 \r\nline two"
    assert write_discussion(student, session_id, hostile).status_code == 303
    with read_session() as db:
        kept = db.get(LabSession, session_id).discussion
    assert kept == "<script>alert(1)</script> =1+1 \nline two"
    page = student.get(f"/lab/sessions/{session_id}").text
    assert "&lt;script&gt;alert(1)&lt;/script&gt;" in page and "<script>alert(1)" not in page
    text = pdf_text(report(student, session_id).content)
    assert "<script>alert(1)</script>" in text  # printed as text, nothing run or fetched

    too_long = write_discussion(student, session_id, "x" * 20_001)
    assert too_long.status_code == 303
    page = student.get(f"/lab/sessions/{session_id}").text
    assert "longer than 20000 characters" in page
    with read_session() as db:
        assert db.get(LabSession, session_id).discussion.startswith("<script>")

    do_lab(student, session_id)
    submit(student, session_id)
    write_discussion(student, session_id, "changed after submitting")
    page = student.get(f"/lab/sessions/{session_id}").text
    assert "waiting for your teacher" in page
    with read_session() as db:
        assert "changed" not in db.get(LabSession, session_id).discussion


@pytest.mark.one_backend
def test_a_zip_build_needs_its_teachers_render_slot(world):
    from app.web.work_slots import pool

    teacher = browser(world, "teacher1")
    base = f"/courses/{world['course']}/assignments/{world['assignment']}"
    with read_session() as db:
        teacher_id = db.exec(select(User.id).where(User.username == "teacher1")).one()
    pool("reports").take(teacher_id)  # a report of theirs is being made
    try:
        refused = post_form(teacher, f"{base}/reports", page=base)
    finally:
        pool("reports").give_back(teacher_id)
    assert refused.status_code == 429 and "still being made" in refused.text
    with read_session() as db:
        assert db.exec(select(ReportJob)).first() is None  # nothing half-started
    missing = teacher.get(f"{base}/reports/999999")
    assert missing.status_code == 404 and "does not exist" in missing.text
