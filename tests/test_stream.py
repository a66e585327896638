"""The simulated gyro's WebSocket stream: stored = streamed, truth never sent, recovery."""

from __future__ import annotations

import asyncio
import json
import re

import numpy as np
import pytest
from sqlmodel import select
from starlette.websockets import WebSocketDisconnect

from app.db import read_session, write_session
from app.lab.sim import SimulatedTake, set_gyro_clock, table_errors
from app.lab.store import load_samples
from app.models import LabSession, Role, Take
from tests.factories import login, make_user, new_session, post_form, post_json

ORIGIN = {"origin": "http://testserver"}


def connect(client, session_id):
    return client.websocket_connect(f"/lab/sessions/{session_id}/stream", headers=ORIGIN)


def record(ws, **message) -> list[dict]:
    ws.send_json({"action": "start", **message})
    frames = []
    while True:
        frame = ws.receive_json()
        frames.append(frame)
        if frame["type"] in ("saved", "error"):
            return frames


def turn(client, session_id, part, position):
    page = f"/lab/sessions/{session_id}"
    return post_json(client, f"{page}/turn", {"part": part, "position": position}, page)


def test_stored_samples_equal_streamed_ones_and_no_truth_is_sent(student_client, monkeypatch):
    from app.lab import stream

    monkeypatch.setattr(stream, "MAX_SPEED", 6000.0)  # pacing is tested on its own below
    session_id = new_session(student_client)
    with write_session() as db:  # the student let the gyro warm up for half an hour
        waited = db.get(LabSession, session_id)
        set_gyro_clock(waited, 1800.0)
        # a truth no streamed number can hold by chance (a drawn 7.234° would be inside a
        # reading of 17.2345… °/h now and then)
        waited.sim_azimuth_deg = 277.3141
        db.add(waited)
    raw = []
    with connect(student_client, session_id) as ws:
        for position in (1, 2, 3, 4):
            if position > 1:
                assert turn(student_client, session_id, "heading", position).status_code == 200
            ws.send_json(
                {
                    "action": "start",
                    "part": "heading",
                    "position": position,
                    "dwell_s": 100,
                    "settle_s": 30,
                    "speed": 6000,
                }
            )
            while True:
                text = ws.receive_text()
                raw.append(text)
                if json.loads(text)["type"] in ("saved", "error"):
                    assert json.loads(text)["type"] == "saved", text
                    break
    frames = [json.loads(text) for text in raw]
    streamed = [v for f in frames if f["type"] == "samples" for v in f["v"]]
    with read_session() as db:
        session = db.get(LabSession, session_id)
        takes = db.exec(select(Take).order_by(Take.position)).all()
        stored = [v for take in takes for v in load_samples(db, take)[0].tolist()]
        times = [load_samples(db, take)[1] for take in takes]
    assert len(takes) == 4 and all(t.source == "simulator" and t.n_samples == 10 for t in takes)
    assert stored == streamed
    # one gyro clock (s since the session switched it on): the settle time was skipped and
    # each recording starts after the one before it ended, plus its own settle time
    assert times[0][0] >= 30.0
    for before, after in zip(times, times[1:], strict=False):
        assert after[0] >= before[-1] + 10.0 + 30.0 - 1e-9  # a reading every 10 s
        assert np.all(np.diff(after) == pytest.approx(10.0))
    truth = GyroTruth(session)
    everything = "".join(raw)
    for secret in truth.values():
        assert secret not in everything
    assert max(len(f.get("v", [])) for f in frames) > 1  # batched frames
    results = student_client.get(f"/lab/sessions/{session_id}/results.json").json()
    # the gyro finds its own axis, off the dial zero by the table's misalignment
    axis = session.sim_azimuth_deg + table_errors(session)["misalign_h_deg"]
    error = (results["heading"]["azimuth_deg"] - axis + 180) % 360 - 180
    assert abs(error) < 5 * results["heading"]["azimuth_sigma_deg"] + 0.2
    # the simulated gyro's noise model is known: the σ includes its correlated noise
    assert results["heading"]["uncertainty_model"] == "allan"
    page = student_client.get(f"/lab/sessions/{session_id}").text
    assert 'data-model="allan"' in page


def GyroTruth(session) -> dict[str, str]:  # noqa: N802
    take = SimulatedTake(session, "heading", 1)
    bias = take.stream.turn_on_bias_deg_h
    return {
        "azimuth": f"{session.sim_azimuth_deg:.3f}",
        "azimuth_repr": repr(session.sim_azimuth_deg),
        "seed": str(session.sim_seed),
        "bias": f"{bias:.6f}",
        "true_rate": repr(take.true_rate),
    }


