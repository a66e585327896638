"""Load test on loopback: a class of simulated students working at once, with a teacher.

    .venv/bin/python bench/load_test.py [--students 60] [--backend sqlite|postgresql|both]

Each student logs in, opens the lab, starts the assignment's session, turns the virtual
table and streams all eight positions from the simulated gyro over one WebSocket, then
starts a practice session and uploads the handout's two CSV tables (preview, then save),
reads the results of both sessions (JSON and the page) and submits the assignment.  Meanwhile
the teacher refreshes the class dashboard.  Everything runs at once in one asyncio client.

Reported per backend: throughput, p50/p95/p99 latency per route, the lag of stream frames
behind the simulated clock, errors, and lost samples: what the server acknowledged
(``saved`` frames, CSV replies) counted against what the database holds afterwards.
SQLite runs one uvicorn worker; PostgreSQL (a durable server started for the run,
``fsync`` on) runs two.  Exit status 1 on any error or lost sample.
"""

from __future__ import annotations

import argparse
import asyncio
import contextlib
import contextvars
import json
import os
import platform
import random
import re
import ssl
import subprocess
import sys
import tempfile
import time
import traceback
from collections import Counter, defaultdict
from dataclasses import dataclass, field
from pathlib import Path

import httpx
import numpy as np
from websockets.asyncio.client import connect

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from bench_handoffs import call_handoff_chances, hand_off_constants  # noqa: E402  (bench/)
from capacity import cpu_seconds, postgres_pids, server_pids  # noqa: E402
from run_queue import RunQueueWatch  # noqa: E402

from tests.e2e.conftest import running_server  # noqa: E402
from tests.pgserver import PostgresServer  # noqa: E402

DATA = ROOT / "tests" / "data"
PASSWORD = "load-test-pass-1"
CSRF_RE = re.compile(r'name="csrf_token" value="([^"]+)"')
# GYROLAB_BENCH_CLIENT_TIMES=FILE: each HTTP request's ``method path sent_s answered_s who``
# (time.perf_counter, the same clock as the server probe's GYROLAB_BENCH_SERVER_TIMES), to
# set the client's time of a request beside the server's; ``who``: the student's number,
# or ``teacher`` (a run's steps per browser, in order, for replay.py)
CLIENT_TIMES = os.environ.get("GYROLAB_BENCH_CLIENT_TIMES")
# whose browser the running task is (each student's task sets it: a context variable)
BROWSER: contextvars.ContextVar[str] = contextvars.ContextVar("browser", default="-")
# GYROLAB_BENCH_STREAM_TIMES=FILE: each position streamed, as the load generator saw it:
# ``session part position`` and the times (time.perf_counter, s) it sent "start" and
# received "started", its first and its last samples, and "saved"
STREAM_TIMES = os.environ.get("GYROLAB_BENCH_STREAM_TIMES")
HANDOFFS_LABEL = "hand-offs just before / after the class (bench_handoffs.py)"
CALL_HANDOFFS_LABEL = "SQLite calls handing the interpreter on (bench_handoffs.py --calls)"
# GYROLAB_BENCH_SQLITE_CALLS=FILE (the probe's, in the server): each SQLite call's CPU, µs;
# with --handoffs, the class's own calls give the chance that one hands the interpreter on
SQLITE_CALLS = os.environ.get("GYROLAB_BENCH_SQLITE_CALLS")
MACHINE_LABEL = "the whole machine during the class (/proc/stat, /proc/pressure/cpu)"
RUN_QUEUE_LABEL = "waited for a core / ran during the class (run_queue.py)"
# each group's CPU by the class's time, for queue_model.py to set beside its own
RUN_QUEUE_BIN_S = 0.25
RAN_BY_TIME_LABEL = (
    f"on a core in each {RUN_QUEUE_BIN_S} s from the first request (run_queue.py), s"
)
STEAL_LABEL = "the host's steal during the class (/proc/stat)"
# A run in which the hypervisor kept the cores from the class for more than this share of
# the time it wanted them measures the host as much as the app: 41-60 % in three runs of
# 2026-12-06 made every p95 3-10x a quiet hour's (bench/README.md, thirty-seventh part)
STEAL_NOTE_SHARE = 0.05
LOOPS = "of it the event loops"  # the server's workers' main threads
PARTS = ("heading", "latitude")
# One TLS context for every simulated browser.  httpx builds a new one per client unless
# given one, loading the CA bundle: ≈ 28 ms of the load generator's CPU per client, and
# 60 students' clients made within the 3 s ramp blocked its one event loop for ≈ 1.7 s --
# time the class's first requests measured as the server's.  (The server is plain http
# on loopback; a browser does not pay that per tab.)
CLIENT_TLS = ssl.create_default_context()


