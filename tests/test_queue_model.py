"""The load test's queueing model (bench/queue_model.py, queue_sim.py, class_cpu.py): its
simulation against cases whose answer is known without it, and the class's CPU read."""

from __future__ import annotations

import os
import sys
import time
from collections import Counter
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "bench"))

import class_cpu  # noqa: E402  (bench/)
import queue_model  # noqa: E402
import queue_sim  # noqa: E402
import request_waits  # noqa: E402

from tests.probed_apps import PROBE, run_probed  # noqa: E402

MS = 1e-3


def costs(server=4 * MS, db=1 * MS, client=2 * MS, calls=10.0, trips=4.0, loop=1 * MS):
    """The same (server, database, client, SQLite calls, thread trips, loop) for every
    route; stream frames cost a tenth."""
    routes = {route for kind, route in queue_sim.student_script() if kind == "request"}
    table = {route: (server, db, client, calls, trips, loop) for route in routes}
    table["GET dashboard (teacher)"] = (server, db, client, calls, trips, loop)
    table[queue_sim.STREAM] = (server / 10, db / 10, client / 10, 1.0, 0.0, loop / 10)
    return table


def test_a_student_alone_waits_for_nothing_but_the_work_of_each_request():
    """Woken threads reaching a core at once (``wake_free=False``): each request's latency
    is its work."""
    result = queue_sim.simulate(
        costs(), 1, 1, 2.0, ramp=0.0, hash_s=2 * MS, teacher=False, wake_free=False
    )
    expected = Counter(route for kind, route in queue_sim.student_script() if kind == "request")
    saved = result["latencies"].pop(queue_sim.SAVED)
    assert {route: len(v) for route, v in result["latencies"].items()} == expected
    for route, latencies in result["latencies"].items():
        # client + server (its event loop's part included) + database, nothing waited
        assert latencies == pytest.approx([7 * MS] * len(latencies), abs=1e-5), route
    # each position's save: half of what its 15 frames cost in threads and the database
    # (a frame: 0.4 ms of server CPU, 0.1 of it the loop's, and 0.1 ms the database's)
    assert saved == pytest.approx([7.5 * (0.3 + 0.1) * MS] * 8, abs=1e-5)


def test_every_request_of_a_class_is_answered_and_the_cores_are_never_overdrawn():
    students, cores = 40, 2.0
    result = queue_sim.simulate(costs(), students, workers=1, cores=cores, teacher=False)
    expected = Counter(route for kind, route in queue_sim.student_script() if kind == "request")
    assert len(result["latencies"].pop(queue_sim.SAVED)) == 8 * students  # every position
    counts = {route: len(v) for route, v in result["latencies"].items()}
    assert counts == {route: n * students for route, n in expected.items()}
    cpu = sum(result["cpu"].values())
    assert result["wall"] >= cpu / cores


def test_many_short_calls_wait_a_turn_of_the_busy_threads_at_each_call():
    """CPython's GIL: a thread that gives the interpreter up at each database call queues
    again behind threads that hold it for their whole interval.  Writes of 60 short calls
    among reads that never give it up: evenly shared (processor sharing), the writes wait
    far less and the reads more -- the convoy the switch interval makes.  (Every call
    handing the interpreter on: ``call_handoff=None``; the app's short calls mostly do not,
    the next test.)"""
    mixed = costs(server=8 * MS, calls=0.0, trips=0.0)
    for route in mixed:
        if route.startswith("POST"):
            mixed[route] = (3 * MS, 1 * MS, 2 * MS, 60.0, 4.0, 1 * MS)
    # every request inside at once (no work places): the interpreter alone decides
    shared = queue_sim.simulate(
        mixed, 40, 1, 2.0, teacher=False, switch_interval_s=0.0, work_places=0
    )
    turns = queue_sim.simulate(mixed, 40, 1, 2.0, teacher=False, work_places=0, call_handoff=None)

    def p95(result: dict, route: str) -> float:
        return float(np.percentile(result["latencies"][route], 95))

    write, read = "POST /lab/sessions/{id}/csv", "GET /lab/sessions/{id}/results.json"
    assert p95(turns, write) > 2 * p95(shared, write)
    assert p95(turns, read) < p95(shared, read)


def test_a_call_that_ends_before_the_waiter_runs_keeps_the_interpreter():
    """bench_handoffs.py: a thread woken at an SQLite call takes the interpreter only if it
    reaches a core before the call is over.  The writes' 60 short calls: when none hands it
    on, the writes wait no turns at their calls; with the measured chances a few; when
    every call does, a turn at each.  A call kept still woke the waiter for nothing.  (The
    event loop's releases, which take the same chance by default, queue as before here:
    the calls' effect alone.)"""
    mixed = costs(server=8 * MS, calls=0.0, trips=0.0)
    for route in mixed:
        if route.startswith("POST"):
            mixed[route] = (3 * MS, 1 * MS, 2 * MS, 60.0, 4.0, 1 * MS)

    def run(call_handoff):  # 20 students on one core: as crowded as 40 on two, half the work
        return queue_sim.simulate(
            mixed, 20, 1, 1.0, teacher=False, work_places=0, call_handoff=call_handoff,
            loop_keeps=False,
        )  # fmt: skip

    def p95(result: dict) -> float:
        return float(np.percentile(result["latencies"]["POST /lab/sessions/{id}/csv"], 95))

    never, measured, every = run((0.0, 0.0)), run(queue_sim.CALL_HANDOFF), run(None)
    assert p95(never) < p95(measured) < p95(every)
    assert p95(every) > 1.5 * p95(never)
    # kept calls are wake-ups too: the waiter woken and asleep again
    assert never["wake-ups"]["server"] > 0
    assert never["run queue"]["server"][1] >= never["wake-ups"]["server"] * queue_sim.HANDOFF_S


def test_the_event_loop_can_keep_the_interpreter_between_its_callbacks_as_a_call_does():
    """uvloop runs each callback in C holding no interpreter and takes it back for the
    next: the release is a call's, handed to a waiting thread only if that thread reaches a
    core first (``loop_keeps``, the default since 2026-12-05: with it the model's requests
    wait off a core about as long as the probe measured).  Requests whose loop work wakes
    many times among threads that hold the interpreter: kept, their loop work waits no
    turns; handed on every time, the model is the one without the option, request for
    request.  (Each request's work in one thread, ``trips_in_turn=False``: its twenty
    trips are the loop's many wake-ups here, not twenty pool threads.)"""
    busy = costs(server=8 * MS, calls=0.0, trips=20.0, loop=3 * MS)

    def run(loop_keeps: bool, call_handoff):
        # the interpreter under test, not the cores: shared evenly, in half the time
        return queue_sim.simulate(
            busy, 40, 1, 2.0, teacher=False, work_places=0, loop_keeps=loop_keeps,
            call_handoff=call_handoff, trips_in_turn=False, per_core=False,
        )  # fmt: skip

    def mean(result: dict) -> float:
        return float(np.mean(result["latencies"]["GET /lab/sessions/{id}/results.json"]))

    queued, kept = run(False, (0.0, 0.0)), run(True, (0.0, 0.0))
    assert mean(kept) < 0.8 * mean(queued)
    assert run(True, None)["latencies"] == run(False, None)["latencies"]
    # kept releases still wake a waiter for nothing
    assert kept["wake-ups"]["server"] > queued["wake-ups"]["server"]


def test_a_request_waits_for_a_work_place():
    """Two students arrive together at a worker with one place: the second's first request
    waits the first's whole stay (its threads' and database work), then takes as long."""
    table = costs(server=20 * MS, db=0.0, client=0.0, calls=0.0, trips=0.0, loop=0.0)
    for places, expected in ((1, [20 * MS, 40 * MS]), (0, [40 * MS, 40 * MS])):
        result = queue_sim.simulate(
            table, 2, 1, 2.0, ramp=0.0, teacher=False, switch_interval_s=0.0,
            work_places=places,
        )  # fmt: skip
        first = sorted(result["latencies"]["GET /login"])
        # one place: one after the other; unlimited: both share the one interpreter
        assert first == pytest.approx(expected, abs=1e-4), places


def test_a_threads_cpu_without_the_interpreter_runs_beside_the_others():
    """``released_share``: two requests of 20 ms of thread CPU at once on two cores. All
    of it holding the interpreter, they share it: 40 ms each. Half of it released (SQLite's
    own work, system calls), the held halves share the interpreter for 20 ms and the
    released halves then run side by side on the two cores: 30 ms each."""
    table = costs(server=20 * MS, db=0.0, client=0.0, calls=0.0, trips=0.0, loop=0.0)
    for released, expected in ((0.0, 40 * MS), (0.5, 30 * MS)):
        result = queue_sim.simulate(
            table, 2, 1, 2.0, ramp=0.0, teacher=False, switch_interval_s=0.0,
            work_places=0, released_share=released,
        )  # fmt: skip
        assert result["latencies"]["GET /login"] == pytest.approx([expected] * 2, abs=1e-4)
        assert result["cpu"]["server"] == pytest.approx(64 * 20 * MS)  # the same CPU asked


PROBED_ROUTES = """
@app.get("/on-the-loop/{n}")
async def on_the_loop(n: int):
    burn(0.03)
    await asyncio.sleep(0.01)  # waiting costs nothing
    burn(0.01)
    return {}

@app.get("/in-a-thread/{n}")
def in_a_thread(n: int):
    burn(0.03)
    return {}
"""
PROBED_CALLS = [
    'client.get("/on-the-loop/0")',  # first calls: the framework's own set-up
    'client.get("/in-a-thread/0")',
    'asyncio.gather(client.get("/on-the-loop/1"), client.get("/in-a-thread/2"))',
]


def test_the_probe_gives_each_request_the_cpu_of_its_own_task(tmp_path):
    """``GYROLAB_BENCH_REQUEST_CPU``: CPU its coroutine spent on the event loop and its
    functions in the thread pool, by the thread's CPU clock (work that burns a known amount
    of CPU; waiting counts nothing), requests running at once kept apart."""

    out = tmp_path / "cpu.txt"
    run_probed(PROBED_ROUTES, PROBED_CALLS, {"GYROLAB_BENCH_REQUEST_CPU": str(out)})
    rows = {}
    for line in out.read_text().splitlines():
        kind, method, path, loop_ms, threads_ms, frames = line.split()
        rows[path] = (kind, method, float(loop_ms), float(threads_ms), int(frames))
    loop_kind, _, loop_ms, loop_threads, _ = rows["/on-the-loop/1"]
    assert loop_kind == "http" and 40 <= loop_ms < 60 and loop_threads == 0
    _, _, thread_loop, threads_ms, _ = rows["/in-a-thread/2"]
    assert 30 <= threads_ms < 45 and thread_loop < 10
    means = class_cpu.attributed_costs(out.read_text())
    assert 0.040 <= means.means["GET /on-the-loop/{id}"][0] < 0.060  # both calls of the route
    assert means.means["GET /on-the-loop/{id}"][1] == 0


PROBED_STREAM = """
from fastapi import WebSocket
from starlette.concurrency import run_in_threadpool
from starlette.testclient import TestClient

def _mark_started():
    burn(0.01)

def SimulatedTake():  # the stream's functions by their names in app.lab.stream
    burn(0.02)

def _save():
    burn(0.03)

@app.websocket("/lab/sessions/{n}/stream")
async def stream(websocket: WebSocket, n: int):
    await websocket.accept()
    await run_in_threadpool(_mark_started)
    await run_in_threadpool(SimulatedTake)
    await websocket.send_text('{"type":"samples","v":[]}')
    await run_in_threadpool(_save)
    await websocket.close()

def talk():
    with TestClient(app).websocket_connect("/lab/sessions/7/stream") as socket:
        socket.receive_text()
"""


def test_the_probe_times_each_garbage_collection_on_the_client_times_clock(tmp_path):
    """``GYROLAB_BENCH_GC``: a line per collection, ``pid generation ms collected began``,
    ``began`` on ``time.perf_counter`` (the load generator's clock); a full one adds what
    the oldest generation keeps."""
    import subprocess
    import time

    out = tmp_path / "gc.txt"
    env = {**os.environ, "PYTHONPATH": str(PROBE), "GYROLAB_BENCH_GC": str(out)}
    code = "import gc, time; print(time.perf_counter()); gc.collect(0); gc.collect()"
    before = time.perf_counter()
    done = subprocess.run(
        [sys.executable, "-c", code], env=env, capture_output=True, text=True, timeout=120
    )
    after = time.perf_counter()
    asked = float(done.stdout.split()[0])
    lines = [line.split() for line in out.read_text().splitlines()]
    young = [fields for fields in lines if fields[1] == "0"][-1]
    full = lines[-1]
    assert young[0] == full[0] and full[1] == "2" and len(full) > 5
    assert float(young[2]) >= 0 and int(young[3]) >= 0
    assert before <= asked <= float(young[4]) <= float(full[4]) <= after


