"""A queueing model of the load test: per-route p95 predicted from measured CPU per request.

    .venv/bin/python bench/queue_model.py [--students 60 120] [--backend sqlite|postgresql]
                                          [--measure 3] [--compare FILE ...]
                                          [--costs FILE] [--department STUDENTS WORKERS ...]
    .venv/bin/python bench/queue_model.py --costs FILE --class-cpu CPU ... --class-run RUN ...
                                          [--server-times TIMES ...] [--seeds 20]

1. Measure: the load test's own scenario (``load_test.student``) runs for ``--measure``
   students one after another -- nothing else runs -- against a real server, and every
   request's CPU is read: the server's (all its threads, ``/proc/<pid>/task/*/schedstat``,
   nanoseconds; a thread that ends keeps its last reading), of it the event loop's (the
   worker's main thread), PostgreSQL's (every ``postgres`` process) and the load
   generator's own (``time.process_time``).  A probe loaded into that server only
   (``bench/probe/sitecustomize.py``) counts each request's database calls (SQLite's, or
   PostgreSQL's round trips) and thread-pool trips: the places where its threads give up
   the interpreter.  What a student's stream costs besides its requests (frames, the saves
   at each position's end) is divided by the frames it received.  The CPU of one password
   check is measured in process.  With ``--class-cpu`` each request instead costs what
   one of the class's own requests of its route cost, one near its own place in the
   class's order (the probe's ``GYROLAB_BENCH_REQUEST_CPU`` lines of a load test, in the
   order answered, ``class_cpu.py``; ``--costs-at-random``: any of them), its unseen part
   scaled so that the class's CPU adds up to what that run used.
2. Predict: a discrete-event simulation replays the scenario for N students -- the same
   start times as the load test; each student's connection reaches one worker and keeps
   it; each request's client work, the event loop's first half (the request read and
   routed), a work place (every HTTP request: 2 per worker, ``web.admission``; a write
   waiting over 50 ms for the write lock gives it back), a write place (state-changing
   requests: 8 per worker), the threads' work (on SQLite inside the one write lock for the
   writes; on PostgreSQL cut at each round trip to the database server, whose share of
   the work and a round trip's wait come between; a log-in's password hash outside the
   interpreter, at most 4 at once, its work place given to another request from then on),
   the event loop's second half, the client's again;
   each stream position 15 frames 0.2 s apart. Each worker's interpreter runs one thread
   at a time, handed on round robin when a thread gives it up (at each counted call or
   trip; the event loop at each wake-up) or after 5 ms with others waiting (CPython's
   GIL); each hand-off to a waiting thread leaves the interpreter idle while that thread
   is woken (``queue_sim.HANDOFF_S``, measured by ``bench_handoffs.py``), longer when more
   is asked of the cores than they have (``WAKE_BUSY_S``); the event loop runs its tasks
   one by one. The load generator is one Python thread; each thread ready to run sits on
   one of the machine's cores (a woken one on an idle core if there is one, else on
   either) and shares that core with the others there (``--cores-shared-evenly``: every
   ready thread shares all the cores, each slowing in proportion, as before).  Each
   prediction is the median of ``--seeds`` simulations (which worker each connection
   reaches, which measured costs each request draws).
3. Compare: ``--compare`` reads the tables ``load_test.py`` printed and puts each route's
   measured p95 (the median of the runs, and their range) beside the prediction, and the
   CPU the runs used beside the CPU the costs ask for; with ``--class-cpu`` every
   ``--class-run`` is predicted from the CPU per request measured in it (and with the
   hand-off measured just before and after its class, where ``load_test.py --handoffs``
   measured it: it drifts with the host; and with a busy wake-up's wait the run's own,
   its server threads' wait on the run queue per time on a core, where
   ``load_test.py --run-queue`` measured it, else the one measured beside it), then the runs of
   each class size are summed up: the median predicted and measured p95 per route, each
   run's error, and whether each run's p95 lies inside the band its seeds gave (the 10th
   to 90th percentile of the seeds' p95: how far one run's p95 moves by chance alone, so
   how near any prediction of one run can be; ``--seeds 20`` for a band worth reading).
   With ``--pooled`` (and ``--client-times``) the runs of one class size are also taken
   together, as one run as long as all of them: each route's p95 over all their requests,
   known to about 1/√K of one run's interval, against the p95 of the model's requests of
   every seed of every run's prediction.  ``--by-time ROUTE`` sets a route's requests side
   by side by when they were sent from the class's start.

``bench/README.md`` has how far it is from measured, and what it still leaves out.  The
simulation is in ``queue_sim.py``; a class's own CPU per request is read in
``class_cpu.py``.
"""

from __future__ import annotations

import argparse
import asyncio
import contextlib
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
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "bench"))

import connections  # noqa: E402  (bench/, the script's folder)
import convoys  # noqa: E402
import load_test  # noqa: E402
import p95_interval  # noqa: E402
import replay  # noqa: E402
import request_waits  # noqa: E402
from capacity import postgres_pids, server_pids, thread_cpu  # noqa: E402
from class_cpu import (  # noqa: E402
    ClientFit,
    attributed_costs,
    fitted_client_cpu,
    in_class,
    lock_trace_by_route,
    locked_shares,
    route_of,
    server_times,
    worker_shares,
)
from queue_sim import (  # noqa: E402
    CALL_HANDOFF,
    HANDOFF_S,
    LOGIN_TRIPS_AFTER_HASH,
    OUTSIDE,
    STREAM,
    STREAM_SPLIT,
    SWITCH_INTERVAL_S,
    TIMELINE_BIN_S,
    WAKE_BUSY_S,
    WORK_PLACES,
    WRITE_SLOTS,
    simulate,
)
from sched_trace import busy_report  # noqa: E402

from tests.e2e.conftest import running_server  # noqa: E402
from tests.pgserver import PostgresServer  # noqa: E402

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

    async with load_test.browser(base) as client:
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


# --- 3. measured against predicted -----------------------------------------------------------


FRAMES_LINE = re.compile(r"(\d+) stream frames")
CPU_LINE = re.compile(
    r"CPU used during the class: server ([\d.]+) s, PostgreSQL ([\d.]+) s, "
    r"load generator ([\d.]+) s"
)


HANDOFFS_LINE = re.compile(
    r"the interpreter's ([\d /]+) µs, a busy wake-up ([\d /-]+) µs a core asked beyond"
)
CALL_HANDOFFS_LINE = re.compile(r"measured after it: a core free ([\d.]+)%, none free ([\d.]+)%")
ELSEWHERE_LINE = re.compile(r"anything else (-?[\d.]+) s")
MACHINE_BUSY_LINE = re.compile(r"busy ([\d.]+) s .*a task waited for a core during ([\d.]+) s")
STEAL_LINE = re.compile(r": ([\d.]+) s, (\d+)% of the cores' time")
# CPU beyond this, spent on the machine during a class by neither the class's processes nor
# the kernel's usual few tenths: the run shared the cores (another job beside it)
ELSEWHERE_S = 2.0
RUN_QUEUE_GROUP = re.compile(
    r"(server|PostgreSQL|load generator|of it the event loops) ([\d.]+) / ([\d.]+) s"
    r" \(\d+%(?:, (\d+) slices)?\)"
)
RUN_QUEUE_KEYS = {
    "server": "server", "PostgreSQL": "db", "load generator": "client",
    load_test.LOOPS: "loop",
}  # fmt: skip


def run_client_fit(run: Path, index: int, args, alone: dict) -> ClientFit | None:
    """The load generator's CPU per request, per frame and whatever it sent as run number
    ``index`` spent it (``class_cpu.fitted_client_cpu``), or None where the run does not
    tell it (no ``--run-queue`` line, no client or stream times given for it)."""
    ran = ran_by_time(run).get("client")
    frames = FRAMES_LINE.search(run.read_text())
    if not ran or not frames or len(args.client_times) <= index or len(args.stream_times) <= index:
        return None
    lines = p95_interval.client_lines(args.client_times[index])
    requests = [(route_of(method, url), sent, answered)
                for method, url, sent, answered, _ in lines]  # fmt: skip
    spans = [(float(fields[5]), float(fields[6]))
             for fields in map(str.split, args.stream_times[index].read_text().splitlines())
             if len(fields) == 8]  # fmt: skip
    return fitted_client_cpu(
        ran, load_test.RUN_QUEUE_BIN_S, requests, spans, int(frames.group(1)), alone
    )


