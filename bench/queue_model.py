"""A queueing model of the load test: per-route p95 predicted from measured CPU per request.

    .venv/bin/python bench/queue_model.py [--students 60 120] [--backend sqlite|postgresql]
                                          [--measure 3] [--compare FILE ...]

1. Measure: the load test's own scenario (``load_test.student``) runs for ``--measure``
   students one after another -- nothing else runs -- against a real server, and every
   request's CPU is read: the server's (all its threads, ``/proc/<pid>/task/*/schedstat``,
   nanoseconds), PostgreSQL's (every ``postgres`` process) and the load generator's own
   (``time.process_time``).  What a student's stream costs besides its requests (frames,
   the saves at each position's end) is divided by the frames it received.
2. Predict: a discrete-event simulation replays the scenario for N students -- the same
   start times as the load test, each request's client work, then the server's, then
   PostgreSQL's, then the client's again; each stream position 15 frames 0.2 s apart --
   on processor-sharing pools: the load generator (one core: one Python thread), the
   server (one core per worker: the GIL), PostgreSQL; all on the machine's cores (when
   more is asked of them than they have, every pool slows in proportion).
3. Compare: ``--compare`` reads the tables ``load_test.py`` printed and puts each route's
   measured p95 beside the prediction.

What the model leaves out, on purpose: SQLite's one writer (its lock is held 0.2–6 ms a
write, ``bench/README.md``: < 5 % busy at 60 students), the write admission queue (8 per
worker) and the interpreter's 5 ms thread switch interval.  Where measured and predicted
part, those are the first suspects.
"""

from __future__ import annotations

import argparse
import asyncio
import heapq
import os
import random
import re
import sys
import tempfile
import time
from collections import defaultdict
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "bench"))

import load_test  # noqa: E402  (bench/, the script's folder)
from capacity import server_pids  # noqa: E402

from tests.e2e.conftest import running_server  # noqa: E402
from tests.pgserver import PostgresServer  # noqa: E402

FRAMES_PER_POSITION = 15  # 3 s of streaming (60 s at 20×), one frame every 0.2 s
FRAME_SECONDS = 0.2
TEACHER_PERIOD_S = 2.0
STREAM = "stream frame"


# --- 1. measuring CPU per request ----------------------------------------------------------


def thread_cpu(pids: list[int]) -> float:
    """CPU seconds of every thread of these processes (schedstat: nanoseconds)."""
    total = 0
    for pid in pids:
        for task in Path(f"/proc/{pid}/task").glob("*"):
            try:
                total += int((task / "schedstat").read_text().split()[0])
            except (OSError, ValueError, IndexError):
                continue
    return total / 1e9


def postgres_pids() -> list[int]:
    pids = []
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            try:
                if (entry / "comm").read_text().strip() == "postgres":
                    pids.append(int(entry.name))
            except OSError:
                continue
    return pids


class CostTally(load_test.Tally):
    """The load test's tally, also recording each request's CPU: server, database, client."""

    def __init__(self, server: list[int]):
        super().__init__()
        self.server = server
        self.costs: dict[str, list[tuple[float, float, float]]] = defaultdict(list)

    def snapshot(self) -> tuple[float, float]:
        return thread_cpu(self.server), thread_cpu(postgres_pids())

    async def request(self, client, method, url, route, ok=(200,), **kw):
        server0, pg0 = self.snapshot()
        client0 = time.process_time()
        try:
            return await super().request(client, method, url, route, ok=ok, **kw)
        finally:
            client_cpu = time.process_time() - client0
            server1, pg1 = self.snapshot()
            self.costs[route].append((server1 - server0, pg1 - pg0, client_cpu))

    def timed_total(self) -> np.ndarray:
        """(server, database, client) CPU of every timed request so far."""
        rows = [cost for values in self.costs.values() for cost in values]
        return np.sum(rows, axis=0) if rows else np.zeros(3)


