"""The capacity model's inputs, measured, and one check of its prediction.

    .venv/bin/python bench/capacity.py [--requests 200] [--seconds 8]

1. Server CPU per request, route by route: one worker (SQLite), sequential requests, the
   server process's CPU time (``/proc/<pid>/stat``: user + system) divided by the number
   of requests -- the cost a core pays per request, whatever the client does.
2. Bytes stored per student per lab: the database file's growth per student after a full
   lab (eight simulator positions of 60 s at 10 Hz plus the handout's two tables).
3. The check: the model predicts the results endpoint's throughput with two workers on
   PostgreSQL from (1) -- ``server cores / CPU per request`` -- and eight client threads
   measure it; the client's and PostgreSQL's own CPU are read too, since everything shares
   the machine's two cores.
"""

from __future__ import annotations

import argparse
import os
import sqlite3
import sys
import tempfile
import threading
import time
from pathlib import Path

import httpx

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from handout import handout_session  # noqa: E402  (bench/, the script's folder)

from tests.e2e.conftest import running_server  # noqa: E402
from tests.pgserver import PostgresServer  # noqa: E402

PASSWORD = "capacity-pass-1"
TICKS = os.sysconf("SC_CLK_TCK")


def cpu_seconds(pids: list[int]) -> float:
    """User + system CPU of these processes and their children so far."""
    total = 0
    for pid in pids:
        try:
            fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
        except FileNotFoundError:
            continue
        total += sum(int(x) for x in fields[11:15])  # utime stime cutime cstime
    return total / TICKS


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


def server_pids(root: int) -> list[int]:
    """The server process and its worker processes."""
    pids = [root]
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            try:
                stat = (entry / "stat").read_text().rsplit(")", 1)[1].split()
            except OSError:
                continue
            if int(stat[1]) == root:
                pids.append(int(entry.name))
    return pids


def create_student(var: Path, database_url: str | None) -> None:
    import subprocess

    env = {**os.environ, "GYROLAB_VAR_DIR": str(var)}
    if database_url:
        env["GYROLAB_DATABASE_URL"] = database_url
    for role, name in (("teacher", "teacher"), ("student", "student")):
        subprocess.run(
            [sys.executable, "-m", "app.cli.main", "create-user", "--role", role,
             "--username", name],
            input=PASSWORD + "\n", env=env, text=True, check=True, capture_output=True,
        )  # fmt: skip


def browser_login(url: str) -> httpx.Client:
    client = httpx.Client(base_url=url, timeout=60)
    token = client.get("/login").text.split('name="csrf_token" value="')[1].split('"')[0]
    client.post("/login", data={"username": "student", "password": PASSWORD, "csrf_token": token})
    return client


