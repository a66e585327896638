"""The queueing model's simulation (``queue_model.py``): the load test's class replayed as
discrete events -- each request's client work, the event loop, a work place, the write
lock, the interpreter handed round as CPython's GIL does, the database, the cores shared
in proportion -- from the CPU each request costs."""

from __future__ import annotations

import heapq
import random
import sys
from collections import Counter, defaultdict
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

import load_test  # noqa: E402  (bench/, this file's folder)

FRAMES_PER_POSITION = 15  # 3 s of streaming (60 s at 20×), one frame every 0.2 s
FRAME_SECONDS = 0.2
TEACHER_PERIOD_S = 2.0
SAVED = "WS save (last frame → saved)"  # as load_test.py names it
STREAM = "stream frame"
# A position streamed: its start (the checks and the mark, in a write transaction, then
# the gyro's take made ready outside it) and its save (the readings stored, in a write
# transaction), with what a position's frames cost in threads shared between them as
# measured (``costs[STREAM_SPLIT]``: the parts of a stream's thread CPU spent marking,
# making the take ready and saving, the probe's per-function lines of a load test), else
# half each, both under the lock (the model before 2026-12-03); the frames between cost
# only the event loop's work and the client's.
STREAM_START = "stream: a position started"
STREAM_TAKE = "stream: a position's take made ready"
STREAM_SAVE = "stream: a position saved"
STREAMED = {STREAM, STREAM_START, STREAM_TAKE, STREAM_SAVE}
STREAM_SPLIT = "stream split"
CONTINUED = {STREAM_TAKE, STREAM_SAVE}  # no hop through the event loop before them


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
# worker, its work place given to another request from then on (``db.give_way``).
# PostgreSQL: row locks, none.
WRITES = {
    "POST /lab/sessions",
    "POST /lab/sessions/{id}/csv",
    "POST /lab/sessions/{id}/submit",
    "POST /lab/sessions/{id}/turn",
    STREAM_START,
    STREAM_SAVE,
}
LOGIN = "POST /login"
LOGIN_LOCKED_S = 0.001
# threads running outside the interpreter, on a core a woken server thread may land on
OUTSIDE = ("hash", "client", "released")
# state-changing requests wait for one of a worker's write places (web.admission,
# GYROLAB_WRITE_CONCURRENCY) and hold it until the server has answered; the CSV preview is
# declared read-only and passes
WRITE_SLOTS = 8
WORK_PLACES = 2  # GYROLAB_REQUEST_CONCURRENCY: HTTP requests inside a worker at once
TURN_PATIENCE_S = 0.05  # app.db: a write waiting longer for the lock gives its place back
HASH_SLOTS = 4
# A log-in's round trips to PostgreSQL after its password hash: a connection checked out
# (its ping), the transaction begun, the charges deleted, the session row inserted, the
# commit (``accounts.security.log_in``, ``accounts.pages.login``; counted in the app by
# ``test_a_log_ins_round_trips_after_its_hash_are_the_models``)
LOGIN_TRIPS_AFTER_HASH = 5


# a served worker's sys.getswitchinterval(): GYROLAB_SWITCH_INTERVAL_MS, 1 ms since
# 2026-11-27 (CPython's own 5 ms before: ``--switch-interval 5`` for the runs of then)
SWITCH_INTERVAL_S = 0.001
# The interpreter handed to a thread that was waiting for it: from the release to the
# waiting thread's first instruction (woken by the GIL's condition variable, scheduled on a
# core) nobody runs Python.  bench/bench_handoffs.py on the 2-core machine, 2026-11-27:
# mean 30 / 33 / 38 / 39 µs in four runs.  A class's burst hands the interpreter on
# thousands of times a second: ≈ 15 % of it.
HANDOFF_S = 35e-6
# A round trip to PostgreSQL beyond the CPU both sides spend on it (loopback, wake-ups):
# bench/bench_handoffs.py --postgresql, mean 14 / 20 µs.  A request's thread gives up the
# interpreter at each round trip, as at each SQLite call, and waits for the server.
ROUND_TRIP_S = 17e-6
# A thread woken when more is asked of the cores than they have waits for one: most times
# a few µs, now and then a whole time slice, the more often the more is asked.
# bench/bench_handoffs.py on 2 cores, a wake-up with 2 / 3 / 4 / 6 processes spinning (a
# demand of 1.5 / 2 / 2.5 / 3.5 cores with the waking thread) less one with a core free:
# mean 120 / 151 / 324 / 479 µs, p50 9 µs, 5 / 5 / 13 / 19 % over 1 ms (those 1.6-2.4 ms):
# ≈ 195 µs for each core asked beyond the cores there are (least squares through 0).
# Paid at each hand-off of the interpreter and by both wake-ups of a database round trip,
# as a slice of WAKE_SLICE_S with the chance that gives that mean.
WAKE_BUSY_S = 195e-6
WAKE_SLICE_S = 2e-3
# A thread woken through a socket is put on its waker's core ("sync" wake-ups); a waker
# that goes on running keeps the core until it stops or its slice ends: the kernel's
# se.slice on the 2-core machine (/proc/self/sched), 1.4 ms
STACKED_SLICE_S = 1.4e-3
# An SQLite call releases the GIL while the database runs; a thread waiting for the
# interpreter is woken, but takes it only if it reaches a core before the call is over --
# else the caller takes it back and the waiter sleeps again.  bench/bench_handoffs.py
# --calls over the app's calls (the probe's GYROLAB_BENCH_SQLITE_CALLS, 20 students on
# SQLite: 10,411 calls, median 8.8 µs of CPU, 90 % under 32 µs): with a core free, calls
# under ≈ 15 µs are never handed on and calls over ≈ 60 µs almost always (8 % of the app's);
# with none free, 7-23 % of calls of any length (10 %).  None: every call hands it on
# (the model before 2026-11-27).
CALL_HANDOFF = (0.08, 0.10)
# "threads by time": each group's time run and waited for a core in bins of the class's time
TIMELINE_BIN_S = 0.25
# ``client_floor``: the load generator's CPU whatever it sends (its event loop's timers,
# its collector), run as a piece of client work this often while the class runs
CLIENT_FLOOR_PERIOD_S = 0.01