def browser(base: str) -> httpx.AsyncClient:
    """A simulated browser: one student's (or the teacher's) HTTP client."""
    return httpx.AsyncClient(base_url=base, timeout=120, verify=CLIENT_TLS)


SEED_SCRIPT = """
import sys
from sqlmodel import select
from app.db import write_session
from app.migrate import upgrade_to_head
from app.models import Assignment, Course, Enrollment, User
from app.accounts.security import hash_password
upgrade_to_head()
students, password = int(sys.argv[1]), sys.argv[2]
digest = hash_password(password)
with write_session() as db:
    teacher = User(username='teacher', display_name='Load teacher', role='teacher',
                   password_hash=digest)
    db.add(teacher); db.flush()
    course = Course(name='Load class', teacher_id=teacher.id); db.add(course); db.flush()
    # the tactical gyro streams 10 readings a second: the load the test is about
    assignment = Assignment(course_id=course.id, title='North finding', latitude_deg=39.93,
                            earth_rate_deg_h=15.04, allowed_methods='manual,csv,simulator',
                            simulator_preset='tactical-fog')
    db.add(assignment); db.flush()
    for i in range(students):
        user = User(username=f's{i:03d}', display_name=f'学生 {i}', role='student',
                    password_hash=digest)
        db.add(user); db.flush()
        db.add(Enrollment(course_id=course.id, student_id=user.id))
    print(course.id, assignment.id)
"""


@dataclass
class Tally:
    """Latencies per route, frame lags, errors, and acknowledged samples per session."""

    latencies: dict[str, list[float]] = field(default_factory=lambda: defaultdict(list))
    frame_lags: list[float] = field(default_factory=list)
    errors: list[str] = field(default_factory=list)
    acknowledged: dict[tuple[int, str, int], int] = field(default_factory=dict)
    frames: int = 0
    streamed_samples: int = 0
    ws_extensions: set[str] = field(default_factory=set)  # what the server agreed to
    cpu: tuple[float, float, float] = (0.0, 0.0, 0.0)  # s: server, PostgreSQL, load generator
    sent: list[str] = field(default_factory=list)  # with CLIENT_TIMES: each request's times
    streamed: list[str] = field(default_factory=list)  # with STREAM_TIMES: each position's
    # with --handoffs: (the interpreter's hand-off, a busy wake-up's extra per core asked
    # beyond each core), s, measured just before and just after the class
    handoffs: list[tuple[float, float]] = field(default_factory=list)
    # with --handoffs and the probe's SQLITE_CALLS: (the class's calls, their median CPU s,
    # the chance one hands the interpreter on with a core free, with none)
    call_handoffs: tuple[int, float, float, float] | None = None
    # with --run-queue: per group of processes, its threads' (ran, waited for a core) s, and
    # how many times they were put on a core
    run_queue: dict[str, tuple[float, float, int]] = field(default_factory=dict)
    # with --run-queue: the whole machine over the class (run_queue.machine_times)
    machine: tuple[float, ...] = ()
    # when the class's first request was sent (time.perf_counter), and with --run-queue
    # per group of processes its time on a core in each RUN_QUEUE_BIN_S from then, s
    first_sent: float | None = None
    ran_by_time: dict[str, list[float]] = field(default_factory=dict)

    async def request(
        self, client: httpx.AsyncClient, method: str, url: str, route: str, ok=(200,), **kw
    ) -> httpx.Response:
        start = time.perf_counter()
        if self.first_sent is None:
            self.first_sent = start
        try:
            response = await client.request(method, url, **kw)
        except httpx.HTTPError as error:
            self.errors.append(f"{route}: {error!r}")
            raise
        self.latencies[route].append(time.perf_counter() - start)
        if CLIENT_TIMES:
            answered = time.perf_counter()
            self.sent.append(f"{method} {url} {start:.6f} {answered:.6f} {BROWSER.get()}\n")
        if response.status_code not in ok:
            self.errors.append(f"{route}: HTTP {response.status_code} {response.text[:200]}")
            raise RuntimeError(f"{route} answered {response.status_code}")
        return response


