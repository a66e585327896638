"""Issue 31, item 2: PDF renders are bounded per process and per person; past the limit a
clear answer with Retry-After, and the slot comes back after every render.  A rendered PDF
is kept by what it shows and served again without a render until that changes."""

from __future__ import annotations

import pytest

from app.reports.pdf_cache import pdf_cache
from app.web.work_slots import pool
from tests.factories import do_lab, new_session, post_form


@pytest.mark.one_backend
def test_a_second_render_of_the_same_person_waits_its_turn(student_client, monkeypatch):
    session_id = new_session(student_client)
    url = f"/lab/sessions/{session_id}/report.pdf"
    first = student_client.get(url)
    assert first.status_code == 200 and first.content.startswith(b"%PDF")
    assert not pool("reports").people  # the slot came back
    from app.db import read_session
    from app.models import LabSession

    with read_session() as db:
        owner = db.get(LabSession, session_id).owner_id
    pdf_cache().clear()  # a report not made yet
    pool("reports").take(owner)
    try:
        busy = student_client.get(url)
        assert busy.status_code == 429 and busy.headers["retry-after"] == "5"
        assert "still being made" in busy.text
    finally:
        pool("reports").give_back(owner)
    assert student_client.get(url).status_code == 200


@pytest.mark.one_backend
def test_the_process_renders_at_most_so_many_at_once(student_client, monkeypatch):
    session_id = new_session(student_client)
    url = f"/lab/sessions/{session_id}/report.pdf"
    others = [10_001, 10_002]  # two renders of other people under way
    pdf_cache().clear()
    for other in others:
        pool("reports").take(other)
    try:
        busy = student_client.get(url, headers={"Accept": "application/json"})
        assert busy.status_code == 503 and busy.headers["retry-after"] == "10"
        assert "making other reports" in busy.json()["detail"]
    finally:
        for other in others:
            pool("reports").give_back(other)
    assert student_client.get(url).status_code == 200


@pytest.mark.one_backend
def test_a_pdf_is_rendered_once_per_content_and_language(student_client):
    session_id = new_session(student_client)
    url = f"/lab/sessions/{session_id}/report.pdf"
    cache = pdf_cache()
    first = student_client.get(url)
    assert first.status_code == 200 and (cache.hits, cache.misses) == (0, 1)
    # the same content: the same bytes, no render -- even with the person's slot taken
    from app.db import read_session
    from app.models import LabSession

    with read_session() as db:
        owner = db.get(LabSession, session_id).owner_id
    pool("reports").take(owner)
    try:
        again = student_client.get(url)
    finally:
        pool("reports").give_back(owner)
    assert again.status_code == 200 and again.content == first.content
    assert (cache.hits, cache.misses) == (1, 1)
    # another language is another PDF
    chinese = student_client.get(url, headers={"Accept-Language": "zh-CN"})
    assert chinese.status_code == 200 and chinese.content != first.content
    assert cache.misses == 2
    # a change that shows (the discussion) makes a new one
    saved = post_form(
        student_client, f"/lab/sessions/{session_id}/discussion",
        {"discussion": "The bias drifted 漂移 by 0.1 °/h."}, page=f"/lab/sessions/{session_id}",
    )  # fmt: skip
    assert saved.status_code in (200, 303)
    changed = student_client.get(url)
    assert changed.status_code == 200 and changed.content != first.content
    assert cache.misses == 3