def measure_costs(backend: str, students: int) -> dict[str, tuple[float, float, float]]:
    """Mean (server, database, client) CPU seconds per route and per stream frame."""
    args = argparse.Namespace(students=students, dwell=60.0, speed=20.0, ramp=0.0)
    with tempfile.TemporaryDirectory(prefix="gyrolab-model-") as var:
        pg = None
        database_url = f"sqlite:///{Path(var) / 'gyrolab.db'}"
        serve_args = ["--no-demo", "--no-access-log"]
        if backend == "postgresql":
            pg = PostgresServer().start(durable=True)
            database_url = pg.create_database("gyrolab_model")
            serve_args += ["--workers", "2"]
        try:
            env = {**os.environ, "GYROLAB_VAR_DIR": var, "GYROLAB_DATABASE_URL": database_url}
            course, assignment = load_test.seed(env, students + 1)
            url = database_url if backend == "postgresql" else None
            with running_server(Path(var), *serve_args, database_url=url) as server:
                pids = server_pids(server.process.pid)
                tally = CostTally(pids)
                stream = []

                async def everyone():
                    # a first student warms the server up (templates compiled, caches
                    # filled, connections opened): not counted
                    await load_test.student(
                        students, server.url, assignment, load_test.Tally(), args
                    )
                    for index in range(students):
                        before = np.array([*tally.snapshot(), time.process_time()])
                        timed = tally.timed_total()
                        frames = tally.frames
                        await load_test.student(index, server.url, assignment, tally, args)
                        after = np.array([*tally.snapshot(), time.process_time()])
                        outside = (after - before) - (tally.timed_total() - timed)
                        stream.append(outside / max(tally.frames - frames, 1))
                    await teacher_costs(tally, server.url, course, assignment)

                asyncio.run(everyone())
        finally:
            if pg is not None:
                pg.stop()
    costs = {route: tuple(np.mean(values, axis=0)) for route, values in tally.costs.items()}
    costs[STREAM] = tuple(np.mean(stream, axis=0))  # what a stream costs per frame received
    return costs


async def teacher_costs(tally, base: str, course: int, assignment: int) -> None:
    import httpx

    async with httpx.AsyncClient(base_url=base, timeout=120) as client:
        page = await client.get("/login")
        await client.post(
            "/login",
            data={
                "username": "teacher",
                "password": load_test.PASSWORD,
                "csrf_token": load_test.csrf(page.text),
            },
        )
        path = f"/courses/{course}/assignments/{assignment}"
        for _ in range(5):
            await tally.request(client, "GET", path, "GET dashboard (teacher)")


# --- 2. the simulation ---------------------------------------------------------------------


def student_script():
    """The load test's student, as (kind, route) steps."""
    yield "request", "GET /login"
    yield "request", "POST /login"
    yield "request", "GET /lab"
    yield "request", "POST /lab/sessions"
    yield "request", "GET /lab/sessions/{id}"
    for _part in load_test.PARTS:
        for position in range(1, 5):
            if position > 1:
                yield "request", "POST /lab/sessions/{id}/turn"
            yield "stream", STREAM
    yield "request", "POST /lab/sessions"
    for _part in load_test.PARTS:
        yield "request", "POST /lab/sessions/{id}/csv/preview"
        yield "request", "POST /lab/sessions/{id}/csv"
    yield "request", "GET /lab/sessions/{id}/results.json"
    yield "request", "GET /lab/sessions/{id}/results.json"
    yield "request", "GET /lab/sessions/{id}"
    yield "request", "POST /lab/sessions/{id}/submit"


# SQLite's one writer: a write request's server work runs holding the lock (log-in: only
# its last 2 ms -- the password hash comes first, without it).  PostgreSQL: row locks, none.
WRITES = {
    "POST /lab/sessions",
    "POST /lab/sessions/{id}/csv",
    "POST /lab/sessions/{id}/submit",
    "POST /lab/sessions/{id}/turn",
}
LOGIN_LOCKED_S = 0.002