def csrf(html: str) -> str:
    match = CSRF_RE.search(html)
    assert match, "no CSRF token on the page"
    return match.group(1)


def session_id_of(response: httpx.Response) -> int:
    return int(response.headers["location"].rstrip("/").rsplit("/", 1)[1])


async def stream_all_positions(
    base: str, cookie: str, session: int, token: str, client, tally: Tally, args
) -> None:
    """Turn the table and stream each position in turn, as the lab page does."""
    ws_url = base.replace("http://", "ws://") + f"/lab/sessions/{session}/stream"
    headers = {"Cookie": f"gyrolab_session={cookie}"}
    start = time.perf_counter()
    async with connect(ws_url, additional_headers=headers, max_size=2**22) as ws:
        tally.latencies["WS connect"].append(time.perf_counter() - start)
        tally.ws_extensions.update(extension.name for extension in ws.protocol.extensions)
        for part in PARTS:
            for position in range(1, 5):
                if position > 1:
                    await tally.request(
                        client,
                        "POST",
                        f"/lab/sessions/{session}/turn",
                        "POST /lab/sessions/{id}/turn",
                        json={"part": part, "position": position},
                        headers={"X-CSRF-Token": token},
                    )
                asked_at = time.perf_counter()
                first_at = last_at = None
                await ws.send(
                    json.dumps(
                        {
                            "action": "start",
                            "part": part,
                            "position": position,
                            "dwell_s": args.dwell,
                            "speed": args.speed,
                        }
                    )
                )
                started_at = None
                rate_hz = 1.0
                while True:
                    message = json.loads(await asyncio.wait_for(ws.recv(), timeout=60))
                    now = time.perf_counter()
                    if message["type"] == "started":
                        started_at, rate_hz = now, message["rate_hz"]
                    elif message["type"] == "samples":
                        first_at, last_at = first_at or now, now
                        tally.frames += 1
                        tally.streamed_samples += len(message["v"])
                        due = started_at + message["done"] / rate_hz / args.speed
                        tally.frame_lags.append(now - due)
                    elif message["type"] == "saved":
                        tally.latencies["WS save (last frame → saved)"].append(
                            now - (started_at + message["n"] / rate_hz / args.speed)
                        )
                        tally.acknowledged[session, part, position] = message["n"]
                        if STREAM_TIMES:
                            tally.streamed.append(
                                f"{session} {part} {position} {asked_at:.6f} {started_at:.6f}"
                                f" {first_at:.6f} {last_at:.6f} {now:.6f}\n"
                            )
                        break
                    else:
                        tally.errors.append(f"stream: {message}")
                        return


def handout_csv(name: str) -> tuple[str, list[int]]:
    text = (DATA / name).read_text(encoding="utf-8")
    rows = text.strip().splitlines()
    counts = [len(rows) - 1] * 4
    return text, counts


async def student(index: int, base: str, assignment: int, tally: Tally, args) -> None:
    BROWSER.set(str(index))  # this student's task's own
    await asyncio.sleep(random.Random(index).uniform(0, args.ramp))
    async with browser(base) as client:
        page = await tally.request(client, "GET", "/login", "GET /login")
        await tally.request(
            client,
            "POST",
            "/login",
            "POST /login",
            ok=(303,),
            data={"username": f"s{index:03d}", "password": PASSWORD, "csrf_token": csrf(page.text)},
        )
        home = await tally.request(client, "GET", "/lab", "GET /lab")
        created = await tally.request(
            client,
            "POST",
            "/lab/sessions",
            "POST /lab/sessions",
            ok=(303,),
            data={"assignment_id": str(assignment), "csrf_token": csrf(home.text)},
        )
        session = session_id_of(created)
        page = await tally.request(
            client, "GET", f"/lab/sessions/{session}", "GET /lab/sessions/{id}"
        )
        token = csrf(page.text)
        cookie = client.cookies.get("gyrolab_session")
        await stream_all_positions(base, cookie, session, token, client, tally, args)

        practice = await tally.request(
            client,
            "POST",
            "/lab/sessions",
            "POST /lab/sessions",
            ok=(303,),
            data={"station": "handout", "preset": "tactical-fog", "csrf_token": token},
        )
        practice_id = session_id_of(practice)
        for part, name in (
            ("heading", "handout_horizontal.csv"),
            ("latitude", "handout_vertical.csv"),
        ):
            text, counts = handout_csv(name)
            body = {"part": part, "unit": "deg/h", "text": text}
            headers = {"X-CSRF-Token": token}
            await tally.request(
                client,
                "POST",
                f"/lab/sessions/{practice_id}/csv/preview",
                "POST /lab/sessions/{id}/csv/preview",
                json=body,
                headers=headers,
            )
            await tally.request(
                client,
                "POST",
                f"/lab/sessions/{practice_id}/csv",
                "POST /lab/sessions/{id}/csv",
                json=body,
                headers=headers,
            )
            for position, n in enumerate(counts, start=1):
                tally.acknowledged[practice_id, part, position] = n
        for sid in (session, practice_id):
            await tally.request(
                client,
                "GET",
                f"/lab/sessions/{sid}/results.json",
                "GET /lab/sessions/{id}/results.json",
            )
        await tally.request(client, "GET", f"/lab/sessions/{session}", "GET /lab/sessions/{id}")
        await tally.request(
            client,
            "POST",
            f"/lab/sessions/{session}/submit",
            "POST /lab/sessions/{id}/submit",
            ok=(303,),
            data={"csrf_token": token},
        )


