"""A queueing model of the load test: per-route p95 predicted from measured CPU per request.

    .venv/bin/python bench/queue_model.py [--students 60 120] [--backend sqlite|postgresql]
                                          [--measure 3] [--compare FILE ...]
                                          [--costs FILE] [--department STUDENTS WORKERS ...]

1. Measure: the load test's own scenario (``load_test.student``) runs for ``--measure``
   students one after another -- nothing else runs -- against a real server, and every
   request's CPU is read: the server's (all its threads, ``/proc/<pid>/task/*/schedstat``,
   nanoseconds; a thread that ends keeps its last reading), of it the event loop's (the
   worker's main thread), PostgreSQL's (every ``postgres`` process) and the load
   generator's own (``time.process_time``).  A probe loaded into that server only
   (``bench/probe/sitecustomize.py``) counts each request's SQLite calls and thread-pool
   trips: the places where its threads give up the interpreter.  What a student's stream
   costs besides its requests (frames, the saves at each position's end) is divided by
   the frames it received.  The CPU of one password check is measured in process.
2. Predict: a discrete-event simulation replays the scenario for N students -- the same
   start times as the load test; each request's client work, the event loop's first half
   (the request read and routed), a work place (every HTTP request: 2 per worker,
   ``web.admission``; a write waiting over 50 ms for the write lock gives it back), a write
   place (state-changing requests: 8 per worker), the threads' work (on SQLite inside the
   one write lock for the writes; a log-in's password hash outside the interpreter, at most
   4 at once), the database's, the event loop's second half, the client's again; each
   stream position 15 frames 0.2 s apart. Each worker's interpreter runs one thread at a
   time, handed on round robin when a thread gives it up (at each counted call or trip; the
   event loop at each wake-up) or after 5 ms with others waiting (CPython's GIL); the event
   loop runs its tasks one by one. The load generator is one Python thread; every pool
   shares the machine's cores (when more is asked of them than they have, each slows in
   proportion).
3. Compare: ``--compare`` reads the tables ``load_test.py`` printed and puts each route's
   measured p95 beside the prediction, and the CPU the run used beside the CPU the costs
   ask for.

What the model still leaves out: the kernel's scheduling of threads on the cores (a
thread holding the interpreter can be descheduled), the cost of handing the interpreter
on, and that a class's requests cost less CPU each than one student's alone (the CPU
check: 0.64–0.87× on the server), and whatever makes the measured writes queue for their
places (p50 ≈ 0.5 s at 60 students on SQLite, where it predicts ≈ 0.15 s; it predicted a
cut in the writes' statements would halve their p95, and the load test did not move).
``bench/README.md`` has how far it is from measured.
"""

from __future__ import annotations

import argparse
import asyncio
import contextlib
import heapq
import json
import os
import random
import re
import struct
import sys
import tempfile
import time
from collections import defaultdict
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "bench"))

import load_test  # noqa: E402  (bench/, the script's folder)
from capacity import postgres_pids, server_pids, thread_cpu  # noqa: E402

from tests.e2e.conftest import running_server  # noqa: E402
from tests.pgserver import PostgresServer  # noqa: E402

FRAMES_PER_POSITION = 15  # 3 s of streaming (60 s at 20×), one frame every 0.2 s
FRAME_SECONDS = 0.2
TEACHER_PERIOD_S = 2.0
STREAM = "stream frame"


# --- 1. measuring CPU per request ----------------------------------------------------------


PROBE = Path(__file__).resolve().parent / "probe"  # its sitecustomize counts GIL releases


def thread_cpu_of(pid: int, tid: int) -> float:
    """CPU seconds of one thread (schedstat), 0 if it is gone."""
    try:
        return int(Path(f"/proc/{pid}/task/{tid}/schedstat").read_text().split()[0]) / 1e9
    except (OSError, ValueError, IndexError):
        return 0.0


def probe_counts(path: Path) -> tuple[int, int]:
    """The server's SQLite calls and thread-pool trips so far, as the probe counted them."""
    return struct.unpack("<2q", path.read_bytes())