def ran_by_time(path: Path) -> dict[str, list[float]]:
    """Per group ("server", "db", "client"), its threads' time on a core in each
    ``load_test.RUN_QUEUE_BIN_S`` from the class's first request, s, as ``load_test.py
    --run-queue`` printed it (the last class in the file); empty where it did not."""
    found: dict[str, list[float]] = {}
    for line in path.read_text().splitlines():
        if load_test.RAN_BY_TIME_LABEL not in line:
            continue
        found = {}
        for part in line.split(load_test.RAN_BY_TIME_LABEL + ":", 1)[1].split(";"):
            words = part.split()
            numbers = [word for word in words if re.fullmatch(r"-?[\d.]+", word)]
            group = " ".join(word for word in words if word not in numbers)
            if group in RUN_QUEUE_KEYS:
                found[RUN_QUEUE_KEYS[group]] = [float(number) for number in numbers]
    return found


def measured_p95(path: Path) -> dict[str, dict[str, float]]:
    """Per backend heading ("SQLite", "PostgreSQL") → route → p95 ms, from load_test's output
    (and, under the keys "cpu server", "cpu db", "cpu client", the CPU the run used, s; with
    ``load_test.py --handoffs``, under "handoff us" and "wake busy us" the mean of what was
    measured just before and after the class, and with the probe's SQLite calls under
    "call free" and "call busy" the chance that one hands the interpreter on; with
    ``--run-queue``, under "waited server",
    "ran server" and so for "db" and "client", each group's time waiting for a core and on
    one during the class, s, and under "cpu elsewhere" the machine's CPU that went to
    neither the class's processes nor the kernel, under "busy" the cores' busy time and
    under "pressure" the time some task waited for a core, s; and under "steal" and "steal
    share" the time the hypervisor kept the cores from the class, s, and its share of the
    time the class wanted them)."""
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
        if backend and load_test.RUN_QUEUE_LABEL in line:
            for group, waited, ran, slices in RUN_QUEUE_GROUP.findall(line):
                tables[backend][f"waited {RUN_QUEUE_KEYS[group]}"] = float(waited)
                tables[backend][f"ran {RUN_QUEUE_KEYS[group]}"] = float(ran)
                if slices:
                    tables[backend][f"slices {RUN_QUEUE_KEYS[group]}"] = float(slices)
        machine = MACHINE_BUSY_LINE.search(line)
        if backend and load_test.MACHINE_LABEL in line and machine:
            tables[backend]["busy"], tables[backend]["pressure"] = map(float, machine.groups())
        stolen = STEAL_LINE.search(line)
        if backend and load_test.STEAL_LABEL in line and stolen:
            tables[backend]["steal"] = float(stolen.group(1))
            tables[backend]["steal share"] = float(stolen.group(2)) / 100
        elsewhere = ELSEWHERE_LINE.search(line)
        if backend and load_test.MACHINE_LABEL in line and elsewhere:
            tables[backend]["cpu elsewhere"] = float(elsewhere.group(1))
        chances = CALL_HANDOFFS_LINE.search(line)
        if backend and chances:
            for key, value in zip(("call free", "call busy"), chances.groups(), strict=True):
                tables[backend][key] = float(value) / 100
        waits = HANDOFFS_LINE.search(line)
        if backend and waits:
            for key, values in zip(("handoff us", "wake busy us"), waits.groups(), strict=True):
                tables[backend][key] = float(np.mean([float(v) for v in values.split("/")]))
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
        "--costs-at-random",
        action="store_true",
        help="with --class-cpu: each request costs one of its route's in the class drawn at "
        "random, not one near its place in the class's order (the model before 2026-12-03)",
    )
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
        "--department-slice",
        type=int,
        default=DEPARTMENT_SLICE,
        help="with --department: this many workers simulated together on as many cores "
        f"(default {DEPARTMENT_SLICE}; 1: each on a core of its own, the model before "
        "2026-12-05)",
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
        nargs="+",
        help="each route's own CPU as a class spent it: the file a load test's server wrote "
        "with the probe (PYTHONPATH=bench/probe GYROLAB_BENCH_REQUEST_CPU=FILE load_test.py), "
        "in place of one student's alone; several runs: each predicted from its own",
    )
    parser.add_argument(
        "--handoff-us",
        type=float,
        help="the interpreter's hand-off to a waiting thread, µs (bench_handoffs.py's first "
        "line; it drifts with the host: 30-55 µs seen on one machine in a day); default: "
        "what a --class-run measured beside its class (load_test.py --handoffs), else "
        f"{HANDOFF_S * 1e6:.0f}",
    )
    parser.add_argument(
        "--wake-busy-us",
        type=float,
        help="a wake-up's extra wait for each core asked beyond each core, µs "
        "(bench_handoffs.py's last line; 159-266 µs seen); default: as --handoff-us, else "
        f"{WAKE_BUSY_S * 1e6:.0f}",
    )
    parser.add_argument(
        "--every-call-hands",
        action="store_true",
        help="every SQLite call hands the interpreter to a waiting thread (the model before "
        "2026-11-27), not only with the chance bench_handoffs.py --calls measured",
    )
    parser.add_argument(
        "--call-handoff",
        type=float,
        nargs=2,
        metavar=("FREE", "BUSY"),
        help="the chance (0-1) that an SQLite call hands the interpreter to a waiting thread, "
        "with a core free and with none: e.g. what a --class-run measured after its class "
        "(load_test.py --handoffs with the probe's GYROLAB_BENCH_SQLITE_CALLS; printed beside "
        f"its prediction); default {CALL_HANDOFF[0]:.2f} {CALL_HANDOFF[1]:.2f}",
    )
    parser.add_argument(
        "--loop-queues",
        action="store_true",
        help="the event loop queues for the interpreter again behind the waiting threads "
        "after each of its callbacks (the model before 2026-12-05), not giving it up as an "
        "SQLite call does (handed on with the call's chance, else kept)",
    )
    parser.add_argument(
        "--cpu-scale",
        type=float,
        default=1.0,
        help="every request's server CPU (its event loop's part and a log-in's hash too) "
        "times this: how far a p95 moves when the CPU per request is a few per cent off",
    )
    parser.add_argument(
        "--wake-from-handoffs",
        action="store_true",
        help="a busy wake-up's wait a core asked beyond as bench_handoffs.py measured it "
        "beside the class (the model before 2026-12-05, late morning), not the run's own "
        "wait of its server threads on the run queue per time on a core",
    )
    parser.add_argument(
        "--wake-beside-itself",
        action="store_true",
        help="a busy wake-up's wait grows with the cores asked beyond the cores there are "
        "without the woken thread (the model before 2026-12-05), not counting it as "
        "bench_handoffs.py measured it",
    )
    parser.add_argument(
        "--socket-stacking",
        action="store_true",
        help="a thread woken through a socket by one that goes on running waits on the "
        "waker's core until it stops or its slice ends",
    )
    parser.add_argument(
        "--trips-in-one-thread",
        action="store_true",
        help="one thread does all of a request's work, the loop's part before it (the model "
        "before 2026-12-05), not a pool thread woken for each trip and the coroutine's next "
        "step on the event loop between them, as in the app",
    )
    parser.add_argument(
        "--woken-at-once",
        action="store_true",
        help="a thread woken to a free interpreter runs at once (the model before "
        "2026-11-27), not after the hand-off's wait for a core",
    )
    parser.add_argument(
        "--seeds",
        type=int,
        default=5,
        help="simulations per prediction, each with its own seed (which worker each "
        "connection reaches, which measured costs each request draws); the p95 is their "
        "median",
    )
    parser.add_argument(
        "--mean-costs",
        action="store_true",
        help="with --class-cpu: every request of a route costs the route's mean (else each "
        "simulated request costs one of the class's own requests, drawn at random)",
    )
    parser.add_argument(
        "--server-times",
        type=Path,
        nargs="*",
        default=[],
        help="what the probe's GYROLAB_BENCH_SERVER_TIMES wrote in the --class-run runs (one "
        "file per run, in order): the server's part of each latency, and of it the wait "
        "for a work place, measured beside predicted; with several workers, each worker's "
        "share of the run's requests is its chance of a new connection in the simulation; "
        "with --client-times too, each student's HTTP connection and WebSocket reach the "
        "workers they reached in the run (the probe's WebSocket lines, since 2026-12-06)",
    )
    parser.add_argument(
        "--connections-at-random",
        action="store_true",
        help="with --server-times and --client-times: the connections reach the workers at "
        "random in the runs' shares, not as in the run (the model before 2026-12-06)",
    )
    parser.add_argument(
        "--request-waits",
        type=Path,
        nargs="*",
        default=[],
        help="what the probe's GYROLAB_BENCH_REQUEST_WAITS wrote in the --class-run runs (one "
        "file per run, in order): where each request's time inside the server went (CPU, "
        "waits off a core, on the run queue), and how crowded the work places were, "
        "measured beside predicted",
    )
    parser.add_argument(
        "--client-times",
        type=Path,
        nargs="*",
        default=[],
        help="what load_test.py's GYROLAB_BENCH_CLIENT_TIMES wrote in the --class-run runs "
        "(one file per run, in order, with --server-times): each request's time outside the "
        "app, before it and after it, measured beside predicted",
    )
    parser.add_argument(
        "--trips-inside-lock",
        action="store_true",
        help="a write's thread-pool trips hand the interpreter on inside its locked part "
        "too, in proportion to the CPU (the model before 2026-12-05's twenty-eighth part)",
    )
    parser.add_argument(
        "--released-share",
        type=float,
        default=0.0,
        help="the share of a thread's CPU that runs with the interpreter released (SQLite's "
        "own work in its calls, the kernel's in system calls), on a core after the part that "
        "holds it (default 0: all of it holds the interpreter)",
    )
    parser.add_argument(
        "--frames-in-a-thread",
        action="store_true",
        help="each stream frame also queues for the interpreter as a thread's work of 1 µs "
        "(the model before 2026-12-05's thirty-second part; in the app a frame is the event "
        "loop's work alone)",
    )
    parser.add_argument(
        "--stream-times",
        type=Path,
        nargs="*",
        default=[],
        help="what load_test.py's GYROLAB_BENCH_STREAM_TIMES wrote in the --class-run runs "
        "(one file per run, in order, with --client-times): how the students fell into "
        "step, turn by turn, measured beside predicted (convoys.py)",
    )
    parser.add_argument(
        "--landing-us",
        type=float,
        default=0.0,
        help="a server thread woken to run lands on a core at random; one running a thread "
        "outside the interpreter (a log-in's hash, the load generator) puts it off its core "
        "this long, µs (bench_gil_wakes.py --beside: 223-424 µs a time); 0: never",
    )
    parser.add_argument(
        "--landing-on",
        nargs="+",
        choices=("hash", "client", "released"),
        default=list(OUTSIDE),
        help="with --landing-us: the threads outside the interpreter a woken server thread "
        "puts off their core (the scheduler's trace of a class, sched_trace.py: the load "
        "generator preempted 2,536 times, the server's threads 29,726)",
    )
    parser.add_argument(
        "--cores-shared-evenly",
        action="store_true",
        help="every ready thread shares all the cores evenly (the model before 2026-12-06's "
        "fortieth part), instead of each sitting on one core and sharing that one with the "
        "others there (a woken thread to an idle core if there is one, else to either)",
    )
    parser.add_argument(
        "--balance-us",
        type=float,
        default=0.0,
        help="each thread on its own core: how long a core idles while another has two "
        "ready threads before it takes one, µs (0: at once; the kernel's trace of a class: "
        "more makes the model's burst far too slow)",
    )
    parser.add_argument(
        "--yielding",
        nargs="*",
        default=[],
        choices=["hash", "client", "released", "db"],
        help="each thread on its own core: these pools' threads run only on what the others "
        "leave of their core, and a thread woken does not wait for them (a long-running "
        "thread behind threads woken for short bursts, as the kernel's EEVDF has it)",
    )
    parser.add_argument(
        "--yield-share",
        type=float,
        default=0.0,
        metavar="S",
        help="with --yielding: the least a yielding thread runs, as a share S of an even "
        "share of its core (0: only what the others leave; 1: an even share)",
    )
    parser.add_argument(
        "--hash-scale",
        type=float,
        default=1.0,
        metavar="X",
        help="a log-in's password hash X times its CPU measured alone (beside a busy core: "
        "1.08-1.13, bench/README.md forty-third part)",
    )
    parser.add_argument(
        "--login-trips-after-hash",
        type=int,
        default=LOGIN_TRIPS_AFTER_HASH,
        metavar="N",
        help="a log-in's last N round trips to PostgreSQL after its hash, as the app makes "
        "them (0: all before it, the model before the forty-fourth part)",
    )
    parser.add_argument(
        "--client-frame-weight",
        type=lambda value: value if value == "fit" else float(value),
        default=1.0,
        metavar="W",
        help="with --class-run: the load generator's CPU per stream frame W times its share "
        "beside its requests' as one student's alone has them (the run's total kept); "
        "'fit': each run's own, fitted to when it spent its CPU (needs the run's "
        "--run-queue line, --client-times and --stream-times)",
    )
    parser.add_argument(
        "--client-floor",
        action="store_true",
        help="with --class-run: the load generator's CPU whatever it sends (a share of a "
        "core, fitted to each run as --client-frame-weight fit is, with the same files) run "
        "apart while the class runs, not spread over its requests and frames",
    )
    parser.add_argument(
        "--client-in-order",
        action="store_true",
        help="the load generator's client work one callback at a time, in the order they "
        "became ready (one event loop), instead of every student's shared evenly",
    )
    parser.add_argument(
        "--replay",
        action="store_true",
        help="with --client-times and --stream-times: the model's server is sent each run's "
        "own requests and positions at the times the run sent them, open loop (replay.py), "
        "instead of students that send each step when the last was answered -- the server's "
        "side of the model judged apart from how the class falls into step",
    )
    parser.add_argument(
        "--paced",
        action="store_true",
        help="with --replay: each browser's steps in order, each at its time in the run or "
        "as long after the model answered the step before as the run's browser took, "
        "whichever is later (the run's client times must name each request's browser)",
    )
    parser.add_argument(
        "--by-time",
        nargs="*",
        default=[],
        metavar="ROUTE",
        help="with --client-times: each ROUTE's requests by when they were sent from the "
        "class's start, 2 s windows, count and p50 / p95, predicted beside measured",
    )
    parser.add_argument(
        "--pooled",
        action="store_true",
        help="with --client-times: the requests of all the --class-run runs of one class "
        "size and database taken together, as one run K times as long: their p95 per route "
        "(and its interval, narrower by about √K) against the p95 of the model's requests "
        "of every seed of every run's prediction (with --model-as-run: an exact model "
        "pooled the same way)",
    )
    parser.add_argument(
        "--model-as-run",
        type=int,
        default=0,
        metavar="N",
        help="with --class-run: simulate each run N more times with seeds the prediction did "
        "not use and score each as if measured (inside its own p95 interval, within 10 %%): "
        "what an exact model would score against one run",
    )
    parser.add_argument(
        "--lock-trace",
        type=Path,
        nargs="*",
        default=[],
        help="what the probe's GYROLAB_BENCH_LOCK_TRACE wrote in the --class-run runs (one "
        "file per run, in order; SQLite): each write route holds the write lock for the "
        "share of its thread CPU its transactions took, and does the rest before (else the "
        "model holds it for all of the route's thread CPU)",
    )
    parser.add_argument(
        "--class-run",
        type=Path,
        nargs="+",
        help="with --class-cpu: what load_test.py printed in that run (one per --class-cpu "
        "file, in order); its class size is the run's, its CPU totals scale what no "
        "request's own task does and the load generator's CPU per request, and the run is "
        "predicted and compared",
    )
    args = parser.parse_args()
    if args.costs and args.costs.exists():
        saved = json.loads(args.costs.read_text())
        alone = {route: tuple(value) for route, value in saved["costs"].items()}
        own = {route: tuple(value) for route, value in saved.get("own", {}).items()}
        hash_s = saved["hash_s"]
    else:
        (alone, own), hash_s = measure_costs(args.backend, args.measure), password_hash_cpu()
        if args.costs:
            saved = {"costs": alone, "own": own, "hash_s": hash_s}
            args.costs.write_text(json.dumps(saved, indent=1))
    if args.class_cpu and (not own or len(args.class_run or []) != len(args.class_cpu)):
        parser.error("--class-cpu needs costs measured with each request's own CPU, and one "
                     "--class-run per --class-cpu file")  # fmt: skip
    if args.hash_scale != 1.0:
        hash_s *= args.hash_scale
    print(f"a log-in's password hash: {hash_s * 1000:.1f} ms of CPU, outside the interpreter")
    workers = 1 if args.backend == "sqlite" else 2
    name = "SQLite" if args.backend == "sqlite" else "PostgreSQL"

    def waits_of(table: dict | None = None) -> dict[str, float]:
        return run_waits(
            table or {}, args.handoff_us, args.wake_busy_us, args.call_handoff,
            args.every_call_hands, not args.wake_from_handoffs,
        )  # fmt: skip

    # the model's choices where an earlier model is asked for (``queue_sim.simulate``'s)
    options = {
        "loop_keeps": not args.loop_queues,
        "trips_in_turn": not args.trips_in_one_thread,
        "wake_counts_itself": not args.wake_beside_itself,
        "socket_stacking": args.socket_stacking,
        "trips_outside_lock": not args.trips_inside_lock,
        "released_share": args.released_share,
        "frames_on_loop": not args.frames_in_a_thread,
        "landing_s": args.landing_us / 1e6,
        "landing_on": tuple(args.landing_on),
        "client_in_order": args.client_in_order,
        "per_core": not args.cores_shared_evenly,
        "balance_s": args.balance_us / 1e6,
        "yielding": tuple(args.yielding),
        "yield_share": args.yield_share,
        "login_trips_after_hash": args.login_trips_after_hash,
    }

    def simulate_seed(
        costs: dict,
        students: int,
        shares: list[float] | None,
        waits: dict | None,
        locked: dict[str, float] | None,
        seed: int,
        arrivals: list | None = None,
        placed: connections.Connections | None = None,
        client_floor: float = 0.0,
    ) -> dict:
        """The class simulated once with ``seed`` (which worker each connection reaches,
        which measured costs each request draws); ``shares``: each worker's chance of a
        new connection; ``waits``: ``waits_of``'s; ``arrivals``: a run's, replayed;
        ``placed``: the workers each browser's connections reached in the run (then
        ``shares`` unused); ``client_floor``: the load generator's, a share of a core."""
        return simulate(
            with_cpu_scaled(costs, args.cpu_scale),
            students,
            workers,
            args.cores,
            one_writer=workers == 1,
            hash_s=hash_s * args.cpu_scale,
            write_slots=args.write_slots,
            switch_interval_s=args.switch_interval / 1000,
            work_places=args.work_places,
            seed=2026 + seed,
            worker_shares=shares,
            wake_free=not args.woken_at_once,
            costs_in_order=not args.costs_at_random,
            locked_shares=locked,
            arrivals=arrivals,
            teacher=arrivals is None,
            student_workers=placed.of_students(students) if placed else None,
            teacher_worker=placed.http.get(connections.TEACHER) if placed else None,
            client_floor=client_floor,
            **options,
            **(waits or waits_of()),
        )

    def predict(
        costs: dict,
        students: int,
        shares: list[float] | None = None,
        waits: dict | None = None,
        locked: dict[str, float] | None = None,
        arrivals: list | None = None,
        placed: connections.Connections | None = None,
        client_floor: float = 0.0,
    ) -> dict:
        """``simulate_seed`` once per seed of ``--seeds``, combined."""
        return combine(
            [
                simulate_seed(
                    costs, students, shares, waits, locked, seed, arrivals, placed, client_floor
                )
                for seed in range(args.seeds)
            ]
        )

    costs = alone
    if args.class_cpu:  # each run predicted from the CPU per request measured in it
        predicted: dict[int, list[tuple[dict, dict]]] = defaultdict(list)
        # per class size, each run's p95 and its interval; --model-as-run's
        measured_rows: dict[int, list[p95_interval.Row]] = defaultdict(list)
        exact_rows: dict[int, list[p95_interval.Row]] = defaultdict(list)
        # --pooled: per class size, the runs' requests and the model's, per route (ms);
        # the model's unused seeds by seed, each pooled over the runs
        pools = {size: Pool() for size in {_students_of(run) for run in args.class_run}}
        for index, (cpu, run) in enumerate(zip(args.class_cpu, args.class_run, strict=True)):
            students = _students_of(run)
            frame_weight, floor = args.client_frame_weight, None
            fit = run_client_fit(run, index, args, alone)  # None where the run does not tell it
            if frame_weight == "fit" or args.client_floor:
                if fit is None:
                    parser.error(
                        f"--client-frame-weight fit, --client-floor: {run} does not tell it"
                        " (needs its --run-queue line, --client-times and --stream-times)"
                    )
                print(f"\nthe load generator's CPU fitted to {run}: {fit.requests:.2f}×"
                      f" its requests' alone, {fit.frames:.2f}× its frames', a floor of"
                      f" {fit.floor:.3f} of a core (frames {fit.frame_weight:.2f}×)")  # fmt: skip
                frame_weight = fit.frame_weight if frame_weight == "fit" else frame_weight
                floor = fit if args.client_floor else None
            costs = class_costs(
                alone, own, cpu, run, not args.mean_costs, frame_weight,
                floor.floor_s if floor else 0.0,
            )  # fmt: skip
            print_costs(costs, args.backend)
            times = args.server_times[index] if len(args.server_times) > index else None
            shares = worker_shares(times) if times and workers > 1 else None
            placed = None
            if shares and len(args.client_times) > index and not args.connections_at_random:
                placed = connections.connections_of(times, args.client_times[index])
                if placed is None or placed.of_students(students) is None:
                    placed = None
            if placed:
                http, streams = (
                    " / ".join(f"{share:.0%}" for share in placed.shares(kind))
                    for kind in (placed.http, placed.websocket)
                )
                print("each student's connections reach the workers they reached in the run:"
                      f" HTTP {http}, WebSocket {streams}")  # fmt: skip
            elif shares:
                print("each worker's share of the run's requests (a new connection's chance):"
                      f" {' / '.join(f'{share:.0%}' for share in shares)}")  # fmt: skip
            table = measured_p95(run)[name]
            if table.get("cpu elsewhere", 0.0) > ELSEWHERE_S:
                print(f"\nNOTE: {run} shared the machine -- {table['cpu elsewhere']:.1f} s of"
                      " CPU went to neither the class nor the kernel during it; its p95s are"
                      " not the class's alone")  # fmt: skip
            if table.get("steal share", 0.0) > load_test.STEAL_NOTE_SHARE:
                print(f"\nNOTE: in {run} the host kept the cores from the class"
                      f" {table['steal share']:.0%} of the time it wanted them"
                      f" ({table['steal']:.1f} s of steal); the model has no steal, and the"
                      " run's p95s are the host's as much as the app's")  # fmt: skip
            waits = waits_of(table)
            locked = None
            if len(args.lock_trace) > index:
                seen = attributed_costs(cpu.read_text())
                locked = locked_shares(args.lock_trace[index].read_text(), seen)
                print("  each write's thread CPU in the write lock (the lock trace): " + ", ".join(
                    f"{route} {share:.0%}" for route, share in sorted(locked.items())
                ))  # fmt: skip
            arrivals = None
            if args.replay:
                if len(args.client_times) <= index or len(args.stream_times) <= index:
                    parser.error("--replay needs --client-times and --stream-times of each run")
                try:
                    arrivals = replay.arrivals_of(
                        args.client_times[index], args.stream_times[index], args.paced
                    )
                except ValueError as error:
                    parser.error(str(error))
                print(
                    f"  replayed: the run's {len(arrivals)} arrivals, "
                    + ("each browser's paced" if args.paced else "sent at their times")
                )
            result = predict(
                costs, students, shares, waits, locked, arrivals, placed,
                floor.floor if floor else 0.0,
            )  # fmt: skip
            print(f"\n{students} students, {name}, {workers} worker(s), the run in {run}:"
                  f" predicted wall {result['wall']:.1f} s; hand-off"
                  f" {waits['handoff_s'] * 1e6:.0f} µs, busy wake-up"
                  f" {waits['wake_busy_s'] * 1e6:.0f} µs, an SQLite call hands on"
                  f" {describe_call_handoff(waits['call_handoff'])}")  # fmt: skip
            if result.get("busy while waiting"):
                print(f"  the model's cores: {busy_report(result['busy while waiting'])}")
            if result.get("threads by time"):
                print("\n".join(request_waits.threads_report(
                    result["threads by time"], TIMELINE_BIN_S, "the model's threads")))  # fmt: skip
                if measured_ran := ran_by_time(run):
                    print("\n".join(request_waits.ran_report(
                        result["threads by time"], TIMELINE_BIN_S, measured_ran,
                        load_test.RUN_QUEUE_BIN_S,
                    )))  # fmt: skip
                    if fit is not None and args.client_frame_weight != "fit":
                        print(f"  the load generator's CPU per frame against its requests'"
                              f" as the run spent it: {fit.frame_weight:.2f}, and a floor of"
                              f" {fit.floor:.3f} of a core (fitted by the bin; use them:"
                              f" --client-frame-weight fit --client-floor)")  # fmt: skip
            if "call free" in table:
                free, busy = table["call free"], table["call busy"]
                print(f"  (the run measured an SQLite call handing on"
                      f" {describe_call_handoff((free, busy))} after its class:"
                      f" --call-handoff {free:.3f} {busy:.3f})")  # fmt: skip
            compare(result, [table])
            if times:
                inside_the_server(result, server_times(times))
            if len(args.lock_trace) > index:
                compare_lock(result, lock_trace_by_route(args.lock_trace[index].read_text()))
            intervals = {}
            if len(args.client_times) > index:
                requests = p95_interval.client_requests(args.client_times[index])
                seen_latencies = p95_interval.latencies_of(requests)
                intervals = p95_interval.intervals_of(seen_latencies)
                measured_rows[students] += p95_interval.compare(result["p95"], intervals)
                pools[students].add_run(seen_latencies, result["pooled"])
                for route in args.by_time:
                    compare_by_time(route, result["timelines"], sent_from_start(requests, students))
                if len(args.stream_times) > index and not arrivals:
                    print(f"how the class fell into step (convoys.py; {args.stream_times[index]}):")
                    convoys.compare(
                        [convoys.from_model({"students": seed}) for seed in result["students"]],
                        convoys.read_run(args.client_times[index], args.stream_times[index]),
                    )
            for seed in range(args.seeds, args.seeds + args.model_as_run):
                # a seed the prediction did not use, scored as a measured run (of the
                # routes the run's requests' times have, where it has them)
                run_of_model = simulate_seed(
                    costs, students, shares, waits, locked, seed, arrivals, placed
                )
                latencies = {
                    route: np.array(values) * 1000
                    for route, values in run_of_model["latencies"].items()
                    if not intervals or route in intervals
                }
                exact_rows[students] += p95_interval.score(
                    result["p95"], p95_interval.intervals_of(latencies)
                )
                pools[students].add_model_run(seed - args.seeds, latencies)
            if times and len(args.client_times) > index:
                outside = request_waits.outside_the_app(args.client_times[index], times)
                request_waits.compare_outside(result, outside)
            if len(args.request_waits) > index:
                measured = request_waits.read(args.request_waits[index])
                request_waits.compare(request_waits.modelled(result), measured)
                request_waits.compare_windows(request_waits.modelled(result), measured)
                if workers == 1:
                    request_waits.compare_crowding(result["places"], measured)
            predicted[students].append((result, table))
        for students, pairs in sorted(predicted.items()):
            summary(students, name, pairs)
        for students in sorted(set(measured_rows) | set(exact_rows)):
            print(f"\n{students} students, {name}:", end="")
            p95_interval.print_ceiling(measured_rows[students], exact_rows[students])
        if args.pooled:
            for students, pool in sorted(pools.items()):
                if pool.runs:
                    print(f"\n{students} students, {name}, {pool.runs} runs pooled:")
                    pool.compare()
                    print("  " + p95_interval.describe_spread(p95_interval.between_runs(pool.seen)))
    else:
        measured: dict[tuple[str, int | None], list[dict[str, float]]] = defaultdict(list)
        for path in args.compare:
            for backend, table in measured_p95(path).items():
                measured[(backend, _students_of(path))].append(table)
        print_costs(costs, args.backend)
        for students in args.students:
            runs = measured.get((name, students), [])
            result = predict(costs, students)
            print(f"\n{students} students, {name}, {workers} worker(s): predicted wall "
                  f"{result['wall']:.1f} s; measured runs: {len(runs)}")  # fmt: skip
            compare(result, runs)
    if args.department:
        department(
            with_cpu_scaled(costs, args.cpu_scale), hash_s * args.cpu_scale,
            args.department[0], args.department[1:], args.switch_interval, waits_of(),
            args.department_slice, **options,
        )  # fmt: skip
    return 0