def test_the_probe_splits_a_streams_thread_cpu_by_function(tmp_path):
    """A WebSocket's line also gives its thread-pool CPU by function; the model's stream
    takes its mark, its take and its save in those shares."""
    out = tmp_path / "cpu.txt"
    run_probed(PROBED_STREAM, ["asyncio.to_thread(talk)"], {"GYROLAB_BENCH_REQUEST_CPU": str(out)})
    (line,) = [line for line in out.read_text().splitlines() if line.startswith("websocket")]
    kind, method, path, _loop_ms, threads_ms, frames, by_function = line.split()
    assert (path, frames) == ("/lab/sessions/7/stream", "1")
    spent = {name: float(ms) for name, ms in (pair.split("=") for pair in by_function.split(","))}
    assert 10 <= spent["_mark_started"] < 15 and 20 <= spent["SimulatedTake"] < 25
    assert 30 <= spent["_save"] < 37 and float(threads_ms) == pytest.approx(
        sum(spent.values()), abs=0.01
    )
    split = class_cpu.attributed_costs(out.read_text()).stream_split
    assert split == pytest.approx((1 / 6, 2 / 6, 3 / 6), abs=0.03)


def test_a_stream_makes_its_take_ready_outside_the_write_lock():
    """With a measured split, a position's mark and save hold the lock for their shares of
    its thread work and the take holds none; its SQLite calls are the writes' alone."""
    table = costs()
    table[queue_sim.STREAM_SPLIT] = (0.2, 0.3, 0.5)
    result = queue_sim.simulate(
        table, 1, 1, 2.0, ramp=0.0, hash_s=2 * MS, teacher=False, wake_free=False
    )
    held = np.array(result["lock held"])
    positions = 8
    frames_work = queue_sim.FRAMES_PER_POSITION * 0.3 * MS  # 15 frames of 0.3 ms in threads
    assert np.sum(np.isclose(held, 0.2 * frames_work, atol=1e-5)) == positions
    assert np.sum(np.isclose(held, 0.5 * frames_work, atol=1e-5)) == positions
    assert not np.any(np.isclose(held, 0.3 * frames_work, atol=1e-5))


def test_a_positions_take_and_save_go_to_the_thread_pool_without_a_wait_for_the_loop():
    """The stream's coroutine sends the take and the save to the thread pool in the step
    that received the mark's answer or sent the last frame: neither queues on the event
    loop first (the model's save did, 30 ms at its p50 in a busy class, and the WS save was
    predicted +12 … +73 %: bench/README.md, twenty-fifth part).  A position's start comes
    from the socket and does; each answer's way back to the loop does."""
    table = costs()
    table[queue_sim.STREAM_SPLIT] = (0.3, 0.2, 0.5)
    log: list = []
    queue_sim.simulate(table, 1, 1, 2.0, ramp=0.0, teacher=False, stage_log=log)
    stages = {route: pools for route, pools in log}
    assert stages[queue_sim.STREAM_START][:2] == ["client", "loop"]
    assert stages[queue_sim.STREAM_TAKE] == ["client", "server", "db", "loop", "client"]
    assert stages[queue_sim.STREAM_SAVE] == [
        "client", "enter", "lock", "db", "leave", "loop", "client"
    ]  # fmt: skip
    assert stages["POST /lab/sessions/{id}/csv"][:2] == ["client", "loop"]


def test_a_stream_frame_is_the_event_loops_work_alone():
    """The tick takes the samples and sends them on the event loop: a frame's stages are
    the loop's and the client's, with no thread to wake and no turn of the interpreter to
    wait for behind another student's save (``frames_on_loop``); the model before had each
    frame queue for the interpreter as a thread's work of 1 µs."""
    for on_loop, thread_stages in ((True, []), (False, ["server", "db"])):
        log: list = []
        queue_sim.simulate(
            costs(), 1, 1, 2.0, ramp=0.0, teacher=False, stage_log=log, frames_on_loop=on_loop
        )
        frames = [pools for route, pools in log if route == queue_sim.STREAM]
        assert len(frames) == 8 * queue_sim.FRAMES_PER_POSITION
        assert frames[0] == ["client", "loop", *thread_stages, "loop", "client"], on_loop


def test_the_lock_trace_gives_each_writes_share_of_its_thread_cpu_in_the_lock():
    """``GYROLAB_BENCH_LOCK_TRACE`` names each transaction's request and function: a
    route's share of its thread CPU in the lock is its transactions' CPU over its thread
    CPU (the CPU probe's); with it the model holds the lock for that share alone."""
    seen = class_cpu.attributed_costs(
        "\n".join(
            [
                "http POST /lab/sessions/4/csv 2.000 10.000 0",
                "http POST /lab/sessions/5/csv 2.000 10.000 0",
                "websocket WS /lab/sessions/4/stream 30.000 40.000 30"
                " _owner=1.000,_mark_started=9.000,SimulatedTake=10.000,_save=20.000",
            ]
        )
    )
    trace = "\n".join(
        [
            "9.0 6.000 http POST /lab/sessions/4/csv _run_sync_endpoint",
            "8.0 5.000 http POST /lab/sessions/5/csv _run_sync_endpoint",
            "7.0 5.000 websocket WS /lab/sessions/4/stream _mark_started",
            "20.0 15.000 websocket WS /lab/sessions/4/stream _save",
            "60.0 55.000 - - - -",  # start-up's migrations: no request
        ]
    )
    shares = class_cpu.locked_shares(trace, seen)
    assert shares == pytest.approx(
        {"POST /lab/sessions/{id}/csv": 0.55, queue_sim.STREAM_START: 0.5,
         queue_sim.STREAM_SAVE: 0.75}
    )  # fmt: skip
    table = costs(server=4 * MS, loop=1 * MS)  # 3 ms in threads a request
    result = queue_sim.simulate(
        table, 1, 1, 2.0, ramp=0.0, hash_s=2 * MS, teacher=False, wake_free=False,
        locked_shares={"POST /lab/sessions/{id}/csv": 0.5},
    )  # fmt: skip
    held = np.array(result["lock held"])
    assert np.sum(np.isclose(held, 1.5 * MS, atol=1e-5)) == 2  # the two CSV saves
    assert np.sum(np.isclose(held, 3 * MS, atol=1e-5)) >= 8  # the other writes, whole


def test_the_profile_probe_writes_each_routes_thread_pool_functions_by_cpu(tmp_path):
    """``GYROLAB_BENCH_PROFILE``: one cProfile file per route (ids folded), of what its
    requests ran in the thread pool, timed by the thread's CPU clock; the loop's work is
    not in it."""
    import pstats

    run_probed(PROBED_ROUTES, PROBED_CALLS, {"GYROLAB_BENCH_PROFILE": str(tmp_path)})
    files = sorted(path.name.split("-", 1)[1] for path in tmp_path.glob("*.prof"))
    assert files == ["GET_in_a_thread_id.prof"]  # the loop's route sent nothing there
    stats = pstats.Stats(str(next(tmp_path.glob("*.prof"))))
    burnt = [v for (_, _, name), v in stats.stats.items() if name == "in_a_thread"]
    calls, _, _, cumulative, _ = burnt[0]
    assert calls == 2 and 0.055 <= cumulative < 0.09  # two requests, 30 ms of CPU each


LOCKING_SCRIPT = """
import sqlite3, sys, threading, time
from app.writer_turn import WriterTurn
connection = sqlite3.connect(sys.argv[1], isolation_level=None, check_same_thread=False)
connection.execute("CREATE TABLE t (x)")
for pause in (0.0, 0.03):
    connection.execute("BEGIN IMMEDIATE")  # as app.db begins: on the connection itself
    connection.execute("INSERT INTO t VALUES (1)")
    time.sleep(pause)
    connection.commit()
# two writers taking turns: the second asks while the first holds its turn, which the
# first keeps 40 ms from then (not from its own start: on a crowded host the second
# thread once began 40 ms late and found the turn free)
turn, holding = WriterTurn(), threading.Event()
def write(hold):
    turn.acquire(10.0)
    holding.set()
    if hold:
        deadline = time.monotonic() + 10
        while turn.queued < 1 and time.monotonic() < deadline:
            time.sleep(0.001)
    time.sleep(hold)
    connection.execute("BEGIN IMMEDIATE")
    connection.execute("INSERT INTO t VALUES (2)")
    connection.commit()
    turn.release()
first = threading.Thread(target=write, args=(0.04,))
first.start()
holding.wait()
second = threading.Thread(target=write, args=(0.0,))
second.start()
first.join()
second.join()
"""


def test_the_lock_trace_probe_times_each_write_from_begin_immediate_to_commit(tmp_path):
    """``GYROLAB_BENCH_LOCK_TRACE``: one line per write transaction, the wall time from
    ``BEGIN IMMEDIATE`` to its commit and the thread's CPU meanwhile (it once missed
    every write: the app begins on the connection, not on a cursor), and the wait for the
    writers' turn before it (``-`` for a write that did not ask for one)."""
    import os
    import subprocess

    probe = Path(queue_model.__file__).parent / "probe"
    trace = tmp_path / "locks.txt"
    env = {**os.environ, "PYTHONPATH": str(probe), "GYROLAB_BENCH_LOCK_TRACE": str(trace)}
    subprocess.run(
        [sys.executable, "-c", LOCKING_SCRIPT, str(tmp_path / "t.db")],
        env=env,
        check=True,
        timeout=60,
    )
    fields = [line.split() for line in trace.read_text().splitlines()]
    assert [line[2:6] for line in fields] == [["-"] * 4] * 4  # no request, no thread pool
    lines = [[float(x) for x in line[:2]] for line in fields]
    (_quick_wall, quick_cpu), (paused_wall, paused_cpu) = lines[:2]
    assert quick_cpu >= 0
    assert paused_wall >= 30 and paused_cpu < paused_wall - 20  # the pause held it, idle
    assert [line[6] for line in fields[:2]] == ["-", "-"]  # written without a turn
    first, second = (float(line[6]) for line in fields[2:])
    assert first < 10 and second >= 35  # the second waited out the first's 40 ms


def test_the_lock_trace_is_read_per_write_route_with_each_writes_wait_for_its_turn():
    """``class_cpu.lock_trace_by_route``: the stream's writes named by their function, a
    line without a turn's wait (written before 2026-12-05) NaN there, start-up's skipped."""
    trace = "\n".join([
        "44.0 43.6 - - - - 0.007",  # start-up: no request
        "6.0 5.7 http POST /login _run_sync_endpoint 0.5",
        "2.0 1.1 http POST /lab/sessions/7/turn _run_sync_endpoint 4.0",
        "3.0 1.4 websocket WS /lab/sessions/7/stream _mark_started 2.0",
        "6.0 3.4 websocket WS /lab/sessions/7/stream _save",
    ])  # fmt: skip
    rows = class_cpu.lock_trace_by_route(trace)
    assert sorted(rows) == sorted(["POST /login", "POST /lab/sessions/{id}/turn",
                                   queue_sim.STREAM_START, queue_sim.STREAM_SAVE])  # fmt: skip
    assert rows["POST /lab/sessions/{id}/turn"].tolist() == [[4.0, 2.0, 1.1]]
    assert rows[queue_sim.STREAM_START].tolist() == [[2.0, 3.0, 1.4]]
    assert np.isnan(rows[queue_sim.STREAM_SAVE][0, 0])


def test_a_thread_pool_trip_hands_the_interpreter_on_outside_the_write_lock():
    """A write's transaction runs inside one thread-pool function: the trips' releases
    fall before and after it, never between ``BEGIN IMMEDIATE`` and the commit.  Streams
    whose writes make a trip a frame among requests that hold the interpreter: with the
    trips outside the lock (the default), a save holds the lock for less beyond its CPU
    than with them spread over it (the model before 2026-12-05), its CPU the same."""
    table = costs(server=8 * MS, calls=0.0, trips=0.0)
    table[queue_sim.STREAM] = (1 * MS, 0.1 * MS, 0.2 * MS, 2.0, 1.0, 0.1 * MS)
    shares = {queue_sim.STREAM_SAVE: 0.5, queue_sim.STREAM_START: 0.5}

    def save_holds(outside: bool) -> np.ndarray:
        result = queue_sim.simulate(
            table, 20, 1, 2.0, teacher=False, locked_shares=shares, work_places=0,
            trips_outside_lock=outside,
        )  # fmt: skip
        return np.array(result["lock by route"][queue_sim.STREAM_SAVE])[:, 1]

    outside, inside = save_holds(True), save_holds(False)
    cpu = 0.9 * MS * queue_sim.FRAMES_PER_POSITION * 0.5 * 0.5  # the save's locked half
    assert len(outside) == len(inside) == 20 * 8  # every position saved
    assert outside.min() >= cpu - 1e-9 and inside.min() >= cpu - 1e-9
    assert np.mean(outside) - cpu < 0.6 * (np.mean(inside) - cpu)