class Job:
    __slots__ = ("pool", "left", "done")

    def __init__(self, pool: str, work: float, done):
        self.pool, self.left, self.done = pool, max(work, 1e-6), done


def simulate(
    costs,
    students: int,
    workers: int,
    cores: float,
    ramp: float = 3.0,
    one_writer: bool = True,
    clients_elsewhere: bool = False,
) -> dict:
    """Latencies per route of ``students`` running the scenario at once (seconds);
    ``one_writer``: write requests hold one lock while the server works on them;
    ``clients_elsewhere``: the clients are browsers on their own machines (a department),
    not a load generator sharing the server's cores."""
    capacity = {"client": float("inf") if clients_elsewhere else 1.0}
    capacity |= {"server": float(workers), "db": cores}
    now = 0.0
    jobs: list[Job] = []
    timers: list[tuple[float, int, object]] = []  # (time, tie-break, callback)
    order = iter(range(10**9))
    latencies: dict[str, list[float]] = defaultdict(list)
    finished = [0]

    def at(when: float, callback) -> None:
        heapq.heappush(timers, (when, next(order), callback))

    lock_queue: list = []
    lock_held = [False]

    def locked(start) -> None:
        if lock_held[0]:
            lock_queue.append(start)
        else:
            lock_held[0] = True
            start()

    def unlock() -> None:
        if lock_queue:
            lock_queue.pop(0)()
        else:
            lock_held[0] = False

    def phases(route: str, then) -> None:
        server, db, client = costs[route]
        stages = [("client", client / 2), ("server", server), ("db", db), ("client", client / 2)]
        if one_writer and route == "POST /login":
            stages[1:2] = [("server", server - LOGIN_LOCKED_S), ("lock", LOGIN_LOCKED_S)]
        elif one_writer and route in WRITES:
            stages[1] = ("lock", server)

        def run(i: int) -> None:
            if i == len(stages):
                then()
                return
            pool, work = stages[i]
            if pool == "lock":

                def release() -> None:
                    unlock()
                    run(i + 1)

                locked(lambda: jobs.append(Job("server", work, release)))
                return
            jobs.append(Job(pool, work, lambda: run(i + 1)))

        run(0)

    def request(route: str, then) -> None:
        began = now

        def answered() -> None:
            latencies[route].append(now - began)
            then()

        phases(route, answered)

    def run_student(script) -> None:
        step = next(script, None)
        if step is None:
            finished[0] += 1
            return
        kind, route = step
        if kind == "request":
            request(route, lambda: run_student(script))
            return
        left = [FRAMES_PER_POSITION]

        def frame_done() -> None:
            left[0] -= 1
            if left[0] == 0:
                run_student(script)

        for j in range(1, FRAMES_PER_POSITION + 1):
            at(now + j * FRAME_SECONDS, lambda: phases(STREAM, frame_done))

    def teacher() -> None:
        if finished[0] < students:
            request("GET dashboard (teacher)", lambda: at(now + TEACHER_PERIOD_S, teacher))

    for index in range(students):
        start = random.Random(index).uniform(0, ramp)  # the load test's ramp
        at(start, lambda: run_student(student_script()))
    at(0.0, teacher)

    while jobs or timers:
        counts = defaultdict(int)
        for job in jobs:
            counts[job.pool] += 1
        demand = {pool: min(n, capacity[pool]) for pool, n in counts.items()}
        shared = [pool for pool in demand if not (clients_elsewhere and pool == "client")]
        asked = sum(demand[pool] for pool in shared)
        scale = min(1.0, cores / asked) if asked else 1.0
        rate = {pool: demand[pool] * (scale if pool in shared else 1.0) / counts[pool]
                for pool in counts}  # fmt: skip
        next_done = min((job.left / rate[job.pool] for job in jobs), default=float("inf"))
        next_timer = timers[0][0] - now if timers else float("inf")
        step = min(next_done, next_timer)
        for job in jobs:
            job.left -= rate[job.pool] * step
        now += step
        done = [job for job in jobs if job.left <= 1e-9]
        jobs = [job for job in jobs if job.left > 1e-9]
        for job in done:
            job.done()
        while timers and timers[0][0] <= now + 1e-12:
            _, _, callback = heapq.heappop(timers)
            callback()
    return {"latencies": latencies, "wall": now}


