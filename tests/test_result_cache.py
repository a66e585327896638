"""Results solved once per change of the data: the page, the page's JSON, the REST API and
a submission share one cached result, which every change of the data replaces."""

from __future__ import annotations

import json
from types import SimpleNamespace

import pytest
from sqlmodel import select

from app.db import read_session
from app.lab import result_cache
from app.lab.result_cache import CachedResults, ResultCache, data_key
from app.models import Assignment, Attempt, LabSession
from tests.factories import (
    browser,
    build_world,
    csrf_from,
    do_lab,
    handout,
    new_session,
    post_form,
    post_json,
    save_manual,
    start,
)


@pytest.fixture
def solves(monkeypatch) -> list[int]:
    """Each time a session's results are solved from its samples (a cache miss)."""
    result_cache.CACHE.clear()
    calls: list[int] = []
    solve = result_cache.session_results

    def counted(db, session):
        calls.append(session.id)
        return solve(db, session)

    monkeypatch.setattr(result_cache, "session_results", counted)
    return calls


def heading(client, session_id) -> float:
    return client.get(f"/lab/sessions/{session_id}/results.json").json()["heading"]["theta_deg"]


def test_every_reader_shares_one_solve_until_the_data_changes(student_client, solves):
    session_id = new_session(student_client)
    save_manual(student_client, session_id, "heading", handout("handout_horizontal.csv"))
    solves.clear()
    first = heading(student_client, session_id)
    for _ in range(3):
        assert student_client.get(f"/lab/sessions/{session_id}").status_code == 200
        assert heading(student_client, session_id) == first
    assert solves == [session_id]  # one solve for three pages and four JSON reads

    columns = handout("handout_horizontal.csv")
    columns[1] = [30.0] * 3 + [value + 2.0 for value in columns[1]]  # re-record position 1
    save_manual(student_client, session_id, "heading", {1: columns[1]})
    moved = heading(student_client, session_id)
    assert moved != first and solves == [session_id, session_id]

    page = f"/lab/sessions/{session_id}"
    trim = {"part": "heading", "position": 1, "trim": 3}
    assert post_json(student_client, f"{page}/trim", trim, page).status_code == 200
    assert heading(student_client, session_id) not in (first, moved)
    assert len(solves) == 3


def test_the_page_shows_the_numbers_of_the_current_data(student_client, solves):
    session_id = new_session(student_client)
    save_manual(student_client, session_id, "heading", handout("handout_horizontal.csv"))
    student_client.get(f"/lab/sessions/{session_id}")  # cached with the first data
    save_manual(student_client, session_id, "heading", {2: [5.0] * 9 + [5.5]})
    page = student_client.get(f"/lab/sessions/{session_id}").text
    assert "5.050" in page  # position 2's new mean, not the cached one
    assert "n = 10" in page


def test_a_change_of_station_or_assignment_is_a_new_key(student_client):
    session_id = new_session(student_client)
    save_manual(student_client, session_id, "heading", handout("handout_horizontal.csv"))
    with read_session() as db:
        session = db.get(LabSession, session_id)
        before = data_key(db, session, None)
        assert data_key(db, session, None) == before  # stable
        session.latitude_deg += 0.5
        assert data_key(db, session, None) != before
        assignment = Assignment(course_id=1, title="x", latitude_deg=39.9, earth_rate_deg_h=15.04)
        with_assignment = data_key(db, session, assignment)
        assignment.gyro_characterisation = "{}"  # a characterised station: another σ
        assert data_key(db, session, assignment) != with_assignment


def test_symmetric_order_switch_is_a_new_result(student_client, solves):
    session_id = new_session(student_client)
    save_manual(student_client, session_id, "heading", handout("handout_horizontal.csv"))
    heading(student_client, session_id)
    solved = len(solves)
    page = f"/lab/sessions/{session_id}"
    post_form(student_client, f"{page}/order", {"symmetric": "on"}, page=page)
    with read_session() as db:
        assert db.get(LabSession, session_id).symmetric_order
    heading(student_client, session_id)
    heading(student_client, session_id)
    assert len(solves) == solved + 1


def test_the_cache_is_bounded():
    cache = ResultCache(max_entries=2, max_figure_bytes=100)
    for key in "abc":
        cache.put(CachedResults(key, {}))
    assert cache.get("a") is None and cache.get("b") is not None
    entry = cache.get("c")
    cache.add_figures(entry, "en", (frozenset(), "x" * 80))
    cache.add_blocks(cache.get("b"), "en", True, {"heading": "y" * 80})
    assert cache.get("c") is None  # the least recently used went over the byte bound
    assert cache.get("b") is not None


def test_a_racing_solve_keeps_one_entry():
    cache = ResultCache()
    first = cache.put(CachedResults("k", {}))
    assert cache.put(CachedResults("k", {})) is first