def run_waits(
    table: dict[str, float],
    handoff_us: float | None,
    wake_busy_us: float | None,
    call_handoff: tuple[float, float] | None = None,
    every_call_hands: bool = False,
    wake_from_run: bool = True,
) -> dict:
    """The hand-off and the busy wake-up to simulate a run with, s: as given (0 turns one
    off), else as measured beside the run (``measured_p95``'s "handoff us", "wake busy
    us"), else the constants of ``queue_sim``; and the chance that an SQLite call hands the
    interpreter on (with a core free, with none): as given (``every_call_hands``: every
    call), else ``queue_sim.CALL_HANDOFF`` -- not what the run measured after its class
    ("call free", "call busy"), which on six runs of 2026-12-03 predicted no better
    (bench/README.md, twenty-fifth part).  The busy wake-up, unless given: with
    ``wake_from_run`` the run's own wait of its server threads on the run queue per time
    on a core ("waited server" ÷ "slices server", ``load_test.py --run-queue``) where the
    run has them -- 86–100 µs on SQLite and 211–335 µs on PostgreSQL on 2026-12-05, where
    ``bench_handoffs.py`` measured 135–164 µs beside each class; a small gain over nine
    runs (bench/README.md, twenty-ninth part) -- else the one measured beside the run,
    else the constant."""
    if handoff_us is None:
        handoff_us = table.get("handoff us", HANDOFF_S * 1e6)
    if wake_busy_us is None and wake_from_run and table.get("slices server"):
        wake_busy_us = table["waited server"] / table["slices server"] * 1e6
    if wake_busy_us is None:
        wake_busy_us = table.get("wake busy us", WAKE_BUSY_S * 1e6)
    return {
        "handoff_s": handoff_us / 1e6,
        "wake_busy_s": wake_busy_us / 1e6,
        "call_handoff": None if every_call_hands else call_handoff or CALL_HANDOFF,
    }