class CostTally(load_test.Tally):
    """The load test's tally, also recording each request's cost: server CPU, database CPU,
    client CPU, and the times the server's thread gave up the interpreter."""

    def __init__(self, server: list[int], probe: Path):
        super().__init__()
        self.server, self.probe = server, probe
        self.costs: dict[str, list[tuple[float, ...]]] = defaultdict(list)
        self.threads: dict[tuple[int, str], float] = {}  # CPU last seen, ended threads kept

    def snapshot(self) -> tuple[float, float, float, float]:
        """Server CPU, database CPU, SQLite calls, thread-pool trips, the event loops' CPU
        (the workers' main
        threads) so far.  The thread pool's idle threads end after a while: each thread's
        CPU is kept as last seen, so an ended thread's work is not lost from the total."""
        for pid in self.server:
            for task in Path(f"/proc/{pid}/task").glob("*"):
                self.threads[pid, task.name] = thread_cpu_of(pid, int(task.name)) or (
                    self.threads.get((pid, task.name), 0.0)
                )
        loops = sum(self.threads.get((pid, str(pid)), 0.0) for pid in self.server)
        return (
            sum(self.threads.values()),
            thread_cpu(postgres_pids()),
            *probe_counts(self.probe),
            loops,
        )

    async def request(self, client, method, url, route, ok=(200,), **kw):
        before = self.snapshot()
        client0 = time.process_time()
        try:
            return await super().request(client, method, url, route, ok=ok, **kw)
        finally:
            client_cpu = time.process_time() - client0
            server, db, calls, trips, loop = np.subtract(self.snapshot(), before)
            self.costs[route].append((server, db, client_cpu, calls, trips, loop))

    def timed_total(self) -> np.ndarray:
        """(server, database, client, calls, trips, loop) of every timed request so far."""
        rows = [cost for values in self.costs.values() for cost in values]
        return np.sum(rows, axis=0) if rows else np.zeros(6)


@contextlib.contextmanager
def probed_server(probe: Path, attributed: Path) -> Iterator[None]:
    """Servers started inside load the probe (bench/probe/sitecustomize.py), counting into
    ``probe`` and writing each request's own CPU to ``attributed``."""
    names = ("GYROLAB_BENCH_PROBE", "GYROLAB_BENCH_REQUEST_CPU", "PYTHONPATH")
    saved = {name: os.environ.get(name) for name in names}
    os.environ["GYROLAB_BENCH_PROBE"] = str(probe)
    os.environ["GYROLAB_BENCH_REQUEST_CPU"] = str(attributed)
    os.environ["PYTHONPATH"] = os.pathsep.join(filter(None, [str(PROBE), saved["PYTHONPATH"]]))
    try:
        yield
    finally:
        for name, value in saved.items():
            if value is None:
                os.environ.pop(name, None)
            else:
                os.environ[name] = value


def measure_costs(backend: str, students: int) -> tuple[dict, dict]:
    """Per route and per stream frame, the means of: CPU seconds of the server, the
    database and the client; the server's SQLite calls and thread-pool trips (the probe
    does not count psycopg's calls); the CPU seconds of it on the event loop.  And, as
    ``attributed_costs`` reads them, each route's means of its own task's CPU."""
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
            probe = Path(var) / "probe.bin"
            probe.write_bytes(bytes(16))
            attributed = Path(var) / "request-cpu.txt"
            attributed.touch()
            warm = [0]
            with (
                probed_server(probe, attributed),
                running_server(Path(var), *serve_args, database_url=url) as server,
            ):
                pids = server_pids(server.process.pid)
                tally = CostTally(pids, probe)
                stream = []

                async def everyone():
                    # a first student warms the server up (templates compiled, caches
                    # filled, connections opened): not counted
                    await load_test.student(
                        students, server.url, assignment, load_test.Tally(), args
                    )
                    warm[0] = attributed.stat().st_size
                    for index in range(students):
                        before = np.array(tally.snapshot())
                        before = np.insert(before, 2, time.process_time())
                        timed = tally.timed_total()
                        frames = tally.frames
                        await load_test.student(index, server.url, assignment, tally, args)
                        after = np.insert(np.array(tally.snapshot()), 2, time.process_time())
                        outside = (after - before) - (tally.timed_total() - timed)
                        stream.append(outside / max(tally.frames - frames, 1))
                    await teacher_costs(tally, server.url, course, assignment)

                asyncio.run(everyone())
            with attributed.open("rb") as lines:
                lines.seek(warm[0])
                own = attributed_costs(lines.read().decode()).means
        finally:
            if pg is not None:
                pg.stop()
    costs = {route: tuple(np.mean(values, axis=0)) for route, values in tally.costs.items()}
    costs[STREAM] = tuple(np.mean(stream, axis=0))  # what a stream costs per frame received
    return costs, own


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


def password_hash_cpu(tries: int = 5) -> float:
    """CPU seconds of one password check (argon2id at the app's cost), median of ``tries``."""
    from app.accounts.security import hash_password, verify_password

    stored = hash_password("queue-model-pass")
    spent = []
    for _ in range(tries):
        began = time.thread_time()
        verify_password("queue-model-pass", stored)
        spent.append(time.thread_time() - began)
    return float(np.median(spent))