@pytest.mark.one_backend
def test_a_cached_report_is_found_without_drawing_its_figures(student_client, monkeypatch):
    """The key stands for the figures by what they are drawn from: a render draws each
    figure once, a cached download draws none, and a change only a figure shows (a
    reading's time) is a new key."""
    from dataclasses import replace

    import app.reports.figures as figures
    from app.db import read_session
    from app.models import LabSession
    from app.reports.content import build_report
    from app.reports.pdf_cache import content_key

    session_id = new_session(student_client)
    do_lab(student_client, session_id)
    drawn = []
    original = figures._svg
    monkeypatch.setattr(figures, "_svg", lambda draw: drawn.append(1) or original(draw))
    url = f"/lab/sessions/{session_id}/report.pdf"
    assert student_client.get(url).status_code == 200
    assert len(drawn) == 4  # readings and fit of both parts, each drawn once
    assert student_client.get(url).status_code == 200
    assert len(drawn) == 4 and pdf_cache().hits == 1
    with read_session() as db:
        report = build_report(db, db.get(LabSession, session_id))
    heading = report.results["heading"]
    first = heading.positions[1]
    retimed = replace(first, times=(first.times if first.times is not None else 0) + 1.0)
    moved = replace(heading, positions={**heading.positions, 1: retimed})
    other = replace(report, results={**report.results, "heading": moved})
    assert content_key(other, "en") != content_key(report, "en")
    assert len(drawn) == 4


@pytest.mark.one_backend
def test_a_streamed_export_holds_one_slot_per_person_until_it_ends(student_client):
    session_id = new_session(student_client)
    from app.db import read_session
    from app.models import LabSession

    with read_session() as db:
        owner = db.get(LabSession, session_id).owner_id
    url = f"/lab/sessions/{session_id}/export.csv"
    exports = pool("exports")
    assert student_client.get(url).status_code == 200
    assert owner not in exports.people  # given back when the download ended
    exports.take(owner)  # a download of theirs still running
    try:
        busy = student_client.get(url)
        assert busy.status_code == 429 and "still running" in busy.text
    finally:
        exports.give_back(owner)
    # a body dropped before its first block gives its slot back too
    from app.web.work_slots import held_while_streaming

    stream = held_while_streaming("exports", owner, iter([b"x"]))
    assert owner in exports.people
    del stream
    assert owner not in exports.people
    assert student_client.get(url).status_code == 200


def test_the_figures_inputs_keep_each_run_of_numbers_apart():
    """The key's digest of the figures' inputs: readings moved from one run to the next
    (values to times, angles to means) are other inputs, not the same bytes."""
    from types import SimpleNamespace

    import numpy as np

    from app.reports.figures import figure_inputs

    def part(values, times, angles=(0.0, 90.0), means=(1.0, 2.0)):
        fit = SimpleNamespace(angles_deg=angles, means=means, position_sigmas=None, a=1, b=2, c=3)
        item = SimpleNamespace(
            values=np.array(values), times=None if times is None else np.array(times)
        )
        return SimpleNamespace(part="heading", positions={1: item}, result=SimpleNamespace(fit=fit))

    base = figure_inputs(part([1.0, 2.0], [3.0, 4.0]))
    assert base == figure_inputs(part([1.0, 2.0], [3.0, 4.0]))
    assert base != figure_inputs(part([1.0, 2.0, 3.0], [4.0]))
    assert base != figure_inputs(part([1.0, 2.0], None))
    shifted = figure_inputs(part([1.0, 2.0], [3.0, 4.0], angles=(0.0, 90.0, 1.0), means=(2.0,)))
    assert base != shifted


def test_a_slot_given_back_by_a_finalizer_inside_the_pools_lock_never_blocks():
    """A streamed export's slot is given back by its ``__del__`` wherever the collector
    runs it -- possibly in a thread inside ``take()`` with the pool's lock held."""
    import threading

    from app.web.work_slots import WorkPool

    work = WorkPool(2, "export.busy", "export.busy_person")
    work.take(1)

    def finalizer_inside_the_lock() -> None:
        with work._lock:  # as take() holds it when the collector runs a __del__
            work.give_back(1)

    thread = threading.Thread(target=finalizer_inside_the_lock, daemon=True)
    thread.start()
    thread.join(5.0)
    assert not thread.is_alive(), "give_back waited for the lock its own thread held"
    assert work.people == set()
    work.take(1)  # the slot is free again
    work.take(2)
