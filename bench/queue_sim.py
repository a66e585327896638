"""The queueing model's simulation (``queue_model.py``): the load test's class replayed as
discrete events -- each request's client work, the event loop, a work place, the write
lock, the interpreter handed round as CPython's GIL does, the database, the cores shared
in proportion -- from the CPU each request costs."""

from __future__ import annotations

import heapq
import random
import sys
from collections import defaultdict
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

import load_test  # noqa: E402  (bench/, this file's folder)

FRAMES_PER_POSITION = 15  # 3 s of streaming (60 s at 20×), one frame every 0.2 s
FRAME_SECONDS = 0.2
TEACHER_PERIOD_S = 2.0
STREAM = "stream frame"


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