def with_cpu_scaled(costs: dict, factor: float) -> dict:
    """``costs`` with every request's server CPU times ``factor``: the server's, its event
    loop's part and the request's own task's on the loop; the database's and the load
    generator's CPU, the calls and the trips as they were (a list per route: each)."""
    if factor == 1.0:
        return costs

    def scaled(cost):
        if isinstance(cost, list):
            return [scaled(each) for each in cost]
        if not isinstance(cost, tuple) or len(cost) < 6:
            return cost  # the stream's split: shares, not CPU
        server, db, client, calls, trips, loop, *own_loop = cost
        return (server * factor, db, client, calls, trips, loop * factor,
                *(part * factor for part in own_loop))  # fmt: skip

    return {route: scaled(cost) for route, cost in costs.items()}


def describe_call_handoff(chance: tuple[float, float] | None) -> str:
    """``run_waits``'s call hand-off in words."""
    if chance is None:
        return "always"
    return f"{chance[0]:.0%} / {chance[1]:.0%} (a core free / none)"


def combine(results: list[dict]) -> dict:
    """Simulations of one class with different seeds as one prediction: per route the
    median over the seeds of the p50 and p95 (ms), the p95s' lowest and highest, and their
    band from the 10th to the 90th percentile over the seeds (how far one run's p95 moves
    with nothing changed but chance: which worker each connection reached, which request
    came when); the CPU asked (the mean), and the waits inside the server and the write
    lock's holds of all seeds together; "places": how crowded the work places were
    (``request_waits.place_queue`` of each seed, the median; one worker's)."""
    routes = set.intersection(*(set(result["latencies"]) for result in results))
    p95 = {r: [np.percentile(x["latencies"][r], 95) * 1000 for x in results] for r in routes}
    p50 = {r: [np.percentile(x["latencies"][r], 50) * 1000 for x in results] for r in routes}
    server: dict[str, list] = defaultdict(list)
    for result in results:
        for route, pairs in result["server"].items():
            server[route] += pairs
    keys = set().union(*(result["cpu"] for result in results))
    return {
        "p95": {route: float(np.median(values)) for route, values in p95.items()},
        "p95 range": {route: (min(values), max(values)) for route, values in p95.items()},
        "p95 band": {
            route: tuple(float(v) for v in np.percentile(values, [10, 90]))
            for route, values in p95.items()
        },
        "p50": {route: float(np.median(values)) for route, values in p50.items()},
        "pooled": {
            route: np.concatenate([x["latencies"][route] for x in results]) * 1000
            for route in routes
        },
        "timelines": [result.get("timeline", []) for result in results],
        "students": [result.get("students", []) for result in results],
        "mean": {
            route: float(np.mean(np.concatenate([x["latencies"][route] for x in results])))
            for route in routes
        },
        "cpu": {key: float(np.mean([x["cpu"].get(key, 0.0) for x in results])) for key in keys},
        "run queue": {
            group: tuple(
                float(np.mean([x["run queue"].get(group, (0.0, 0.0))[i] for x in results]))
                for i in (0, 1)
            )
            for group in set().union(*(x.get("run queue", {}) for x in results))
        },  # fmt: skip
        **{
            key: {
                group: float(np.mean([x.get(key, {}).get(group, 0) for x in results]))
                for group in set().union(*(x.get(key, {}) for x in results))
            }
            for key in ("wake-ups", "waiting wake-ups")
        },
        "lock held": [held for result in results for held in result["lock held"]],
        "lock by route": {
            route: [pair for x in results for pair in x.get("lock by route", {}).get(route, [])]
            for route in set().union(*(x.get("lock by route", {}) for x in results))
        },
        "pressure": tuple(
            float(np.mean([x.get("pressure", (0.0, 0.0))[i] for x in results])) for i in (0, 1)
        ),
        "busy while waiting": {
            busy: float(np.mean([x.get("busy while waiting", {}).get(busy, 0.0) for x in results]))
            for busy in set().union(*(x.get("busy while waiting", {}) for x in results))
        },
        "threads by time": {
            key: tuple(
                float(np.mean([x["threads by time"].get(key, (0.0, 0.0))[i] for x in results]))
                for i in (0, 1)
            )
            for key in set().union(*(x.get("threads by time", {}) for x in results))
        },
        "server": dict(server),
        "places": tuple(
            np.median([request_waits.simulated_crowding(result) for result in results], axis=0)
        ),
        "wall": float(np.median([result["wall"] for result in results])),
        "seeds": len(results),
    }