def test_a_submission_freezes_the_shown_result(student_client, solves):
    session_id = new_session(student_client)
    save_manual(student_client, session_id, "heading", handout("handout_horizontal.csv"))
    solves.clear()
    shown = heading(student_client, session_id)
    page = f"/lab/sessions/{session_id}"
    student_client.post(f"{page}/submit", data={"csrf_token": csrf_from(student_client, page)})
    with read_session() as db:
        attempt = db.exec(select(Attempt).where(Attempt.session_id == session_id)).one()
        assert json.loads(attempt.results_json)["heading"]["theta_deg"] == shown
    assert solves == [session_id]  # the submission and the page after it: no new solve


def _counted_reads(monkeypatch) -> list[tuple[int, str, int]]:
    """(session, part, position) of every take whose samples the dashboard reads."""
    from app.review import service

    read: list[tuple[int, str, int]] = []
    load = service.iter_takes_data

    def counted(db, takes):
        for item in load(db, takes):
            read.append((item.take.session_id, item.take.part, item.take.position))
            yield item

    monkeypatch.setattr(service, "iter_takes_data", counted)
    return read


def test_the_dashboard_reads_samples_only_of_sessions_that_changed(app, teacher, monkeypatch):
    world = build_world(app, teacher)
    sessions = {}
    for name in ("s1", "s2", "s3"):
        client = browser(world, name)
        sessions[name] = start(client, world)
        do_lab(client, sessions[name])
    read = _counted_reads(monkeypatch)
    teacher_client = browser(world, teacher.username)
    dashboard = f"/courses/{world['course']}/assignments/{world['assignment']}"
    assert teacher_client.get(dashboard).status_code == 200
    assert sorted({sid for sid, _part, _position in read}) == sorted(sessions.values())
    read.clear()
    assert teacher_client.get(dashboard).status_code == 200
    assert read == []  # nothing changed: no samples read
    s2 = browser(world, "s2")
    save_manual(s2, sessions["s2"], "heading", {1: [30.0] * 10})  # a spike-free new take
    page = teacher_client.get(dashboard).text
    # typed readings: the changed session's own takes again (its data evidence), no other's
    assert {sid for sid, _part, _position in read} == {sessions["s2"]}
    assert page.count("学生") >= 3


def _record(session_id: int, part: str, position: int, values, source: str, times=None) -> None:
    """A position recorded again, in a transaction of its own (dial angle 90° a step)."""
    from app.db import write_session
    from app.lab.store import store_take

    with write_session() as db:
        store_take(
            db,
            db.get(LabSession, session_id),
            part=part,
            position=position,
            angle_deg=90.0 * (position - 1),
            values=values,
            times=times,
            source=source,
        )


def _simulated_session(owner_id: int, assignment_id: int, seed: int) -> int:
    """A session of the assignment with both parts as the simulated gyro records them."""
    import numpy as np

    from app.db import write_session
    from app.lab.store import store_take

    rng = np.random.default_rng(seed)
    with write_session() as db:
        session = LabSession(
            owner_id=owner_id, assignment_id=assignment_id, title="t", latitude_deg=40.0
        )
        db.add(session)
        db.flush()
        for part in ("heading", "latitude"):
            for position in range(1, 5):
                store_take(
                    db,
                    session,
                    part=part,
                    position=position,
                    angle_deg=90.0 * (position - 1),
                    values=rng.normal(10.0 + position, 0.1, 30),
                    times=np.arange(30.0) + 40 * position,
                    source="simulator",
                )
        return session.id


def test_a_session_recording_position_after_position_is_read_one_take_at_a_time(
    app, teacher, monkeypatch
):
    """The dashboard keeps each take's summary: a new take of a streamed session is the
    only one read, and the summaries put together equal those made from scratch."""
    import numpy as np

    from app.lab.recent_samples import RECENT
    from app.models import User
    from app.review.service import class_rows
    from app.review.take_summaries import TAKE_SUMMARIES

    world = build_world(app, teacher)
    with read_session() as db:
        owner = db.exec(select(User).where(User.username == "s1")).one()
    session_id = _simulated_session(owner.id, world["assignment"], 1)
    RECENT.clear()
    read = _counted_reads(monkeypatch)
    teacher_client = browser(world, teacher.username)
    dashboard = f"/courses/{world['course']}/assignments/{world['assignment']}"
    assert teacher_client.get(dashboard).status_code == 200
    assert sorted(read) == [
        (session_id, p, k) for p in ("heading", "latitude") for k in (1, 2, 3, 4)
    ]
    read.clear()
    values = np.random.default_rng(2).normal(13.0, 0.1, 30)
    values[7] = 40.0  # position 3 recorded again, with a spike this time
    _record(session_id, "heading", 3, values, "simulator", times=np.arange(30.0) + 400)
    RECENT.clear()
    assert teacher_client.get(dashboard).status_code == 200
    assert read == [(session_id, "heading", 3)]

    def summary_of_the_row() -> tuple:
        with read_session() as db:
            rows = class_rows(db, db.get(Assignment, world["assignment"]))
        row = next(r for r in rows if r.session and r.session.id == session_id)
        return row.flags, row.prints, row.data_evidence

    kept = summary_of_the_row()
    assert {"key": "flag.spikes", "params": {"position": 3, "n": 1}} in kept[0]
    result_cache.SUMMARIES.clear()
    TAKE_SUMMARIES.clear()
    assert summary_of_the_row() == kept  # from scratch: the same flags, prints, evidence


