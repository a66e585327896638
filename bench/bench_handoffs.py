"""What a hand-off costs on this machine, beyond CPU: the two waits the queueing model
(``queue_sim.py``) adds to the CPU each request is measured to cost.

    .venv/bin/python bench/bench_handoffs.py [--postgresql]

1. The interpreter handed to a waiting thread.  Thread A runs Python for 0.5 ms, then makes
   a call that releases the GIL (an SQLite query of ≈ 0.3 ms); thread B, waiting to run
   Python, takes it.  The gap is from A's release to B's first instruction: B is woken by
   the GIL's condition variable and scheduled on a core, and meanwhile nobody runs Python.
   Measured at the app's switch interval (1 ms), as its served workers run; releases B
   missed (A's call over first) are counted apart.  A class's burst hands the interpreter
   on thousands of times a second (``queue_sim.HANDOFF_S``).
2. A wake-up when more is asked of the cores than they have.  Two threads wake each other
   in turn (an event each way) while processes spin: with a core free the woken thread runs
   at once; with every core asked for, it waits for one, most times a few µs, now and then
   a whole time slice of the scheduler, the more often the more is asked.  Measured with
   ``cores`` − 1 (a core free), then ``cores`` … ``cores`` + 4 spinning; the mean beyond the
   free case per core asked beyond the cores (the waking thread counted) is what a class's
   burst pays at each hand-off and round trip (``queue_sim.WAKE_BUSY_S``; the chance of a
   slice, ``WAKE_SLICE_S``, follows from it).
3. An SQLite call handing the interpreter on (``--calls FILE``).  A thread waiting for the
   interpreter is woken at each release, but takes it only if it reaches a core before
   the call is over; with a core free, calls under ≈ 40 µs are never handed on and calls
   over ≈ 100 µs always; with none free, 5-35 % of any length.  Measured for calls of
   several lengths and averaged over the app's own calls (the probe's
   ``GYROLAB_BENCH_SQLITE_CALLS``): ``queue_sim.CALL_HANDOFF``.
4. A round trip to PostgreSQL (``--postgresql``: a throw-away server on loopback): the wall
   time of ``SELECT 1`` less the CPU spent on it by this thread and by the server's
   backend -- the wake-ups and the loopback between them (``queue_sim.ROUND_TRIP_S``).

Each is printed as p10 / p50 / p90 and mean over several hundred hand-offs.  They drift
with the host (the hand-off 30-55 µs, the busy wake-up's slope 195-266 µs on one machine
in a day): measure them in the hour of the runs to be predicted and give them to
``queue_model.py --handoff-us … --wake-busy-us …``, or let ``load_test.py --handoffs``
measure them just before and after its class (``queue_model.py`` reads them from its
output).
"""

from __future__ import annotations

import argparse
import bisect
import contextlib
import multiprocessing
import os
import sqlite3
import sys
import threading
import time
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))


# A gap between two of thread B's back-to-back clock readings longer than this: B lost the
# interpreter (or its core) in between.  Its loop reads the clock every 0.1-0.2 µs; losing
# the interpreter and taking it back takes ≥ 5 µs.  (At 20 µs, with a 1 ms switch interval,
# a first reading after a short hold of the other thread's was missed: the hand-off's p50
# 22 µs against 12 µs every reading kept.)
RESUMED_AFTER_S = 1e-6


def beside_a_waiting_thread(work, resumed_after_s: float = RESUMED_AFTER_S) -> list[float]:
    """Runs ``work()`` in a thread while another (B) reads the clock whenever it has the
    interpreter; returns B's readings (``time.perf_counter``), in order, that came after
    a gap (``resumed_after_s``; 0: every reading): each first reading once B has the
    interpreter back.

    Every reading was kept before 2026-12-06: ≈ 10 million a second of B's time, and on a
    host that held the threads' cores for a minute a load test's measurement grew to 24 GB
    and was killed.  The readings the callers look for -- B's first after the other thread
    released the interpreter -- all come after such a gap: B had lost the interpreter to
    it.  Kept, ≈ 3,000 a second of B's time."""
    marks: list[float] = []  # thread B's first clock reading after each gap
    stop = threading.Event()

    def waiting_thread() -> None:
        mark, clock = marks.append, time.perf_counter
        last = clock()
        while not stop.is_set():
            now = clock()
            if now - last > resumed_after_s:
                mark(now)
            last = now

    other = threading.Thread(target=waiting_thread)
    other.start()
    time.sleep(0.02)
    working = threading.Thread(target=work)
    working.start()
    working.join()
    stop.set()
    other.join()
    return marks