def test_recording_needs_the_table_turned_first(student_client):
    session_id = new_session(student_client, preset="tactical-fog")
    with connect(student_client, session_id) as ws:
        frames = record(ws, part="heading", position=2, dwell_s=5, speed=60)
    assert frames[-1]["type"] == "error" and "Turn the table to position 2" in frames[-1]["message"]


def test_a_log_in_ended_during_a_stream_ends_its_next_recording(student_client):
    """The socket stays open, but each recording checks the log-in again when it starts
    (with its mark, in one transaction): after a log-out nothing is marked or recorded."""
    session_id = new_session(student_client, preset="tactical-fog")
    page = f"/lab/sessions/{session_id}"
    assert turn(student_client, session_id, "heading", 1).status_code == 200
    with connect(student_client, session_id) as ws:
        assert record(ws, part="heading", position=1, dwell_s=3, speed=60)[-1]["type"] == "saved"
        assert turn(student_client, session_id, "heading", 2).status_code == 200
        assert post_form(student_client, "/logout", page=page).status_code == 303
        frames = record(ws, part="heading", position=2, dwell_s=3, speed=60)
    assert frames[-1]["type"] == "error" and frames[-1]["key"] == "stream.gone"
    assert [f["type"] for f in frames] == ["error"]  # not started: no samples sent
    with read_session() as db:
        session = db.get(LabSession, session_id)
        assert session.stream_part is None and session.stream_position is None
        positions = db.exec(
            select(Take.position).where(Take.session_id == session_id, Take.part == "heading")
        ).all()
    assert positions == [1]


@pytest.mark.one_backend  # input refused before any write
@pytest.mark.parametrize(
    ("message", "text"),
    [
        ({"part": "heading", "position": 1, "dwell_s": True}, "must be a number"),
        ({"part": "heading", "position": 1, "dwell_s": 99999}, "between"),
        ({"part": "heading", "position": 1, "speed": "fast"}, "must be a number"),
        ({"part": "nowhere", "position": 1}, "No such position"),
        ({"part": "heading", "position": 9}, "No such position"),
    ],
)
def test_bad_stream_requests(student_client, message, text):
    session_id = new_session(student_client, preset="tactical-fog")
    with connect(student_client, session_id) as ws:
        frames = record(ws, **message)
    assert frames[-1]["type"] == "error" and text in frames[-1]["message"]


@pytest.mark.one_backend  # refused before any database work
@pytest.mark.parametrize(
    ("frame", "key"),
    [
        ("hello", "stream.bad_frame"),
        (b"\x00\x01\xff", "stream.bad_frame"),  # a binary frame that is no UTF-8
        ("[1, 2]", "stream.bad_frame"),
        ('{"action": "jump"}', "stream.bad_frame"),
        ('{"action": ["start"]}', "stream.bad_frame"),
        ('{"action": "\\ud800"}', "stream.bad_frame"),  # a lone surrogate
        # these three ended the frame reader: the socket hung, open, answering nothing
        ('{"action": "start", "a": ' + "9" * 5000 + "}", "json.out_of_range"),
        ("[" * 100_000 + "]" * 100_000, "json.too_deep"),
        ('{"a": ' * 50_000 + "1" + "}" * 50_000, "json.too_deep"),
        # an OverflowError that closed the socket with 1011; an int that float() takes
        (
            '{"action": "start", "part": "heading", "position": 1, "dwell_s": 1' + "0" * 400 + "}",
            "json.out_of_range",
        ),  # fmt: skip
        (
            '{"action": "start", "part": "heading", "position": 1, "dwell_s": 1' + "0" * 299 + "}",
            "stream.out_of_range",
        ),  # fmt: skip
        ('{"action": "start", "part": "heading", "position": 1, "dwell_s": NaN}', "json.constant"),
        ('{"action": "start", "part": "heading", "position": true}', "stream.bad_position"),
    ],
)
def test_a_frame_that_is_no_request_is_answered_and_the_stream_goes_on(student_client, frame, key):
    """Whatever a frame holds, the server says what is wrong with it, in the page's
    language, and the same socket then records."""
    session_id = new_session(student_client, preset="tactical-fog")
    headers = {**ORIGIN, "accept-language": "zh-CN"}
    path = f"/lab/sessions/{session_id}/stream"
    with student_client.websocket_connect(path, headers=headers) as ws:
        ws.send_bytes(frame) if isinstance(frame, bytes) else ws.send_text(frame)
        answer = ws.receive_json()
        assert (answer["type"], answer["key"]) == ("error", key)
        assert re.search("[\u4e00-\u9fff]", answer["message"]), answer
        frames = record(ws, part="heading", position=1, dwell_s=10, speed=60)
    assert frames[-1]["type"] == "saved", frames[-1]
    with read_session() as db:
        assert db.exec(select(Take)).one().n_samples == frames[-1]["n"]