def test_class_costs_replace_each_routes_own_cpu_and_keep_the_rest():
    lines = "\n".join(
        [
            "http GET /lab/sessions/12 3.000 5.000 0",
            "http GET /lab/sessions/13 1.000 3.000 0",
            "http GET /courses/4/assignments/7 2.000 10.000 0",
            "websocket WS /lab/sessions/12/stream 30.000 10.000 20",
            "websocket WS /lab/sessions/13/stream 10.000 10.000 20",
        ]
    )
    seen = class_cpu.attributed_costs(lines)
    assert seen.means["GET /lab/sessions/{id}"] == pytest.approx((2 * MS, 4 * MS))
    assert seen.means["GET dashboard (teacher)"] == pytest.approx((2 * MS, 10 * MS))
    assert seen.means[queue_sim.STREAM] == pytest.approx((1 * MS, 0.5 * MS))  # per frame
    assert seen.counts == {"GET /lab/sessions/{id}": 2, "GET dashboard (teacher)": 1,
                           queue_sim.STREAM: 40}  # fmt: skip
    assert seen.total_s == pytest.approx(84 * MS)
    table = costs(server=10 * MS, loop=3 * MS)
    own = {"GET /lab/sessions/{id}": (2 * MS, 6 * MS)}  # 8 of its 10 ms: the rest unseen
    adjusted, scale, _ = class_cpu.in_class(table, own, seen)
    server, db, client, calls, trips, loop, own_loop = adjusted["GET /lab/sessions/{id}"]
    assert scale == 1.0
    assert own_loop == pytest.approx(2 * MS)  # its task's part: inside its work place
    assert server == pytest.approx(10 * MS - 8 * MS + 6 * MS)
    assert loop == pytest.approx(3 * MS - 2 * MS + 2 * MS)
    assert (db, client, calls, trips) == table["GET /lab/sessions/{id}"][1:5]
    assert adjusted["POST /login"] == table["POST /login"]  # not seen alone: unchanged


def test_each_request_of_the_class_keeps_its_own_cpu():
    """A route's requests do not cost the same (a dashboard that redoes many sessions, a
    results read that solves): with ``each`` the costs are one per request the class made,
    with the same unseen part, and their mean is the route's mean costs."""
    lines = "\n".join(
        [
            "http GET /lab/sessions/12 3.000 5.000 0",
            "http GET /lab/sessions/13 1.000 3.000 0",
            "http GET /lab/sessions/14 2.000 31.000 0",
        ]
    )
    seen = class_cpu.attributed_costs(lines)
    route = "GET /lab/sessions/{id}"
    assert np.array(seen.each[route]) == pytest.approx(
        np.array([(3 * MS, 5 * MS), (1 * MS, 3 * MS), (2 * MS, 31 * MS)])
    )
    table = costs(server=10 * MS, loop=3 * MS)
    own = {route: (2 * MS, 6 * MS)}
    mean, _, _ = class_cpu.in_class(table, own, seen)
    each, _, _ = class_cpu.in_class(table, own, seen, each=True)
    assert isinstance(each[route], list) and len(each[route]) == 3
    assert [cost[0] for cost in each[route]] == pytest.approx([10 * MS, 6 * MS, 35 * MS])
    assert np.mean(each[route], axis=0) == pytest.approx(mean[route])
    assert each["POST /login"] == table["POST /login"]  # not seen: one student's, as before


def test_a_route_of_varied_requests_has_the_tail_of_its_slowest():
    """Costs drawn per request: a lone student's page that costs 1 ms nine times in ten and
    41 ms once has a p95 near the slow one's; costed at its mean (5 ms) every request
    takes the mean."""
    route = "GET /lab/sessions/{id}/results.json"
    fast, slow = (1 * MS, 0.0, 0.0, 0.0, 0.0, 0.0), (41 * MS, 0.0, 0.0, 0.0, 0.0, 0.0)
    table = costs(server=1 * MS, db=0.0, client=0.0, calls=0.0, trips=0.0, loop=0.0)
    varied = dict(table, **{route: [fast] * 9 + [slow]})
    at_mean = dict(table, **{route: tuple(np.mean(varied[route], axis=0))})
    latencies = {}
    for name, chosen in (("varied", varied), ("mean", at_mean)):
        result = queue_sim.simulate(
            chosen, 40, 1, 2.0, ramp=600.0, teacher=False, switch_interval_s=0.0
        )
        latencies[name] = np.array(result["latencies"][route])
    # (students spread over ten minutes: now and then two requests meet, ≤ 1 ms apart)
    assert latencies["mean"] == pytest.approx(np.full(80, 5 * MS), abs=0.5 * MS)
    varied = latencies["varied"]
    assert np.all((varied < 3 * MS) | ((varied > 40 * MS) & (varied < 43 * MS)))
    assert 0.05 < np.mean(varied > 20 * MS) < 0.2
    assert np.percentile(varied, 95) > 40 * MS > 7 * np.percentile(latencies["mean"], 95)


def test_a_routes_measured_requests_are_drawn_in_the_order_the_class_made_them():
    """The lab page is cheap at a class's start and dear in its burst: the model's first
    pages cost the first measured, its last the last -- not a random mix of both."""
    students, page = 4, "GET /lab/sessions/{id}"
    table = costs(client=0.0)
    cheap, dear = table[page], (60 * MS, *table[page][1:5], 1 * MS)
    table[page] = [cheap] * students + [dear] * students  # in the order the class made them
    kwargs = dict(students=students, workers=1, cores=2.0, ramp=0.0, teacher=False)
    in_order = queue_sim.simulate(table, **kwargs, wake_free=False)["latencies"][page]
    assert len(in_order) == 2 * students
    assert max(in_order[:3]) < 30 * MS  # the first pages: the cheap ones (4 ms, waits)
    assert min(in_order[-3:]) > 60 * MS  # the last: the dear ones
    at_random = [
        queue_sim.simulate(table, **kwargs, wake_free=False, costs_in_order=False, seed=seed)
        for seed in range(4)
    ]
    assert any(max(result["latencies"][page][:3]) > 60 * MS for result in at_random)


def test_a_log_in_gives_its_work_place_to_another_request_while_it_hashes():
    """As the app does (``db.give_way`` before argon2id): two log-ins at once on one work
    place hash side by side; the second does not wait for the first's hash."""
    hash_s = 200 * MS
    table = costs(server=1 * MS, db=0.0, client=0.0, calls=1.0, trips=1.0, loop=0.1 * MS)
    table[queue_sim.LOGIN] = (hash_s + 2 * MS, 0.0, 0.0, 2.0, 1.0, 0.1 * MS)
    result = queue_sim.simulate(
        table, 2, 1, 2.0, ramp=0.0, hash_s=hash_s, teacher=False, work_places=1
    )
    log_ins = result["latencies"][queue_sim.LOGIN]
    assert len(log_ins) == 2
    assert max(log_ins) < 1.5 * hash_s  # held through the hash, the second took ≥ 2 hashes


def test_a_thread_woken_onto_a_hashs_core_puts_the_hash_off_it():
    """``landing_s``: a server thread woken to run lands on a core at random, and on one
    running a hash the hash waits that long (bench_gil_wakes.py --beside).  A log-in hashing
    while other students' requests take turns at the interpreter takes longer with it; no
    landing, no change; every request is answered either way."""
    hash_s = 20 * MS
    table = costs(server=4 * MS, db=0.0, client=0.5 * MS, calls=12.0, trips=3.0)
    table[queue_sim.LOGIN] = (hash_s + 2 * MS, 0.0, 0.5 * MS, 2.0, 1.0, 0.1 * MS)

    def log_ins(landing_s: float) -> list[float]:
        result = queue_sim.simulate(
            table, 12, 1, 2.0, ramp=0.05, hash_s=hash_s, teacher=False, landing_s=landing_s
        )
        assert len(result["latencies"][queue_sim.LOGIN]) == 12
        return result["latencies"][queue_sim.LOGIN]

    assert log_ins(0.0) == log_ins(0.0)  # the landings' draws change nothing without it
    assert np.mean(log_ins(1 * MS)) > np.mean(log_ins(0.0)) + 1 * MS


def test_a_thread_put_off_its_core_leaves_the_core_to_the_thread_woken_onto_it():
    """A landed-on thread waits without running and without holding a core: the cores'
    busy time and the load generator's time on one stay as without landings however long it
    waits (before 2026-12-06 it kept its share of the cores idle meanwhile: the load
    generator 'ran' 0.56 s for 0.19 s of CPU with 5 ms landings); ``landing_on``: which
    threads outside the interpreter a woken one lands on."""
    hash_s = 20 * MS
    table = costs(server=4 * MS, db=0.0, client=0.5 * MS, calls=12.0, trips=3.0)
    table[queue_sim.LOGIN] = (hash_s + 2 * MS, 0.0, 0.5 * MS, 2.0, 1.0, 0.1 * MS)

    def run(landing_s: float, on: tuple[str, ...] = queue_sim.OUTSIDE) -> dict:
        return queue_sim.simulate(
            table, 12, 1, 2.0, ramp=0.05, hash_s=hash_s, teacher=False, landing_s=landing_s,
            landing_on=on,
        )  # fmt: skip

    still = run(0.0)
    for landed in (run(5 * MS), run(5 * MS, ("hash",))):
        assert landed["pressure"][1] == pytest.approx(still["pressure"][1], rel=1e-6)
        assert landed["run queue"]["client"][0] == pytest.approx(still["run queue"]["client"][0])
    everyone, hashes_only = run(5 * MS), run(5 * MS, ("hash",))
    assert everyone["run queue"]["client"][1] > 10 * hashes_only["run queue"]["client"][1] > 0


def test_the_load_generators_callbacks_run_one_at_a_time_in_order():
    """``client_in_order``: the load generator is one event loop.  Twelve students ready at
    the same instant have their first pages one client callback apart; shared evenly
    (processor sharing) their callbacks end together and the pages spread as the server
    answers them."""
    client = 4 * MS
    table = costs(server=0.2 * MS, db=0.0, client=client, calls=0.0, trips=1.0)

    def first_pages(in_order: bool) -> list[float]:
        result = queue_sim.simulate(
            table, 12, 1, 2.0, starts=[0.0] * 12, teacher=False, client_in_order=in_order
        )
        return sorted(result["latencies"]["GET /login"])

    shared, in_order = first_pages(False), first_pages(True)
    assert len(in_order) == len(shared) == 12
    # in order: each callback (half the client work before the send) one after another
    assert np.diff(in_order) == pytest.approx([client / 2] * 11, abs=0.2 * MS)
    assert np.diff(shared) != pytest.approx([client / 2] * 11, abs=0.2 * MS)


def test_with_the_runs_cpu_the_class_costs_add_up_to_it():
    """The unseen part of each request is scaled so that the class's requests and frames
    ask the server for the CPU the run used, and the load generator likewise."""
    lines = "\n".join(["http GET /lab/sessions/12 1.000 3.000 0"] * 10)
    seen = class_cpu.attributed_costs(lines)
    table = costs(server=10 * MS, loop=3 * MS, client=2 * MS)
    own = {"GET /lab/sessions/{id}": (2 * MS, 6 * MS)}  # unseen alone: 2 ms, 1 of it the loop's
    used = {"server": 0.07, "client": 0.01}  # 40 ms seen, so 30 ms for 10 × 2 ms unseen
    adjusted, scale, client_scale = class_cpu.in_class(table, own, seen, used)
    server, db, client, calls, trips, loop, _ = adjusted["GET /lab/sessions/{id}"]
    assert scale == pytest.approx(1.5) and client_scale == pytest.approx(0.5)
    assert 10 * server == pytest.approx(used["server"])
    assert 10 * client == pytest.approx(used["client"])
    assert loop == pytest.approx(1 * MS + 1.5 * 1 * MS)


def test_the_load_generators_cpu_can_weigh_a_frame_apart_from_a_request():
    """``frame_weight``: ten requests of 2 ms of the load generator's CPU alone and forty
    frames of 0.2 ms ask 28 ms.  Weighed alike, the 14 ms a run used is each at 0.5×: 1 ms
    a request, 0.1 ms a frame.  A frame weighed at a quarter of a request's share, the
    11 ms another run used is 1 ms a request and 0.025 ms a frame."""
    lines = ["http GET /lab/sessions/12 1.000 3.000 0"] * 10 + ["websocket - - 4.0 4.0 40"]
    seen = class_cpu.attributed_costs("\n".join(lines))
    table = costs(server=10 * MS, loop=3 * MS, client=2 * MS)
    own = {"GET /lab/sessions/{id}": (2 * MS, 6 * MS), queue_sim.STREAM: (0.1 * MS, 0.1 * MS)}
    for weight, client, frame in ((1.0, 0.014, 0.1 * MS), (0.25, 0.011, 0.025 * MS)):
        used = {"server": 0.09, "client": client}
        adjusted, _, _ = class_cpu.in_class(table, own, seen, used, frame_weight=weight)
        assert adjusted["GET /lab/sessions/{id}"][2] == pytest.approx(1 * MS), weight
        assert adjusted[queue_sim.STREAM][2] == pytest.approx(frame), weight
    # without the run's CPU there is nothing to share out: one student's costs, as they are
    alone, _, _ = class_cpu.in_class(table, own, seen, frame_weight=0.25)
    assert alone[queue_sim.STREAM][2] == pytest.approx(0.2 * MS)
    # 5 ms of a run's 16 ms spent whatever it sent (``client_floor_s``): run apart, the
    # other 11 ms shared out as before
    used = {"server": 0.09, "client": 0.016}
    apart, _, _ = class_cpu.in_class(
        table, own, seen, used, frame_weight=0.25, client_floor_s=0.005
    )
    assert apart["GET /lab/sessions/{id}"][2] == pytest.approx(1 * MS)
    assert apart[queue_sim.STREAM][2] == pytest.approx(0.025 * MS)