def test_the_results_blocks_are_rendered_once_per_key_language_and_editable(
    student_client, solves, monkeypatch
):
    from app.lab import pages
    from app.web.i18n import translator

    rendered: list[tuple[str, bool]] = []
    add = result_cache.CACHE.add_blocks

    def counted(entry, language, editable, blocks):
        rendered.append((language, editable))
        add(entry, language, editable, blocks)

    monkeypatch.setattr(result_cache.CACHE, "add_blocks", counted)
    session_id = new_session(student_client)
    save_manual(student_client, session_id, "heading", handout("handout_horizontal.csv"))
    rendered.clear()
    page = f"/lab/sessions/{session_id}"
    english = student_client.get(page).text
    assert student_client.get(page).text.count('class="trim-form"') == 1
    assert rendered == [("en", True)]
    token = csrf_from(student_client, page)
    student_client.post("/lang", data={"lang": "zh-CN", "csrf_token": token})
    chinese = student_client.get(page).text
    assert rendered == [("en", True), ("zh-CN", True)]
    assert "<h3>结果</h3>" in chinese and "<h3>Results</h3>" in english
    assert solves.count(session_id) == 1  # once for both languages

    # The same result shown read-only (a submitted assignment, the teacher's desk): no trim.
    with read_session() as db:
        session = db.get(LabSession, session_id)
        entry = result_cache.CACHE.get(data_key(db, session, None))
    texts, _json = entry.figures["en"]
    blocks = pages._cached_blocks(entry, texts, "en", False, translator("en"))
    assert "trim-form" not in blocks["heading"] and "positions-table" in blocks["heading"]

    save_manual(student_client, session_id, "heading", {2: [5.0] * 9 + [5.5]})
    assert "5.050" in student_client.get(page).text  # a new key: rendered again
    assert rendered[-1] == ("zh-CN", True)


def test_the_figure_bytes_held_are_the_sum_over_the_entries_held():
    """The running total the byte bound uses, after any mix of additions, additions to an
    entry already dropped, racing puts and evictions, equals the sum counted afresh."""
    import random

    from app.lab.result_cache import figure_bytes

    rng = random.Random(20261125)
    cache = ResultCache(max_entries=6, max_figure_bytes=900)
    taken: list[CachedResults] = []
    for _ in range(2000):
        action = rng.random()
        if action < 0.3:
            taken.append(cache.put(CachedResults(rng.choice("abcdefghij"), {})))
        elif taken and action < 0.65:
            text = "f" * rng.randrange(0, 300)
            cache.add_figures(rng.choice(taken), rng.choice(["en", "zh-CN"]), ({}, text))
        elif taken:
            blocks = {"heading": "b" * rng.randrange(0, 300)}
            cache.add_blocks(rng.choice(taken), rng.choice(["en", "zh-CN"]), True, blocks)
        held = list(cache._entries.values())
        assert cache.held_bytes == sum(figure_bytes(e) for e in held)
        assert len(held) <= 6 and (len(held) == 1 or cache.held_bytes <= 900)


def test_a_first_view_draws_the_cached_result_without_solving_it_again(student_client, monkeypatch):
    """The page's figures draw the samples beside the fit: once the result is cached (a
    save or the JSON read solved it), the first view reads the samples and solves
    nothing; what it draws is what a fresh solve of the same data draws."""
    from app.lab import pages, results
    from app.lab.result_cache import cached_results
    from app.web.i18n import translator

    session_id = new_session(student_client)
    save_manual(student_client, session_id, "heading", handout("handout_horizontal.csv"))
    save_manual(student_client, session_id, "latitude", handout("handout_vertical.csv"))
    result_cache.CACHE.clear()
    heading(student_client, session_id)  # solved and cached, no figures yet
    solved: list[str] = []
    solve = results.solve_part
    monkeypatch.setattr(
        results,
        "solve_part",
        lambda session, part, *a: solved.append(part) or solve(session, part, *a),
    )
    page = student_client.get(f"/lab/sessions/{session_id}")
    assert page.status_code == 200
    assert solved == []
    _ = translator("en")
    with read_session() as db:
        session = db.get(LabSession, session_id)
        entry = cached_results(db, session)
        drawn = pages._figures(results.with_samples(db, session, entry.parts), _)
        fresh = pages._figures(results.session_results(db, session), _)
    assert solved == ["heading", "latitude"]  # the fresh solve only
    assert json.dumps(drawn, sort_keys=True, default=str) == json.dumps(
        fresh, sort_keys=True, default=str
    )
    assert {"heading-readings", "heading-fit", "latitude-readings"} <= set(drawn[0])