# --- 1b. CPU per request inside a class ------------------------------------------------------


ID_IN_PATH = re.compile(r"/\d+")


def route_of(method: str, path: str) -> str:
    """The load test's name of a request (ids replaced; the teacher's page by its role)."""
    if path.startswith("/courses/"):
        return "GET dashboard (teacher)"
    return f"{method} {ID_IN_PATH.sub('/{id}', path)}"


@dataclass
class ClassCpu:
    """What the probe saw of a class: per route the mean CPU seconds (on the event loop,
    in the thread pool) of its own task (the stream: per frame of samples), how many, and
    their sum."""

    means: dict[str, tuple[float, float]]
    counts: dict[str, int]
    total_s: float


def attributed_costs(text: str) -> ClassCpu:
    """From the probe's per-request lines (``GYROLAB_BENCH_REQUEST_CPU``): per route the
    mean CPU seconds (on the event loop, in the thread pool) of its own task; for the
    stream, per frame of samples sent (the WebSockets' whole CPU over their frames)."""
    spent: dict[str, list[tuple[float, float]]] = defaultdict(list)
    stream = np.zeros(3)
    for line in text.splitlines():
        kind, method, path, loop_ms, threads_ms, frames = line.split()
        cpu = (float(loop_ms) / 1000, float(threads_ms) / 1000)
        if kind == "websocket":
            stream += (*cpu, int(frames))
        else:
            spent[route_of(method, path)].append(cpu)
    means = {route: tuple(np.mean(values, axis=0)) for route, values in spent.items()}
    counts = {route: len(values) for route, values in spent.items()}
    total = sum(float(np.sum(values)) for values in spent.values()) + stream[0] + stream[1]
    if stream[2]:
        means[STREAM] = (stream[0] / stream[2], stream[1] / stream[2])
        counts[STREAM] = int(stream[2])
    return ClassCpu(means, counts, float(total))


def in_class(costs, own, seen: ClassCpu, used: dict[str, float] | None = None):
    """The costs per request as a class spent them.  Each route's own CPU (its task's,
    ``seen`` by the probe in a load test) replaces one student's alone (``own``).  What the
    probe does not see -- the server's socket work, the collector; per frame of a lone
    stream, most of its cost -- is shared out in a class; with ``used`` (the CPU the same
    run used: "server", "client" seconds) each route's unseen part is scaled so that the
    class's requests and frames add up to the server's CPU, and the load generator's per
    request to its own.  Routes the class run did not see keep one student's costs."""
    shared = routes = [r for r in costs if r in seen.means and r in own]
    unseen = {r: costs[r][0] - sum(own[r]) for r in routes}
    scale = client_scale = 1.0
    if used:
        alone_unseen = sum(seen.counts[r] * max(unseen[r], 0.0) for r in shared)
        if alone_unseen > 0:
            scale = max(used["server"] - seen.total_s, 0.0) / alone_unseen
        asked = sum(seen.counts[r] * costs[r][2] for r in shared)
        client_scale = used["client"] / asked if asked > 0 else 1.0
    adjusted = dict(costs)
    for route in routes:
        server, db, client, calls, trips, loop = costs[route]
        loop_alone, (loop_class, threads_class) = own[route][0], seen.means[route]
        loop_unseen = max(loop - loop_alone, 0.0)
        threads_unseen = max(unseen[route] - loop_unseen, 0.0)
        loop_now = loop_class + scale * loop_unseen
        server_now = max(loop_now + threads_class + scale * threads_unseen, 1e-6)
        adjusted[route] = (server_now, db, client * client_scale, calls, trips, loop_now,
                           loop_class)  # fmt: skip
    return adjusted, scale, client_scale


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


# SQLite's one writer: a write request's server work runs holding the lock.  A log-in
# writes twice (its attempt is charged, then uncharged with the session row added), each
# time for LOGIN_LOCKED_S; its password hash comes between, outside the lock and outside
# the interpreter (argon2-cffi releases the GIL), in one of ``login_hash_slots`` (4) per
# worker.  PostgreSQL: row locks, none.
WRITES = {
    "POST /lab/sessions",
    "POST /lab/sessions/{id}/csv",
    "POST /lab/sessions/{id}/submit",
    "POST /lab/sessions/{id}/turn",
}
LOGIN = "POST /login"
LOGIN_LOCKED_S = 0.001
# state-changing requests wait for one of a worker's write places (web.admission,
# GYROLAB_WRITE_CONCURRENCY) and hold it until the server has answered; the CSV preview is
# declared read-only and passes
WRITE_SLOTS = 8
WORK_PLACES = 2  # GYROLAB_REQUEST_CONCURRENCY: HTTP requests inside a worker at once
TURN_PATIENCE_S = 0.05  # app.db: a write waiting longer for the lock gives its place back
HASH_SLOTS = 4


