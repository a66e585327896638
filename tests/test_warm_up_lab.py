"""Issue 30 in the web lab: the session's simulated gyro says how long it has been on and
when it is warm, waiting runs its clock on, and a run recorded cold is flagged in words
with a 1σ that covers it."""

from __future__ import annotations

import pytest

from app.db import read_session
from app.lab.sim import gyro_clock_s
from app.models import LabSession
from tests.factories import new_session, post_form
from tests.test_stream import connect, turn


def clock(session_id: int) -> float:
    with read_session() as db:
        return gyro_clock_s(db.get(LabSession, session_id))


@pytest.mark.one_backend
def test_the_gyro_says_how_long_it_has_been_on_and_waiting_warms_it(student_client):
    session_id = new_session(student_client)
    page = student_client.get(f"/lab/sessions/{session_id}").text
    assert "The simulated gyro has been on for 0 min." in page
    assert "Wait 25 min (the simulated clock runs on)" in page  # teaching gyro: 5 × 5 min
    before = clock(session_id)
    reply = post_form(student_client, f"/lab/sessions/{session_id}/wait",
                      {"minutes": "25"}, page=f"/lab/sessions/{session_id}")  # fmt: skip
    assert reply.status_code == 303
    assert clock(session_id) == pytest.approx(before + 1500.0, abs=30.0)
    page = student_client.get(reply.headers["location"]).text
    assert "It is warm: its bias has settled." in page and "Wait 25 min" not in page
    for bad in ("0", "61", "x", "1e9"):
        reply = post_form(student_client, f"/lab/sessions/{session_id}/wait",
                          {"minutes": bad}, page=f"/lab/sessions/{session_id}")  # fmt: skip
        assert (
            "Wait between 1 and 60 minutes." in student_client.get(reply.headers["location"]).text
        )
    post_form(student_client, "/lang", {"lang": "zh-CN", "next": "/"})
    assert "模拟陀螺已开机" in student_client.get(f"/lab/sessions/{session_id}").text


def test_the_wait_is_csrf_protected(student_client):
    """(Who may wait on which session: tests/test_route_matrix.py, rule "owner".)"""
    session_id = new_session(student_client)
    before = clock(session_id)
    reply = student_client.post(f"/lab/sessions/{session_id}/wait", data={"minutes": "5"})
    assert reply.status_code == 403 and clock(session_id) < before + 60


def record_heading(student_client, session_id: int, dwell: float) -> None:
    """Four heading positions from the simulated gyro (callers raise the stream's speed
    limit with monkeypatch, so nothing leaks into other tests)."""
    with connect(student_client, session_id) as ws:
        for position in (1, 2, 3, 4):
            if position > 1:
                assert turn(student_client, session_id, "heading", position).status_code == 200
            ws.send_json({"action": "start", "part": "heading", "position": position,
                          "dwell_s": dwell, "speed": 6000})  # fmt: skip
            while (frame := ws.receive_json())["type"] not in ("saved", "error"):
                pass
            assert frame["type"] == "saved", frame


@pytest.mark.one_backend  # the words and the σ of a run; streamed saves on both: test_stream
def test_a_cold_run_is_flagged_in_words_and_its_sigma_holds_the_warm_up(
    student_client, monkeypatch
):
    from app.lab import stream

    monkeypatch.setattr(stream, "MAX_SPEED", 6000.0)
    session_id = new_session(student_client)
    record_heading(student_client, session_id, 100)
    results = student_client.get(f"/lab/sessions/{session_id}/results.json").json()["heading"]
    assert results["warm_up"]["flagged"] and "model" in results["warm_up"]["witnesses"]
    assert results["warm_up"]["warm_up_share"] > 0.25
    page = student_client.get(f"/lab/sessions/{session_id}").text
    assert "it is still warming up and its bias drifts through the run" in page
    # waited for the gyro and recorded again: warm, no flag, a sharper σ
    warm = new_session(student_client)
    post_form(student_client, f"/lab/sessions/{warm}/wait", {"minutes": "30"},
              page=f"/lab/sessions/{warm}")  # fmt: skip
    record_heading(student_client, warm, 100)
    again = student_client.get(f"/lab/sessions/{warm}/results.json").json()["heading"]
    # the model sees a warm gyro; the closure and trend witnesses are 3σ tests of the noise,
    # which flag ≈ 1 % of warm runs by chance (seen once in a full run: "assert not flagged"
    # failed), so only a drift they see could flag this run, never the warm-up model
    assert "model" not in again["warm_up"]["witnesses"]
    assert not again["warm_up"]["flagged"] or set(again["warm_up"]["witnesses"]) <= {
        "closure",
        "trend",
        "combined",
    }
    # the σ's warm-up part is the model's (deterministic); the scatter's part is random
    # (the two σ compared directly failed once in a full run: 0.133 vs 0.128)
    assert again["warm_up"]["warm_up_share"] < results["warm_up"]["warm_up_share"] / 2


@pytest.mark.slow
@pytest.mark.one_backend  # the words of a PDF, not the database
def test_the_pdf_report_says_the_gyro_was_warming_up(student_client, monkeypatch):
    from app.lab import stream
    from tests.factories import pdf_text

    monkeypatch.setattr(stream, "MAX_SPEED", 6000.0)
    session_id = new_session(student_client)
    record_heading(student_client, session_id, 100)
    report = student_client.get(f"/lab/sessions/{session_id}/report.pdf")
    assert report.status_code == 200
    text = " ".join(pdf_text(report.content).split())
    assert "it is still warming up and its bias drifts through the run" in text