def test_the_class_wide_keys_are_each_sessions_own_key(student_client):
    """The dashboard's keys (one query for a class, read through Core) are the keys each
    session's own page and API use (the ORM): a summary kept under one is found by the
    other."""
    from app.lab.result_cache import data_keys

    recorded = new_session(student_client)
    save_manual(student_client, recorded, "heading", handout("handout_horizontal.csv"))
    save_manual(student_client, recorded, "latitude", handout("handout_vertical.csv"))
    empty = new_session(student_client)
    with read_session() as db:
        sessions = [db.get(LabSession, recorded), db.get(LabSession, empty)]
        keys = data_keys(db, sessions, None)
        assert keys == {s.id: data_key(db, s, None) for s in sessions}
        assert len(set(keys.values())) == 2


def test_the_key_of_loaded_takes_is_the_key_read_by_query(student_client):
    """A page and a submission make the key from the current takes they have loaded (no
    query of their own): the same key as the query's, for takes read back, trimmed, or
    stored a moment ago in the same transaction (the source then an ``InputMethod``)."""
    import numpy as np

    from app.db import write_session
    from app.lab.store import current_takes, store_take
    from app.models import InputMethod

    session_id = new_session(student_client)
    doubled = {k: values * 2 for k, values in handout("handout_horizontal.csv").items()}
    save_manual(student_client, session_id, "heading", doubled)
    page = f"/lab/sessions/{session_id}"
    trimmed = post_json(
        student_client, f"{page}/trim", {"part": "heading", "position": 2, "trim": 3}, page
    )
    assert trimmed.status_code == 200, trimmed.text
    with read_session() as db:
        session = db.get(LabSession, session_id)
        takes = current_takes(db, session_id)
        assert len(takes) == 4 and any(take.trim_start == 3 for take in takes)
        assert data_key(db, session, None, list(reversed(takes))) == data_key(db, session, None)
    with write_session() as db:
        session = db.get(LabSession, session_id)
        store_take(
            db,
            session,
            part="latitude",
            position=1,
            angle_deg=0.0,
            values=np.full(10, 11.0),
            times=None,
            source=InputMethod.csv,
        )
        takes = current_takes(db, session_id)
        before = data_key(db, session, None, takes)
        assert before == data_key(db, session, None)
        db.rollback()


def test_takes_changed_while_the_dashboard_reads_them_are_no_error_and_not_kept(
    app, teacher, monkeypatch
):
    """Between the dashboard's list of current takes and its read of their samples a
    student may record again (the take is superseded) or append readings (its count
    grows): both are read as they are, and the appended take's summary is not kept under
    the count it was listed with."""
    import numpy as np

    from app.db import write_session
    from app.lab.recent_samples import RECENT
    from app.lab.take_appends import append_samples
    from app.models import Take, User
    from app.review import service
    from app.review.take_summaries import TAKE_SUMMARIES, known_summary

    world = build_world(app, teacher)
    with read_session() as db:
        owner = db.exec(select(User).where(User.username == "s1")).one()
    session_id = _simulated_session(owner.id, world["assignment"], 3)
    # heading 1 from a script instead: readings can be appended
    _record(session_id, "heading", 1, np.random.default_rng(4).normal(11.0, 0.1, 30), "api")
    with read_session() as db:
        assignment = db.get(Assignment, world["assignment"])
        listed = service.current_take_rows(db, [db.get(LabSession, session_id)], assignment)
        heading_1 = db.get(Take, listed[session_id][0][0])
        stale = SimpleNamespace(**heading_1.model_dump())
    with write_session() as db:
        session = db.get(LabSession, session_id)
        append_samples(
            db,
            session,
            part="heading",
            position=1,
            angle_deg=0.0,
            values=np.full(5, 11.0),
            times=None,
        )
    heading_2 = np.random.default_rng(5).normal(12.0, 0.1, 30)
    _record(session_id, "heading", 2, heading_2, "simulator")  # recorded again
    monkeypatch.setattr(service, "current_take_rows", lambda *_args: listed)
    RECENT.clear()
    result_cache.SUMMARIES.clear()
    TAKE_SUMMARIES.clear()
    with read_session() as db:
        rows = service.class_rows(db, db.get(Assignment, world["assignment"]))
    assert any(row.session and row.session.id == session_id for row in rows)
    assert stale.n_samples == 30 and known_summary(stale) is None  # 35 were read