def test_the_load_generators_floor_runs_while_the_class_does_and_delays_its_callbacks():
    """``client_floor``: the load generator spends its share of a core from the class's
    start to its last student's end, in line with its requests' client work.  One student
    with 1 ms of client work a request: with a floor of 0.5 the load generator asks for
    half a core more over the class, and its callbacks wait behind the floor's pieces."""
    table = costs(server=1 * MS, db=0.0, client=1 * MS, calls=0.0, trips=1.0, loop=0.0)

    def run(floor: float) -> dict:
        return queue_sim.simulate(
            table, 1, 1, 2.0, starts=[0.0], teacher=False, switch_interval_s=0.0,
            handoff_s=0.0, client_in_order=True, client_floor=floor,
        )  # fmt: skip

    bare, floored = run(0.0), run(0.5)
    floor_cpu = floored["cpu"]["client"] - bare["cpu"]["client"]
    assert floor_cpu == pytest.approx(
        0.5 * floored["wall"], abs=0.5 * queue_sim.CLIENT_FLOOR_PERIOD_S
    )
    ran = floored["run queue"]["client"][0] - bare["run queue"]["client"][0]
    assert ran == pytest.approx(floor_cpu, rel=1e-3)
    assert floored["wall"] > bare["wall"]
    waited = {name: sum(map(sum, result["latencies"].values())) for name, result in
              (("bare", bare), ("floored", floored))}  # fmt: skip
    assert waited["floored"] > waited["bare"] + 0.01


def test_a_probe_file_holding_more_than_its_run_is_refused():
    """The probe appends to its files: a second run written to the same file counts the
    class's requests twice, and the CPU it saw outgrows the CPU the run used (0.87-0.92 of
    it in a run's own file; 1.8 with two runs' lines).  Refused, not scaled to nothing."""
    lines = "\n".join(["http GET /lab/sessions/12 1.000 3.000 0"] * 10)
    seen = class_cpu.attributed_costs(lines)  # 40 ms seen
    table = costs(server=10 * MS, loop=3 * MS, client=2 * MS)
    own = {"GET /lab/sessions/{id}": (2 * MS, 6 * MS)}
    class_cpu.in_class(table, own, seen, {"server": 0.04, "client": 0.01})  # all of it seen
    with pytest.raises(ValueError, match="more than that run"):
        class_cpu.in_class(table, own, seen, {"server": 0.035, "client": 0.01})
    twice = class_cpu.attributed_costs(lines + "\n" + lines)
    with pytest.raises(ValueError, match="more than that run"):
        class_cpu.in_class(table, own, twice, {"server": 0.05, "client": 0.01})


def test_inside_the_server_a_lone_request_waits_for_no_place():
    """The model's part of each latency inside the server (what the probe's
    GYROLAB_BENCH_SERVER_TIMES measures): from asking for a work place to the answer,
    and of it the wait for the place."""
    result = queue_sim.simulate(
        costs(), 1, 1, 2.0, ramp=0.0, hash_s=2 * MS, teacher=False, wake_free=False
    )
    for route, pairs in result["server"].items():
        waited, inside = np.array(pairs).T[:2]
        assert np.all(waited == 0), route
        # the threads' work (server less its event loop's part) and the database's
        assert inside == pytest.approx(np.full(len(inside), 4 * MS), abs=1e-5), route
    crowded = queue_sim.simulate(costs(), students=40, workers=1, cores=2.0, teacher=False)
    waits = np.concatenate([np.array(p)[:, 0] for p in crowded["server"].values()])
    assert waits.max() > 0 and np.all(waits >= 0)


def test_server_times_are_read_per_route(tmp_path):
    path = tmp_path / "times.txt"
    path.write_text(
        "GET /lab/sessions/3 12.5 10.0\nGET /lab/sessions/4 2.5 0.0\nPOST /login 30 1\n"
    )
    read = class_cpu.server_times(path)
    assert read["GET /lab/sessions/{id}"].tolist() == [[10.0, 12.5], [0.0, 2.5]]
    assert read["POST /login"].tolist() == [[1.0, 30.0]]


def test_the_event_loops_part_inside_the_app_holds_the_work_place():
    """Routing, dependencies and the answer run on the event loop inside the admission:
    a request holds its place meanwhile; the server's socket work comes before and after."""
    table = {route: (*values, 0.6 * MS) for route, values in costs().items()}
    result = queue_sim.simulate(
        table, 1, 1, 2.0, ramp=0.0, hash_s=2 * MS, teacher=False, wake_free=False
    )
    for route, pairs in result["server"].items():
        waited, inside = np.array(pairs).T[:2]
        assert inside == pytest.approx(np.full(len(inside), 4.6 * MS), abs=1e-5), route
    result["latencies"].pop(queue_sim.SAVED)
    for route, latencies in result["latencies"].items():  # the same work in all
        assert latencies == pytest.approx([7 * MS] * len(latencies), abs=1e-5), route


def test_each_streamed_position_starts_and_saves_in_the_write_lock():
    """A position's start (its checks and mark) and its save are writes: on SQLite each
    holds the one write lock, as the HTTP writes do and a log-in twice; the frames between
    take no lock (a class whose positions end together queues its saves and turns)."""
    result = queue_sim.simulate(
        costs(), 1, 1, 2.0, ramp=0.0, hash_s=2 * MS, teacher=False, wake_free=False
    )
    writes = sum(
        1 for kind, route in queue_sim.student_script() if kind == "request" and route in
        queue_sim.WRITES
    )  # fmt: skip
    positions = sum(1 for kind, _ in queue_sim.student_script() if kind == "stream")
    assert positions == 8
    assert len(result["lock held"]) == writes + 2 + 2 * positions  # + a log-in's two
    # a position's start and save each hold it for half its frames' thread work (15 frames
    # of 0.3 ms); the requests' writes for their threads' 3 ms, a log-in 1 ms twice
    held = np.array(result["lock held"])
    assert np.sum(np.isclose(held, 7.5 * 0.3 * MS, atol=1e-5)) == 2 * positions
    assert np.sum(np.isclose(held, 3 * MS, atol=1e-5)) == writes


def test_the_load_tests_browsers_share_one_tls_context():
    """A new httpx client loads the CA bundle (≈ 28 ms of CPU) unless given a context:
    60 of them in the class's 3 s ramp blocked the load generator's event loop, and the
    first requests measured it as the server's latency.  Every simulated browser shares
    one (httpx's own attribute path, pinned in constraints.txt)."""
    import load_test

    made = [load_test.browser(f"http://127.0.0.1:{port}") for port in (8001, 8002)]
    assert all(c._transport._pool._ssl_context is load_test.CLIENT_TLS for c in made)


def test_a_hand_off_idles_the_interpreter_only_when_a_thread_waited_for_it():
    """Each time the interpreter passes to a thread that was waiting for it, nobody runs
    Python while that thread is woken (``handoff_s``).  A student alone never waits for the
    interpreter, so hands nothing off: the same latencies with or without it; a crowded
    class hands off at every call and is slower by it."""
    alone = {
        handoff: queue_sim.simulate(
            costs(), 1, 1, 2.0, ramp=0.0, teacher=False, handoff_s=handoff, wake_free=False
        )["latencies"]
        for handoff in (0.0, 1 * MS)
    }
    for route, latencies in alone[0.0].items():
        assert alone[1 * MS][route] == pytest.approx(latencies, abs=1e-9), route
    crowded = {
        handoff: queue_sim.simulate(costs(), 40, 1, 2.0, teacher=False, handoff_s=handoff)
        for handoff in (0.0, 0.2 * MS)
    }
    slow, fast = (crowded[h]["latencies"]["POST /lab/sessions/{id}/csv"] for h in (0.2 * MS, 0))
    assert np.percentile(slow, 95) > 1.2 * np.percentile(fast, 95)
    assert crowded[0.2 * MS]["cpu"] == pytest.approx(crowded[0.0]["cpu"])  # idle, not CPU


def test_on_postgresql_each_database_call_is_a_round_trip():
    """With no one writer (PostgreSQL) a request's thread stops at each database call: the
    database server's share of the work, and ``round_trip_s`` of loopback and wake-ups.  A
    student alone: each request's latency is its CPU (client, server, database) and one
    round trip per call (10 calls here); on SQLite the calls run in the thread itself."""
    alone = {"ramp": 0.0, "teacher": False, "round_trip_s": 0.1 * MS, "wake_free": False}
    postgres = queue_sim.simulate(costs(), 1, 1, 2.0, one_writer=False, **alone)
    sqlite = queue_sim.simulate(costs(), 1, 1, 2.0, **alone)
    for route in ("GET /lab/sessions/{id}", "POST /lab/sessions/{id}/csv"):
        assert postgres["latencies"][route] == pytest.approx([8 * MS] * 2, abs=1e-5)
        assert sqlite["latencies"][route] == pytest.approx([7 * MS] * 2, abs=1e-5)


def test_a_wake_up_waits_longer_when_more_is_asked_of_the_cores_than_they_have():
    """``wake_busy_s`` is paid at each round trip's two wake-ups and each hand-off only
    while the cores are overdrawn: a student alone on two cores pays nothing; eight at
    once on half a core (client, worker and database asking for more than it has) pay
    it at every round trip."""

    def mean_latency(students: int, cores: float, busy: float) -> float:
        result = queue_sim.simulate(
            costs(), students, 1, cores, ramp=0.0, teacher=False, one_writer=False,
            wake_busy_s=busy,
        )  # fmt: skip
        return float(np.mean(result["latencies"]["GET /lab/sessions/{id}"]))

    assert mean_latency(1, 2.0, 1 * MS) == pytest.approx(mean_latency(1, 2.0, 0.0), abs=1e-9)
    assert mean_latency(8, 0.5, 1 * MS) > mean_latency(8, 0.5, 0.0) + 20 * MS


def test_a_prediction_is_the_median_of_its_seeds():
    """Which worker each connection reaches is random: a prediction combines simulations
    with different seeds -- per route the median p95 and its range."""
    one = {"latencies": {"GET /lab": [0.010] * 19 + [0.050]}, "server": {}, "cpu": {"server": 1.0},
           "lock held": [0.001], "wall": 10.0}  # fmt: skip
    two = {"latencies": {"GET /lab": [0.020] * 20}, "server": {}, "cpu": {"server": 3.0},
           "lock held": [0.002], "wall": 12.0}  # fmt: skip
    three = {"latencies": {"GET /lab": [0.030] * 20}, "server": {}, "cpu": {"server": 2.0},
             "lock held": [], "wall": 11.0}  # fmt: skip
    combined = queue_model.combine([one, two, three])
    # the first seed's p95: 10 ms but for one 50 ms in twenty (interpolated: 12 ms)
    assert combined["p95"]["GET /lab"] == pytest.approx(20.0)
    assert combined["p95 range"]["GET /lab"] == pytest.approx((12.0, 30.0))
    # the band from the 10th to the 90th percentile of 12, 20 and 30 ms
    assert combined["p95 band"]["GET /lab"] == pytest.approx((13.6, 28.0))
    assert combined["cpu"]["server"] == pytest.approx(2.0)
    assert combined["lock held"] == [0.001, 0.002] and combined["wall"] == 11.0


PG_CALLS_SCRIPT = """
import mmap, struct, sys
from sqlalchemy import create_engine, text
engine = create_engine(sys.argv[1])
engine.connect().close()  # the dialect's first connection asks the server about itself
held = open(sys.argv[2], "r+b")
counts = mmap.mmap(held.fileno(), 16)
before = struct.unpack("<2q", counts)[0]
with engine.begin() as connection:
    for _ in range(3):
        connection.execute(text("SELECT 1")).all()
print(struct.unpack("<2q", counts)[0] - before)
"""


def test_the_probe_counts_each_round_trip_to_postgresql(tmp_path, postgres):
    """``GYROLAB_BENCH_PROBE`` counts PostgreSQL's round trips as the database calls of a
    request (psycopg's statements and its BEGIN and COMMIT): three statements in one
    transaction are five."""
    import os
    import subprocess

    _, url = postgres.new_database()
    probe = Path(queue_model.__file__).parent / "probe"
    counts = tmp_path / "probe.bin"
    counts.write_bytes(bytes(16))
    env = {**os.environ, "PYTHONPATH": str(probe), "GYROLAB_BENCH_PROBE": str(counts)}
    done = subprocess.run(
        [sys.executable, "-c", PG_CALLS_SCRIPT, url, str(counts)],
        env=env, timeout=60, capture_output=True, text=True,
    )  # fmt: skip
    assert done.returncode == 0, done.stderr
    assert int(done.stdout) == 5