class Pool:
    """The requests of several runs of one class taken together, as one run as long as
    all of them (``--pooled``): a route's p95 over K runs' requests is known to about
    1/√K of one run's interval (``p95_interval``), so a prediction 10 % off can be told
    from a right one at 60 students too. The prediction pooled the same way: every seed's
    requests of every run's prediction, each run predicted from its own CPU; the p95 of
    that mixture is what the runs' pooled p95 estimates."""

    def __init__(self) -> None:
        self.runs = 0
        self.seen: dict[str, list[np.ndarray]] = defaultdict(list)
        self.model: dict[str, list[np.ndarray]] = defaultdict(list)
        self.exact: dict[int, dict[str, list[np.ndarray]]] = defaultdict(lambda: defaultdict(list))

    def add_run(self, seen: dict[str, np.ndarray], model: dict[str, np.ndarray]) -> None:
        """One run's requests (per route, ms) and its prediction's, all seeds (ms)."""
        self.runs += 1
        for route, values in seen.items():
            self.seen[route].append(values)
        for route, values in model.items():
            self.model[route].append(values)

    def add_model_run(self, index: int, latencies: dict[str, np.ndarray]) -> None:
        """The ``index``-th unused seed of one run's model, scored as a run (ms)."""
        for route, values in latencies.items():
            self.exact[index][route].append(values)

    def predicted(self) -> dict[str, float]:
        """Per route, the p95 of the model's requests of all runs and seeds (ms)."""
        return {
            route: float(np.percentile(np.concatenate(parts), 95))
            for route, parts in self.model.items()
        }

    def compare(self) -> tuple[list[p95_interval.Row], list[p95_interval.Row]]:
        """Print the pooled runs' p95 per route, its interval and the pooled prediction,
        then the model against them beside an exact model pooled the same way (each of
        the unused seeds, over the same runs). Returns (the model's rows, the exact's)."""
        predicted = self.predicted()
        seen = {route: np.concatenate(parts) for route, parts in self.seen.items()}
        rows = p95_interval.compare(predicted, p95_interval.intervals_of(seen))
        exact = [
            row
            for by_route in self.exact.values()
            for row in p95_interval.score(
                predicted,
                p95_interval.intervals_of(
                    {route: np.concatenate(parts) for route, parts in by_route.items()}
                ),
            )
        ]
        if exact:
            p95_interval.print_ceiling(rows, exact)
        return rows, exact