def table_of(rows: int) -> sqlite3.Connection:
    """An in-memory table of ``rows`` numbers, on a connection any thread may use.  Made
    before the waiting thread starts: beside it each insert waits to take the interpreter
    back (20,000 inserts took 22 s beside a reader that keeps only its resumptions)."""
    connection = sqlite3.connect(":memory:", check_same_thread=False)
    connection.execute("CREATE TABLE t (x)")
    connection.executemany("INSERT INTO t VALUES (?)", [(i,) for i in range(rows)])
    return connection


# Thread A's Python between its releases of the interpreter: about what a class's request
# runs between two of its SQLite calls or thread-pool trips (its CPU over them: a turn's
# 6.3 ms over 17, a CSV save's 7.3 ms over 17, a results read's 8.3 ms over 12; 0.4-0.7 ms),
# and under the app's switch interval, so that each release is a call's, not a forced switch
HOLD_S = 0.0005


def app_switch_interval_s() -> float:
    """The interpreter's switch interval the app's served workers set (s; the settings',
    ``GYROLAB_SWITCH_INTERVAL_MS``)."""
    from app.config import Settings

    return Settings().switch_interval_ms / 1000


@dataclass
class Handoffs:
    """What ``measure_handoffs`` saw: the gaps (s) of the releases the waiting thread took
    (the interpreter idle from A's release to B's first instruction), how many releases it
    missed (A's call was over and A took the interpreter back first: nobody waited on an
    idle interpreter), and the switch interval they were measured at (s)."""

    gaps: np.ndarray
    missed: int
    switch_interval_s: float


def measure_handoffs(
    count: int = 400,
    hold_s: float = HOLD_S,
    switch_interval_s: float | None = None,
    rows: int = 20_000,
) -> Handoffs:
    """``count`` releases of the interpreter by a thread (A) that runs Python for ``hold_s``
    and then makes an SQLite call, with another (B) waiting to run Python; at the app's
    switch interval (``switch_interval_s``: else the settings'), the process's own put
    back after; the call sums ``rows`` numbers (20,000: ≈ 0.3 ms).

    Before 2026-12-06 this ran at Python's 5 ms with 2 ms holds: a waiting thread then sleeps
    up to 5 ms between its asks for the interpreter, and a core idle that long wakes slower
    (bench/README.md, thirty-eighth part) -- and each release it missed added A's whole next
    hold to the mean.  The app's workers run at 1 ms: B is never asleep longer."""
    clock = time.perf_counter
    releases: list[float] = []
    ends: list[float] = []
    connection = table_of(rows)
    interval = app_switch_interval_s() if switch_interval_s is None else switch_interval_s

    def releasing_thread() -> None:
        for _ in range(count):
            busy_until = clock() + hold_s
            while clock() < busy_until:  # Python: B waits for the interpreter
                pass
            releases.append(clock())
            connection.execute("SELECT sum(x) FROM t").fetchone()  # B takes it meanwhile
            ends.append(clock())  # A has the interpreter back
        connection.close()

    before = sys.getswitchinterval()
    sys.setswitchinterval(interval)
    try:
        marks = beside_a_waiting_thread(releasing_thread)
    finally:
        sys.setswitchinterval(before)
    gaps, missed = [], 0
    for released, ended in zip(releases, ends, strict=True):
        after = bisect.bisect_right(marks, released)
        if after < len(marks) and marks[after] < ended:
            gaps.append(marks[after] - released)
        else:
            missed += 1
    return Handoffs(np.array(gaps), missed, interval)


def interpreter_handoffs(count: int = 400) -> np.ndarray:
    """Seconds from a thread's release of the interpreter to a waiting thread's first
    instruction, for the releases it took (``measure_handoffs``)."""
    return measure_handoffs(count).gaps


def _spin(stop) -> None:
    while not stop.is_set():
        pass


@contextlib.contextmanager
def spinning_processes(count: int) -> Iterator[None]:
    """``count`` processes spinning on the cores while the block runs (given 0.3 s to
    start)."""
    stop = multiprocessing.Event()
    processes = [multiprocessing.Process(target=_spin, args=(stop,)) for _ in range(count)]
    for process in processes:
        process.start()
    time.sleep(0.3)
    try:
        yield
    finally:
        stop.set()
        for process in processes:
            process.join()


def handoffs_beside(spinning: int, count: int = 400) -> np.ndarray:
    """``interpreter_handoffs`` while ``spinning`` processes keep cores busy: with no core
    free, the thread woken for the interpreter waits for one, and meanwhile the thread that
    released it takes it back at the end of its call (CPython's GIL is not handed in
    order), so the waiting thread's gap grows to milliseconds while the interpreter itself
    does not idle."""
    with spinning_processes(spinning):
        return interpreter_handoffs(count)