async def teacher(base: str, course: int, assignment: int, tally: Tally, done: asyncio.Event):
    BROWSER.set("teacher")
    async with browser(base) as client:
        page = await tally.request(client, "GET", "/login", "GET /login")
        await tally.request(
            client,
            "POST",
            "/login",
            "POST /login",
            ok=(303,),
            data={"username": "teacher", "password": PASSWORD, "csrf_token": csrf(page.text)},
        )
        path = f"/courses/{course}/assignments/{assignment}"
        while not done.is_set():
            with contextlib.suppress(RuntimeError, httpx.HTTPError):  # counted in the tally
                await tally.request(client, "GET", path, "GET dashboard (teacher)")
            with contextlib.suppress(TimeoutError):
                await asyncio.wait_for(done.wait(), timeout=2.0)


async def run_class(base: str, course: int, assignment: int, args) -> tuple[Tally, float]:
    tally = Tally()
    done = asyncio.Event()
    watcher = asyncio.create_task(teacher(base, course, assignment, tally, done))
    start = time.perf_counter()
    results = await asyncio.gather(
        *(student(i, base, assignment, tally, args) for i in range(args.students)),
        return_exceptions=True,
    )
    wall = time.perf_counter() - start
    done.set()
    await watcher
    for result in results:
        if isinstance(result, BaseException):
            where = traceback.extract_tb(result.__traceback__)[-1]
            tally.errors.append(
                f"student failed: {result!r} at {Path(where.filename).name}:{where.lineno}"
            )
    return tally, wall


async def login_burst(base: str, students: int) -> tuple[str, bool]:
    """Every student logs in at the same instant (each has fetched the form first): the
    time until the last log-in is answered, and each one's latency."""
    clients = [browser(base) for _ in range(students)]
    try:
        forms = await asyncio.gather(*(client.get("/login") for client in clients))
        latencies: list[float] = []
        errors: list[str] = []

        async def log_in(index: int, client: httpx.AsyncClient, form: httpx.Response) -> None:
            began = time.perf_counter()
            response = await client.post(
                "/login",
                data={
                    "username": f"s{index:03d}",
                    "password": PASSWORD,
                    "csrf_token": csrf(form.text),
                },
            )
            latencies.append(time.perf_counter() - began)
            if response.status_code != 303:
                errors.append(f"s{index:03d}: {response.status_code}")

        start = time.perf_counter()
        pairs = enumerate(zip(clients, forms, strict=True))
        await asyncio.gather(*(log_in(i, client, form) for i, (client, form) in pairs))
        wall = time.perf_counter() - start
    finally:
        await asyncio.gather(*(client.aclose() for client in clients))
    text = (
        f"{students} log-ins at once: all answered in {wall:.2f} s; latency p50 "
        f"{percentile_ms(latencies, 50)} / p95 {percentile_ms(latencies, 95)} / max "
        f"{max(latencies) * 1000:.0f} ms; errors {len(errors)} {errors[:3]}"
    )
    return text, not errors and wall <= 3.0