SWITCH_INTERVAL_S = 0.005  # CPython's sys.getswitchinterval()


class Job:
    """CPU work in one pool; in the server's, cut into ``segments`` by the places where
    the thread gives up the interpreter (and queues for it again)."""

    __slots__ = ("pool", "left", "done", "segment", "segment_left", "worker")

    def __init__(self, pool: str, work: float, done, segments: float = 1.0, worker: int = 0):
        self.pool, self.left, self.done = pool, max(work, 1e-6), done
        self.segment = self.segment_left = self.left / max(segments, 1.0)
        self.worker = worker


def simulate(
    costs,
    students: int,
    workers: int,
    cores: float,
    ramp: float = 3.0,
    one_writer: bool = True,
    clients_elsewhere: bool = False,
    hash_s: float = 0.0,
    write_slots: int = WRITE_SLOTS,
    switch_interval_s: float = SWITCH_INTERVAL_S,
    teacher: bool = True,
    work_places: int = WORK_PLACES,
) -> dict:
    """Latencies per route of ``students`` running the scenario at once (seconds);
    ``one_writer``: write requests hold one lock while the server works on them;
    ``clients_elsewhere``: the clients are browsers on their own machines (a department),
    not a load generator sharing the server's cores; ``hash_s``: the CPU of a log-in's
    password hash (its part of the log-in's server CPU runs outside the interpreter);
    ``write_slots``: each worker's write places (0: no admission queue);
    ``work_places``: HTTP requests inside each worker at once, the rest waiting on its
    event loop from when their body has arrived to when a place is free; a write that
    waits for the write lock longer than ``TURN_PATIENCE_S`` gives its place back (0: no
    limit);
    ``teacher``: a teacher's dashboard is read every 2 s while the class runs;
    ``switch_interval_s``: each worker's interpreter runs one thread at a time, handed on
    round robin when the thread gives it up (a database call, a trip to the thread pool)
    or after this long with others waiting (0: the server's work is shared evenly instead,
    as processor sharing).

    The interpreter, as CPython's GIL does it: a thread that gives it up and wants it
    back queues behind the threads already waiting; the one holding it keeps it until
    it gives it up or another has waited ``switch_interval_s``.  A request that makes
    many short database calls therefore waits about one turn of the others per call."""
    capacity = {"client": float("inf") if clients_elsewhere else 1.0}
    capacity |= {"server": float(workers), "db": cores, "hash": float(HASH_SLOTS * workers)}
    capacity["loop"] = float(workers)
    now = 0.0
    jobs: list[Job] = []
    timers: list[tuple[float, int, object]] = []  # (time, tie-break, callback)
    order = iter(range(10**9))
    latencies: dict[str, list[float]] = defaultdict(list)
    # per HTTP request: (waited for a work place, from asking for it to the answer), s --
    # what the probe's GYROLAB_BENCH_SERVER_TIMES measures in the server
    inside: dict[str, list[tuple[float, float]]] = defaultdict(list)
    finished = [0]

    def at(when: float, callback) -> None:
        heapq.heappush(timers, (when, next(order), callback))

    class Gate:
        """A FIFO semaphore of the simulation: ``enter(start)`` runs ``start`` when a place
        is free; ``leave()`` hands the place to the next in line."""

        def __init__(self, places: float) -> None:
            self.places, self.waiting = places, []

        def enter(self, start) -> None:
            if self.places > 0:
                self.places -= 1
                start()
            else:
                self.waiting.append(start)

        def leave(self) -> None:
            if self.waiting:
                self.waiting.pop(0)()
            else:
                self.places += 1

    spent: dict[str, float] = defaultdict(float)  # CPU asked of each, s
    lock = Gate(1)
    lock_held: list[float] = []  # how long each write held it, s
    slots = Gate(write_slots * workers if write_slots else float("inf"))
    places = [Gate(work_places if work_places else float("inf")) for _ in range(workers)]

    interpreters: list[list[Job]] = [[] for _ in range(workers)]  # [0] holds it
    turn_ends = [0.0] * workers
    pick = random.Random(2026)

    def server_job(work: float, done, releases: float, worker: int) -> None:
        job = Job("server", work, done, releases + 1, worker)
        if not switch_interval_s:
            jobs.append(job)
            return
        queue = interpreters[worker]
        queue.append(job)
        if len(queue) <= 2:  # it now holds the interpreter, or is the first to wait
            turn_ends[worker] = now + switch_interval_s

    loops: list[list[list]] = [[] for _ in range(workers)]  # [work left, done] in order

    def loop_task(work: float, done, worker: int, wakeups: float) -> None:
        """Work on the worker's event loop: one thread, one task after another, each
        taking the interpreter ``wakeups`` times (uvloop's callbacks take it one by one)."""
        tasks = loops[worker]
        tasks.append([max(work, 1e-6), done, wakeups])
        if len(tasks) == 1:  # the loop wakes up and wants the interpreter
            loop_thread = Job("loop", tasks[0][0], None, wakeups, worker)
            if not switch_interval_s:
                jobs.append(loop_thread)
                return
            queue = interpreters[worker]
            queue.append(loop_thread)
            if len(queue) <= 2:
                turn_ends[worker] = now + switch_interval_s

    def phases(route: str, then) -> None:
        server, db, client, calls, trips, loop, *inside_place = costs[route]
        releases = calls + trips  # a thread gives the interpreter up at each, and
        # the event loop at each wake-up: the request's bytes, its answer, each trip's end
        worker = pick.randrange(workers)  # the kernel hands connections to workers
        spent["server"] += server
        spent["db"] += db
        spent["client"] += client
        slotted = route in WRITES or route == LOGIN
        threads = max(server - loop - (hash_s if route == LOGIN else 0.0), 1e-6)
        if route == LOGIN:
            if one_writer:
                locked = min(LOGIN_LOCKED_S, threads / 3)
                work = [("server", threads - 2 * locked), ("lock", locked), ("hash", hash_s),
                        ("lock", locked)]  # fmt: skip
            else:
                work = [("server", threads), ("hash", hash_s)]
        elif one_writer and route in WRITES:
            work = [("lock", threads)]
        else:
            work = [("server", threads)]
        http = route != STREAM  # a stream frame arrives on its WebSocket: no place
        # the event loop's part inside the app (routing, dependencies, the answer: the
        # request's own task, ``in_class``) runs holding the request's places; the rest
        # (the server reading and writing its socket) before and after
        loop_inside = min(inside_place[0], loop) if inside_place and http else 0.0
        outside = loop - loop_inside
        stages = [("client", client / 2), ("loop", outside / 2)]
        stages += [("admit", 0.0)] if http else []
        stages += [("enter", 0.0)] if slotted else []
        stages += [("loop", loop_inside)] if loop_inside else []
        stages += [*work, ("db", db)]
        stages += [("leave", 0.0)] if slotted else []
        stages += [("dismiss", 0.0)] if http else []
        stages += [("loop", outside / 2), ("client", client / 2)]
        holding = [False]  # whether this request holds one of its worker's places
        asked, waited = [0.0], [0.0]  # when it asked for a place, how long it waited

        def give_back() -> None:
            if holding[0]:
                holding[0] = False
                places[worker].leave()

        def run(i: int) -> None:
            if i == len(stages):
                then()
                return
            pool, work = stages[i]
            if pool == "admit":
                asked[0] = now

                def admitted() -> None:
                    holding[0] = True
                    waited[0] = now - asked[0]
                    run(i + 1)

                places[worker].enter(admitted)
            elif pool == "dismiss":
                inside[route].append((waited[0], now - asked[0]))
                give_back()
                run(i + 1)
            elif pool == "enter":
                slots.enter(lambda: run(i + 1))
            elif pool == "leave":
                slots.leave()
                run(i + 1)
            elif pool == "lock":

                def release() -> None:
                    lock_held.append(now - taken[0])
                    lock.leave()
                    run(i + 1)

                def take() -> None:
                    taken[0] = now
                    server_job(work, release, share(work), worker)

                taken: list[float | None] = [None]
                lock.enter(take)
                if taken[0] is None and holding[0]:  # waiting; past its patience it gives way

                    def impatient() -> None:
                        if taken[0] is None:
                            give_back()

                    at(now + TURN_PATIENCE_S, impatient)
            elif pool == "server":
                server_job(work, lambda: run(i + 1), share(work), worker)
            elif pool == "loop":
                loop_task(work, lambda: run(i + 1), worker, 1 + trips / 2)
            else:
                jobs.append(Job(pool, work, lambda: run(i + 1)))

        def share(work: float) -> float:
            """This stage's part of the request's releases (in proportion to its CPU)."""
            return releases * work / threads

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

    def watch() -> None:
        if finished[0] < students:
            request("GET dashboard (teacher)", lambda: at(now + TEACHER_PERIOD_S, watch))

    for index in range(students):
        start = random.Random(index).uniform(0, ramp)  # the load test's ramp
        at(start, lambda: run_student(student_script()))
    if teacher:
        at(0.0, watch)

    def running() -> list[Job]:
        return [queue[0] for queue in interpreters if queue]

    while jobs or timers or any(interpreters):
        counts = defaultdict(int)
        for job in jobs:
            counts[job.pool] += 1
        holders = running()
        if holders:
            counts["server"] += len(holders)
        demand = {pool: min(n, capacity[pool]) for pool, n in counts.items()}
        shared = [pool for pool in demand if not (clients_elsewhere and pool == "client")]
        asked = sum(demand[pool] for pool in shared)
        scale = min(1.0, cores / asked) if asked else 1.0
        rate = {pool: demand[pool] * (scale if pool in shared else 1.0) / counts[pool]
                for pool in counts}  # fmt: skip
        if holders:
            rate["interpreter"] = scale  # a holder runs on one core, shared with the rest
        next_done = min((job.left / rate[job.pool] for job in jobs), default=float("inf"))
        for job in holders:
            next_done = min(next_done, min(job.left, job.segment_left) / rate["interpreter"])
            if len(interpreters[job.worker]) > 1:
                next_done = min(next_done, max(turn_ends[job.worker] - now, 0.0))
        next_timer = timers[0][0] - now if timers else float("inf")
        step = min(next_done, next_timer)
        for job in jobs:
            job.left -= rate[job.pool] * step
        for job in holders:
            job.left -= rate["interpreter"] * step
            job.segment_left -= rate["interpreter"] * step
        now += step
        done = [job for job in jobs if job.left <= 1e-9]
        jobs = [job for job in jobs if job.left > 1e-9]
        for job in [job for job in done if job.pool == "loop"]:  # processor sharing only
            done.remove(job)
            tasks = loops[job.worker]
            done.append(Job("loop", 0.0, tasks.pop(0)[1]))
            if tasks:
                jobs.append(Job("loop", tasks[0][0], None, tasks[0][2], job.worker))
        for job in holders:
            queue = interpreters[job.worker]
            if job.left <= 1e-9 and job.pool == "loop":
                tasks = loops[job.worker]
                done.append(Job("loop", 0.0, tasks.pop(0)[1]))
                if tasks:  # its next callback takes the interpreter again, behind others
                    job.left, job.segment = tasks[0][0], tasks[0][0] / tasks[0][2]
                    job.segment_left = job.segment
                    queue.append(queue.pop(0))
                else:
                    queue.pop(0)  # the loop goes back to waiting for sockets
            elif job.left <= 1e-9:
                queue.pop(0)
                done.append(job)
            elif job.segment_left <= 1e-9:  # a call, or the loop's next callback: queues again
                job.segment_left = job.segment
                queue.append(queue.pop(0))
            elif len(queue) > 1 and now >= turn_ends[job.worker] - 1e-12:
                queue.append(queue.pop(0))  # another waited a whole interval
            else:
                continue
            turn_ends[job.worker] = now + switch_interval_s
        for job in done:
            job.done()
        while timers and timers[0][0] <= now + 1e-12:
            _, _, callback = heapq.heappop(timers)
            callback()
    return {
        "latencies": latencies,
        "server": inside,
        "wall": now,
        "cpu": dict(spent),
        "lock held": lock_held,
    }