def call_handoffs(rows: int, count: int = 2000, python_s: float = 0.0003) -> tuple[float, float]:
    """How often a thread waiting for the interpreter takes it during an SQLite call of
    the other: thread A runs Python for ``python_s``, then a query over ``rows`` rows
    (the GIL released while SQLite runs), ``count`` times; thread B runs Python whenever it
    has the interpreter.  Returns (the chance that B ran during one of A's calls, the
    calls' median CPU in s).  B is woken at each release, but if A's call is over before B
    reaches a core, A takes the interpreter back and B sleeps again."""
    clock = time.perf_counter
    calls: list[tuple[float, float]] = []
    spent: list[float] = []
    connection = table_of(max(rows, 1))

    def calling_thread() -> None:
        query = "SELECT sum(x) FROM t" if rows else "SELECT 1"
        cursor = connection.cursor()
        for _ in range(count):
            busy_until = clock() + python_s
            while clock() < busy_until:
                pass
            began, cpu = clock(), time.thread_time()
            cursor.execute(query)
            spent.append(time.thread_time() - cpu)
            calls.append((began, clock()))
        connection.close()

    marks = beside_a_waiting_thread(calling_thread)
    taken = 0
    for began, ended in calls:
        after = bisect.bisect_right(marks, began)
        taken += after < len(marks) and marks[after] < ended
    return taken / len(calls), float(np.median(spent))


CALL_ROWS = (0, 200, 400, 600, 800, 1000, 3000, 10_000)


def call_handoff_curve(spinning: int) -> list[tuple[float, float]]:
    """(a call's CPU s, the chance it hands the interpreter on) for calls of several
    lengths, while ``spinning`` processes keep cores busy; sorted by length."""
    with spinning_processes(spinning):
        return sorted((length, chance) for chance, length in map(call_handoffs, CALL_ROWS))


def call_handoff_chance(curve: list[tuple[float, float]], durations: np.ndarray) -> float:
    """The chance that one of the app's calls (``durations``, s: the probe's
    GYROLAB_BENCH_SQLITE_CALLS) hands the interpreter on: the curve at each call's length
    (linear between its points, flat beyond its ends), averaged over the calls."""
    lengths, chances = zip(*curve, strict=True)
    return float(np.mean(np.interp(durations, lengths, chances)))


def call_handoff_chances(durations: np.ndarray, report=None) -> tuple[float, float]:
    """The chance that one of the app's SQLite calls (``durations``, s) hands the
    interpreter on, with a core free and with none (``queue_sim.CALL_HANDOFF``), each from
    a curve measured now; ``report``: called with each curve's line."""
    chances = []
    cores = os.cpu_count() or 1  # the calling and the waiting thread want two of them
    for spinning, label in ((max(cores - 2, 0), "a core free"), (cores - 1, "no core free")):
        curve = call_handoff_curve(spinning)
        chances.append(call_handoff_chance(curve, durations))
        if report:
            points = ", ".join(f"{length * 1e6:.0f} µs {chance:.0%}" for length, chance in curve)
            report(f"a call handing the interpreter on, {label}: {points}; the app's calls:"
                   f" {chances[-1]:.1%}")  # fmt: skip
    return chances[0], chances[1]


def wake_ups(busy_processes: int, count: int = 3000) -> np.ndarray:
    """Seconds of each wake-up (half a round trip of two threads waking each other) while
    ``busy_processes`` processes spin; between round trips the waking thread runs Python
    for 0.5 ms, as a thread holding the interpreter does."""
    with spinning_processes(busy_processes):
        return _wake_ups(count)


def _wake_ups(count: int) -> np.ndarray:
    ping, pong = threading.Event(), threading.Event()

    def answering() -> None:
        for _ in range(count):
            ping.wait()
            ping.clear()
            pong.set()

    other = threading.Thread(target=answering)
    other.start()
    time.sleep(0.05)
    halves = []
    try:
        for _ in range(count):
            began = time.perf_counter()
            ping.set()
            pong.wait()
            pong.clear()
            halves.append((time.perf_counter() - began) / 2)
            busy_until = time.perf_counter() + 0.0005
            while time.perf_counter() < busy_until:
                pass
    finally:
        other.join()
    return np.array(halves)