def stored_counts(database_url: str) -> dict[tuple[int, str, int], tuple[int, int]]:
    """(session, part, position) → (take.n_samples, samples in its chunks) of current takes."""
    from sqlalchemy import create_engine, text

    engine = create_engine(database_url)
    with engine.connect() as connection:
        rows = connection.execute(
            text(
                "SELECT take.session_id, take.part, take.position, take.n_samples,"
                ' COALESCE(SUM(LENGTH(sample_chunk."values")), 0) / 8'
                " FROM take LEFT JOIN sample_chunk ON sample_chunk.take_id = take.id"
                " WHERE take.superseded_at IS NULL"
                " GROUP BY take.id, take.session_id, take.part, take.position, take.n_samples"
            )
        ).all()
    engine.dispose()
    return {(s, part, p): (n, int(chunks)) for s, part, p, n, chunks in rows}


def seed(env: dict, students: int) -> tuple[int, int]:
    done = subprocess.run(
        [sys.executable, "-c", SEED_SCRIPT, str(students), PASSWORD],
        env=env,
        capture_output=True,
        text=True,
        check=True,
        cwd=ROOT,
    )
    course, assignment = (int(x) for x in done.stdout.split())
    return course, assignment


def steal_line(busy_s: float, steal_s: float) -> str:
    """The report's line on the hypervisor's steal over the class: its seconds, its share of
    the time the class wanted the cores (busy + steal), and a note where that share is over
    ``STEAL_NOTE_SHARE``."""
    share = steal_s / (busy_s + steal_s) if busy_s + steal_s > 0 else 0.0
    line = f"- {STEAL_LABEL}: {steal_s:.2f} s, {share:.0%} of the cores' time the class wanted"
    if share > STEAL_NOTE_SHARE:
        line += (
            " -- the host kept the cores from the class: these p95s are the host's as much as"
            " the app's (compare runs of a quiet hour)"
        )
    return line


def percentile_ms(values: list[float], q: float) -> str:
    return f"{np.percentile(values, q) * 1000:.0f}" if values else "-"


def report(name: str, tally: Tally, wall: float, lost: int, checked: int, workers: int) -> str:
    requests = sum(len(v) for k, v in tally.latencies.items() if not k.startswith("WS"))
    lines = [
        f"### {name} ({workers} worker{'s' if workers > 1 else ''})",
        "",
        f"- wall time {wall:.1f} s; {requests} HTTP requests → {requests / wall:.1f} req/s;"
        f" {tally.frames} stream frames, {tally.streamed_samples} streamed samples",
        f"- errors: {len(tally.errors)}; lost samples: {lost} of {checked} positions checked"
        " (acknowledged against stored)",
        f"- stream frame lag behind the simulated clock: p50 {percentile_ms(tally.frame_lags, 50)}"
        f" ms, p95 {percentile_ms(tally.frame_lags, 95)} ms, p99"
        f" {percentile_ms(tally.frame_lags, 99)} ms, max {percentile_ms(tally.frame_lags, 100)} ms",
        f"- CPU used during the class: server {tally.cpu[0]:.1f} s, PostgreSQL"
        f" {tally.cpu[1]:.1f} s, load generator {tally.cpu[2]:.1f} s",
        "- WebSocket extensions the server agreed to: "
        + (", ".join(sorted(tally.ws_extensions)) or "none"),
    ]
    if tally.handoffs:
        handoffs = " / ".join(f"{h * 1e6:.0f}" for h, _ in tally.handoffs)
        wakes = " / ".join(f"{w * 1e6:.0f}" for _, w in tally.handoffs)
        lines.append(
            f"- {HANDOFFS_LABEL}: the interpreter's {handoffs} µs, a busy wake-up {wakes} µs"
            " a core asked beyond each core"
        )
    if tally.call_handoffs:
        count, median_s, free, busy = tally.call_handoffs
        lines.append(
            f"- {CALL_HANDOFFS_LABEL}, the class's {count} calls (p50 {median_s * 1e6:.1f} µs),"
            f" measured after it: a core free {free:.1%}, none free {busy:.1%}"
        )
    if tally.run_queue:
        lines.append(f"- {RUN_QUEUE_LABEL}: " + ", ".join(
            f"{group} {waited:.2f} / {ran:.2f} s ({waited / max(ran + waited, 1e-9):.0%},"
            f" {slices} slices)"
            for group, (ran, waited, slices) in tally.run_queue.items()
        ))  # fmt: skip
    if tally.ran_by_time:
        lines.append(f"- {RAN_BY_TIME_LABEL}: " + "; ".join(
            f"{group} " + " ".join(f"{ran:.3f}" for ran in series)
            for group, series in tally.ran_by_time.items()
        ))  # fmt: skip
    if tally.machine:
        lines.append(steal_line(*tally.machine[:2]))
    if tally.machine and tally.run_queue:
        busy, steal, idle, pressure = tally.machine
        mine = sum(ran for group, (ran, _, _) in tally.run_queue.items() if group != LOOPS)
        lines.append(
            f"- {MACHINE_LABEL}: busy {busy:.2f} s (the groups above {mine:.2f} s, anything"
            f" else {busy - mine:.2f} s), steal {steal:.2f} s, idle {idle:.2f} s; a task"
            f" waited for a core during {pressure:.2f} s"
        )
    lines += [
        "",
        "| route | count | p50 ms | p95 ms | p99 ms | max ms |",
        "|---|---:|---:|---:|---:|---:|",
    ]
    for route, values in sorted(tally.latencies.items()):
        lines.append(
            f"| {route} | {len(values)} | {percentile_ms(values, 50)} | "
            f"{percentile_ms(values, 95)} | {percentile_ms(values, 99)} | "
            f"{percentile_ms(values, 100)} |"
        )
    for error, count in Counter(tally.errors).most_common():
        lines.append(f"\nerror ({count}×): {error}")
    return "\n".join(lines)


