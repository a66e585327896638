"""bench/replay.py and ``queue_sim.simulate``'s ``arrivals``: a run's requests and positions
sent to the model's server at the times the run sent them (open loop)."""

from __future__ import annotations

import asyncio
import sys
from pathlib import Path

import httpx
import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "bench"))

import load_test  # noqa: E402  (bench/)
import queue_sim  # noqa: E402
import replay  # noqa: E402

MS = 1e-3
TURN = "POST /lab/sessions/{id}/turn"


def costs() -> dict:
    """(server, database, client, SQLite calls, thread trips, loop) for every route."""
    table = {route: (3 * MS, 0.5 * MS, 1 * MS, 6.0, 3.0, 0.5 * MS)
             for kind, route in queue_sim.student_script() if kind == "request"}  # fmt: skip
    table["GET dashboard (teacher)"] = (6 * MS, 1 * MS, 1 * MS, 20.0, 3.0, 1 * MS)
    table[queue_sim.STREAM] = (0.3 * MS, 0.05 * MS, 0.1 * MS, 1.0, 0.0, 0.1 * MS)
    return table


def arrivals_from(result: dict, paced: bool = False) -> list[tuple]:
    """A closed-loop simulation's students as a trace: each request at the time it was
    sent, each position at the time it was asked for, on the student's connection;
    ``paced``: with the student as its browser and the time from the student's step before
    it ended (answered, saved) as its think."""
    trace = []
    for student, record in enumerate(result["students"]):
        steps = [(sent, sent + latency, "request", route)
                 for route, sent, latency in record["requests"]]  # fmt: skip
        steps += [(asked, saved, "stream", queue_sim.STREAM)
                  for asked, _, _, saved in record["positions"]]  # fmt: skip
        ended = None
        for sent, end, kind, route in sorted(steps):
            if paced:
                think = 0.0 if ended is None else sent - ended
                trace.append((sent, kind, route, student, student, think))
            else:
                trace.append((sent, kind, route, student))
            ended = end
    return sorted(trace, key=lambda arrival: arrival[0])


def test_a_run_is_read_as_arrivals_in_the_order_sent_each_sessions_on_its_connection(tmp_path):
    """Requests by their route's name (the teacher's page by its role), positions as the
    stream's; times counted from the first arrival; a session's requests share one
    connection and its positions another; a request of no session has none; lines cut
    short are left out."""
    client = tmp_path / "client.txt"
    client.write_text(
        "GET /login 10.000000 10.002000\n"
        "POST /lab/sessions/7/turn 13.500000 13.512000\n"
        "GET /courses/1/assignments/1 12.000000 12.030000\n"
        "GET /lab/sessions/7 11.000000 11.010000\n"
        "POST /lab/sess\n"
    )
    streams = tmp_path / "stream.txt"
    streams.write_text(
        "7 heading 1 11.020 11.03 11.23 14.03 14.035\n8 heading 1 11.050 11.06 11.26\n"
    )
    assert replay.arrivals_of(client, streams) == [
        (0.0, "request", "GET /login", None, None, 0.0),
        (pytest.approx(1.0), "request", "GET /lab/sessions/{id}", ("http", 7), None, 0.0),
        (pytest.approx(1.02), "stream", queue_sim.STREAM, ("websocket", 7), None, 0.0),
        (pytest.approx(2.0), "request", "GET dashboard (teacher)", None, None, 0.0),
        (pytest.approx(3.5), "request", TURN, ("http", 7), None, 0.0),
    ]
    with pytest.raises(ValueError, match="names no browser"):
        replay.arrivals_of(client, streams, paced=True)


def test_paced_each_browsers_steps_have_the_think_after_the_step_before(tmp_path):
    """The client times' fifth field names the browser; a position's browser is its
    session's; each step's think runs from the browser's step before it ended (answered,
    or a position saved) to its own sending; the teacher is a browser of its own."""
    client = tmp_path / "client.txt"
    client.write_text(
        "GET /login 10.000000 10.002000 0\n"
        "POST /login 10.005000 10.030000 0\n"
        "GET /login 10.001000 10.003000 teacher\n"
        "GET /lab/sessions/7 11.000000 11.010000 0\n"
        "POST /lab/sessions/7/turn 14.040000 14.052000 0\n"
    )
    streams = tmp_path / "stream.txt"
    streams.write_text(
        "7 heading 1 11.020 11.03 11.23 14.03 14.035\n"
        "9 heading 1 11.020 11.03 11.23 14.03 14.035\n"  # a session no request names
    )
    http, ws = ("http", "0"), ("websocket", 7)
    assert replay.arrivals_of(client, streams, paced=True) == [
        (0.0, "request", "GET /login", http, "0", 0.0),
        (pytest.approx(0.001), "request", "GET /login", ("http", "teacher"), "teacher", 0.0),
        (pytest.approx(0.005), "request", "POST /login", http, "0", pytest.approx(0.003)),
        (pytest.approx(1.0), "request", "GET /lab/sessions/{id}", http, "0", pytest.approx(0.97)),
        (pytest.approx(1.02), "stream", queue_sim.STREAM, ws, "0", pytest.approx(0.01)),
        (pytest.approx(4.04), "request", TURN, http, "0", pytest.approx(0.005)),
    ]