def per_route_cpu(url: str, pid: int, count: int) -> dict[str, float]:
    """Server CPU milliseconds per request of each route (sequential, warmed up)."""
    api = httpx.Client(base_url=url, timeout=60)
    token = api.post("/api/v1/auth/token", data={"username": "student", "password": PASSWORD})
    auth = {"Authorization": f"Bearer {token.json()['access_token']}"}
    session = handout_session(api, auth)
    page = browser_login(url)
    samples = {"samples": [10.0 + i / 1000 for i in range(600)]}
    routes = {
        "GET /api/v1/sessions/{id}/results": lambda: api.get(
            f"/api/v1/sessions/{session}/results", headers=auth
        ),
        "GET /lab/sessions/{id} (page)": lambda: page.get(f"/lab/sessions/{session}"),
        "GET /lab (page)": lambda: page.get("/lab"),
        "PUT …/positions/{k} (600 samples, JSON)": lambda: api.put(
            f"/api/v1/sessions/{session}/heading/positions/1", headers=auth, json=samples
        ),
    }
    costs = {}
    pids = server_pids(pid)
    for name, call in routes.items():
        for _ in range(10):
            call().raise_for_status()
        before = cpu_seconds(pids)
        for _ in range(count):
            call().raise_for_status()
        costs[name] = (cpu_seconds(pids) - before) / count * 1000
    before = cpu_seconds(pids)
    logins = max(count // 10, 10)
    for _ in range(logins):
        httpx.post(
            f"{url}/api/v1/auth/token", data={"username": "student", "password": PASSWORD}
        ).raise_for_status()
    costs["POST /api/v1/auth/token (log-in, argon2id)"] = (
        (cpu_seconds(pids) - before) / logins * 1000
    )
    return costs


def checkpointed_size(database: Path) -> int:
    """The database file's size with its write-ahead log folded in (the log's own size
    says how much was written lately, not how much is stored)."""
    with sqlite3.connect(database) as connection:
        connection.execute("PRAGMA wal_checkpoint(TRUNCATE)")
    return database.stat().st_size


def stored_bytes_per_student(url: str, var: Path) -> float:
    """Database growth for one full lab: eight streamed positions are approximated by
    API uploads of the same size (600 samples with times each), plus the handout tables."""
    database = var / "gyrolab.db"
    before = checkpointed_size(database)
    api = httpx.Client(base_url=url, timeout=60)
    token = api.post("/api/v1/auth/token", data={"username": "student", "password": PASSWORD})
    auth = {"Authorization": f"Bearer {token.json()['access_token']}"}
    labs = 5
    for _ in range(labs):
        session = handout_session(api, auth, "capacity")
        timed = {"samples": [10.0] * 600, "times_s": [i / 10 for i in range(600)]}
        for part in ("heading", "latitude"):
            for k in range(1, 5):
                api.put(
                    f"/api/v1/sessions/{session}/{part}/positions/{k}", headers=auth, json=timed
                ).raise_for_status()
    api.post("/api/v1/auth/token", data={"username": "student", "password": PASSWORD})
    time.sleep(1)
    after = checkpointed_size(database)
    return (after - before) / labs


def throughput(url: str, threads: int, seconds: float) -> tuple[float, float]:
    """Requests per second of the results endpoint from ``threads`` clients, and the
    client process's CPU share of the run (cores)."""
    api = httpx.Client(base_url=url, timeout=60)
    token = api.post("/api/v1/auth/token", data={"username": "student", "password": PASSWORD})
    auth = {"Authorization": f"Bearer {token.json()['access_token']}"}
    session = handout_session(api, auth)
    done = [0] * threads
    stop = time.monotonic() + seconds

    def worker(i: int) -> None:
        client = httpx.Client(base_url=url, timeout=60)
        while time.monotonic() < stop:
            client.get(f"/api/v1/sessions/{session}/results", headers=auth).raise_for_status()
            done[i] += 1

    start_cpu, start = time.process_time(), time.monotonic()
    pool = [threading.Thread(target=worker, args=(i,)) for i in range(threads)]
    for thread in pool:
        thread.start()
    for thread in pool:
        thread.join()
    wall = time.monotonic() - start
    return sum(done) / wall, (time.process_time() - start_cpu) / wall


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--requests", type=int, default=200)
    parser.add_argument("--seconds", type=float, default=8.0)
    args = parser.parse_args()
    os.environ["GYROLAB_API_RATE_PER_MINUTE"] = "1000000"  # measure the app, not its limit
    with tempfile.TemporaryDirectory() as tmp:
        var = Path(tmp) / "sqlite"
        var.mkdir()
        create_student(var, None)
        with running_server(var, "--no-demo") as server:
            costs = per_route_cpu(server.url, server.process.pid, args.requests)
            per_lab = stored_bytes_per_student(server.url, var)
        print("server CPU per request, one worker on SQLite (ms):")
        for name, cost in costs.items():
            print(f"  {name:48s} {cost:7.2f}")
        print(f"database growth per student per lab: {per_lab / 1024:.0f} KiB")

        pg = PostgresServer().start(durable=True)
        try:
            url = pg.create_database("gyrolab_capacity")
            pg_var = Path(tmp) / "pg"
            pg_var.mkdir()
            create_student(pg_var, url)
            with running_server(pg_var, "--no-demo", "--workers", "2", database_url=url) as srv:
                cost = per_route_cpu(srv.url, srv.process.pid, args.requests)
                pids = server_pids(srv.process.pid)
                results_ms = cost["GET /api/v1/sessions/{id}/results"]
                before = cpu_seconds(pids)
                measured, client_cores = throughput(srv.url, 8, args.seconds)
                server_cores = (cpu_seconds(pids) - before) / args.seconds
            cores = os.cpu_count() or 1
            predicted_all = cores / (results_ms / 1000)
            predicted_left = max(cores - client_cores, 0.1) / (results_ms / 1000)
            print(f"PostgreSQL, 2 workers: results endpoint {results_ms:.2f} ms CPU each")
            print(
                f"  predicted {predicted_all:.0f} req/s with all {cores} cores, "
                f"{predicted_left:.0f} req/s with the cores the client left "
                f"({cores - client_cores:.2f})"
            )
            print(
                f"  measured  {measured:.0f} req/s (8 client threads); server workers used "
                f"{server_cores:.2f} cores, the client {client_cores:.2f}"
            )
        finally:
            pg.stop()


if __name__ == "__main__":
    main()