def test_a_stop_after_the_recording_is_no_error_and_json_in_a_binary_frame_is_read(
    student_client,
):
    session_id = new_session(student_client, preset="tactical-fog")
    with connect(student_client, session_id) as ws:
        ws.send_json({"action": "stop"})  # a second click on Stop, after the save
        start = {"action": "start", "part": "heading", "position": 1, "dwell_s": 10, "speed": 60}
        ws.send_bytes(json.dumps(start).encode())
        frames = []
        while not frames or frames[-1]["type"] not in ("saved", "error"):
            frames.append(ws.receive_json())
    assert frames[0]["type"] == "started" and frames[-1]["type"] == "saved", frames


def test_stop_early_keeps_what_was_recorded(student_client):
    session_id = new_session(student_client, preset="tactical-fog")
    with connect(student_client, session_id) as ws:
        ws.send_json(
            {"action": "start", "part": "latitude", "position": 1, "dwell_s": 600, "speed": 10}
        )
        seen = 0
        while seen < 12:
            frame = ws.receive_json()
            assert frame["type"] in ("started", "samples"), frame  # not wait for more forever
            seen = frame.get("done", 0)
        ws.send_json({"action": "stop"})
        while frame["type"] not in ("saved", "error"):
            frame = ws.receive_json()
        assert frame["type"] == "saved", frame
    with read_session() as db:
        take = db.exec(select(Take)).one()
    assert 12 <= take.n_samples < 600 and frame["n"] == take.n_samples


def test_stopping_before_the_minimum_saves_nothing_and_says_why(student_client):
    session_id = new_session(student_client, preset="tactical-fog")
    with connect(student_client, session_id) as ws:
        ws.send_json(
            {"action": "start", "part": "latitude", "position": 1, "dwell_s": 600, "speed": 1}
        )
        ws.receive_json()  # started
        ws.send_json({"action": "stop"})
        frame = ws.receive_json()
        while frame["type"] == "samples":
            frame = ws.receive_json()
    assert frame["type"] == "error" and "at least 10 are required" in frame["message"]
    with read_session() as db:
        assert db.exec(select(Take)).first() is None
        assert db.get(LabSession, session_id).stream_part is None


def test_a_dropped_connection_saves_nothing_and_the_page_says_so(student_client):
    session_id = new_session(student_client, preset="tactical-fog")
    with connect(student_client, session_id) as ws:
        ws.send_json(
            {"action": "start", "part": "heading", "position": 1, "dwell_s": 600, "speed": 1}
        )
        assert ws.receive_json()["type"] == "started"
    with read_session() as db:
        assert db.exec(select(Take)).first() is None
    page = student_client.get(f"/lab/sessions/{session_id}").text
    assert "was interrupted and not saved" in page
    with connect(student_client, session_id) as ws:  # recording again clears the notice
        frames = record(ws, part="heading", position=1, dwell_s=10, speed=60)
    assert frames[-1]["type"] == "saved"
    assert "was interrupted" not in student_client.get(f"/lab/sessions/{session_id}").text


def test_redo_gives_a_new_take_with_new_noise(student_client):
    session_id = new_session(student_client, preset="tactical-fog")
    with connect(student_client, session_id) as ws:
        record(ws, part="heading", position=1, dwell_s=10, speed=60)
        record(ws, part="heading", position=1, dwell_s=10, speed=60)
    with read_session() as db:
        takes = db.exec(select(Take).order_by(Take.id)).all()
        first, second = (load_samples(db, t)[0] for t in takes)
    assert takes[0].superseded_at is not None and takes[1].superseded_at is None
    assert not np.array_equal(first, second)


def test_each_turn_gets_an_indexing_error(student_client):
    session_id = new_session(student_client, preset="tactical-fog")
    for position in (2, 3, 2):
        turn(student_client, session_id, "heading", position)
    turn(student_client, session_id, "heading", 2)  # already there: not a turn
    with read_session() as db:
        assert db.get(LabSession, session_id).sim_turns == 3