class Job:
    """CPU work in one pool; in the server's, cut into ``segments`` by the places where
    the thread gives up the interpreter (and queues for it again); ``handing`` is what is
    left of the hand-off to it (s of wall time: the interpreter is its, not yet running)."""

    __slots__ = (
        "pool", "left", "done", "segment", "segment_left", "worker", "handing", "call_share",
        "waits", "bumped",
    )  # fmt: skip

    def __init__(
        self,
        pool: str,
        work: float,
        done,
        segments: float = 1.0,
        worker: int = 0,
        call_share: float = 0.0,
    ):
        self.pool, self.left, self.done = pool, max(work, 1e-6), done
        self.segment = self.segment_left = self.left / max(segments, 1.0)
        self.worker = worker
        self.handing = 0.0
        self.bumped = 0.0  # off its core for a thread woken onto it (``landing_s``)
        self.call_share = call_share  # of its releases, the SQLite calls'
        # its request's waits (``simulate``'s "server" tuples): for the interpreter, being
        # handed it (on the run queue), holding it for a core, for the write lock or the
        # database server
        self.waits: list[float] | None = None


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
    handoff_s: float = HANDOFF_S,
    round_trip_s: float = ROUND_TRIP_S,
    wake_busy_s: float = WAKE_BUSY_S,
    seed: int = 2026,
    worker_shares: list[float] | None = None,
    call_handoff: tuple[float, float] | None = CALL_HANDOFF,
    wake_free: bool = True,
    costs_in_order: bool = True,
    locked_shares: dict[str, float] | None = None,
    stage_log: list | None = None,
    loop_keeps: bool = True,
    trips_in_turn: bool = True,
    wake_counts_itself: bool = True,
    socket_stacking: bool = False,
    trips_outside_lock: bool = True,
    released_share: float = 0.0,
    script=student_script,
    starts: list[float] | None = None,
    frames_on_loop: bool = True,
    arrivals: list[tuple] | None = None,
    landing_s: float = 0.0,
    landing_on: tuple[str, ...] = OUTSIDE,
    client_in_order: bool = False,
    student_workers: list[tuple[int, int]] | None = None,
    teacher_worker: int | None = None,
    per_core: bool = True,
    balance_s: float = 0.0,
    yielding: tuple[str, ...] = (),
    yield_share: float = 0.0,
    login_trips_after_hash: int = LOGIN_TRIPS_AFTER_HASH,
    client_floor: float = 0.0,
) -> dict:
    """Latencies per route of ``students`` running the scenario at once (seconds);
    ``costs``: per route (server, database, client CPU s, SQLite calls, thread trips,
    the server's CPU on its event loop[, of it the request's own task's]), or a list of
    such, one drawn at random for each request (a class's own requests, ``in_class``);
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
    as processor sharing); ``handoff_s``: each time the interpreter passes to a thread
    that was waiting for it, it runs nothing for this long (the waiting thread is woken and
    scheduled; no CPU is spent); ``round_trip_s``: with ``one_writer`` off (PostgreSQL), a
    request's database calls are round trips to the database server: its thread's work is
    cut at each, the database's share done and this long waited, then the interpreter
    asked for again; ``wake_busy_s``: while more is asked of the cores than they have,
    each of those wake-ups waits this much longer for a core, on average, for each core
    asked beyond them (a whole slice of ``WAKE_SLICE_S``, now and then); ``seed``: which worker each
    connection reaches and which of a route's measured costs each request draws (the
    students' start times are the load test's own); ``worker_shares``: each worker's share
    of the students' connections (the kernel's accept race is not even: a run on two
    workers served 33 % and 67 % of the requests), else each connection to a worker at
    random; ``call_handoff``: (with a core free, with none) the chance that an SQLite
    call hands the interpreter to a thread waiting for it (None: every call does);
    ``wake_free``: a thread woken from sleep waits the hand-off for a core even when it
    finds the interpreter free (False: it runs at once, the model before 2026-11-27);
    ``costs_in_order``: a student's route's measured requests (a list, in the order the
    class answered them) are drawn in that order -- the route's k-th request here costs
    one of the measured within 5 % of the k-th (scaled to this class's size) -- not at
    random (False; the teacher's always at random): a route's CPU changes over a class
    (the lab page is empty at the start, 2.3× dearer with results and charts in the
    burst; bench/README.md, twenty-third part); ``locked_shares``: per write route (and
    ``STREAM_START``, ``STREAM_SAVE``), the share of its thread CPU that holds SQLite's
    write lock, the rest done before it (``class_cpu.locked_shares``); else all of it;
    ``stage_log``: a list to which each request's and stream part's (route, its stages'
    pools in order) is appended; ``loop_keeps``: the event loop, between its callbacks and
    its tasks, gives up the interpreter as an SQLite call does (uvloop's C code releases
    it and takes it back at once): handed on with ``call_handoff``'s chance, else kept for
    the next callback within its switch interval (False: every callback queues again
    behind the threads waiting, the model before 2026-12-05: its requests waited off a
    core 3-8× less than the probe measured; bench/README.md, twenty-sixth part);
    ``trips_in_turn``: an HTTP request's trips to the thread pool are steps of their own,
    as in the app: its thread work is cut into one piece per trip (a write's locked part one
    of them, between the others; on PostgreSQL each piece makes its share of the round
    trips), each a pool thread woken for it, and between them its coroutine's steps on the
    event loop (its own loop CPU shared among them), each waiting for the loop's other
    callbacks and for the interpreter -- the hops the probe measures (its "dispatch" and
    "back") -- (False: one thread does all of the request's work, giving the interpreter up
    at each trip but keeping it if nobody waits, the loop's part before it: the model before
    2026-12-05); ``wake_counts_itself``: a busy wake-up's mean wait is ``wake_busy_s`` for
    each core asked beyond the cores there are counting the woken thread, as
    bench_handoffs.py measured it (2 processes spinning on 2 cores and the waking thread:
    half a core beyond), and a call hands the interpreter on with ``call_handoff``'s "none
    free" chance once the cores are all asked for (False: the cores asked for without the
    woken thread, the model before 2026-12-05: both cores busy cost a wake-up nothing);
    ``socket_stacking``: a thread woken through a socket by one that goes on running (the
    load generator by the server's answer, the event loop by a request) is put on the
    waker's core and waits there until the waker stops or its slice ends
    (``STACKED_SLICE_S``), even with the other core idle (counted in the run queue's
    waits, not in "pressure"); ``trips_outside_lock``: where ``locked_shares`` splits a
    write into its work before ``BEGIN IMMEDIATE`` and its transaction (one thread-pool
    function), the locked part gives the interpreter up at its SQLite calls alone and the
    thread-pool trips' releases fall in the unlocked part (False, or a write locked for
    all of its CPU: both in proportion to the CPU, the model before 2026-12-05, in which
    a stream's save handed the interpreter on inside the lock at ≈ 1.3 trips a save);
    ``released_share``: the share of a thread's CPU that runs with the interpreter released
    (SQLite's own work inside its calls, the kernel's in system calls), run on a core after
    the thread's part holding the interpreter (0: all of it holds the interpreter, the
    model before 2026-12-05); ``script``: a student's steps, as ``student_script``'s (the
    load test's student, the default); ``starts``: when each student begins, s (else at
    random in the first ``ramp`` seconds, as the load test's students); ``frames_on_loop``:
    a stream's frame is work on the event loop alone, as in the app (the tick takes the
    samples and sends them on the loop) (False: each frame also queues for the interpreter
    as a thread's work of 1 µs, handed to it and woken -- the model before 2026-12-05's
    thirty-second part, in which a frame right behind another student's save waited for it);
    ``arrivals``: a trace to replay instead of the students (``students``, ``script``,
    ``starts`` and ``teacher`` unused; ``replay.py``): each (time from the start s,
    "request" or "stream", route, connection[, browser, think s]) -- the requests of one
    connection reaching one worker (None: a connection of its own).  Without a browser an
    arrival is sent at its time whatever was answered before it (open loop); a browser's
    arrivals go in order, each at its time or ``think`` after the one before it ended,
    whichever is later (paced); ``client_in_order``: the load generator is
    one event loop: its client work runs one callback at a time, in the order the callbacks
    became ready, at the load generator's share of a core (False: every student's client
    work shared that core evenly, processor sharing, the model before 2026-12-05's
    thirty-fourth part); ``student_workers``: per student (the load test's number), the
    worker its HTTP connection and its WebSocket reached, as a run measured them
    (``connections.py``; ``worker_shares`` then unused); ``teacher_worker``: the
    teacher's (else each at random); ``per_core``: each thread ready to run sits on one
    core and shares that core alone with the others on it (a thread woken goes to an idle
    core if there is one, else to either at random, and stays there while it runs),
    instead of every ready thread sharing all the cores evenly; ``balance_s``: with
    ``per_core``, how long a core idles while another has two ready threads before it takes
    one (0: at once, no core idles while a thread waits; the kernel's balancing skips a
    core idle for shorter than its migration cost, 0.5 ms, and leaves a thread that ran in
    the last 0.5 ms where it is); ``yielding``: with ``per_core``, the pools ("hash",
    "client", …) whose threads run only on what the others leave of their core (a
    long-running thread behind threads woken for short bursts; none by default), and a
    thread woken waits for a core only as long as the other pools' threads ask for more
    than the cores there are (it goes before the long runners, as the kernel's EEVDF puts
    a thread woken for a short burst before one that has run for long); whole cores only
    (else shared evenly); ``yield_share``: with ``yielding``, the least a yielding thread
    runs, as a share of an even share of its core (EEVDF is fair over time: a long runner
    waits behind short bursts, not forever behind threads that keep running; 0: only what
    the others leave, 1: an even share, as if nothing yielded);
    ``login_trips_after_hash``: on PostgreSQL, a log-in's last round trips that the app
    makes after the password hash, without its work place
    (the charges deleted, the session row inserted, the commit; 0: all before the hash,
    the model before 2026-12-06 night); ``client_floor``: the share of a core the load
    generator spends whatever it sends, from the class's start until its last student is
    done (a piece of its client work every ``CLIENT_FLOOR_PERIOD_S``, in line with its
    other callbacks; ``class_cpu.fitted_client_cpu``'s floor; 0: none, its CPU all in its
    requests' and frames', the model before 2026-12-07).

    The interpreter, as CPython's GIL does it: a thread that gives it up and wants it
    back queues behind the threads already waiting; the one holding it keeps it until
    it gives it up or another has waited ``switch_interval_s``.  A request that makes
    many short database calls therefore waits about one turn of the others per call.

    Returns "latencies" (per route, s), "timeline" (each HTTP request's route, the
    time it was sent from the class's start and its latency, s), "students" (per student
    in the order they arrived: "requests", its HTTP requests' route, sent and latency, and
    "positions", each position streamed: asked for, started, its last frame, saved, s),
    "server" (per route,
    each HTTP request's wait for a work place, time from asking for it to the answer, of
    that its threads' waits for the interpreter, for a hand-off of it, for a core while
    holding it and for the write lock or the database server, when it asked for a place,
    and the server's CPU it drew for its time in the place, s), "wall", "cpu" asked of
    each pool, "lock held" (each SQLite write's time holding the lock; "lock by route":
    per route, each write's wait for the lock and its hold), and "run queue":
    per group ("server", "db", "client"), the time its threads ran and the time they were
    ready and waited for a core, s -- the hand-offs included: a woken thread waits on the run
    queue until it runs (run_queue.py measures the same in a run) -- and "wake-ups": per
    group, how many times one of its threads was woken to run (the interpreter handed to
    it, a round trip's answer; under "loop", of the server's those of the event loops),
    and "pressure": the time some thread waited for a core (more asked of the cores than
    they have, or one woken and not yet on a core: the kernel's /proc/pressure/cpu "some")
    and the cores' busy time, s; "busy while waiting": the time some thread waited for a
    core, by how many cores were busy meanwhile, s (with ``per_core`` and ``balance_s``, a
    core can idle while a thread waits; shared evenly, never); "threads by time": per
    (bin of ``TIMELINE_BIN_S`` from the class's start, group), the time its threads ran and
    waited for a core, s, as "run queue" counts them but with the log-ins' hashes a group
    of their own ("hash"; ``sched_trace.threads_by_time`` reads the same from a trace)."""
    capacity = {"client": float("inf") if clients_elsewhere else 1.0}
    capacity |= {"server": float(workers), "db": cores, "hash": float(HASH_SLOTS * workers)}
    capacity["loop"] = float(workers)
    capacity["released"] = cores  # threads' CPU without the interpreter
    now = 0.0
    jobs: list[Job] = []
    timers: list[tuple[float, int, object]] = []  # (time, tie-break, callback)
    order = iter(range(10**9))
    latencies: dict[str, list[float]] = defaultdict(list)
    timeline: list[tuple[str, float, float]] = []  # each HTTP request's (route, sent, latency)
    # per HTTP request: (waited for a work place, from asking for it to the answer), s --
    # what the probe's GYROLAB_BENCH_SERVER_TIMES measures in the server
    inside: dict[str, list[tuple[float, float]]] = defaultdict(list)
    finished = [0]
    overdrawn = [0.0]  # the cores asked for now beyond the cores there are, per core
    asked_now = [0.0]  # the cores asked for now
    waking = random.Random(seed + 2)

    # per pool, the time its threads were ready to run and waited for a core, s (what the
    # kernel's schedstat counts as run-queue waits: run_queue.py), and the time they ran
    queued: dict[str, float] = defaultdict(float)
    ran: dict[str, float] = defaultdict(float)
    # both as they stood at the end of each bin of the class's time ("threads by time")
    marks: list[tuple[int, dict[str, float], dict[str, float]]] = []
    next_mark = TIMELINE_BIN_S

    wakeups: dict[str, int] = defaultdict(int)
    # a thread waiting for its worker's interpreter wakes at each switch interval to ask for
    # it (CPython's take_gil: a timed wait) and sleeps again: a time on a core each, counted
    # only (3-7 µs of CPU each, already in the measured CPU; bench_gil_wakes.py)
    waiting_wakeups: dict[str, float] = defaultdict(float)
    # the time some thread waited for a core (more asked of the cores than they have, or a
    # thread woken and not yet on one: what the kernel's /proc/pressure/cpu "some" counts),
    # and the cores' busy time, s
    pressure = [0.0, 0.0]
    # the time some thread waited for a core, by how many cores were busy meanwhile (the
    # kernel's, from a trace: ``sched_trace.busy_while_waiting``), s
    busy_waiting: dict[float, float] = defaultdict(float)

    def busy_wake(pool: str = "server", counted: bool = True) -> float:
        """How much longer a thread of ``pool`` woken now waits for a core (s); counted
        here as a wake-up and a wait on the run queue unless the caller counts it."""
        beyond = overdrawn[0]
        if wake_counts_itself:  # as bench_handoffs.py measured it: the waking thread asks too
            beyond = max((asked_now[0] + 1.0) / cores - 1.0, 0.0)
        mean = wake_busy_s * beyond
        wait = WAKE_SLICE_S if mean and waking.random() < mean / WAKE_SLICE_S else 0.0
        if counted:
            queued[pool] += wait
            wakeups[pool] += 1
        return wait

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
    streamed = costs[STREAM]
    streamed = tuple(np.mean(streamed, axis=0)) if isinstance(streamed, list) else streamed
    server, db, client, calls, trips, loop = streamed[:6]
    marking, making_ready, saving = costs.get(STREAM_SPLIT, (0.5, 0.0, 0.5))

    def position_part(part: float, writes: bool = True) -> tuple[float, ...]:
        """The share ``part`` of a position's work in threads, as costs of a stage: its CPU
        and thread-pool trips in that share; the database's work and calls shared by the
        two writes alone (the take makes no SQLite call)."""
        each = FRAMES_PER_POSITION * part
        in_writes = FRAMES_PER_POSITION * part / (marking + saving) if writes else 0.0
        return ((server - loop) * each, db * in_writes, 0.0, calls * in_writes, trips * each,
                0.0)  # fmt: skip

    frame = (loop, 0.0, client, 0.0, 0.0, loop)
    lock = Gate(1)
    lock_held: list[float] = []  # how long each write held it, s
    # per route, each write's wait for the lock and its hold, s (as the lock trace has them)
    lock_by_route: dict[str, list[tuple[float, float]]] = defaultdict(list)
    slots = Gate(write_slots * workers if write_slots else float("inf"))
    places = [Gate(work_places if work_places else float("inf")) for _ in range(workers)]

    interpreters: list[list[Job]] = [[] for _ in range(workers)]  # [0] holds it
    turn_ends = [0.0] * workers
    pick = random.Random(seed)  # which worker each new connection reaches
    calls_drawn = random.Random(seed + 3)  # which releases hand the interpreter on
    draw = random.Random(seed + 1)  # which of a route's measured requests this one costs
    asked_of_route: dict[str, int] = defaultdict(int)  # requests of each route so far
    # how many of each route the class asks for (a request's place in its route's order)
    if arrivals is None:
        per_student = Counter(route for kind, route in script() if kind == "request")
        of_route = Counter({route: count * students for route, count in per_student.items()})
    else:
        of_route = Counter(arrival[2] for arrival in arrivals if arrival[1] == "request")

    def server_job(
        work: float,
        done,
        releases: float,
        worker: int,
        call_share: float = 0.0,
        woken: bool = True,
        waits: list[float] | None = None,
    ) -> None:
        if released_share and work > 0:  # its part without the interpreter, after it
            held_done, off = done, work * released_share
            work -= off

            def done() -> None:
                jobs.append(Job("released", off, held_done))

        job = Job("server", work, done, releases + 1, worker, call_share)
        job.waits = waits
        if not switch_interval_s:
            jobs.append(job)
            return
        queue = interpreters[worker]
        queue.append(job)
        if len(queue) <= 2:  # it now holds the interpreter, or is the first to wait
            turn_ends[worker] = now + switch_interval_s
        if len(queue) == 1 and woken:
            wake_to_free(job)

    landing = random.Random(seed + 5)  # which core a woken server thread lands on

    def land() -> None:
        """A server thread woken to run lands on a core at random: on one running a thread
        outside the interpreter of a pool in ``landing_on`` (a hash, the load generator),
        that thread is off its core for ``landing_s``, not asking for one meanwhile (the
        woken thread has it)."""
        if not landing_s:
            return
        outside = [job for job in jobs if job.pool in landing_on and not job.bumped
                   and not (clients_elsewhere and job.pool == "client")]  # fmt: skip
        if outside and landing.random() < len(outside) / cores:
            landing.choice(outside).bumped = landing_s

    def wake_to_free(job: Job) -> None:
        """A thread woken from sleep (by the event loop, or the loop by a socket) finds the
        interpreter free: it still waits on the run queue to reach a core, as a thread
        handed the interpreter does (the interpreter is its meanwhile)."""
        if wake_free:
            job.handing = handoff_s + busy_wake(counted=False)
            land()
            wakeups["server"] += 1
            wakeups["loop"] += job.pool == "loop"

    loops: list[list[list]] = [[] for _ in range(workers)]  # [work left, done] in order

    def loop_left(worker: int) -> float:
        """The CPU left in the worker's event loop's callbacks now, s: what it goes on
        running (its current callback's rest and those queued after it)."""
        tasks = loops[worker]
        if not tasks:
            return 0.0
        running = [job for job in interpreters[worker] if job.pool == "loop"]
        first = running[0].left if running else tasks[0][0]
        return first + sum(task[0] for task in tasks[1:])

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
            if len(queue) == 1:
                wake_to_free(loop_thread)

    def one_piece_per_trip(work: list[tuple[str, float]], pieces: int) -> list:
        """A request's thread work (its unlocked "server" and locked "lock" stages) cut into
        ``pieces`` trips: the locked part one trip of its own, second, the rest shared
        evenly among the others (a write's checks, then the write, then its answer)."""
        locked = [stage for stage in work if stage[0] == "lock"]
        unlocked = sum(amount for pool, amount in work if pool == "server")
        others = pieces - len(locked)
        each = [("server", unlocked / others)] * others
        return (each[:1] + locked + each[1:]) if locked else each

    def phases(route: str, then, worker: int, cost: tuple | None = None) -> None:
        cost = cost or costs[route]
        if isinstance(cost, list) and costs_in_order and route in of_route:
            # the k-th of the class's, give or take 5 % (a class of another size: the
            # same place in its order)
            k = asked_of_route[route] * len(cost) / of_route[route]
            asked_of_route[route] += 1
            spread = max(1, len(cost) // 20)
            cost = cost[min(max(int(k) + draw.randint(-spread, spread), 0), len(cost) - 1)]
        elif isinstance(cost, list):  # the class's own requests: one drawn at random
            cost = cost[draw.randrange(len(cost))]
        server, db, client, calls, trips, loop, *inside_place = cost
        releases = calls + trips  # a thread gives the interpreter up at each, and
        # the event loop at each wake-up: the request's bytes, its answer, each trip's end
        spent["server"] += server
        spent["db"] += db
        spent["client"] += client
        slotted = route in WRITES or route == LOGIN
        threads = max(server - loop - (hash_s if route == LOGIN else 0.0), 1e-6)
        if route == LOGIN:
            if one_writer:
                locked = min(LOGIN_LOCKED_S, threads / 3)
                work = [("server", threads - 2 * locked), ("lock", locked), ("give way", 0.0),
                        ("hash", hash_s), ("lock", locked)]  # fmt: skip
            else:
                work = [("server", threads), ("give way", 0.0), ("hash", hash_s)]
        elif one_writer and route in WRITES:
            # the part before BEGIN IMMEDIATE (parsing, checks, packing) outside the lock
            locked = min(max((locked_shares or {}).get(route, 1.0), 0.0), 1.0)
            work = [("server", threads * (1.0 - locked)), ("lock", threads * locked)]
            work = work if locked < 1.0 else work[1:]
        else:
            work = [("server", threads)]
        http = route not in STREAMED  # a stream arrives on its WebSocket: no work place
        pieces = int(round(trips)) if trips_in_turn and http and route != LOGIN else 0
        pieces = pieces if pieces >= 2 else 0
        if pieces:
            work = one_piece_per_trip(work, pieces)
        round_trips = 0 if one_writer else int(round(calls))
        if round_trips and not pieces:  # the thread's work between round trips to the database
            # a log-in's last ones after its hash (the session row and its commit, as the
            # app makes them), with a piece of the thread's work after them
            after_hash = min(login_trips_after_hash, round_trips) if route == LOGIN else 0
            piece = work[0][1] / (round_trips + 1 + (after_hash > 0))
            trip = [("thread", piece), ("db", db / round_trips), ("wait", round_trip_s)]
            work[:1] = trip * (round_trips - after_hash) + [("thread", piece)]
            if after_hash:  # after the give-way and the hash
                work += trip * after_hash + [("thread", piece)]
        # the event loop's part inside the app (routing, dependencies, the answer: the
        # request's own task, ``in_class``) runs holding the request's places; the rest
        # (the server reading and writing its socket) before and after
        loop_inside = min(inside_place[0], loop) if inside_place and http else 0.0
        outside = loop - loop_inside
        stages = [("client", client / 2)]
        # a position's take and its save are sent to the thread pool in the same step of the
        # stream's coroutine as what came before them (the mark's answer, the last frame):
        # no wait for the event loop first; everything else reaches the loop from a socket
        stages += [] if route in CONTINUED else [("loop", outside / 2)]
        stages += [("admit", 0.0)] if http else []
        stages += [("enter", 0.0)] if slotted else []
        if pieces:  # the coroutine's steps on the loop between its trips
            step_on_loop = ("loop step", loop_inside / (pieces + 1))
            stages += [step_on_loop]
            done_share = 0.0
            for pool, amount in work:
                if round_trips:  # its share of the round trips to the database server
                    before = int(round(round_trips * done_share / threads))
                    done_share += amount
                    made = int(round(round_trips * done_share / threads)) - before
                    segment = amount / (made + 1)
                    trip = [("thread", segment), ("db", db / round_trips), ("wait", round_trip_s)]
                    stages += trip * made + [("thread", segment)]
                else:
                    stages += [(f"{pool} piece", amount)]
                stages += [step_on_loop]
            stages += [] if round_trips else [("db", db)]
        elif frames_on_loop and route == STREAM:  # a frame: the loop's work, no thread's
            stages += [("loop", loop_inside)] if loop_inside else []
        else:
            stages += [("loop", loop_inside)] if loop_inside else []
            stages += [*work, ("db", db)] if not round_trips else work
        stages += [("leave", 0.0)] if slotted else []
        stages += [("dismiss", 0.0)] if http else []
        stages += [("loop", outside / 2), ("client", client / 2)]
        if stage_log is not None:
            stage_log.append((route, [pool for pool, _ in stages]))
        # the server's CPU inside its place (the probe's: its steps on the loop, its threads'
        # and a log-in's hash; not the database server's)
        own_cpu = loop_inside + threads + (hash_s if route == LOGIN else 0.0)
        holding = [False]  # whether this request holds one of its worker's places
        # its threads' waits: for the interpreter, a hand-off of it, a core, the write lock
        # or the database server
        waits = [0.0, 0.0, 0.0, 0.0]
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
                inside[route].append((waited[0], now - asked[0], *waits, asked[0], own_cpu))
                give_back()
                run(i + 1)
            elif pool == "give way":  # a log-in's hash: its work place to another request
                give_back()
                run(i + 1)
            elif pool == "enter":
                slots.enter(lambda: run(i + 1))
            elif pool == "leave":
                slots.leave()
                run(i + 1)
            elif pool == "loop step":
                loop_task(work, lambda: run(i + 1), worker, 1)
            elif pool == "server piece":
                server_job(
                    work, lambda: run(i + 1), calls * work / threads, worker,
                    1.0 if calls else 0.0, waits=waits,
                )  # fmt: skip
            elif pool in ("lock", "lock piece"):
                if pool == "lock piece" or (trips_outside_lock and locked_work):
                    # its releases: its calls (the trips' fall in the unlocked part)
                    releases_in, call_share_in = calls * work / threads, 1.0 if calls else 0.0
                else:
                    releases_in, call_share_in = share(work), call_share

                def release() -> None:
                    lock_held.append(now - taken[0])
                    lock_by_route[route].append((taken[0] - wanted, now - taken[0]))
                    lock.leave()
                    run(i + 1)

                def take() -> None:
                    taken[0] = now
                    waits[3] += now - wanted
                    server_job(work, release, releases_in, worker, call_share_in, waits=waits)

                taken: list[float | None] = [None]
                wanted = now
                lock.enter(take)
                if taken[0] is None and holding[0]:  # waiting; past its patience it gives way

                    def impatient() -> None:
                        if taken[0] is None:
                            give_back()

                    at(now + TURN_PATIENCE_S, impatient)
            elif pool == "server" and trips_outside_lock and locked_work:
                # the unlocked part of a write: its calls, and every trip's release
                in_calls = calls * work / threads
                releases_here = in_calls + trips * work / (threads - locked_work)
                server_job(
                    work, lambda: run(i + 1), releases_here, worker,
                    in_calls / releases_here if releases_here else 0.0, waits=waits,
                )  # fmt: skip
            elif pool == "server":
                server_job(work, lambda: run(i + 1), share(work), worker, call_share, waits=waits)
            elif pool == "thread":  # between round trips: only thread-pool trips cut it
                # after a round trip its wake-up is in the round trip's time
                after_trip = i > 0 and stages[i - 1][0] == "wait"
                server_job(
                    work,
                    lambda: run(i + 1),
                    0.0 if pieces else trips * work / threads,  # pieces: a trip each
                    worker,
                    woken=not after_trip,
                    waits=waits,
                )
            elif pool == "wait":  # the server and then this thread woken
                at(now + work + busy_wake("db") + busy_wake(), waited_on_database(i))
            elif pool == "loop" and stacked_behind("client", i):
                wait = min(sum(job.left for job in jobs if job.pool == "client"), STACKED_SLICE_S)
                queued["server"] += wait
                at(now + wait, lambda: loop_task(work, lambda: run(i + 1), worker, 1 + trips / 2))
            elif pool == "loop":
                loop_task(work, lambda: run(i + 1), worker, 1 + trips / 2)
            elif pool == "client" and stacked_behind("loop", i):
                wait = min(loop_left(worker), STACKED_SLICE_S)
                queued["client"] += wait
                at(now + wait, lambda: jobs.append(Job(pool, work, lambda: run(i + 1))))
            elif pool == "db" and round_trips:  # PostgreSQL's CPU between round trips
                jobs.append(Job(pool, work, waited_on_database(i)))
            else:
                jobs.append(Job(pool, work, lambda: run(i + 1)))

        def stacked_behind(waker: str, i: int) -> bool:
            """Whether this stage's thread is woken through a socket by ``waker``'s (the
            stage before it) and waits on the waker's core (``socket_stacking``)."""
            return socket_stacking and not clients_elsewhere and i > 0 and stages[i - 1][0] == waker

        def waited_on_database(i: int):
            """``run(i + 1)`` once the database has answered, its time counted as waited."""
            began = now

            def answered() -> None:
                waits[3] += now - began
                run(i + 1)

            return answered

        # in-process SQLite: of the releases, the calls' (round trips to PostgreSQL are
        # stages of their own, and always hand the interpreter on)
        call_share = calls / releases if one_writer and releases else 0.0
        # the CPU of its unpieced locked stages (``trips_outside_lock``); 0 where the lock
        # stands for the whole of the thread's work (no lock trace: its trips in it too)
        locked_work = sum(amount for stage, amount in stages if stage == "lock")
        locked_work = locked_work if locked_work < threads - 1e-12 else 0.0

        def share(work: float) -> float:
            """This stage's part of the request's releases (in proportion to its CPU)."""
            return releases * work / threads

        run(0)

    def request(route: str, then, worker: int, record: dict | None = None) -> None:
        began = now

        def answered() -> None:
            latencies[route].append(now - began)
            timeline.append((route, began, now - began))
            if record is not None:
                record["requests"].append((route, began, now - began))
            then()

        phases(route, answered, worker)

    # per student, in the order they arrived: its HTTP requests' (route, sent, latency) and
    # each position streamed (asked, started, last frame, saved), s -- as load_test.py's
    # GYROLAB_BENCH_CLIENT_TIMES and GYROLAB_BENCH_STREAM_TIMES record a run's (convoys.py)
    records: list[dict] = []

    def run_student(script, http: int, websocket: int, record: dict) -> None:
        """The student's next step; ``http``, ``websocket``: the workers its two connections
        went to (a browser keeps its connection alive between requests: all of them reach
        the worker that accepted it)."""
        step = next(script, None)
        if step is None:
            finished[0] += 1
            return
        kind, route = step
        if kind == "until":  # a replayed browser's next step: its time, or think after now
            time, think = route
            ready = max(time, now + think)
            if ready > now + 1e-12:
                at(ready, lambda: run_student(script, http, websocket, record))
            else:
                run_student(script, http, websocket, record)
            return
        if kind == "request":
            request(route, lambda: run_student(script, http, websocket, record), http, record)
            return
        left, last_frame = [FRAMES_PER_POSITION], [0.0]
        asked, began = now, [now]

        def started() -> None:
            began[0] = now
            for j in range(1, FRAMES_PER_POSITION + 1):
                at(now + j * FRAME_SECONDS, lambda: phases(STREAM, frame_done, websocket, frame))

        def frame_done() -> None:
            left[0] -= 1
            if left[0] == 0:
                last_frame[0] = now
                phases(STREAM_SAVE, saved, websocket, position_part(saving))

        def saved() -> None:
            latencies[SAVED].append(now - last_frame[0])
            record["positions"].append((asked, began[0], last_frame[0], now))
            run_student(script, http, websocket, record)

        def marked() -> None:
            if making_ready:
                phases(STREAM_TAKE, started, websocket, position_part(making_ready, False))
            else:
                started()

        phases(STREAM_START, marked, websocket, position_part(marking))

    def accepted(kind: int) -> list[int] | None:
        """With ``worker_shares``: which worker each student's connection of one kind (0:
        HTTP, 1: WebSocket) reaches -- each worker as many as its share, in random order."""
        if worker_shares is None:
            return None
        counts = [round(share * students) for share in worker_shares]
        counts[0] += students - sum(counts)
        order = [worker for worker, count in enumerate(counts) for _ in range(count)]
        random.Random(seed + 3 + kind).shuffle(order)
        return order

    https, websockets = accepted(0), accepted(1)
    arrived = iter(range(students))

    def accepting(connections: list[int] | None, student: int) -> int:
        """The worker the kernel hands a new connection to."""
        return pick.randrange(workers) if connections is None else connections[student]

    teachers_worker = pick.randrange(workers)
    if teacher_worker is not None:
        teachers_worker = teacher_worker

    def watch() -> None:
        if finished[0] < students:
            request("GET dashboard (teacher)", look_again, teachers_worker)

    def look_again() -> None:
        at(now + TEACHER_PERIOD_S, watch)

    def arrive(index: int) -> None:
        student = next(arrived)
        record: dict = {"requests": [], "positions": []}
        records.append(record)
        if student_workers is not None:  # the run's own
            http, websocket = student_workers[index]
        else:
            http, websocket = accepting(https, student), accepting(websockets, student)
        run_student(script(), http, websocket, record)

    if arrivals is not None:
        connection_worker: dict[object, int] = {}
        shares = worker_shares or [1.0 / workers] * workers

        def worker_of(connection: object) -> int:
            """The worker a connection reaches (each new one: by the workers' shares)."""
            if connection is None or connection not in connection_worker:
                worker = pick.choices(range(workers), weights=shares)[0]
                if connection is None:
                    return worker
                connection_worker[connection] = worker
            return connection_worker[connection]

        # each browser's steps in order (paced), or each arrival alone (open loop)
        browsers: dict[object, list[tuple]] = {}
        for index, (time, kind, route, connection, *paced) in enumerate(arrivals):
            browser = paced[0] if paced and paced[0] is not None else ("alone", index)
            think = paced[1] if len(paced) > 1 else 0.0
            browsers.setdefault(browser, []).append((time, kind, route, connection, think))

        def replay(steps: list[tuple]) -> None:
            record: dict = {"requests": [], "positions": []}
            records.append(record)
            http = next((step[3] for step in steps if step[1] == "request"), None)
            websocket = next((step[3] for step in steps if step[1] == "stream"), None)

            def script():
                for time, kind, route, _connection, think in steps:
                    yield "until", (time, think)
                    yield kind, route

            run_student(script(), worker_of(http), worker_of(websocket), record)

        for steps in browsers.values():
            at(steps[0][0], lambda steps=steps: replay(steps))
        students = len(browsers)  # each browser finishes as a student does
    else:
        for index in range(students):
            # the load test's ramp, else as asked
            start = random.Random(index).uniform(0, ramp) if starts is None else starts[index]
            at(start, lambda index=index: arrive(index))
        if teacher:
            at(0.0, watch)

    def floor_tick() -> None:
        """The load generator's floor: its next piece of CPU, while a student is not done."""
        if finished[0] < students:
            spent["client"] += client_floor * CLIENT_FLOOR_PERIOD_S
            jobs.append(Job("client", client_floor * CLIENT_FLOOR_PERIOD_S, lambda: None))
            at(now + CLIENT_FLOOR_PERIOD_S, floor_tick)

    if client_floor > 0 and not clients_elsewhere:
        at(0.0, floor_tick)

    def kept_through_call(job: Job, queue: list[Job]) -> bool:
        """At the end of a segment: whether it was an SQLite call that ended before the
        thread woken for the interpreter reached a core (the caller keeps it; the waiter
        was woken for nothing) -- or, with ``loop_keeps``, the event loop's step from one
        callback to its next."""
        if call_handoff is None or len(queue) < 2:
            return False
        loop_step = job.pool == "loop" and loop_keeps  # its release is like a call's
        if not loop_step and (not job.call_share or calls_drawn.random() >= job.call_share):
            return False  # a trip to the thread pool: the thread waits, the turn passes
        none_free = asked_now[0] >= cores if wake_counts_itself else overdrawn[0] > 0
        chance = call_handoff[1] if none_free else call_handoff[0]
        if calls_drawn.random() < chance:
            return False
        wakeups["server"] += 1  # the waiter woken, on the run queue, asleep again
        queued["server"] += handoff_s
        return True

    per_core = per_core and float(cores).is_integer() and cores >= 1
    core_count = int(cores) if per_core else 1
    thread_limit = {pool: capacity[pool] for pool in ("client", "server", "loop")}
    placed: dict[object, int] = {}  # per ready thread (a job, a holder, "client"), its core
    placing = random.Random(seed + 7)
    imbalanced_since: list[float | None] = [None]

    def shared_per_core(holders: list[Job], head: Job | None):
        """``per_core``'s rates: each job's (in the order of ``jobs``), each working
        holder's; per group the share of a core its ready threads ran and waited; the
        cores busy, whether a thread waits for one, and the time to the next balancing."""
        ready: list[tuple[object, str]] = [(job, "server") for job in holders
                                           if job.handing <= 0.0]  # fmt: skip
        # a pool's jobs beyond its threads (the load generator's one event loop, a worker's
        # interpreter shared evenly) share its threads' cores: one ready thread each; the
        # database's processes, the hashes and the threads' work without the interpreter
        # are threads of their own each, however many
        of_pool: dict[str, list[Job]] = {}
        for job in jobs:
            if not job.bumped and in_shares[job.pool]:
                members = of_pool.get(job.pool)
                if members is None:
                    of_pool[job.pool] = [job]
                else:
                    members.append(job)
        threads_of: dict[str, int] = {}  # of the pools whose jobs share their threads
        for pool, members in of_pool.items():
            limit = thread_limit.get(pool)
            group = group_of[pool]
            if limit is None or (limit != 1 and len(members) <= limit):
                ready += [(job, group) for job in members]
            else:
                threads_of[pool] = min(len(members), int(limit))
                ready += [((pool, k), group) for k in range(threads_of[pool])]
        on = [0] * core_count
        core_of = {}
        fresh = []
        for key, _ in ready:
            core = placed.get(key)
            if core is None:
                fresh.append(key)
            else:
                core_of[key] = core
                on[core] += 1
        for key in fresh:  # woken: an idle core if there is one
            if 0 in on:
                core = placing.choice([core for core in range(core_count) if not on[core]])
            else:
                core = placing.randrange(core_count)
            core_of[key] = core
            on[core] += 1
        due = infinity
        while True:
            if 0 not in on or max(on) < 2:
                imbalanced_since[0] = None
                break
            if imbalanced_since[0] is None:
                imbalanced_since[0] = now
            if now - imbalanced_since[0] < balance_s - 1e-9:  # (a step: a ns at least)
                due = imbalanced_since[0] + balance_s - now
                break
            target = on.index(0)
            source = max((core for core in range(core_count) if on[core] > 1),
                         key=lambda core: on[core])  # fmt: skip
            moved = placing.choice([key for key, core in core_of.items() if core == source])
            core_of[moved] = target
            on[source] -= 1
            on[target] += 1
        placed.clear()
        placed.update(core_of)
        share_of = [1.0 / n if n else 0.0 for n in on]
        if not yielding:
            share_by_key = {key: share_of[core_of[key]] for key, _ in ready}
        else:  # a yielding pool's threads run on what the others leave of their core
            share_by_key = {}
            weak = {key for key, _ in ready
                    if (key.pool if isinstance(key, Job) else key[0]) in yielding}  # fmt: skip
            strong_on = [0] * core_count
            for key, _ in ready:
                if key not in weak:
                    strong_on[core_of[key]] += 1
            # each yielding thread's least share (``yield_share`` of an even one)
            guaranteed = [yield_share / n if n else 0.0 for n in on]
            for key, _ in ready:
                core = core_of[key]
                if key not in weak:
                    left = 1.0 - (on[core] - strong_on[core]) * guaranteed[core]
                    share_by_key[key] = left / strong_on[core]
                else:
                    weak_on = on[core] - strong_on[core]
                    share_by_key[key] = guaranteed[core] if strong_on[core] else 1.0 / weak_on
        shares: dict[str, list[float]] = {}
        for key, group in ready:
            share = share_by_key[key]
            cell = shares.get(group)
            if cell is None:
                shares[group] = [share, 1.0 - share]
            else:
                cell[0] += share
                cell[1] += 1.0 - share
        pool_rate = {pool: sum(share_by_key[pool, k] for k in range(threads))
                     for pool, threads in threads_of.items()}  # fmt: skip
        job_rates = []
        for job in jobs:
            if job.bumped:
                job_rates.append(0.0)
            elif not in_shares[job.pool]:  # the clients on their own machines
                job_rates.append(1.0)
            elif job.pool not in pool_rate:
                job_rates.append(share_by_key[job])
            elif head is not None and job.pool == "client":
                job_rates.append(pool_rate["client"] if job is head else 0.0)
            else:
                job_rates.append(pool_rate[job.pool] / len(of_pool[job.pool]))
        holder_rates = {job: share_by_key[job] for job in holders if job in core_of}
        busy = core_count - on.count(0)
        return job_rates, holder_rates, shares, busy, max(on) > 1, due

    infinity = float("inf")
    in_shares = {pool: not (clients_elsewhere and pool == "client") for pool in capacity}
    group_of = {pool: "server" if pool in ("loop", "released") else pool
                for pool in capacity}  # fmt: skip
    while jobs or timers or any(interpreters):
        # (one step to the next event: written out for speed -- a step is ≈ 20 µs of the
        # simulation's time with one or two jobs; the same arithmetic in the same order)
        counts: dict[str, int] = {}
        for job in jobs:
            if not job.bumped:  # off its core: the thread woken onto it has the core
                counts[job.pool] = counts.get(job.pool, 0) + 1
        holders = [queue[0] for queue in interpreters if queue]
        working = 0
        for job in holders:
            if job.handing <= 0.0:  # on a core, not waking
                working += 1
        if working:
            counts["server"] = counts.get("server", 0) + working
        demand = {pool: min(n, capacity[pool]) for pool, n in counts.items()}
        asked = 0
        for pool, wanted in demand.items():
            if in_shares[pool]:
                asked += wanted
        scale = min(1.0, cores / asked) if asked else 1.0
        overdrawn[0] = max(asked / cores - 1.0, 0.0)
        asked_now[0] = asked
        if yielding and per_core:  # a thread woken goes before the long runners
            asked_now[0] -= sum(demand[pool] for pool in yielding
                                if pool in demand and in_shares[pool])  # fmt: skip
        rate = {pool: demand[pool] * (scale if in_shares[pool] else 1.0) / counts[pool]
                for pool in counts}  # fmt: skip
        if holders:
            rate["interpreter"] = scale  # a holder runs on one core, shared with the rest
        head = None  # the load generator's callback running now (``client_in_order``)
        if client_in_order and not clients_elsewhere and counts.get("client"):
            head = next(job for job in jobs if job.pool == "client")
            rate["client head"] = rate["client"] * counts["client"]
        holder_rates: dict[Job, float] = {}
        next_done = infinity
        if per_core:
            rates, holder_rates, on_cores, busy, contended, next_done = shared_per_core(
                holders, head
            )
        else:
            rates = []  # each job's rate, in the order of ``jobs``
            for job in jobs:
                if head is None or job.pool != "client":
                    rates.append(rate.get(job.pool, 0.0))
                else:
                    rates.append(rate["client head"] if job is head else 0.0)

        for job, r in zip(jobs, rates, strict=True):
            until = job.bumped or (job.left / r if r else infinity)
            if until < next_done:
                next_done = until
        for job in holders:
            if job.handing > 0.0:
                next_done = min(next_done, job.handing)
                continue
            holder_rate = holder_rates[job] if per_core else rate["interpreter"]
            next_done = min(next_done, min(job.left, job.segment_left) / holder_rate)
            if len(interpreters[job.worker]) > 1:
                next_done = min(next_done, max(turn_ends[job.worker] - now, 0.0))
        next_timer = timers[0][0] - now if timers else infinity
        step = min(next_done, next_timer)
        crossing = now + step >= next_mark and step < infinity
        if crossing:  # the totals at the step's start, for the bins it ends
            at_step = (dict(ran), dict(queued))
        if step < infinity:
            handing = False
            for job in holders:
                if job.handing > 0.0:
                    handing = True
                    break
            if per_core:
                pressure[0] += step if contended or handing else 0.0
                pressure[1] += busy * step
                if contended or handing:
                    busy_waiting[busy] += step
                for group, (running, waiting) in on_cores.items():
                    ran[group] += running * step
                    queued[group] += waiting * step
            else:
                pressure[0] += step if asked > cores + 1e-12 or handing else 0.0
                pressure[1] += min(asked, cores) * step
                if asked > cores + 1e-12 or handing:
                    busy_waiting[round(min(asked, cores), 2)] += step
                for pool, asked_of in demand.items():
                    if in_shares[pool]:
                        group = group_of[pool]
                        queued[group] += asked_of * (1.0 - scale) * step
                        ran[group] += asked_of * scale * step
        for job, r in zip(jobs, rates, strict=True):
            if job.bumped:  # waiting on its core for the thread woken onto it
                queued[job.pool if job.pool in ("client", "hash") else "server"] += min(
                    job.bumped, step
                )
                job.bumped = job.bumped - step if job.bumped > step + 1e-15 else 0.0
                continue
            job.left -= r * step
        timed_out = 0.0  # each waiter's timed waits for the interpreter in this step
        if switch_interval_s > 0 and step < infinity:
            timed_out = step / switch_interval_s
        for queue in interpreters:
            for waiter in queue[1:]:
                if waiter.waits is not None:
                    waiter.waits[0] += step
                if timed_out:
                    waiting_wakeups["server"] += timed_out
                    if waiter.pool == "loop":
                        waiting_wakeups["loop"] += timed_out
        interpreter_rate = rate.get("interpreter", 0.0)
        for job in holders:
            if per_core and job.handing <= 0.0:
                interpreter_rate = holder_rates[job]
            if job.waits is not None:
                if job.handing > 0.0:
                    job.waits[1] += min(job.handing, step)
                else:
                    job.waits[2] += step * (1.0 - interpreter_rate)
            if job.handing > 0.0:  # woken, on the run queue, not yet on a core
                queued["server"] += min(job.handing, step)
                job.handing = job.handing - step if job.handing > step + 1e-15 else 0.0
                continue
            job.left -= interpreter_rate * step
            job.segment_left -= interpreter_rate * step
        now += step
        while crossing and now >= next_mark:  # each bin's end within the step, its totals
            part = (next_mark - (now - step)) / step if step else 1.0
            marks.append((
                round(next_mark / TIMELINE_BIN_S) - 1,
                *({key: was.get(key, 0.0) + (total - was.get(key, 0.0)) * part
                   for key, total in totals.items()}
                  for was, totals in zip(at_step, (ran, queued), strict=True)),
            ))  # fmt: skip
            next_mark += TIMELINE_BIN_S
        done = []
        remaining = []
        for job in jobs:
            if job.left <= 1e-9:
                done.append(job)
            else:
                remaining.append(job)
        jobs = remaining
        for job in [job for job in done if job.pool == "loop"]:  # processor sharing only
            done.remove(job)
            tasks = loops[job.worker]
            done.append(Job("loop", 0.0, tasks.pop(0)[1]))
            if tasks:
                jobs.append(Job("loop", tasks[0][0], None, tasks[0][2], job.worker))
        for job in holders:
            queue = interpreters[job.worker]
            if job.handing > 0.0:
                continue  # still being handed the interpreter
            if job.left <= 1e-9 and job.pool == "loop":
                tasks = loops[job.worker]
                done.append(Job("loop", 0.0, tasks.pop(0)[1]))
                if tasks:  # its next callback takes the interpreter again, behind others
                    job.left, job.segment = tasks[0][0], tasks[0][0] / tasks[0][2]
                    job.segment_left = job.segment
                    if loop_keeps and kept_through_call(job, queue):
                        turn_ends[job.worker] = now + switch_interval_s  # as after a call
                        continue  # taken back before a waiter reached a core
                    queue.append(queue.pop(0))
                else:
                    queue.pop(0)  # the loop goes back to waiting for sockets
            elif job.left <= 1e-9:
                queue.pop(0)
                done.append(job)
            elif job.segment_left <= 1e-9 and kept_through_call(job, queue):
                job.segment_left = job.segment  # the call ended before a waiter ran;
                turn_ends[job.worker] = now + switch_interval_s  # it waits a new interval
                continue
            elif job.segment_left <= 1e-9:  # a call, or the loop's next callback: queues again
                job.segment_left = job.segment
                queue.append(queue.pop(0))
            elif len(queue) > 1 and now >= turn_ends[job.worker] - 1e-12:
                queue.append(queue.pop(0))  # another waited a whole interval
            else:
                continue
            turn_ends[job.worker] = now + switch_interval_s
            if queue and queue[0] is not job:  # handed to a thread that waited for it
                queue[0].handing = handoff_s + busy_wake(counted=False)
                land()
                wakeups["server"] += 1
                wakeups["loop"] += queue[0].pool == "loop"
        for job in done:
            job.done()
        while timers and timers[0][0] <= now + 1e-12:
            _, _, callback = heapq.heappop(timers)
            callback()
    return {
        "latencies": latencies,
        "timeline": timeline,
        "students": records,
        "server": inside,
        "wall": now,
        "cpu": dict(spent),
        "lock held": lock_held,
        "lock by route": dict(lock_by_route),
        "run queue": {
            group: (
                sum(ran[pool] for pool in ran if fold(pool) == group),
                sum(queued[pool] for pool in queued if fold(pool) == group),
            )
            for group in {fold(pool) for pool in ran}
        },
        "wake-ups": dict(wakeups),
        "waiting wake-ups": dict(waiting_wakeups),
        "pressure": tuple(pressure),
        "busy while waiting": dict(busy_waiting),
        "threads by time": binned(marks, ran, queued),
    }


def fold(group: str) -> str:
    """A group of "threads by time" as "run queue" counts it: the hashes are the server's."""
    return "server" if group == "hash" else group


def binned(
    marks: list[tuple[int, dict[str, float], dict[str, float]]],
    ran: dict[str, float],
    queued: dict[str, float],
) -> dict[tuple[int, str], tuple[float, float]]:
    """Per (bin, group), the time run and waited for a core within the bin, s: the
    differences of the totals as they stood at each bin's end (the last bin ends with the
    class; within a step the rates hold, so a step over a bin's end is split there)."""
    out: dict[tuple[int, str], tuple[float, float]] = {}
    before: tuple[dict[str, float], dict[str, float]] = ({}, {})
    last = marks[-1][0] + 1 if marks else 0
    for index, ran_then, queued_then in [*marks, (last, ran, queued)]:
        for group in set(ran_then) | set(queued_then):
            cell = (
                ran_then.get(group, 0.0) - before[0].get(group, 0.0),
                queued_then.get(group, 0.0) - before[1].get(group, 0.0),
            )
            if cell != (0.0, 0.0):
                out[index, group] = cell
        before = (ran_then, queued_then)
    return out