# --- 3. measured against predicted -----------------------------------------------------------


CPU_LINE = re.compile(
    r"CPU used during the class: server ([\d.]+) s, PostgreSQL ([\d.]+) s, "
    r"load generator ([\d.]+) s"
)


def measured_p95(path: Path) -> dict[str, dict[str, float]]:
    """Per backend heading ("SQLite", "PostgreSQL") → route → p95 ms, from load_test's output
    (and, under the keys "cpu server", "cpu db", "cpu client", the CPU the run used, s)."""
    tables: dict[str, dict[str, float]] = {}
    backend = None
    for line in path.read_text().splitlines():
        heading = re.match(r"### (\w+)", line)
        if heading:
            backend = heading.group(1)
            tables.setdefault(backend, {})
        used = CPU_LINE.search(line)
        if backend and used:
            for key, value in zip(("server", "db", "client"), used.groups(), strict=True):
                tables[backend][f"cpu {key}"] = float(value)
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
        nargs="+",
        metavar="N",
        help="also predict a department: STUDENTS WORKERS [WORKERS ...] -- STUDENTS starting "
        "within a minute on each number of WORKERS, one core each (clients are browsers "
        "elsewhere; each worker simulated with its share of students)",
    )
    parser.add_argument(
        "--switch-interval",
        type=float,
        default=SWITCH_INTERVAL_S * 1000,
        help="ms; 0 shares each worker's interpreter evenly (processor sharing) instead",
    )
    parser.add_argument(
        "--write-slots", type=int, default=WRITE_SLOTS, help="per worker; 0: no admission queue"
    )
    parser.add_argument(
        "--work-places", type=int, default=WORK_PLACES, help="per worker; 0: no limit"
    )
    parser.add_argument(
        "--costs",
        type=Path,
        help="read the CPU per request from this JSON file if it exists, else measure and "
        "write it there (to try the model again without measuring again)",
    )
    parser.add_argument(
        "--class-cpu",
        type=Path,
        help="each route's own CPU as a class spent it: the file a load test's server wrote "
        "with the probe (PYTHONPATH=bench/probe GYROLAB_BENCH_REQUEST_CPU=FILE load_test.py), "
        "in place of one student's alone",
    )
    parser.add_argument(
        "--server-times",
        type=Path,
        nargs="*",
        default=[],
        help="what the probe's GYROLAB_BENCH_SERVER_TIMES wrote in the compared runs (one "
        "file per --students count, in order): the server's part of each latency, and of "
        "it the wait for a work place, measured beside predicted",
    )
    parser.add_argument(
        "--class-run",
        type=Path,
        help="with --class-cpu: what load_test.py printed in that run; its CPU totals scale "
        "what no request's own task does, and the load generator's CPU per request",
    )
    args = parser.parse_args()
    if args.costs and args.costs.exists():
        saved = json.loads(args.costs.read_text())
        costs = {route: tuple(value) for route, value in saved["costs"].items()}
        own = {route: tuple(value) for route, value in saved.get("own", {}).items()}
        hash_s = saved["hash_s"]
    else:
        (costs, own), hash_s = measure_costs(args.backend, args.measure), password_hash_cpu()
        if args.costs:
            saved = {"costs": costs, "own": own, "hash_s": hash_s}
            args.costs.write_text(json.dumps(saved, indent=1))
    if args.class_cpu:
        if not own:
            parser.error("--class-cpu needs costs measured with each request's own CPU")
        seen = attributed_costs(args.class_cpu.read_text())
        used = None
        if args.class_run:
            table = next(iter(measured_p95(args.class_run).values()))
            used = {"server": table["cpu server"], "client": table["cpu client"]}
        costs, scale, client_scale = in_class(costs, own, seen, used)
        print(f"each route's own CPU as the class in {args.class_cpu} spent it:")
        for route in sorted(set(seen.means) & set(own)):
            alone, there = sum(own[route]) * 1000, sum(seen.means[route]) * 1000
            print(f"  {route:42s} alone {alone:6.2f} ms, in the class {there:6.2f} ms"
                  f" ({there / alone:.2f}×)")  # fmt: skip
        if used:
            print(
                f"  what no request's own task does: {scale:.2f}× one student's, and the load"
                f" generator's CPU per request {client_scale:.2f}× (the CPU that run used)"
            )
    print(f"a log-in's password hash: {hash_s * 1000:.1f} ms of CPU, outside the interpreter")
    print(f"per request, {args.backend}: CPU ms (server, of it on the event loop / database /"
          " load generator), SQLite calls, thread-pool trips")  # fmt: skip
    for route, (server, db, client, calls, trips, loop, *_) in sorted(costs.items()):
        print(f"  {route:42s} {server * 1000:6.2f}, {loop * 1000:5.2f} {db * 1000:6.2f}"
              f" {client * 1000:6.2f} {calls:6.1f} {trips:5.1f}")  # fmt: skip
    workers = 1 if args.backend == "sqlite" else 2
    measured = {}
    for path in args.compare:
        for backend, table in measured_p95(path).items():
            measured[(backend, _students_of(path))] = table
    name = "SQLite" if args.backend == "sqlite" else "PostgreSQL"
    for students in args.students:
        table = measured.get((name, students), {})

        result = simulate(
            costs,
            students,
            workers,
            args.cores,
            one_writer=workers == 1,
            hash_s=hash_s,
            write_slots=args.write_slots,
            switch_interval_s=args.switch_interval / 1000,
            work_places=args.work_places,
        )
        print(f"\n{students} students, {name}, {workers} worker(s): predicted wall "
              f"{result['wall']:.1f} s")  # fmt: skip
        for key, label in (("server", "server"), ("db", "PostgreSQL"), ("client", "load gen.")):
            asked, used = result["cpu"].get(key, 0.0), table.get(f"cpu {key}")
            if used:
                print(f"  CPU of the {label}: {asked:.1f} s from the costs per request, "
                      f"{used:.1f} s used in the measured run ({used / asked:.2f}×)")  # fmt: skip
        if result["lock held"]:
            held = np.percentile(result["lock held"], [50, 95]) * 1000
            print(f"  SQLite's write lock held (wall) p50 {held[0]:.1f} ms, p95 {held[1]:.1f} ms")
        print(f"  {'route':42s} {'p50':>6s} {'p95':>6s} {'measured p95':>13s} {'error':>6s}")
        for route, values in sorted(result["latencies"].items()):
            p50, p95 = (np.percentile(values, q) * 1000 for q in (50, 95))
            seen = table.get(route)
            error = f"{(p95 - seen) / seen * 100:+.0f} %" if seen else ""
            shown = f"{seen:.0f}" if seen else "-"
            print(f"  {route:42s} {p50:6.0f} {p95:6.0f} {shown:>13s} {error:>6s}")
        if len(args.server_times) > args.students.index(students):
            measured_inside = server_times(args.server_times[args.students.index(students)])
            print(f"  inside the server, p50 / p95 ms: {'waited for a place':>24s}"
                  f" {'from there to the answer':>26s}")  # fmt: skip
            print(f"  {'route':42s} {'predicted':>12s} {'measured':>11s}"
                  f" {'predicted':>12s} {'measured':>11s}")  # fmt: skip
            for route, pairs in sorted(result["server"].items()):
                model = np.percentile(np.array(pairs) * 1000, [50, 95], axis=0)
                seen = measured_inside.get(route)
                cells = [f"{model[0][0]:5.0f} /{model[1][0]:5.0f}", "-",
                         f"{model[0][1]:5.0f} /{model[1][1]:5.0f}", "-"]  # fmt: skip
                if seen is not None:
                    real = np.percentile(seen, [50, 95], axis=0)
                    cells[1] = f"{real[0][0]:4.0f} /{real[1][0]:5.0f}"
                    cells[3] = f"{real[0][1]:4.0f} /{real[1][1]:5.0f}"
                print(f"  {route:42s} {cells[0]:>12s} {cells[1]:>11s} {cells[2]:>12s}"
                      f" {cells[3]:>11s}")  # fmt: skip
    if args.department:
        department(costs, hash_s, args.department[0], args.department[1:], args.switch_interval)
    return 0