# --- 3. measured against predicted -----------------------------------------------------------


def measured_p95(path: Path) -> dict[str, dict[int, float]]:
    """Per backend heading ("SQLite", "PostgreSQL") → route → p95 ms, from load_test's output."""
    tables: dict[str, dict[str, float]] = {}
    backend = None
    for line in path.read_text().splitlines():
        heading = re.match(r"### (\w+)", line)
        if heading:
            backend = heading.group(1)
            tables.setdefault(backend, {})
        cells = [cell.strip() for cell in line.strip().strip("|").split("|")]
        if backend and len(cells) == 6 and cells[1].isdigit():
            tables[backend][cells[0]] = float(cells[3])
    return tables


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--students", type=int, nargs="+", default=[60, 120])
    parser.add_argument("--backend", choices=("sqlite", "postgresql"), default="sqlite")
    parser.add_argument("--measure", type=int, default=3, help="students measured one by one")
    parser.add_argument("--compare", type=Path, nargs="*", default=[])
    parser.add_argument("--cores", type=float, default=float(os.cpu_count() or 1))
    parser.add_argument(
        "--department",
        type=int,
        nargs=2,
        metavar=("STUDENTS", "WORKERS"),
        help="also predict a department: STUDENTS at once on WORKERS workers, one core each "
        "(clients are browsers elsewhere; each worker simulated with its share of students)",
    )
    args = parser.parse_args()
    costs = measure_costs(args.backend, args.measure)
    print(f"CPU per request, {args.backend}, ms (server / database / load generator):")
    for route, (server, db, client) in sorted(costs.items()):
        print(f"  {route:42s} {server * 1000:7.2f} {db * 1000:7.2f} {client * 1000:7.2f}")
    workers = 1 if args.backend == "sqlite" else 2
    measured = {}
    for path in args.compare:
        for backend, table in measured_p95(path).items():
            measured[(backend, _students_of(path))] = table
    name = "SQLite" if args.backend == "sqlite" else "PostgreSQL"
    for students in args.students:
        result = simulate(costs, students, workers, args.cores, one_writer=workers == 1)
        table = measured.get((name, students), {})
        print(f"\n{students} students, {name}, {workers} worker(s): predicted wall "
              f"{result['wall']:.1f} s")  # fmt: skip
        print(f"  {'route':42s} {'p50':>6s} {'p95':>6s} {'measured p95':>13s} {'error':>6s}")
        for route, values in sorted(result["latencies"].items()):
            p50, p95 = (np.percentile(values, q) * 1000 for q in (50, 95))
            seen = table.get(route)
            error = f"{(p95 - seen) / seen * 100:+.0f} %" if seen else ""
            shown = f"{seen:.0f}" if seen else "-"
            print(f"  {route:42s} {p50:6.0f} {p95:6.0f} {shown:>13s} {error:>6s}")
    if args.department:
        students, workers = args.department
        share = -(-students // workers)
        result = simulate(costs, share, 1, 1.0, ramp=60.0, one_writer=False, clients_elsewhere=True)
        print(f"\ndepartment: {students} students within a minute on {workers} workers "
              f"({share} per worker and core, PostgreSQL's CPU included in that core)")  # fmt: skip
        for route, values in sorted(result["latencies"].items()):
            p50, p95 = (np.percentile(values, q) * 1000 for q in (50, 95))
            print(f"  {route:42s} {p50:6.0f} {p95:6.0f}")
    return 0


def _students_of(path: Path) -> int | None:
    found = re.search(r"; (\d+) students", path.read_text())
    return int(found.group(1)) if found else None


if __name__ == "__main__":
    sys.exit(main())