def sent_from_start(
    requests: dict[str, np.ndarray], students: int, ramp: float = 3.0
) -> dict[str, np.ndarray]:
    """``p95_interval.client_requests``' rows (sent, latency) with the time sent counted
    from the class's start: the first request sent less the earliest student's start in
    the load test's ramp (``random.Random(index)``), the simulation's own starts."""
    first = min(rows[:, 0].min() for rows in requests.values() if len(rows))
    start = first - min(random.Random(index).uniform(0, ramp) for index in range(students))
    return {route: rows - [start, 0.0] for route, rows in requests.items()}


# the gaps between one request of a route sent and the next that ``compare_by_time`` counts
GAP_LIMITS_S = (0.005, 0.010, 0.020)


def close_gaps(sent, limits: tuple[float, ...] = GAP_LIMITS_S) -> np.ndarray | None:
    """Of the gaps between one request sent and the next (``sent``: times, s, any order),
    the share under each of ``limits``; None for fewer than two requests.  Requests sent at
    random at a rate λ have a share 1 − e^(−λ·limit) under each."""
    times = np.sort(np.asarray(sent, dtype=float))
    if len(times) < 2:
        return None
    gaps = np.diff(times)
    return np.array([np.mean(gaps < limit) for limit in limits])


def compare_by_time(
    route: str,
    model: list[list[tuple[str, float, float]]],
    measured: dict[str, np.ndarray],
    window_s: float = 2.0,
) -> None:
    """One route's requests by when they were sent from the class's start, in windows of
    ``window_s``: how many a run (the model: a seed on average), and their p50 / p95 ms,
    the model (``simulate``'s "timeline" of each seed, ``combine``'s "timelines") beside
    the run (``sent_from_start``). A route whose p95 is set by the few requests that meet
    a burst shows it here.  Then, in each part of the class (``request_waits.WINDOWS``), how
    close together its requests were sent (:func:`close_gaps`; the model's within each
    seed): a model whose requests leave more evenly than the run's meets less queueing."""
    model_rows = np.array([(sent, latency) for timeline in model
                           for name, sent, latency in timeline if name == route])  # fmt: skip
    seen = measured.get(route)
    if not len(model_rows) or seen is None:
        return
    print(f"  {route} by when it was sent (count a run, p50 / p95 ms: model | measured);"
          f" p95 over all: {np.percentile(model_rows[:, 1], 95) * 1000:.0f} |"
          f" {np.percentile(seen[:, 1], 95) * 1000:.0f}")  # fmt: skip
    end = max(model_rows[:, 0].max(), seen[:, 0].max())
    for low in np.arange(0.0, end + window_s, window_s):
        cells = []
        for rows, runs in ((model_rows, len(model)), (seen, 1)):
            inside = rows[(rows[:, 0] >= low) & (rows[:, 0] < low + window_s), 1] * 1000
            cells.append(
                f"{len(inside) / runs:5.0f} {np.percentile(inside, 50):5.0f} /"
                f" {np.percentile(inside, 95):5.0f}"
                if len(inside)
                else f"{0:5d} {'-':>13s}"
            )
        print(f"  {low:5.0f}-{low + window_s:<4.0f} s {cells[0]} | {cells[1]}")
    under = " / ".join(f"{limit * 1000:g}" for limit in GAP_LIMITS_S)
    print(f"  the gaps between one sent and the next, % under {under} ms, by the class's parts"
          " (model, each seed's own averaged | measured | sent at random at the measured"
          " rate)")  # fmt: skip
    for name, start, end in request_waits.WINDOWS:
        each_seed = (
            [sent for what, sent, _ in timeline if what == route and start <= sent < end]
            for timeline in model
        )
        seeds = [shares for shares in map(close_gaps, each_seed) if shares is not None]
        times = seen[(seen[:, 0] >= start) & (seen[:, 0] < end), 0]
        shares = close_gaps(times)
        if not seeds or shares is None or times.max() <= times.min():
            continue
        rate = (len(times) - 1) / (times.max() - times.min())
        at_random = 1.0 - np.exp(-rate * np.array(GAP_LIMITS_S))
        cells = [" / ".join(f"{100 * x:3.0f}" for x in row)
                 for row in (np.mean(seeds, axis=0), shares, at_random)]  # fmt: skip
        print(f"  {name:6s} {cells[0]} | {cells[1]} | {cells[2]}")