def postgresql_round_trips(count: int = 2000) -> np.ndarray:
    """Seconds of each ``SELECT 1`` round trip beyond the CPU spent on it (this thread's and
    the server backend's), against a throw-away server on loopback."""
    import psycopg

    from tests.pgserver import PostgresServer

    server = PostgresServer().start(durable=True)
    try:
        url = server.create_database("gyrolab_handoffs").replace("postgresql+psycopg", "postgresql")
        with psycopg.connect(url, autocommit=True) as connection:
            backend = connection.execute("SELECT pg_backend_pid()").fetchone()[0]
            stat = Path(f"/proc/{backend}/schedstat")

            def backend_cpu() -> float:
                return int(stat.read_text().split()[0]) / 1e9

            for _ in range(100):  # warm: the statement prepared, the backend's caches
                connection.execute("SELECT 1").fetchone()
            beyond = []
            for _ in range(count):
                wall, mine, theirs = time.perf_counter(), time.thread_time(), backend_cpu()
                connection.execute("SELECT 1").fetchone()
                spent = (time.thread_time() - mine) + (backend_cpu() - theirs)
                beyond.append(time.perf_counter() - wall - spent)
                time.sleep(0.0005)  # both sides idle between, as in a request's pauses
    finally:
        server.stop()
    return np.array(beyond)


def describe(name: str, seconds: np.ndarray) -> str:
    p10, p50, p90 = np.percentile(seconds, [10, 50, 90]) * 1e6
    return (
        f"{name}: p10 {p10:.0f} µs, p50 {p50:.0f} µs, p90 {p90:.0f} µs,"
        f" mean {np.mean(seconds) * 1e6:.0f} µs over {len(seconds)}"
    )


def hand_off_constants(wakes: int = 3000, report=None) -> tuple[float, float]:
    """The queueing model's two waits as this machine pays them now, seconds: the
    interpreter's hand-off to a waiting thread (mean) and a wake-up's extra wait for each
    core asked beyond each core (least squares through 0 over ``cores`` … ``cores`` + 4
    processes spinning, against a core free); ``wakes``: wake-ups timed at each load;
    ``report``: called with each measurement's line."""
    say = report or (lambda line: None)
    measured = measure_handoffs()
    handoffs = measured.gaps
    interval_ms = measured.switch_interval_s * 1e3
    say(describe("the interpreter handed to a waiting thread", handoffs)
        + f" (missed {measured.missed}; switch interval {interval_ms:g} ms)")  # fmt: skip
    cores = os.cpu_count() or 1
    free = wake_ups(cores - 1, wakes)
    say(describe(f"a wake-up with a core free ({cores - 1} spinning)", free))
    beyond, extra = [], []
    for spinning in (cores, cores + 1, cores + 2, cores + 4):
        busy = wake_ups(spinning, wakes)
        asked = (spinning + 1) / cores - 1  # cores asked beyond the cores, per core
        beyond.append(asked)
        extra.append(np.mean(busy) - np.mean(free))
        say(describe(f"a wake-up with {spinning} spinning", busy))
        say(f"  {asked:.1f} cores asked beyond each core: {extra[-1] * 1e6:.0f} µs more, mean;"
            f" over 1 ms: {np.mean(busy > 1e-3):.1%}")  # fmt: skip
    slope = float(np.dot(beyond, extra) / np.dot(beyond, beyond))
    return float(np.mean(handoffs)), slope


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--postgresql", action="store_true", help="also a PostgreSQL round trip")
    parser.add_argument(
        "--calls",
        type=Path,
        help="the app's SQLite calls (µs, one a line: the probe's GYROLAB_BENCH_SQLITE_CALLS):"
        " the chance that one hands the interpreter on, with a core free and with none"
        " (queue_sim.CALL_HANDOFF)",
    )
    args = parser.parse_args()
    if args.calls:
        durations = np.loadtxt(args.calls) / 1e6
        print(f"{len(durations)} SQLite calls of the app: p50 {np.median(durations) * 1e6:.1f}"
              f" µs, p90 {np.percentile(durations, 90) * 1e6:.1f} µs")  # fmt: skip
        chances = call_handoff_chances(durations, report=print)
        print(f"  queue_sim.CALL_HANDOFF ≈ ({chances[0]:.2f}, {chances[1]:.2f})")
        return 0
    _, slope = hand_off_constants(report=print)
    print(f"  ≈ {slope * 1e6:.0f} µs more a wake-up for each core asked beyond each core")
    busy = (os.cpu_count() or 1) - 1
    print(describe(f"the interpreter handed on with {busy} process(es) spinning (no core free)",
                   handoffs_beside(busy)))  # fmt: skip
    if args.postgresql:
        print(describe("a PostgreSQL round trip beyond its CPU", postgresql_round_trips()))
    return 0


if __name__ == "__main__":
    sys.exit(main())