DEPARTMENT_ROUTES = {
    "GET /lab/sessions/{id}": "lab page",
    "GET /lab/sessions/{id}/results.json": "results",
    "POST /lab/sessions/{id}/csv": "CSV save",
    "POST /lab/sessions/{id}/submit": "submit",
    "POST /login": "log-in",
}


def department(costs, hash_s: float, students: int, workers: list[int], switch_ms: float):
    """p95 per route of ``students`` starting within a minute, for each number of workers
    (one core each, PostgreSQL's CPU counted in it; browsers elsewhere)."""
    print(f"\ndepartment: {students} students starting within a minute, PostgreSQL; p95 ms "
          "(one core per worker, the database's CPU included in it)")  # fmt: skip
    header = " ".join(f"{name:>9s}" for name in DEPARTMENT_ROUTES.values())
    print(f"  {'workers':>7s} {'each':>5s} {header} {'worst':>9s}")
    for count in workers:
        share = -(-students // count)
        result = simulate(
            costs, share, 1, 1.0, ramp=60.0, one_writer=False, clients_elsewhere=True,
            hash_s=hash_s, switch_interval_s=switch_ms / 1000,
        )  # fmt: skip
        p95 = {route: np.percentile(v, 95) * 1000 for route, v in result["latencies"].items()}
        row = " ".join(f"{p95.get(route, float('nan')):9.0f}" for route in DEPARTMENT_ROUTES)
        print(f"  {count:7d} {share:5d} {row} {max(p95.values()):9.0f}")


def server_times(path: Path) -> dict[str, np.ndarray]:
    """Per route, each request's (waited for a work place, server time) in ms, from the
    probe's ``GYROLAB_BENCH_SERVER_TIMES`` lines (``method path ms waited_ms``)."""
    rows: dict[str, list[tuple[float, float]]] = defaultdict(list)
    for line in path.read_text().splitlines():
        method, route, took, waited = line.split()
        rows[route_of(method, route)].append((float(waited), float(took)))
    return {route: np.array(values) for route, values in rows.items()}


def _students_of(path: Path) -> int | None:
    found = re.search(r"; (\d+) students", path.read_text())
    return int(found.group(1)) if found else None


if __name__ == "__main__":
    sys.exit(main())