def test_a_replayed_request_is_sent_at_its_time_whatever_the_answer_before_it():
    """Open loop: two requests of one connection 1 ms apart, each 4.5 ms of work alone -- the
    second is sent 1 ms after the first, not when the first is answered, and the two share
    the server instead."""

    def replayed(arrivals):
        return queue_sim.simulate(costs(), 0, 1, 2.0, wake_free=False, arrivals=arrivals)

    (alone,) = replayed([(0.0, "request", TURN, "a")])["latencies"][TURN]
    assert alone == pytest.approx(4.5 * MS, abs=1e-5)  # client, server, database: its work
    result = replayed([(0.0, "request", TURN, "a"), (0.001, "request", TURN, "a")])
    sent = sorted(sent for record in result["students"] for _, sent, _ in record["requests"])
    assert sent == pytest.approx([0.0, 0.001])
    assert all(latency > alone + 1e-4 for latency in result["latencies"][TURN])  # they met
    assert len(result["latencies"][queue_sim.SAVED]) == 0  # no position asked for


def test_paced_a_step_waits_for_the_model_to_answer_the_one_before_and_its_think():
    """A browser's two requests sent 1 ms apart in the run, the second 0.5 ms after the
    first was answered there: paced, the second waits for the model's answer to the first
    (4.5 ms of work) and the think, not sent at 1 ms; a step whose time comes after that is
    sent at its time."""
    steps = [
        (0.0, "request", TURN, "a", "b", 0.0),
        (0.001, "request", TURN, "a", "b", 0.0005),
        (0.050, "request", TURN, "a", "b", 0.0005),
    ]
    result = queue_sim.simulate(costs(), 0, 1, 2.0, wake_free=False, arrivals=steps)
    (record,) = result["students"]
    sent = [sent for _, sent, _ in record["requests"]]
    assert sent == pytest.approx([0.0, 0.0045 + 0.0005, 0.050], abs=1e-5)
    assert result["latencies"][TURN] == pytest.approx([4.5 * MS] * 3, abs=1e-5)


def test_a_class_replayed_from_its_own_times_has_the_latencies_it_had():
    """A closed-loop class's requests and positions, sent open loop at the times its
    students sent them -- or paced, each student's steps after the one before with the
    think it had -- meet the same server: every route's p95 within 5 % (the same work at
    the same times; only the random draws of who hands the interpreter on differ)."""
    closed = queue_sim.simulate(costs(), 30, 1, 2.0, teacher=False, seed=7)
    trace = arrivals_from(closed)
    assert len(trace) == sum(
        len(record["requests"]) + len(record["positions"]) for record in closed["students"]
    )
    for replayed in (trace, arrivals_from(closed, paced=True)):
        opened = queue_sim.simulate(costs(), 0, 1, 2.0, seed=7, arrivals=replayed)
        assert set(opened["latencies"]) == set(closed["latencies"])
        for route, latencies in closed["latencies"].items():
            assert len(opened["latencies"][route]) == len(latencies), route
            assert np.percentile(opened["latencies"][route], 95) == pytest.approx(
                np.percentile(latencies, 95), rel=0.05
            ), route


def test_the_load_generator_names_each_requests_browser(monkeypatch, tmp_path):
    """``GYROLAB_BENCH_CLIENT_TIMES``' fifth field is the browser whose task sent the
    request (each student's task sets its own; the teacher's is ``teacher``), and replay.py
    reads a browser's steps from it."""
    monkeypatch.setattr(load_test, "CLIENT_TIMES", str(tmp_path / "client.txt"))
    tally = load_test.Tally()
    transport = httpx.MockTransport(lambda request: httpx.Response(200))

    async def browse(name: str, path: str) -> None:
        load_test.BROWSER.set(name)
        async with httpx.AsyncClient(transport=transport, base_url="http://lab") as client:
            await tally.request(client, "GET", path, "GET")
            await tally.request(client, "GET", path, "GET")

    async def class_of_two() -> None:
        await asyncio.gather(
            browse("3", "/lab/sessions/5"), browse("teacher", "/courses/1/assignments/1")
        )

    asyncio.run(class_of_two())
    lines = [line.split() for line in tally.sent]
    assert sorted((fields[1], fields[4]) for fields in lines) == [
        ("/courses/1/assignments/1", "teacher"),
        ("/courses/1/assignments/1", "teacher"),
        ("/lab/sessions/5", "3"),
        ("/lab/sessions/5", "3"),
    ]
    client = tmp_path / "client.txt"
    client.write_text("".join(tally.sent))
    streams = tmp_path / "stream.txt"
    streams.write_text("")
    browsers = [arrival[4] for arrival in replay.arrivals_of(client, streams, paced=True)]
    assert sorted(browsers) == ["3", "3", "teacher", "teacher"]