def test_strangers_and_other_origins_are_refused(client, student, app):
    from fastapi.testclient import TestClient

    make_user("other", Role.student)
    with TestClient(app, follow_redirects=False) as owner:
        login(owner, "student1")
        session_id = new_session(owner, preset="tactical-fog")
        with (
            pytest.raises(WebSocketDisconnect),
            owner.websocket_connect(
                f"/lab/sessions/{session_id}/stream", headers={"origin": "http://evil.example"}
            ) as ws,
        ):
            ws.receive_json()
    login(client, "other")
    with pytest.raises(WebSocketDisconnect), connect(client, session_id) as ws:
        ws.receive_json()
    anonymous = TestClient(app)
    with pytest.raises(WebSocketDisconnect), connect(anonymous, session_id) as ws:
        ws.receive_json()


def test_client_frames_cannot_speed_up_a_recording(student_client):
    """600 samples at 10 Hz and the top speed-up (60×) take one second of the server's clock,
    however many frames the client sends meanwhile (a flood of {} once finished an 1800 s
    recording in 0.2 s)."""
    import time

    session_id = new_session(student_client, preset="tactical-fog")
    with connect(student_client, session_id) as ws:
        start = time.monotonic()
        ws.send_json(
            {"action": "start", "part": "heading", "position": 1, "dwell_s": 60, "speed": 60}
        )
        for _ in range(3000):
            ws.send_text("{}")
        while True:
            frame = ws.receive_json()
            if frame["type"] in ("saved", "error"):
                break
        elapsed = time.monotonic() - start
    assert frame["type"] == "saved" and frame["n"] == 600
    assert elapsed >= 0.9


def test_the_plane_for_part_b_is_set_on_the_table_and_validated(student_client):
    session_id = new_session(student_client, preset="tactical-fog")
    page = f"/lab/sessions/{session_id}"
    reply = post_json(student_client, f"{page}/plane", {"dial_deg": -12.34567}, page)
    assert reply.status_code == 200 and reply.json() == {"dial_deg": -12.346}
    with read_session() as db:
        stored = db.get(LabSession, session_id)
        assert stored.sim_plane_dial_deg == -12.346 and stored.sim_turns == 1
    for bad in (1e9, "north", None):
        reply = post_json(student_client, f"{page}/plane", {"dial_deg": bad}, page)
        assert reply.status_code == 422 and "detail" in reply.json()
    html = student_client.get(page).text
    assert "-12.346" in html  # the latitude panel shows where the table is set


def test_the_teaching_gyro_streams_one_reading_every_ten_seconds(student_client):
    """The handout-like preset: ten readings take 100 s of gyro time (1.7 s at 60×)."""
    session_id = new_session(student_client)
    with connect(student_client, session_id) as ws:
        frames = record(ws, part="heading", position=1, dwell_s=100, speed=60)
    assert frames[0]["rate_hz"] == 0.1 and frames[-1] == {
        "type": "saved", "part": "heading", "position": 1, "n": 10
    }  # fmt: skip
    times = [t for f in frames if f["type"] == "samples" for t in f["t"]]
    assert np.allclose(np.diff(times), 10.0)


def test_the_return_pass_streams_only_in_the_symmetric_order(student_client):
    session_id = new_session(student_client, preset="tactical-fog")
    with connect(student_client, session_id) as ws:
        frames = record(ws, part="heading", position=5, dwell_s=2, speed=60)
    assert frames[-1]["type"] == "error" and "symmetric" in frames[-1]["message"]
    page = f"/lab/sessions/{session_id}"
    assert (
        post_form(student_client, f"{page}/order", {"symmetric": "on"}, page=page).status_code
        == 303
    )
    assert turn(student_client, session_id, "heading", 5).status_code == 200
    with connect(student_client, session_id) as ws:
        frames = record(ws, part="heading", position=5, dwell_s=2, speed=60)
    assert frames[0]["dial_angle_deg"] == -270.0 and frames[-1]["type"] == "saved"