def lost_samples(tally: Tally, database_url: str) -> tuple[int, int]:
    stored = stored_counts(database_url)
    lost = 0
    for key, acknowledged in tally.acknowledged.items():
        n, in_chunks = stored.get(key, (0, 0))
        lost += max(0, acknowledged - n) + abs(n - in_chunks)
    return lost, len(tally.acknowledged)


def run_backend(backend: str, args) -> tuple[str, bool]:
    with tempfile.TemporaryDirectory(prefix="gyrolab-load-") as var:
        var_dir = Path(var)
        pg = None
        database_url = f"sqlite:///{var_dir / 'gyrolab.db'}"
        serve_args = ["--no-demo", "--no-access-log"]
        workers = 1
        if backend == "postgresql":
            if args.database_url:  # an empty database on a server of the caller's (tests)
                database_url = args.database_url
            else:
                pg = PostgresServer().start(durable=True)
                database_url = pg.create_database("gyrolab_load")
            workers = args.pg_workers
            serve_args += ["--workers", str(workers)]
        try:
            env = {**os.environ, "GYROLAB_VAR_DIR": var, "GYROLAB_DATABASE_URL": database_url}
            course, assignment = seed(env, args.students)
            url = database_url if backend == "postgresql" else None
            # before the server starts: its first seconds' own work is not in the measurement
            waits = [hand_off_constants()] if args.handoffs and not args.logins_only else []
            with running_server(var_dir, *serve_args, database_url=url) as server:
                if args.logins_only:
                    text, passed = asyncio.run(login_burst(server.url, args.students))
                    name = "SQLite" if backend == "sqlite" else "PostgreSQL"
                    return f"### {name} ({workers} worker{'s' * (workers > 1)})\n{text}", passed
                pids = server_pids(server.process.pid)

                def cpu() -> tuple[float, float, float]:
                    # whole processes (threads that have ended included), in clock ticks
                    database = cpu_seconds(postgres_pids()) if backend == "postgresql" else 0.0
                    return cpu_seconds(pids), database, time.process_time()

                groups = {"server": lambda: pids, "load generator": lambda: [os.getpid()]}
                if backend == "postgresql":
                    groups["PostgreSQL"] = postgres_pids
                watch = RunQueueWatch(
                    groups if args.run_queue else {}, main_threads={"server": LOOPS}
                )
                calls_from = class_calls_start()
                before = cpu()
                with watch:
                    tally, wall = asyncio.run(run_class(server.url, course, assignment, args))
                after = cpu()
                tally.run_queue = {
                    group: (waits.ran_s, waits.waited_s, waits.slices)
                    for group, waits in watch.waits().items()
                }
                tally.machine = watch.machine()
                if args.run_queue and tally.first_sent is not None:
                    tally.ran_by_time = watch.ran_by_time(tally.first_sent, RUN_QUEUE_BIN_S)
                tally.handoffs = waits + ([hand_off_constants()] if args.handoffs else [])
                if args.handoffs and calls_from is not None and backend == "sqlite":
                    tally.call_handoffs = class_call_handoffs(calls_from)
                tally.cpu = tuple(b - a for a, b in zip(before, after, strict=True))
                if CLIENT_TIMES:  # after the class's CPU is read: not counted in it
                    Path(CLIENT_TIMES).write_text("".join(tally.sent))
                if STREAM_TIMES:
                    Path(STREAM_TIMES).write_text("".join(tally.streamed))
            lost, checked = lost_samples(tally, database_url)
            if tally.errors:  # keep the server's log for the post-mortem
                kept = Path(tempfile.gettempdir()) / f"gyrolab-load-{backend}-server.log"
                kept.write_text((var_dir / "server.log").read_text())
                tally.errors.append(f"server log kept in {kept}")
        finally:
            if pg is not None:
                pg.stop()
    expected_positions = args.students * 16
    if checked != expected_positions:
        tally.errors.append(f"only {checked} of {expected_positions} positions acknowledged")
    name = "SQLite" if backend == "sqlite" else "PostgreSQL"
    text = report(name, tally, wall, lost, checked, workers)
    return text, not tally.errors and lost == 0