def summary(students: int, name: str, pairs: list[tuple[dict, dict]]) -> dict:
    """Over the runs at one class size, each predicted from its own CPU: per route the
    median predicted and measured p95 and the error between them; the half-width of the
    seeds' band (``combine``) against the prediction, median over the runs (the p95's own
    spread from chance alone: no prediction of one run can be surer than that); how many
    runs measured a p95 inside their band; and each run's error.  Returns the counts over
    the routes: "routes", "within 10 %" (the medians), "inside" (runs × routes in their
    band), "runs × routes", "band" (the median half-width, %)."""
    print(f"\n{students} students, {name}: {len(pairs)} runs, each predicted from its own CPU"
          " per request; p95 ms, median over the runs; band: the seeds' 10-90 % band's"
          " half-width (%); in band: runs whose p95 lies in theirs")  # fmt: skip
    print(f"  {'route':42s} {'predicted':>9s} {'measured':>9s} {'error':>6s} {'band':>5s}"
          f" {'in band':>7s}  each run's error")  # fmt: skip
    routes = sorted(set.intersection(*(set(r["p95"]) & set(t) for r, t in pairs)))
    counts = {"routes": len(routes), "within 10 %": 0, "inside": 0,
              "runs × routes": len(routes) * len(pairs)}  # fmt: skip
    widths = []
    for route in routes:
        model = [r["p95"][route] for r, _ in pairs]
        seen = [t[route] for _, t in pairs]
        bands = [(r.get("p95 band") or r["p95 range"])[route] for r, _ in pairs]
        inside = sum(low <= s <= high for (low, high), s in zip(bands, seen, strict=True))
        halves = [(high - low) / 2 / m * 100 for (low, high), m in zip(bands, model, strict=True)]
        width = float(np.median(halves))
        each = " ".join(f"{(m - s) / s * 100:+.0f}" for m, s in zip(model, seen, strict=True))
        middle_model, middle_seen = float(np.median(model)), float(np.median(seen))
        error = (middle_model - middle_seen) / middle_seen * 100
        counts["within 10 %"] += abs(error) <= 10
        counts["inside"] += inside
        widths.append(width)
        print(f"  {route:42s} {middle_model:9.0f} {middle_seen:9.0f} {error:+5.0f}% {width:4.0f}%"
              f" {inside:3d} / {len(pairs)}  {each}")  # fmt: skip
    counts["band"] = float(np.median(widths)) if widths else 0.0
    print(f"  the medians within 10 %: {counts['within 10 %']} of {counts['routes']} routes;"
          f" a run's p95 inside its band: {counts['inside']} of {counts['runs × routes']};"
          f" the band's half-width, median: ±{counts['band']:.0f} %")  # fmt: skip
    return counts


def class_costs(
    alone, own, cpu: Path, run: Path | None, each: bool, frame_weight: float = 1.0,
    client_floor_s: float = 0.0,
) -> dict:  # fmt: skip
    """The costs per request as the class in ``cpu`` (the probe's lines) spent them,
    printed beside one student's alone; ``run``: what load_test.py printed in that run
    (its CPU totals); ``each``: a list per route, one per request the class made;
    ``frame_weight``: the load generator's CPU per stream frame against its requests';
    ``client_floor_s``: its CPU whatever it sent, run apart (``class_cpu.in_class``)."""
    seen = attributed_costs(cpu.read_text())
    used = None
    if run:
        table = next(iter(measured_p95(run).values()))
        used = {"server": table["cpu server"], "client": table["cpu client"]}
        used["db"] = table.get("cpu db", 0.0)  # PostgreSQL's processes (SQLite: in the server)
    try:
        costs, scale, client_scale = in_class(
            alone, own, seen, used, each=each, frame_weight=frame_weight,
            client_floor_s=client_floor_s,
        )  # fmt: skip
    except ValueError as error:
        raise SystemExit(f"{cpu} against {run}: {error}") from error
    print(f"\neach route's own CPU as the class in {cpu} spent it:")
    for route in sorted(set(seen.means) & set(own)):
        one, there = sum(own[route]) * 1000, sum(seen.means[route]) * 1000
        spread = ""
        if route in seen.each:
            mine = np.sum(seen.each[route], axis=1) * 1000
            spread = f", p95 {np.percentile(mine, 95):6.2f} ms"
        print(f"  {route:42s} alone {one:6.2f} ms, in the class {there:6.2f} ms"
              f" ({there / one:.2f}×){spread}")  # fmt: skip
    if used:
        print(
            f"  what no request's own task does: {scale:.2f}× one student's, and the load"
            f" generator's CPU per request {client_scale:.2f}× (the CPU that run used)"
        )
    return costs


def print_costs(costs: dict, backend: str) -> None:
    """Each route's mean costs per request, as the simulation takes them."""
    print(f"per request, {backend}: CPU ms (server, of it on the event loop / database /"
          " load generator), SQLite calls, thread-pool trips (a route's mean)")  # fmt: skip
    for route, cost in sorted(costs.items()):
        if route == STREAM_SPLIT:
            marking, making_ready, saving = cost
            print(f"  a stream's thread CPU: {marking:.0%} marking (a write), {making_ready:.0%}"
                  f" making the take ready, {saving:.0%} saving (a write)")  # fmt: skip
            continue
        mean = np.mean(cost, axis=0) if isinstance(cost, list) else cost
        server, db, client, calls, trips, loop, *_ = mean
        print(f"  {route:42s} {server * 1000:6.2f}, {loop * 1000:5.2f} {db * 1000:6.2f}"
              f" {client * 1000:6.2f} {calls:6.1f} {trips:5.1f}")  # fmt: skip


def compare(result: dict, runs: list[dict[str, float]]) -> None:
    """The predicted p50 / p95 of each route (the median over the seeds, and the p95's
    range) beside the measured runs' p95: their median, lowest and highest (one run's p95
    moves by tens of per cent from run to run at the same load: the model is held to the
    median), and the error against the median."""
    for key, label in (("server", "server"), ("db", "PostgreSQL"), ("client", "load gen.")):
        asked = result["cpu"].get(key, 0.0)
        used = [run[f"cpu {key}"] for run in runs if run.get(f"cpu {key}")]
        if used and asked:
            middle = float(np.median(used))
            print(f"  CPU of the {label}: {asked:.1f} s from the costs per request, "
                  f"{middle:.1f} s used in the measured runs"
                  f" (median, {middle / asked:.2f}×)")  # fmt: skip
    run_queue(result, runs)
    if result["lock held"]:
        held = np.percentile(result["lock held"], [50, 95]) * 1000
        print(f"  SQLite's write lock held (wall) p50 {held[0]:.1f} ms, p95 {held[1]:.1f} ms")
    print(f"  {'route':42s} {'p50':>6s} {'p95 (seeds range)':>18s}"
          f" {'measured p95 median (range)':>28s} {'error':>6s}")  # fmt: skip
    for route in sorted(result["p95"]):
        p50, p95 = result["p50"][route], result["p95"][route]
        low, high = result["p95 range"][route]
        predicted = f"{p95:.0f} ({low:.0f}–{high:.0f})"
        seen = [run[route] for run in runs if route in run]
        shown, error = "-", ""
        if seen:
            middle = float(np.median(seen))
            shown = f"{middle:.0f} ({min(seen):.0f}–{max(seen):.0f})"
            error = f"{(p95 - middle) / middle * 100:+.0f} %"
        print(f"  {route:42s} {p50:6.0f} {predicted:>18s} {shown:>28s} {error:>6s}")