def test_each_workers_share_of_a_runs_requests_is_read_from_the_probe(tmp_path):
    """The server-times lines name the worker that answered: its share of the requests is
    its chance of a new connection in the simulation; older lines without it give none."""
    path = tmp_path / "times.txt"
    lines = ["GET /lab 2.0 0.1 100.5 41"] * 3 + ["GET /lab 2.0 0.1 100.6 42"]
    path.write_text("\n".join(lines) + "\n")
    assert class_cpu.worker_shares(path) == pytest.approx([0.75, 0.25])
    path.write_text("GET /lab 2.0 0.1 100.5\n")
    assert class_cpu.worker_shares(path) is None


def test_connections_reach_the_workers_in_their_shares():
    """A class whose connections all reach one of two workers waits as on one; spread
    evenly it waits less."""

    def burst_p95(shares):
        result = queue_sim.simulate(
            costs(), 50, 2, 2.0, one_writer=False, teacher=False, worker_shares=shares,
            per_core=False,  # the workers under test, not the cores: shared evenly, faster
        )  # fmt: skip
        return np.percentile(result["latencies"]["POST /lab/sessions/{id}/csv"], 95)

    assert burst_p95([1.0, 0.0]) > 1.5 * burst_p95([0.5, 0.5])


def test_the_summary_counts_the_runs_inside_the_band_of_their_seeds(capsys):
    """Each run's measured p95 is held against the band its seeds gave (how far a p95
    moves by chance alone), and the medians over the runs against each other."""
    predicted = [
        {"p95": {"GET /lab": 100.0, "POST /login": 50.0},
         "p95 band": {"GET /lab": (80.0, 120.0), "POST /login": (45.0, 55.0)}},
        {"p95": {"GET /lab": 110.0, "POST /login": 60.0},
         "p95 band": {"GET /lab": (90.0, 130.0), "POST /login": (54.0, 66.0)}},
    ]  # fmt: skip
    measured = [{"GET /lab": 125.0, "POST /login": 52.0}, {"GET /lab": 95.0, "POST /login": 80.0}]
    counts = queue_model.summary(60, "SQLite", list(zip(predicted, measured, strict=True)))
    # GET /lab: medians 105 against 110 (−5 %): within 10 %; 125 is out of [80, 120], 95 in.
    # POST /login: 55 against 66 (−17 %); 52 in [45, 55], 80 out of [54, 66]
    assert counts["within 10 %"] == 1 and counts["routes"] == 2
    assert counts["inside"] == 2 and counts["runs × routes"] == 4
    # half-widths: GET /lab 20 % and 18.2 %, POST /login 10 % and 10 %: medians 19.1 and 10
    assert counts["band"] == pytest.approx((19.09 + 10.0) / 2, abs=0.01)
    assert "1 / 2" in capsys.readouterr().out


def test_the_hand_offs_measured_beside_a_run_are_read_from_its_report(tmp_path):
    """load_test.py --handoffs prints what it measured before and after the class; the
    model reads their means from that report."""
    import load_test

    tally = load_test.Tally()
    tally.latencies["GET /lab"] = [0.010, 0.020]
    tally.handoffs = [(41e-6, 180e-6), (49e-6, 210e-6)]
    report = load_test.report("PostgreSQL", tally, 10.0, 0, 16, 2)
    path = tmp_path / "run.txt"
    path.write_text("machine: x86_64; 1 students\n\n" + report + "\n")
    table = queue_model.measured_p95(path)["PostgreSQL"]
    assert table["handoff us"] == pytest.approx(45.0)
    assert table["wake busy us"] == pytest.approx(195.0)
    assert table["GET /lab"] == pytest.approx(20.0)
    # the run is simulated with them unless others are given; 0 turns one off
    waits = queue_model.run_waits(table, None, None)
    assert (waits["handoff_s"], waits["wake_busy_s"]) == pytest.approx((45e-6, 195e-6))
    waits = queue_model.run_waits(table, 0.0, 100.0)
    assert (waits["handoff_s"], waits["wake_busy_s"]) == pytest.approx((0.0, 100e-6))
    assert waits["call_handoff"] == queue_sim.CALL_HANDOFF  # not measured in this run
    tally.handoffs = []
    path.write_text(load_test.report("SQLite", tally, 10.0, 0, 16, 1))
    table = queue_model.measured_p95(path)["SQLite"]
    assert "handoff us" not in table
    waits = queue_model.run_waits(table, None, None)
    assert (waits["handoff_s"], waits["wake_busy_s"]) == pytest.approx(
        (queue_sim.HANDOFF_S, queue_sim.WAKE_BUSY_S)
    )


def test_a_busy_wake_up_is_the_runs_own_wait_per_time_on_a_core():
    """A busy wake-up's wait is the run's own: its server threads' wait on the run queue
    per time on a core (``load_test.py --run-queue``: 93.74 s over 280,159 slices,
    335 µs), not the one measured beside the class (``--wake-from-handoffs``: 148 µs); a
    wake-up given by hand still wins, and a run without the run queue's figures keeps the
    one measured beside it."""
    table = {"wake busy us": 148.0, "waited server": 93.74, "slices server": 280159.0}
    waits = queue_model.run_waits(table, None, None)
    assert waits["wake_busy_s"] == pytest.approx(93.74 / 280159)
    beside = queue_model.run_waits(table, None, None, wake_from_run=False)
    assert beside["wake_busy_s"] == pytest.approx(148e-6)
    assert queue_model.run_waits(table, None, 100.0)["wake_busy_s"] == pytest.approx(100e-6)
    bare = {"wake busy us": 148.0}
    assert queue_model.run_waits(bare, None, None)["wake_busy_s"] == pytest.approx(148e-6)


def test_an_sqlite_calls_chance_to_hand_on_measured_after_a_run_is_read_from_its_report(
    tmp_path,
):
    """load_test.py --handoffs with the probe's SQLite calls prints the chance that one of
    the class's calls hands the interpreter on (it drifts with the host's hour: 8 % / 10 %
    on 2026-11-27, 20-28 % / 13-14 % on 2026-12-03); the model reads it, and simulates
    with it when given it (not by default: it predicted no better)."""
    import load_test

    tally = load_test.Tally()
    tally.latencies["GET /lab"] = [0.010, 0.020]
    tally.call_handoffs = (27706, 37.6e-6, 0.207, 0.141)
    path = tmp_path / "run.txt"
    path.write_text(load_test.report("SQLite", tally, 10.0, 0, 16, 1))
    assert "the class's 27706 calls (p50 37.6 µs)" in path.read_text()
    table = queue_model.measured_p95(path)["SQLite"]
    assert (table["call free"], table["call busy"]) == pytest.approx((0.207, 0.141))
    assert queue_model.run_waits(table, None, None)["call_handoff"] == queue_sim.CALL_HANDOFF
    given = queue_model.run_waits(table, None, None, (0.5, 0.25))
    assert given["call_handoff"] == (0.5, 0.25)
    assert queue_model.run_waits(table, None, None, None, True)["call_handoff"] is None


def test_the_run_queue_watch_counts_a_thread_born_during_it_from_zero():
    """run_queue.py: a thread that starts inside the watch is counted whole (its CPU from
    zero), a thread that was there before only from the watch's start."""
    import threading
    import time

    import run_queue

    burnt, done = threading.Semaphore(0), threading.Event()

    def burn() -> None:
        end = time.thread_time() + 0.3
        while time.thread_time() < end:
            pass
        burnt.release()
        done.wait()  # alive at the watch's last poll

    before = threading.Thread(target=burn, daemon=True)
    before.start()
    assert burnt.acquire(timeout=30)  # its CPU spent before the watch: not counted
    watching = {"me": lambda: [os.getpid()]}
    with run_queue.RunQueueWatch(watching, poll_s=0.05, main_threads={"me": "main"}) as watch:
        born = threading.Thread(target=burn, daemon=True)
        born.start()
        assert burnt.acquire(timeout=30)
    done.set()
    before.join(10)
    born.join(10)
    waits = watch.waits()["me"]
    assert 0.3 <= waits.ran_s < 0.5  # the born thread's 0.3 s from zero, not the other's
    assert waits.waited_s >= 0.0 and 0.0 <= waits.waited_share < 1.0
    assert waits.autogroups == (run_queue.autogroup(os.getpid()),) or not waits.autogroups
    # the process's main thread on its own (a worker's event loop): it burnt nothing here
    main = watch.waits()["main"]
    assert main.ran_s < 0.3 and main.ran_s <= waits.ran_s and main.slices <= waits.slices


def test_the_run_queue_of_a_run_is_read_from_its_report(tmp_path):
    """load_test.py --run-queue prints each group's wait for a core; the model reads it."""
    import load_test

    tally = load_test.Tally()
    tally.latencies["GET /lab"] = [0.010, 0.020]
    tally.run_queue = {
        "server": (14.25, 1.5, 120000),
        "load generator": (9.0, 3.0, 800),
        "PostgreSQL": (4.0, 0.5, 30000),
        load_test.LOOPS: (3.0, 0.25, 40000),
    }
    path = tmp_path / "run.txt"
    path.write_text(load_test.report("PostgreSQL", tally, 10.0, 0, 16, 2) + "\n")
    table = queue_model.measured_p95(path)["PostgreSQL"]
    assert (table["ran server"], table["waited server"]) == (14.25, 1.5)
    assert (table["ran client"], table["waited client"]) == (9.0, 3.0)
    assert (table["ran db"], table["waited db"]) == (4.0, 0.5)
    assert (table["slices server"], table["slices db"]) == (120000, 30000)
    assert (table["ran loop"], table["waited loop"], table["slices loop"]) == (3.0, 0.25, 40000)
    # the whole machine: what went to neither the class nor the kernel (another job beside
    # the run, which the model then says)
    tally.machine = (35.25, 0.0, 20.0, 3.0)  # busy, steal, idle, pressure
    path.write_text(load_test.report("PostgreSQL", tally, 10.0, 0, 16, 2) + "\n")
    table = queue_model.measured_p95(path)["PostgreSQL"]
    assert table["cpu elsewhere"] == pytest.approx(35.25 - 14.25 - 9.0 - 4.0)
    # and the cores' busy time, and the time some task waited for one (its pressure)
    assert (table["busy"], table["pressure"]) == (35.25, 3.0)


def test_a_running_total_is_binned_by_the_classs_time():
    """run_queue.binned: each bin's growth of a total sampled at uneven times, the edges
    interpolated between the samples (before the first: the first's)."""
    import run_queue

    series = [(10.0, {"a": 0.0, "b": 1.0}), (10.25, {"a": 0.1, "b": 1.0}),
              (10.5, {"a": 0.3, "b": 1.5}), (11.0, {"a": 0.4, "b": 1.5})]  # fmt: skip
    assert run_queue.binned(series, 10.0, 0.25) == {
        "a": pytest.approx([0.1, 0.2, 0.05, 0.05]), "b": pytest.approx([0.0, 0.5, 0.0, 0.0])
    }  # fmt: skip
    # from before the first sample: nothing grew there
    assert run_queue.binned(series, 9.5, 0.5)["a"] == pytest.approx([0.0, 0.3, 0.1])
    assert run_queue.binned([], 0.0, 0.25) == {}


