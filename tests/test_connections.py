"""Which worker each browser's connections reached in a load test (``bench/connections.py``),
the probe's line for each WebSocket, and the model's students placed on those workers."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "bench"))

import class_cpu  # noqa: E402  (bench/)
import connections  # noqa: E402
import queue_sim  # noqa: E402
import request_waits  # noqa: E402

from tests.probed_apps import run_probed  # noqa: E402
from tests.test_queue_model import MS, PROBED_STREAM, costs  # noqa: E402


def test_the_probe_names_the_worker_each_websocket_reached(tmp_path):
    """``GYROLAB_BENCH_SERVER_TIMES`` gets ``WS path - - began pid`` when a WebSocket
    connects; the readers of the requests' lines leave it out."""
    out = tmp_path / "times.txt"
    run_probed(PROBED_STREAM, ["asyncio.to_thread(talk)"], {"GYROLAB_BENCH_SERVER_TIMES": str(out)})
    (line,) = out.read_text().splitlines()
    kind, path, took, waited, began, pid = line.split()
    assert (kind, path, took, waited) == ("WS", "/lab/sessions/7/stream", "-", "-")
    assert float(began) > 0 and int(pid) > 0
    out.write_text(f"GET /lab 2.0 0.1 {began} {pid}\n" + line + "\n")
    assert list(class_cpu.server_times(out)) == ["GET /lab"]
    assert class_cpu.worker_shares(out) == [1.0]
    client = tmp_path / "client.txt"
    client.write_text(f"GET /lab {float(began) - 0.001} {float(began) + 0.01} 0\n")
    assert request_waits.outside_the_app(client, out)["GET /lab"][0] == 1


def _runs_files(tmp_path: Path) -> tuple[Path, Path]:
    """A run of two students and the teacher on workers 41 and 42: student 0's requests
    answered by 41 and its stream by 42, student 1's the other way round, the teacher's
    by 41; one server line nobody the load generator timed asked for."""
    server = [
        "GET /login 1.0 0.1 10.001 41",  # student 0
        "GET /login 1.0 0.1 10.002 42",  # student 1
        "GET /lab/sessions/5 3.0 0.1 10.101 41",
        "GET /lab/sessions/6 3.0 0.1 10.102 42",
        "WS /lab/sessions/5/stream - - 10.200 42",
        "WS /lab/sessions/6/stream - - 10.201 41",
        "POST /lab/sessions/5/turn 2.0 0.1 10.301 41",
        "GET /courses/1/assignments/1 9.0 0.1 10.400 41",  # the teacher
        "GET /lab 1.0 0.1 10.500 42",  # a request the load generator did not time
    ]
    client = [
        "GET /login 10.0005 10.0030 0",
        "GET /login 10.0015 10.0040 1",
        "GET /lab/sessions/5 10.1000 10.1100 0",
        "GET /lab/sessions/6 10.1000 10.1100 1",
        "POST /lab/sessions/5/turn 10.3000 10.3100 0",
        "GET /courses/1/assignments/1 10.3990 10.4200 teacher",
    ]
    (tmp_path / "server.txt").write_text("\n".join(server) + "\n")
    (tmp_path / "client.txt").write_text("\n".join(client) + "\n")
    return tmp_path / "server.txt", tmp_path / "client.txt"


def test_each_browsers_connections_are_the_workers_that_served_them(tmp_path):
    """A request is matched to the server's line of its method and path that began while
    it was on its way; a stream to its student by its session.  Worker 0 answered most."""
    server, client = _runs_files(tmp_path)
    placed = connections.connections_of(server, client)
    assert placed is not None and placed.workers == 2
    assert placed.http == {"0": 0, "1": 1, "teacher": 0}  # 41 answered 4 of 7 requests
    assert placed.websocket == {"0": 1, "1": 0}
    assert placed.of_students(2) == [(0, 1), (1, 0)]
    assert placed.of_students(3) is None  # student 2 unknown: not placed at all
    assert placed.shares(placed.http) == [0.5, 0.5]


def test_lines_that_do_not_name_the_worker_or_the_browser_place_nobody(tmp_path):
    server, client = _runs_files(tmp_path)
    client.write_text("GET /login 10.0005 10.0030\n")  # before the browser was named
    assert connections.connections_of(server, client) is None
    server.write_text("GET /login 1.0 0.1\n")  # before the worker was named
    assert connections.connections_of(server, client) is None


def test_students_placed_on_their_runs_workers_go_there_whatever_the_shares():
    """A class whose students all reached one of two workers waits as on one, whatever
    shares are given beside it; placed one on each in turn, it waits less."""

    def burst_p95(placed, shares=None):
        result = queue_sim.simulate(
            costs(), 50, 2, 2.0, one_writer=False, teacher=False, worker_shares=shares,
            student_workers=placed, per_core=False,  # the workers under test, not the cores
        )  # fmt: skip
        return np.percentile(result["latencies"]["POST /lab/sessions/{id}/csv"], 95)

    on_one = burst_p95([(0, 0)] * 50, shares=[0.5, 0.5])
    assert on_one == pytest.approx(burst_p95([(1, 1)] * 50), rel=0.02)
    assert on_one > 1.5 * burst_p95([(i % 2, i % 2) for i in range(50)], shares=[1.0, 0.0])


def test_the_teachers_worker_is_the_one_it_reached():
    """The teacher's dashboard, read on the worker every student is on, waits for them."""

    def dashboard_p95(teacher_worker):
        result = queue_sim.simulate(
            costs(), 60, 2, 2.0, one_writer=False, student_workers=[(0, 0)] * 60,
            teacher_worker=teacher_worker, per_core=False,  # the workers under test
        )  # fmt: skip
        return np.percentile(result["latencies"]["GET dashboard (teacher)"], 95)

    assert dashboard_p95(0) > 1.5 * dashboard_p95(1)


def test_the_database_servers_costs_add_up_to_what_its_processes_used():
    """PostgreSQL's CPU per request is measured one student at a time; a class's costs it
    less a request (3.0 s used against 4.0 s asked in a 60-student run): scaled to the
    run's, as the server's unseen part and the load generator's are."""
    lines = "\n".join(["http GET /lab/sessions/12 1.000 3.000 0"] * 10)
    seen = class_cpu.attributed_costs(lines)
    table = costs(server=10 * MS, db=2 * MS, loop=3 * MS, client=2 * MS)
    own = {"GET /lab/sessions/{id}": (2 * MS, 6 * MS)}
    used = {"server": 0.07, "client": 0.01, "db": 0.015}
    adjusted, _, _ = class_cpu.in_class(table, own, seen, used)
    assert 10 * adjusted["GET /lab/sessions/{id}"][1] == pytest.approx(used["db"])
    same, _, _ = class_cpu.in_class(table, own, seen, {**used, "db": 0.0})  # SQLite: none
    assert same["GET /lab/sessions/{id}"][1] == pytest.approx(2 * MS)