def class_calls_start() -> int | None:
    """Where the class's SQLite calls begin in the probe's GYROLAB_BENCH_SQLITE_CALLS file
    (bytes; the seeding's and the start-up's calls come before), None without it."""
    if not SQLITE_CALLS:
        return None
    return Path(SQLITE_CALLS).stat().st_size if Path(SQLITE_CALLS).exists() else 0


def class_call_handoffs(start: int) -> tuple[int, float, float, float] | None:
    """The class's SQLite calls (the probe's file from ``start``): how many, their median
    CPU (s), and the chance one hands the interpreter on with a core free and with none,
    from curves measured now (bench_handoffs.py --calls: the chance drifts with the host's
    hour as the calls' length and a wake-up's do)."""
    with open(SQLITE_CALLS, "rb") as calls:
        calls.seek(start)
        durations = np.array(calls.read().split(), dtype=float) / 1e6
    if not len(durations):
        return None
    free, busy = call_handoff_chances(durations)
    return len(durations), float(np.median(durations)), free, busy


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--students", type=int, default=60)
    parser.add_argument("--backend", choices=("sqlite", "postgresql", "both"), default="both")
    parser.add_argument("--pg-workers", type=int, default=2)
    parser.add_argument("--dwell", type=float, default=60.0, help="simulated seconds/position")
    parser.add_argument("--speed", type=float, default=20.0, help="simulated time speed-up")
    parser.add_argument("--ramp", type=float, default=3.0, help="students start within (s)")
    parser.add_argument(
        "--database-url", help="PostgreSQL: an empty database to use instead of starting one"
    )
    parser.add_argument(
        "--logins-only",
        action="store_true",
        help="only the log-in burst: every student logs in at the same instant (goal ≤ 3 s)",
    )
    parser.add_argument(
        "--handoffs",
        action="store_true",
        help="measure the interpreter's hand-off and a busy wake-up (bench_handoffs.py, "
        "≈ 15 s each time) just before and just after the class, for queue_model.py; with "
        "the probe's GYROLAB_BENCH_SQLITE_CALLS, after the class also the chance that one "
        "of its SQLite calls hands the interpreter on (≈ 1 min)",
    )
    parser.add_argument(
        "--run-queue",
        action="store_true",
        help="poll the kernel's schedstat of the server, the database and the load "
        "generator (run_queue.py): how long each waited for a core during the class",
    )
    args = parser.parse_args()
    backends = ("sqlite", "postgresql") if args.backend == "both" else (args.backend,)
    print(
        f"machine: {platform.machine()}, {os.cpu_count()} cores, Python"
        f" {platform.python_version()}; {args.students} students, {args.dwell:g} s per position"
        f" at {args.speed:g}× → {args.dwell / args.speed:g} s of streaming per position\n"
    )
    ok = True
    for backend in backends:
        text, passed = run_backend(backend, args)
        print(text, "\n", flush=True)
        ok = ok and passed
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