def test_the_run_queue_watch_tells_a_groups_cpu_by_the_classs_time():
    """RunQueueWatch.ran_by_time: a process that burns 0.2 s of CPU after 0.3 s asleep
    shows its CPU in the bins after it began, and next to none before.  (Another process:
    a thread of the watch's own process would hold its interpreter and starve the polls.)"""
    import subprocess
    import sys
    import time

    import run_queue

    burner = subprocess.Popen(
        [sys.executable, "-c", (
            "import sys, time\n"
            "print('ready', flush=True); sys.stdin.readline()\n"
            "print('burning', flush=True); end = time.thread_time() + 0.2\n"
            "while time.thread_time() < end: pass\n"
            "print('done', flush=True); sys.stdin.readline()\n"
        )],
        stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True,
    )  # fmt: skip
    try:
        assert burner.stdout.readline().strip() == "ready"
        with run_queue.RunQueueWatch({"it": lambda: [burner.pid]}, poll_s=0.02) as watch:
            start = time.perf_counter()
            time.sleep(0.3)
            burner.stdin.write("go\n")
            burner.stdin.flush()
            assert burner.stdout.readline().strip() == "burning"
            began = time.perf_counter()
            assert burner.stdout.readline().strip() == "done"
            time.sleep(0.3)  # the burn's last bin whole before the watch ends
    finally:
        burner.stdin.write("end\n")
        burner.stdin.close()
        burner.wait(10)
    bins = watch.ran_by_time(start, 0.1)["it"]
    before = int((began - start) // 0.1)  # the whole bins before the burn began
    assert before >= 2 and sum(bins[:before]) < 0.03
    assert 0.17 <= sum(bins) <= 0.3


def test_a_runs_cpu_by_its_time_is_read_and_set_beside_the_models(tmp_path):
    """load_test.py --run-queue prints each group's CPU by the class's time; the model
    reads it and sets it beside its own threads' by window."""
    import load_test
    import request_waits

    tally = load_test.Tally()
    tally.latencies["GET /lab"] = [0.010, 0.020]
    tally.ran_by_time = {
        "server": [0.4] * 40, "load generator": [0.05] * 40, "PostgreSQL": [0.1] * 40,
    }  # fmt: skip
    path = tmp_path / "run.txt"
    path.write_text(load_test.report("PostgreSQL", tally, 10.0, 0, 16, 2) + "\n")
    measured = queue_model.ran_by_time(path)
    assert measured == {"server": [0.4] * 40, "client": [0.05] * 40, "db": [0.1] * 40}
    # the model's 0.25 s bins: the server 0.2 s a bin, the hashes 1 s in its first bin
    bins = {(index, "server"): (0.2, 0.0) for index in range(40)}
    bins[0, "hash"] = (1.0, 0.0)
    lines = request_waits.ran_report(bins, 0.25, measured, load_test.RUN_QUEUE_BIN_S)
    start = next(line for line in lines if line.strip().startswith("start"))
    # 0-5 s: the model's server 20 bins × 0.2 + 1 s of hashes; the run's 20 × 0.4
    assert "5.00 |  8.00" in start and "0.00 |  1.00" in start and "0.00 |  2.00" in start
    assert start.rstrip().endswith("5.00 | 11.00")
    # a window cut at the last bin either has (part A: 5-10 s), a window after it none
    assert any(line.strip().startswith("part A 5-10 s") for line in lines)
    assert not any(line.strip().startswith("part B") for line in lines)


def test_the_load_generators_cpu_per_frame_is_fitted_to_when_a_run_spent_it(tmp_path):
    """class_cpu.fitted_client_cpu: a run whose load generator spent 0.9× its requests'
    alone CPU, 0.1× its frames' and 0.02 s a bin besides, bin by bin, gives back 0.9, 0.1
    (a frame weight of 0.1 / 0.9) and a floor of 0.08 of a core over the class's time (its
    first request to its last answer, in whole bins); a run without requests' CPU tells
    none."""
    import p95_interval
    from class_cpu import fitted_client_cpu, route_of

    costs = {"GET /lab": (0.0, 0.0, 0.002), "POST /lab/sessions/{id}/turn": (0.0, 0.0, 0.003),
             queue_sim.STREAM: (0.0, 0.0, 0.0013)}  # fmt: skip
    rng = np.random.default_rng(5)
    t0 = 100.0
    lines, spent = [], []  # (when, CPU) as the load generator spent it
    for route, low, high, count in (("GET /lab", 0.0, 2.0, 100), ("/lab/sessions/7/turn",
                                     4.0, 8.0, 50)):  # fmt: skip
        name = "GET /lab" if route == "GET /lab" else "POST /lab/sessions/{id}/turn"
        method, path = ("GET", "/lab") if route == "GET /lab" else ("POST", route)
        for sent in np.sort(rng.uniform(low, high, count)):
            answered = sent + rng.uniform(0.01, 0.2)
            lines.append(f"{method} {path} {t0 + sent:.6f} {t0 + answered:.6f} 3\n")
            spent += [(sent, 0.9 * costs[name][2] / 2), (answered, 0.9 * costs[name][2] / 2)]
    lines.sort(key=lambda line: float(line.split()[2]))
    lines[0] = lines[0].replace(lines[0].split()[2], f"{t0:.6f}")  # the class's first
    spent[0] = (0.0, spent[0][1])
    positions = []
    for k in range(20):
        first = 3.0 + 0.1 * k
        positions.append(f"{k} heading 1 0 0 {t0 + first:.6f} {t0 + first + 5:.6f} 0\n")
        spent += [(when, 0.1 * 0.0013) for when in np.linspace(first, first + 5, 20)]
    client, stream = tmp_path / "client.txt", tmp_path / "stream.txt"
    client.write_text("".join(lines))
    stream.write_text("".join(positions))
    requests = [
        (route_of(method, url), sent, answered)
        for method, url, sent, answered, _ in p95_interval.client_lines(client)
    ]
    spans = [(float(fields[5]), float(fields[6]))
             for fields in map(str.split, stream.read_text().splitlines())]  # fmt: skip
    edges = np.arange(0.0, 10.25, 0.25)
    when, cpu = zip(*spent, strict=True)
    ran = np.histogram(when, bins=edges, weights=cpu)[0] + 0.02
    fit = fitted_client_cpu(list(ran), 0.25, requests, spans, 400, costs)
    assert (fit.requests, fit.frames) == (pytest.approx(0.9), pytest.approx(0.1))
    assert fit.frame_weight == pytest.approx(0.1 / 0.9, rel=1e-6)
    assert fit.floor == pytest.approx(0.08)
    last = max(answered for _, _, answered in requests) - t0
    assert last < fit.span_s <= last + 0.25 and fit.floor_s == pytest.approx(0.08 * fit.span_s)
    assert fitted_client_cpu([0.02] * 40, 0.25, requests, spans, 400, costs) is None


def test_a_runs_steal_is_reported_and_read_with_or_without_the_run_queue(tmp_path):
    """Every run says how long the hypervisor kept the cores from the class (steal) and its
    share of the time the class wanted them; over 5 % it notes that the p95s are the host's
    as much as the app's; the model reads both."""
    import load_test

    tally = load_test.Tally()
    tally.latencies["GET /lab"] = [0.010, 0.020]
    path = tmp_path / "run.txt"
    for busy, steal, share, noted in ((30.0, 0.6, 0.02, False), (27.0, 41.0, 0.60, True)):
        tally.machine = (busy, steal, 30.0, 5.0)  # no --run-queue: no groups, no machine line
        text = load_test.report("SQLite", tally, 40.0, 0, 16, 1)
        assert load_test.MACHINE_LABEL not in text
        [line] = [line for line in text.splitlines() if load_test.STEAL_LABEL in line]
        assert ("the host's as much as the app's" in line) is noted
        path.write_text(text + "\n")
        table = queue_model.measured_p95(path)["SQLite"]
        assert table["steal"] == steal
        assert table["steal share"] == pytest.approx(share, abs=0.005)
    # with --run-queue, the machine's line as well, and the steal read from its own line
    tally.run_queue = {"server": (14.0, 1.0, 1000)}
    path.write_text(load_test.report("SQLite", tally, 40.0, 0, 16, 1) + "\n")
    table = queue_model.measured_p95(path)["SQLite"]
    assert (table["steal"], table["busy"]) == (41.0, 27.0)
    # a run on a machine that was never read (no /proc): no steal line, nothing read
    tally.machine, tally.run_queue = (), {}
    assert load_test.STEAL_LABEL not in load_test.report("SQLite", tally, 40.0, 0, 16, 1)


def test_the_model_counts_a_wait_for_a_core_only_when_more_is_asked_than_there_are():
    """One student alone on two cores never waits for one; a class on half a core waits
    for it: its groups' waits are then the time they wanted beyond what the core gave."""
    alone = queue_sim.simulate(
        costs(), students=1, workers=1, cores=2.0, ramp=0.0, hash_s=2 * MS, teacher=False
    )
    # alone, a thread waits on the run queue only to be woken: the hand-off at each wake-up
    waits = {group: waited for group, (_, waited) in alone["run queue"].items()}
    assert waits.pop("server") == pytest.approx(
        alone["wake-ups"]["server"] * queue_sim.HANDOFF_S, rel=1e-9
    )
    assert all(waited == 0.0 for waited in waits.values())
    assert sum(ran for ran, _ in alone["run queue"].values()) == pytest.approx(
        sum(alone["cpu"].values()), rel=0.02
    )
    crowded = queue_sim.simulate(costs(), students=20, workers=1, cores=0.5, teacher=False)
    ran = sum(r for r, _ in crowded["run queue"].values())
    waited = sum(w for _, w in crowded["run queue"].values())
    assert ran == pytest.approx(sum(crowded["cpu"].values()), rel=0.02)
    # whatever ran on the half core took at least twice as long to be given
    assert waited >= ran
    # each hand-off of the interpreter to a thread that waited for it is a wake-up, its
    # thread on the run queue for at least the hand-off
    woken = crowded["wake-ups"]["server"]
    assert woken > 0
    assert crowded["run queue"]["server"][1] >= woken * queue_sim.HANDOFF_S


def test_a_thread_woken_to_a_free_interpreter_still_waits_to_reach_a_core():
    """``wake_free``: a thread woken from sleep (a thread-pool thread by the event loop,
    the loop by a socket) waits the hand-off to reach a core even when the interpreter is
    free.  A student alone: each request is its work and a whole number of hand-offs (the
    loop woken for the request and its answer, the thread for its work)."""
    kwargs = {"ramp": 0.0, "hash_s": 2 * MS, "teacher": False, "handoff_s": 1 * MS}
    woken = queue_sim.simulate(costs(), 1, 1, 2.0, **kwargs)
    at_once = queue_sim.simulate(costs(), 1, 1, 2.0, wake_free=False, **kwargs)
    for route in ("GET /lab", "POST /lab/sessions/{id}/csv"):
        extra = np.array(woken["latencies"][route]) - np.array(at_once["latencies"][route])
        hand_offs = extra / (1 * MS)
        assert np.all(hand_offs >= 2.9), route  # the loop twice and the thread at least
        assert hand_offs == pytest.approx(np.round(hand_offs), abs=1e-6), route
    assert woken["cpu"] == pytest.approx(at_once["cpu"])  # waited, not spent


CALLING_SCRIPT = """
import sqlite3, sys
connection = sqlite3.connect(":memory:")
connection.execute("CREATE TABLE t (x)")
cursor = connection.cursor()
cursor.executemany("INSERT INTO t VALUES (?)", [(i,) for i in range(50_000)])
cursor.execute("SELECT sum(x) FROM t")  # tens of ms: the whole table
cursor.fetchone()
"""


def test_the_sqlite_calls_probe_writes_each_calls_cpu(tmp_path):
    """``GYROLAB_BENCH_SQLITE_CALLS``: one line per call that runs the database (the
    connection's execute, the cursor's execute, executemany and fetches), its CPU in µs."""
    import subprocess

    probe = Path(queue_model.__file__).parent / "probe"
    calls = tmp_path / "calls.txt"
    env = {**os.environ, "PYTHONPATH": str(probe), "GYROLAB_BENCH_SQLITE_CALLS": str(calls)}
    subprocess.run([sys.executable, "-c", CALLING_SCRIPT], env=env, check=True, timeout=60)
    spent = [float(line) for line in calls.read_text().split()]
    assert len(spent) == 4  # CREATE, executemany, SELECT, fetchone
    assert all(value >= 0 for value in spent)
    assert spent[1] > 1000 and spent[2] > 100  # 50,000 inserts; a sum over them


def test_a_call_hands_the_interpreter_on_with_the_chance_of_its_length():
    """bench_handoffs.py: the chance for the app's calls is the measured curve at each
    call's length (linear between its points, flat beyond), averaged; and the measurement
    itself gives a chance and a call's CPU."""
    import bench_handoffs

    curve = [(10e-6, 0.0), (60e-6, 1.0)]
    calls = np.array([5e-6, 10e-6, 35e-6, 60e-6, 200e-6])
    # 0, 0, 0.5, 1, 1
    assert bench_handoffs.call_handoff_chance(curve, calls) == pytest.approx(2.5 / 5)
    chance, spent = bench_handoffs.call_handoffs(rows=200, count=50)
    assert 0.0 <= chance <= 1.0
    assert 0.0 < spent < 0.01


def test_the_hand_off_is_measured_at_the_apps_switch_interval_and_missed_releases_apart():
    """bench_handoffs.py times the interpreter's hand-off as the app's workers run: at the
    settings' switch interval (the process's own put back after), and only over the
    releases the waiting thread took.  At Python's 5 ms with 2 ms holds the waiter slept up
    to 5 ms between its asks, and each release it missed added a whole hold to the mean:
    130-194 µs where the app's 1 ms gave 16-21 µs (bench/README.md, thirty-eighth part).
    A call of a few µs (an empty table) is over before the waiter reaches a core: missed,
    not a hand-off of a millisecond."""
    import bench_handoffs

    from app.config import Settings

    interval = sys.getswitchinterval()
    try:
        sys.setswitchinterval(0.005)
        measured = bench_handoffs.measure_handoffs(count=30)
        assert sys.getswitchinterval() == 0.005  # put back
        assert measured.switch_interval_s == Settings().switch_interval_ms / 1000
        assert len(measured.gaps) + measured.missed == 30
        assert all(gap > 0 for gap in measured.gaps)
        empty = bench_handoffs.measure_handoffs(count=30, switch_interval_s=0.002, rows=0)
        assert empty.switch_interval_s == 0.002 and sys.getswitchinterval() == 0.005
        # each release is a gap (the waiter got in during A's call) or a miss, counted
        # apart (as a gap, a miss would be A's whole next hold).  How many are missed is
        # the machine's: 23-30 of 30 on quiet fresh clones, 13 on a CI run beside the
        # suite's other workers -- the test holds the accounting, not the share
        assert len(empty.gaps) + empty.missed == 30
        assert np.all(empty.gaps >= 0), empty
    finally:
        sys.setswitchinterval(interval)


def test_the_thread_beside_the_work_keeps_only_its_first_reading_after_each_wait():
    """bench_handoffs.py's waiting thread reads the clock millions of times a second; it
    keeps only the first reading after each wait (a minute of a stalled host grew a load
    test's measurement to 24 GB) -- and among those is every reading a hand-off is measured
    by: the first after each release of the interpreter, as every reading kept would give
    it, at the interpreter's default switch interval and at the app's 1 ms."""
    import bisect

    import bench_handoffs

    def sleeper() -> None:  # the interpreter free for 0.3 s: the reader spins all along
        time.sleep(0.3)

    marks = bench_handoffs.beside_a_waiting_thread(sleeper)
    assert len(marks) < 30_000  # kept: one per wait (≤ a few thousand a second), not millions
    assert marks == sorted(marks)

    connection = bench_handoffs.table_of(20_000)
    releases: list[float] = []

    def releasing() -> None:
        for _ in range(20):
            busy_until = time.perf_counter() + 0.002
            while time.perf_counter() < busy_until:  # the reader waits meanwhile
                pass
            releases.append(time.perf_counter())
            connection.execute("SELECT sum(x) FROM t").fetchone()

    interval = sys.getswitchinterval()
    try:
        for switch_interval_s in (0.005, 0.001):
            sys.setswitchinterval(switch_interval_s)
            releases.clear()
            every = bench_handoffs.beside_a_waiting_thread(releasing, resumed_after_s=0.0)
            gap = bench_handoffs.RESUMED_AFTER_S
            pairs = zip(every, every[1:], strict=False)
            kept = [after for before, after in pairs if after - before > gap]
            for released in releases:
                first = bisect.bisect_right(every, released)
                if first < len(every):  # the reader ran again before the end
                    assert kept[bisect.bisect_right(kept, released)] == every[first]
    finally:
        sys.setswitchinterval(interval)
        connection.close()


def test_each_trip_is_a_pool_thread_between_steps_on_the_loop():
    """``trips_in_turn`` (the default since 2026-12-05): a request's four trips are four
    pieces of its thread work, each a thread woken for it, with the coroutine's steps on
    the event loop before, between and after them; a write's locked part is one piece of
    its own, the second, and holds the lock alone.  Alone, the request still costs only its
    CPU; each piece and each step is a wake-up, so with a hand-off of 0.1 ms it pays seven
    more than the model before (4 pieces and 5 steps against its 2 threads' stages: before
    the lock and in it)."""
    route = "POST /lab/sessions/{id}/csv"
    table = costs()
    log: list = []
    quiet = {"ramp": 0.0, "teacher": False, "locked_shares": {route: 0.5}}
    turned = queue_sim.simulate(table, 1, 1, 2.0, wake_free=False, stage_log=log, **quiet)
    stages = dict(log)[route]
    inside = stages[stages.index("enter") + 1 : stages.index("db")]
    assert inside == [
        "loop step", "server piece", "loop step", "lock piece", "loop step", "server piece",
        "loop step", "server piece", "loop step",
    ]  # fmt: skip
    assert turned["latencies"][route] == pytest.approx([7 * MS] * 2, abs=1e-5)
    assert np.sum(np.isclose(turned["lock held"], 1.5 * MS, atol=1e-5)) == 2  # two saves
    woken = {"wake_free": True, "handoff_s": 0.1 * MS, **quiet}
    one_thread = queue_sim.simulate(table, 1, 1, 2.0, trips_in_turn=False, **woken)
    in_turn = queue_sim.simulate(table, 1, 1, 2.0, **woken)
    extra = np.array(in_turn["latencies"][route]) - np.array(one_thread["latencies"][route])
    assert extra == pytest.approx([7 * 0.1 * MS] * 2, abs=1e-5)


def test_postgresqls_round_trips_are_shared_among_a_requests_trips():
    """On PostgreSQL each piece makes its share of the request's ten round trips: alone,
    a request's latency is still its CPU and one round trip per call."""
    alone = {"ramp": 0.0, "teacher": False, "round_trip_s": 0.1 * MS, "wake_free": False}
    log: list = []
    postgres = queue_sim.simulate(costs(), 1, 1, 2.0, one_writer=False, stage_log=log, **alone)
    for route in ("GET /lab/sessions/{id}", "POST /lab/sessions/{id}/csv"):
        assert postgres["latencies"][route] == pytest.approx([8 * MS] * 2, abs=1e-5)
        stages = dict(log)[route]
        assert stages.count("wait") == 10 and stages.count("loop step") == 5


def test_a_log_in_on_postgresql_makes_its_last_round_trips_after_the_hash():
    """The app writes a log-in's session row after the password hash, its work place given
    back: the model's log-in makes its last ``LOGIN_TRIPS_AFTER_HASH`` round trips after
    the hash (0: all before it, the model before).  Alone, its latency is the same either
    way: its CPU, its hash and one round trip per call."""
    alone = {"ramp": 0.0, "teacher": False, "round_trip_s": 0.1 * MS, "wake_free": False}
    login = "POST /login"
    latencies = {}
    for after in (0, queue_sim.LOGIN_TRIPS_AFTER_HASH):
        log: list = []
        result = queue_sim.simulate(
            costs(), 1, 1, 2.0, one_writer=False, hash_s=2 * MS, stage_log=log,
            login_trips_after_hash=after, **alone,
        )  # fmt: skip
        stages = dict(log)[login]
        assert stages.count("wait") == 10  # the route's ten calls, each a round trip
        assert stages[stages.index("hash") :].count("wait") == after
        assert stages.index("give way") < stages.index("hash")
        latencies[after] = result["latencies"][login]
    # 2 client, 1 loop, 1 thread, 2 hash, 1 database, 10 round trips of 0.1 ms
    assert latencies[0] == pytest.approx([8 * MS], abs=1e-5)
    assert latencies[queue_sim.LOGIN_TRIPS_AFTER_HASH] == pytest.approx(latencies[0], abs=1e-5)


@pytest.mark.postgres_only
def test_a_log_ins_round_trips_after_its_hash_are_the_models(client):
    """The model's ``LOGIN_TRIPS_AFTER_HASH`` is what the app does: after a log-in's
    password check, its round trips to PostgreSQL -- a connection's ping, BEGIN, each
    statement, COMMIT -- counted as SQLAlchemy sends them."""
    import threading

    from sqlalchemy import event

    import app.accounts.security as security
    from app.config import get_settings
    from app.db import engine_for
    from app.models import Role
    from tests.factories import PASSWORD, csrf_from, make_user

    make_user("counted", Role.student)
    token = csrf_from(client, "/login")
    sent: list[tuple[int, str]] = []  # (thread, what): the log-in's own thread's are counted
    engine = engine_for(get_settings().database_url)

    def note(what: str) -> None:
        sent.append((threading.get_ident(), what))

    listeners = {
        "before_cursor_execute": lambda *args: note(args[2].split()[0].upper()),
        "begin": lambda *args: note("BEGIN"),
        "commit": lambda *args: note("COMMIT"),
    }
    for name, listener in listeners.items():
        event.listen(engine, name, listener)
    checked = security.check_password

    def marked(*args, **kwargs):
        note("hash")
        return checked(*args, **kwargs)

    try:
        with pytest.MonkeyPatch.context() as patch:
            patch.setattr(security, "check_password", marked)
            answer = client.post(
                "/login",
                data={"username": "counted", "password": PASSWORD, "csrf_token": token},
            )
    finally:
        for name, listener in listeners.items():
            event.remove(engine, name, listener)
    assert answer.status_code == 303
    [(hashing, _)] = [entry for entry in sent if entry[1] == "hash"]
    mine = [what for thread, what in sent if thread == hashing]
    after = mine[mine.index("hash") + 1 :]
    assert "INSERT" in after and after[-1] == "COMMIT"  # the session row, committed
    assert len(after) == queue_sim.LOGIN_TRIPS_AFTER_HASH, after


def test_the_cpu_scale_moves_the_servers_cpu_alone():
    """``--cpu-scale``: each request's server CPU (its loop's part and its own task's on
    the loop too) times the factor, in a route's list of requests as in a mean; the
    database's and the client's CPU, the calls, trips and the stream's split unchanged."""
    table = {
        "GET /lab": (4 * MS, 1 * MS, 2 * MS, 10.0, 2.0, 1 * MS),
        "POST /lab/sessions/{id}/csv": [(5 * MS, 0.0, 1 * MS, 8.0, 2.0, 2 * MS, 0.5 * MS)],
        queue_sim.STREAM_SPLIT: (0.3, 0.2, 0.5),
    }
    assert queue_model.with_cpu_scaled(table, 1.0) is table
    scaled = queue_model.with_cpu_scaled(table, 1.5)
    assert scaled["GET /lab"] == pytest.approx((6 * MS, 1 * MS, 2 * MS, 10.0, 2.0, 1.5 * MS))
    assert scaled["POST /lab/sessions/{id}/csv"][0] == pytest.approx(
        (7.5 * MS, 0.0, 1 * MS, 8.0, 2.0, 3 * MS, 0.75 * MS)
    )
    assert scaled[queue_sim.STREAM_SPLIT] == (0.3, 0.2, 0.5)


def test_a_wake_up_counts_itself_among_the_cores_asked_for():
    """``wake_counts_itself`` (the default since 2026-12-05): bench_handoffs.py timed a
    wake-up with the cores' spinners and the waking thread all asking, so with both cores
    busy a woken thread already waits (half a core beyond).  Eight students on two cores
    pay for it; without the woken thread counted (the model before) the two busy cores
    cost it nothing, and the class is no slower for ``wake_busy_s``.  Alone, neither pays.
    (The log-ins' round trips all inside their work places, so that the worker's two
    places keep two threads at most asking for the two cores.)"""

    def mean_latency(students: int, busy: float, counts_itself: bool) -> float:
        result = queue_sim.simulate(
            costs(), students, 1, 2.0, ramp=0.0, teacher=False, one_writer=False,
            wake_busy_s=busy, wake_counts_itself=counts_itself, login_trips_after_hash=0,
        )  # fmt: skip
        return float(np.mean(result["latencies"]["GET /lab/sessions/{id}"]))

    assert mean_latency(8, 1 * MS, True) > mean_latency(8, 0.0, True) + 5 * MS
    assert mean_latency(8, 1 * MS, False) < mean_latency(8, 0.0, False) + 1 * MS
    for counts_itself in (True, False):
        assert mean_latency(1, 1 * MS, counts_itself) == mean_latency(1, 0.0, counts_itself)


def test_the_departments_workers_share_their_cores(capsys):
    """``department`` simulates a slice of the machine: four workers, each with its share
    of the students, on four cores together, where a worker's burst borrows a core another
    leaves idle.  Each worker alone on a core of its own (``pooled=1``, the model before)
    has no such core to borrow: on a class that keeps a core busy, its p95 is higher."""

    def worst(pooled: int) -> float:
        queue_model.department(costs(server=8 * MS), 2 * MS, 40, [4], 1.0, {}, pooled=pooled)
        row = capsys.readouterr().out.strip().splitlines()[-1].split()
        assert row[:2] == ["4", "10"]  # 4 workers, 10 students each
        return float(row[-1])

    assert worst(4) < worst(1)


def test_the_model_says_how_long_some_thread_waited_for_a_core():
    """ "pressure": the time some thread waited for a core, as /proc/pressure/cpu's "some"
    counts it, and the cores' busy time.  A student alone on two cores, each woken thread
    reaching a core at once: no one ever waits, and the cores are busy for the CPU spent.
    A class of 20 on two cores waits only while a woken thread reaches one (the hand-offs);
    on half a core, some thread waits for half the class, twenty times as long."""
    alone = queue_sim.simulate(
        costs(), 1, 1, 2.0, ramp=0.0, hash_s=2 * MS, teacher=False, wake_free=False
    )
    some, busy = alone["pressure"]
    assert some == 0.0
    assert busy == pytest.approx(sum(alone["cpu"].values()), rel=0.02)

    def class_on(cores: float) -> dict:
        return queue_sim.simulate(costs(), students=20, workers=1, cores=cores, teacher=False)

    roomy, crowded = class_on(2.0), class_on(0.5)
    assert 0 < roomy["pressure"][0] < 0.05 * roomy["wall"]
    assert crowded["pressure"][0] > 20 * roomy["pressure"][0]
    assert crowded["pressure"][0] > 0.4 * crowded["wall"]
    for result in (roomy, crowded):
        assert result["pressure"][1] == pytest.approx(sum(result["cpu"].values()), rel=0.02)
    assert crowded["pressure"][1] <= 0.5 * crowded["wall"] + 1e-9


def test_a_thread_woken_through_a_socket_can_wait_on_its_wakers_core():
    """``socket_stacking``: the load generator woken by an answer waits on the event
    loop's core while the loop goes on with its callbacks (at most a slice), and the loop
    woken by a request while the load generator goes on.  Alone, the loop has nothing left
    when it answers: nothing changes.  In a class the load generator waits for a core
    longer, never more than a slice for each of its wake-ups."""
    alone = {"ramp": 0.0, "teacher": False}
    assert (
        queue_sim.simulate(costs(), 1, 1, 2.0, socket_stacking=True, **alone)["latencies"]
        == queue_sim.simulate(costs(), 1, 1, 2.0, **alone)["latencies"]
    )
    plain = queue_sim.simulate(costs(), 20, 1, 2.0, teacher=False)
    stacked = queue_sim.simulate(costs(), 20, 1, 2.0, teacher=False, socket_stacking=True)
    waited, plain_waited = stacked["run queue"]["client"][1], plain["run queue"]["client"][1]
    assert waited > 2 * plain_waited
    answers = sum(len(v) for route, v in stacked["latencies"].items() if route != queue_sim.SAVED)
    frames = 20 * 8 * queue_sim.FRAMES_PER_POSITION
    assert waited - plain_waited <= (answers + frames) * queue_sim.STACKED_SLICE_S


def test_a_thread_waiting_for_the_interpreter_wakes_once_a_switch_interval():
    """CPython's take_gil waits for the interpreter in timed waits of one switch interval,
    so each waiting thread is put on a core once an interval (bench_gil_wakes.py: ≈ 1,000
    a second each at 1 ms).  The model counts them beside its other wake-ups: the time its
    threads waited for the interpreter over the interval -- the requests' own waits, the
    event loop's and the streams'; none for a lone student or under processor sharing."""
    table = costs(server=20 * MS, db=0.0, client=0.0, calls=0.0, trips=0.0, loop=0.0)

    def run(students: int, interval: float) -> dict:
        return queue_sim.simulate(
            table, students, 1, 2.0, ramp=0.0, teacher=False, work_places=0,
            switch_interval_s=interval,
        )  # fmt: skip

    for interval in (1 * MS, 5 * MS):
        result = run(2, interval)
        woken = result["waiting wake-ups"]
        requests_waited = sum(row[2] for rows in result["server"].values() for row in rows)
        assert requests_waited > 0.1
        others = woken["server"] * interval - requests_waited  # the loop's and the streams'
        assert woken["loop"] * interval <= others <= woken["loop"] * interval + 0.05
    assert run(1, 1 * MS)["waiting wake-ups"] == {}
    assert run(2, 0.0)["waiting wake-ups"] == {}


def test_the_waiting_threads_wake_at_each_switch_interval():
    """bench_gil_wakes.py on this machine's CPython: three threads wanting the interpreter
    wake from their timed waits far more often at a 1 ms switch interval than at 20 ms
    (about once an interval each, not once a turn).

    Counted as voluntary switches: a crowded host (the suite's other worker, browsers)
    preempts the spinning threads too, a few hundred times a second each, which made the
    times on a core (``slices``) only 1.9x apart in one fresh-clone run; the wake-ups
    were 10-20x apart idle and beside six busy loops on two cores (≈ 390 and 40 a second).
    A host that starves the 1 ms run of a core for part of its 0.3 s can only lower its
    count (3.9x apart once, in a fresh-clone run): the pair is measured again, up to three
    times, until the interpreter's behaviour shows -- never a higher count than it gives.
    """
    import bench_gil_wakes

    before = sys.getswitchinterval()
    for _attempt in range(3):
        short = bench_gil_wakes.contended(3, 0.001, seconds=0.3)
        long = bench_gil_wakes.contended(3, 0.020, seconds=0.3)
        if short.sleeps_per_thread_s > 4 * long.sleeps_per_thread_s:
            break
    assert short.sleeps_per_thread_s > 4 * long.sleeps_per_thread_s
    assert short.sleeps_per_thread_s > 150
    assert short.adds_per_s > 0 and sys.getswitchinterval() == before  # restored


def test_threads_on_their_own_cores_leave_a_core_idle_until_balanced():
    """``per_core``: three log-ins' hashes at once on two cores.  Shared evenly (the fluid
    model) each runs at two thirds of a core and all end together; each on its own core,
    the third shares a core with one of the others while the lone one ends first, and the
    pair goes on sharing their core until balancing moves one of them to the idle one (at
    once with ``balance_s`` 0; never within the run with a long ``balance_s``).  The cores'
    busy time is the same; only the idle core's time differs."""
    hash_s = 100 * MS
    table = costs(server=0.1 * MS, db=0.0, client=0.0, calls=0.0, trips=1.0)
    table[queue_sim.LOGIN] = (hash_s + 0.1 * MS, 0.0, 0.0, 0.0, 1.0, 0.0)

    def log_ins(**options) -> tuple[list[float], dict]:
        result = queue_sim.simulate(
            table, 3, 1, 2.0, starts=[0.0] * 3, teacher=False, clients_elsewhere=True,
            hash_s=hash_s, **options,
        )  # fmt: skip
        return sorted(result["latencies"][queue_sim.LOGIN]), result

    shared, fluid = log_ins(per_core=False)
    balanced, at_once = log_ins()
    stuck, never = log_ins(balance_s=10.0)
    assert shared == pytest.approx([0.150] * 3, abs=5 * MS)
    assert balanced == pytest.approx([0.100, 0.150, 0.150], abs=5 * MS)
    assert stuck == pytest.approx([0.100, 0.200, 0.200], abs=5 * MS)
    busy = [result["pressure"][1] for result in (fluid, at_once, never)]
    assert busy == pytest.approx([busy[0]] * 3, rel=1e-3)
    # the stuck pair waited 100 ms each for their core while the other idled
    assert never["run queue"]["server"][1] - at_once["run queue"]["server"][1] == pytest.approx(
        0.100, abs=5 * MS
    )
    # and what a kernel trace says of it (``sched_trace.busy_while_waiting``): while some
    # thread waited, both cores were busy -- but for the stuck pair's last 100 ms, on one
    # (with none busy: the wakes of the requests before, a thread woken onto an idle core
    # not yet on it)
    waited = [result["busy while waiting"] for result in (fluid, at_once, never)]
    assert [v for w in waited for v in (w.get(2, 0.0), w.get(1, 0.0))] == pytest.approx(
        [0.150, 0.0, 0.100, 0.0, 0.100, 0.100], abs=12 * MS
    )


def test_the_threads_time_run_and_waited_is_told_by_the_classs_time():
    """The model's "threads by time": three log-ins' 300 ms hashes at once on two cores,
    each thread on a core and never balanced.  The lone hash runs alone to 0.3 s; the
    other two share a core to 0.6 s, each waiting half of that.  In bins of 0.25 s the
    hashes ran 0.5, 0.3 and 0.1 s and waited 0.25, 0.25 and 0.1 s (a step over a bin's
    end split there); the bins add up to "run queue", where the hashes are the server's."""
    hash_s = 300 * MS
    table = costs(server=0.1 * MS, db=0.0, client=0.0, calls=0.0, trips=1.0)
    table[queue_sim.LOGIN] = (hash_s + 0.1 * MS, 0.0, 0.0, 0.0, 1.0, 0.0)
    result = queue_sim.simulate(
        table, 3, 1, 2.0, starts=[0.0] * 3, teacher=False, clients_elsewhere=True,
        hash_s=hash_s, balance_s=10.0,
    )  # fmt: skip
    bins = result["threads by time"]
    assert queue_sim.TIMELINE_BIN_S == 0.25
    hashing = [bins.get((index, "hash"), (0.0, 0.0)) for index in range(4)]
    # (the hashes begin a few ms in: the log-in page and the log-in's own work come first)
    assert [ran for ran, _ in hashing] == pytest.approx([0.5, 0.3, 0.1, 0.0], abs=10 * MS)
    assert [waited for _, waited in hashing] == pytest.approx([0.25, 0.25, 0.1, 0.0], abs=10 * MS)
    for group, (ran, waited) in result["run queue"].items():
        members = ("server", "hash") if group == "server" else (group,)
        cells = [cell for (_, of), cell in bins.items() if of in members]
        assert sum(c[0] for c in cells) == pytest.approx(ran, abs=1e-9)
        assert sum(c[1] for c in cells) == pytest.approx(waited, abs=1e-9)
    windows = request_waits.threads_by_window(bins, queue_sim.TIMELINE_BIN_S)
    assert windows["start", "hash"] == pytest.approx((0.9, 0.6), abs=10 * MS)
    assert windows["part A", "hash"] == (0.0, 0.0)
    report = request_waits.threads_report(bins, queue_sim.TIMELINE_BIN_S, "the model's threads")
    assert [line[2:8].strip() for line in report[1:]] == [n for n, _, _ in request_waits.WINDOWS]
    assert report[1].split(" · ")[1].split()[:3] == ["0.90", "/", "0.60"]  # the hashes


def test_a_yielding_hash_runs_on_what_the_other_threads_leave_of_its_core():
    """``yielding``: on one core, a log-in's 100 ms hash and a page's 20 ms of CPU that
    arrives 50 ms into it.  Shared evenly on the core, the page takes 40 ms; with the
    hash's pool yielding, the page has the core and takes its 20 ms, and the hash ends
    20 ms later instead of 20 ms sooner."""
    hash_s = 100 * MS
    table = costs(server=20 * MS, db=0.0, client=0.0, calls=0.0, trips=1.0)
    table[queue_sim.LOGIN] = (hash_s + 0.1 * MS, 0.0, 0.0, 0.0, 1.0, 0.0)

    def first_two(**options) -> tuple[list[float], list[float]]:
        result = queue_sim.simulate(
            table, 2, 1, 1.0, starts=[0.0, 0.05], teacher=False, clients_elsewhere=True,
            hash_s=hash_s, switch_interval_s=0.0, **options,
        )  # fmt: skip
        latencies = result["latencies"]
        return latencies["GET /login"], latencies[queue_sim.LOGIN]

    (pages, log_ins), (pages_yielded, log_ins_yielded) = first_two(), first_two(yielding=("hash",))
    assert pages == pytest.approx([20 * MS, 40 * MS], abs=1 * MS)
    assert pages_yielded == pytest.approx([20 * MS, 20 * MS], abs=1 * MS)
    assert log_ins_yielded[0] == pytest.approx(log_ins[0] + 20 * MS, abs=1 * MS)


def test_a_thread_woken_beside_a_yielding_hash_does_not_wait_for_its_core():
    """``yielding``: a thread woken (a round trip to PostgreSQL answered) goes before the
    long runners, so a busy wake-up counts only the other pools' threads.  Two cores, two
    log-ins' 100 ms hashes, and a page of 10 ms of CPU in five round trips that comes
    while both run; a busy wake-up is a whole slice when the cores are asked one beyond
    (``wake_busy_s`` = ``WAKE_SLICE_S``).  With the hashes yielding, the page takes its
    10 ms (and the round trips' 17 µs); were they counted, each round trip's two wake-ups
    would add 2 ms each (30 ms)."""
    hash_s = 100 * MS
    table = costs(server=10 * MS, db=0.0, client=0.0, calls=5.0, trips=1.0, loop=0.0)
    table[queue_sim.LOGIN] = (hash_s + 0.1 * MS, 0.0, 0.0, 0.0, 1.0, 0.0)
    result = queue_sim.simulate(
        table, 3, 1, 2.0, starts=[0.0, 0.0, 0.05], teacher=False, clients_elsewhere=True,
        hash_s=hash_s, switch_interval_s=0.0, one_writer=False, handoff_s=0.0,
        wake_busy_s=queue_sim.WAKE_SLICE_S, yielding=("hash",),
    )  # fmt: skip
    during = [latency for route, sent, latency in result["timeline"]
              if route == "GET /login" and sent >= 0.05]  # fmt: skip
    assert during == pytest.approx([10 * MS], abs=0.5 * MS)


@pytest.mark.parametrize(("share", "page_ms"), [(0.0, 100.0), (0.5, 400 / 3), (1.0, 200.0)])
def test_a_yielding_hash_keeps_its_least_share_of_its_core(share, page_ms):
    """``yield_share``: on one core, a log-in's 100 ms hash (yielding) beside a page of
    100 ms of CPU, both sent at once.  The hash gets ``share`` of an even share (half the
    core) while the page runs: the page ends at 100 ms / (1 − share / 2) -- 100 ms with
    nothing left to the hash, 133 ms with a quarter of the core, 200 ms shared evenly --
    and the log-in, whose work is the same 100 ms, at 200 ms whatever the share."""
    hash_s = 100 * MS
    table = costs(server=100 * MS, db=0.0, client=0.0, calls=0.0, trips=1.0, loop=0.0)
    table[queue_sim.LOGIN] = (hash_s + 1e-6, 0.0, 0.0, 0.0, 1.0, 0.0)
    arrivals = [(0.0, "request", queue_sim.LOGIN, None), (0.0, "request", "GET /lab", None)]
    result = queue_sim.simulate(
        table, 0, 1, 1.0, arrivals=arrivals, clients_elsewhere=True, hash_s=hash_s,
        switch_interval_s=0.0, one_writer=False, handoff_s=0.0, wake_busy_s=0.0,
        yielding=("hash",), yield_share=share,
    )  # fmt: skip
    assert result["latencies"]["GET /lab"] == pytest.approx([page_ms * MS], abs=0.5 * MS)
    assert result["latencies"][queue_sim.LOGIN] == pytest.approx([200 * MS], abs=0.5 * MS)