def test_a_save_that_waits_past_the_busy_timeout_says_so_and_the_stream_stays(
    student_client, monkeypatch
):
    """The write lock held past SQLite's busy timeout: an error frame (nothing saved, try
    again) instead of a crashed connection; the next recording on it works."""
    import sqlite3

    from sqlalchemy.exc import OperationalError

    from app.lab import stream

    session_id = new_session(student_client, preset="tactical-fog")
    save = stream._save
    calls = []

    def busy_once(*args):
        calls.append(1)
        if len(calls) == 1:
            raise OperationalError("BEGIN", {}, sqlite3.OperationalError("database is locked"))
        return save(*args)

    monkeypatch.setattr(stream, "_save", busy_once)
    with connect(student_client, session_id) as ws:
        frames = record(ws, part="heading", position=1, dwell_s=2, speed=60)
        assert frames[-1]["type"] == "error" and "very busy" in frames[-1]["message"]
        frames = record(ws, part="heading", position=1, dwell_s=2, speed=60)
        assert frames[-1]["type"] == "saved"


def test_the_gyros_history_is_replayed_off_the_event_loop(student_client, monkeypatch):
    """A recording late in a session replays up to 6 h of the gyro's noise before its
    first sample (≈ 60 ms at 10 Hz): never on the event loop, where it would hold up every
    other student's frames."""
    import asyncio

    from app.lab import stream

    on_loop = []

    class Watched(SimulatedTake):
        def __init__(self, *args, **kwargs):
            try:
                asyncio.get_running_loop()
                on_loop.append(True)
            except RuntimeError:
                on_loop.append(False)
            super().__init__(*args, **kwargs)

    monkeypatch.setattr(stream, "SimulatedTake", Watched)
    monkeypatch.setattr(stream, "MAX_SPEED", 6000.0)
    session_id = new_session(student_client, preset="tactical-fog")
    with connect(student_client, session_id) as ws:
        frames = record(ws, part="heading", position=1, dwell_s=20, speed=6000)
    assert frames[-1]["type"] == "saved" and on_loop == [False]


def test_a_recordings_noise_is_made_off_the_event_loop(student_client, monkeypatch):
    """The take is built in the thread pool with the recording's whole dwell: the frames
    on the event loop only hand its samples out (made frame by frame there, ≈ 1 ms a
    position held up every other student's frames)."""
    from app.core.gyro_stream import GyroStream

    reads = []
    read = GyroStream.read

    def watched(self, *args, **kwargs):
        try:
            asyncio.get_running_loop()
            reads.append("loop")
        except RuntimeError:
            reads.append("pool")
        return read(self, *args, **kwargs)

    monkeypatch.setattr(GyroStream, "read", watched)
    session_id = new_session(student_client, preset="tactical-fog")
    with connect(student_client, session_id) as ws:
        frames = record(ws, part="heading", position=1, dwell_s=30, speed=60)
    assert frames[-1] == {"type": "saved", "part": "heading", "position": 1, "n": 300}
    assert reads and set(reads) == {"pool"}, reads


class CountingInbox(asyncio.Queue):
    """A stream's inbox that counts how often the pacer waited on it."""

    waits = 0

    def get(self):
        self.waits += 1
        return super().get()


@pytest.mark.parametrize("loop", ["uvloop", "asyncio"])
def test_each_frame_is_one_wait_on_the_event_loop_and_holds_every_sample_due(loop):
    """uvicorn runs on uvloop, whose clock and timers count whole milliseconds: a frame's
    timer fires while the clock still reads up to 1 ms short.  The frame is due then, once
    (waiting again until the clock agreed spun the loop dozens of times a frame: 783 waits
    for these 12), and with every sample due by the tick's own time (0.02 s steps summed
    fall a rounding error short of k × 0.02 s more often than not)."""
    import uvloop

    from app.lab.stream import FramePacer

    frame_s, frames, per_s = 0.02, 12, 200.0  # 4 samples a frame

    async def pace():
        inbox = CountingInbox()
        pacer = FramePacer(inbox, per_s, frame_s)
        due = [await pacer.due() for _ in range(frames)]
        return inbox.waits, due

    waits, due = (uvloop.run if loop == "uvloop" else asyncio.run)(pace())
    assert waits == frames and not any(stopped for _, stopped in due)
    counts = [count for count, _ in due]
    assert all(count >= 4 * (k + 1) for k, count in enumerate(counts)), counts
    assert counts == sorted(counts)


def test_a_stop_is_due_at_once_and_other_client_frames_wait_for_the_tick():
    from app.lab.stream import FramePacer

    async def pace():
        inbox = CountingInbox()
        pacer = FramePacer(inbox, 10.0, frame_s=60.0)
        for message in ({}, {"action": "start"}, {"action": "stop"}):
            inbox.put_nowait(message)
        return await pacer.due(), inbox.waits

    (count, stopped), waits = asyncio.run(pace())
    assert stopped and count < 600 and waits == 3