def waiting_wakes(result: dict, group: str) -> str:
    """`` + N waiting (… in all)``: the wake-ups of ``group``'s threads while they waited
    for the interpreter, one a switch interval (``bench_gil_wakes.py``), beside the rest."""
    waiting = result.get("waiting wake-ups", {}).get(group, 0.0)
    if not waiting:
        return ""
    every = result.get("wake-ups", {}).get(group, 0.0) + waiting
    return f" + {waiting:,.0f} waiting for the interpreter ({every:,.0f} in all)"


def run_queue(result: dict, runs: list[dict[str, float]]) -> None:
    """Each group's wait for a core, predicted (as the model shares its cores)
    beside what the kernel counted in the runs (``load_test.py --run-queue``): waited s /
    ran s and the waited share of the time wanted.  For SQLite the database is the
    server's own threads."""
    model = dict(result.get("run queue", {}))
    if "db" in model and not any(run.get("ran db") for run in runs):  # SQLite: in-process
        ran, waited = model.pop("db")
        model["server"] = (model.get("server", (0.0, 0.0))[0] + ran,
                           model.get("server", (0.0, 0.0))[1] + waited)  # fmt: skip
    loops = [run["slices loop"] for run in runs if "slices loop" in run]
    if loops and "loop" in result.get("wake-ups", {}):
        predicted = result["wake-ups"]["loop"]
        measured = float(np.median(loops))
        print(f"  times on a core, the event loops: predicted wake-ups {predicted:,.0f}"
              f"{waiting_wakes(result, 'loop')}, measured {measured:,.0f}")  # fmt: skip
    pressed = [(run["pressure"], run["busy"]) for run in runs if "pressure" in run]
    if pressed and "pressure" in result:
        some, busy = result["pressure"]
        seen_some, seen_busy = (float(np.median(v)) for v in zip(*pressed, strict=True))
        waited = sum(w for _, w in model.values())
        seen_waited = sum(
            float(np.median([run[f"waited {key}"] for run in runs if f"waited {key}" in run]))
            for key in ("server", "db", "client")
            if any(f"waited {key}" in run for run in runs)
        )
        deep, seen_deep = (
            w / t if t else 0.0 for w, t in ((waited, some), (seen_waited, seen_some))
        )
        print(f"  the cores: busy {busy:.1f} s predicted, {seen_busy:.1f} s measured; some"
              f" thread waiting for one {some:.1f} s predicted, {seen_some:.1f} s measured"
              f" (/proc/pressure/cpu), with on average {deep:.1f} / {seen_deep:.1f} waiting"
              " then")  # fmt: skip
    for key, label in (("server", "server"), ("db", "PostgreSQL"), ("client", "load gen.")):
        ran, waited = model.get(key, (0.0, 0.0))
        seen = [(run[f"ran {key}"], run[f"waited {key}"]) for run in runs
                if f"waited {key}" in run]  # fmt: skip
        if not seen or not ran + waited:
            continue
        seen_ran, seen_waited = (float(np.median(v)) for v in zip(*seen, strict=True))
        woken = result.get("wake-ups", {}).get(key, 0.0)
        slices = [run[f"slices {key}"] for run in runs if f"slices {key}" in run]
        if slices:
            print(f"  times on a core, {label}: predicted wake-ups {woken:,.0f}"
                  f"{waiting_wakes(result, key)}, measured {float(np.median(slices)):,.0f}"
                  " (schedstat's slices)")  # fmt: skip
        print(
            f"  waited for a core, {label}: predicted {waited:.2f} s ({share(ran, waited):.0%}"
            f" of {ran + waited:.1f} s wanted), measured {seen_waited:.2f} s"
            f" ({share(seen_ran, seen_waited):.0%} of {seen_ran + seen_waited:.1f} s)"
        )


def compare_lock(result: dict, trace: dict[str, np.ndarray]) -> None:
    """Each write route's wait for SQLite's write lock (the writers' turn) and its hold of
    it, the model's (``simulate``'s "lock by route") beside the run's lock trace
    (``class_cpu.lock_trace_by_route``), mean and p95 ms."""
    print("  the write lock per route, ms: wait for it mean / p95 | hold mean / p95"
          " (model | lock trace)")  # fmt: skip
    for route in sorted(set(result.get("lock by route", {})) & set(trace)):
        model = np.array(result["lock by route"][route]) * 1000
        seen = trace[route]
        waited = seen[:, 0][~np.isnan(seen[:, 0])]

        def both(values: np.ndarray) -> str:
            if not len(values):
                return "    -/    -"
            return f"{np.mean(values):5.1f}/{np.percentile(values, 95):5.1f}"

        print(
            f"  {route:42s} {both(model[:, 0])} | {both(waited)}   "
            f"{both(model[:, 1])} | {both(seen[:, 1])}"
        )


def share(ran: float, waited: float) -> float:
    """The part of the time wanted on a core spent waiting for one."""
    return waited / (ran + waited) if ran + waited else 0.0


def inside_the_server(result: dict, measured_inside: dict[str, np.ndarray]) -> None:
    """The wait for a work place and the time from asking for it to the answer, p50 / p95,
    predicted beside what the probe measured in the server."""
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


DEPARTMENT_ROUTES = {
    "GET /lab/sessions/{id}": "lab page",
    "GET /lab/sessions/{id}/results.json": "results",
    "POST /lab/sessions/{id}/csv": "CSV save",
    "POST /lab/sessions/{id}/submit": "submit",
    "POST /login": "log-in",
}


# The department's workers simulated together on as many cores (a slice of the machine):
# a worker's burst borrows a core another leaves idle, as on the real machine, and the
# simulation stays small (its time grows with the square of the students in it)
DEPARTMENT_SLICE = 4


def department(
    costs,
    hash_s: float,
    students: int,
    workers: list[int],
    switch_ms: float,
    waits: dict,
    pooled: int = DEPARTMENT_SLICE,
    **options,
):
    """p95 per route of ``students`` starting within a minute, for each number of workers
    (one core each, PostgreSQL's CPU counted in it; browsers elsewhere): ``pooled`` of the
    workers, each with its share of the students, simulated together on as many cores (1:
    each worker on a core of its own, the model before 2026-12-05 -- a worker's burst then
    never finds a core another has left idle); ``options``: the model's choices, as
    ``queue_sim.simulate``'s (``loop_keeps``, ``trips_in_turn``, ``wake_counts_itself``)."""
    print(f"\ndepartment: {students} students starting within a minute, PostgreSQL; p95 ms "
          f"(one core per worker, the database's CPU included in it; {pooled} workers"
          " simulated together on as many cores)")  # fmt: skip
    header = " ".join(f"{name:>9s}" for name in DEPARTMENT_ROUTES.values())
    print(f"  {'workers':>7s} {'each':>5s} {header} {'worst':>9s}")
    for count in workers:
        share = -(-students // count)
        together = max(min(pooled, count), 1)
        result = simulate(
            costs, share * together, together, float(together), ramp=60.0, one_writer=False,
            clients_elsewhere=True, hash_s=hash_s, switch_interval_s=switch_ms / 1000,
            worker_shares=[1 / together] * together, **options, **waits,
        )  # fmt: skip
        p95 = {route: np.percentile(v, 95) * 1000 for route, v in result["latencies"].items()}
        row = " ".join(f"{p95.get(route, float('nan')):9.0f}" for route in DEPARTMENT_ROUTES)
        print(f"  {count:7d} {share:5d} {row} {max(p95.values()):9.0f}")


def _students_of(path: Path) -> int | None:
    found = re.search(r"; (\d+) students", path.read_text())
    return int(found.group(1)) if found else None


if __name__ == "__main__":
    sys.exit(main())
