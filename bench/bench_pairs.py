"""Two requests of one route sent a set time apart to a quiet server, beside the queueing
model's answer for the same two: does the model serve a pair as the server does?

A class's requests meet in twos and threes; how much each delays the other sets its
queueing.  Here one route's request is sent alone, and in pairs whose second is sent 0, 2,
4 or 8 ms after the first (two students, in a shuffled order, 30 ms apart), to a real
server (one worker on SQLite) with the probe on: its time inside the app, its CPU on the
event loop and in threads, and how often its threads gave up the interpreter.  The model
(``queue_sim.simulate`` with a one-request script and the two students' start times) is
given the CPU the same requests used and answers for the same offsets.

    .venv/bin/python bench/bench_pairs.py [--route page|turn] [--reps 60]
"""

from __future__ import annotations

import argparse
import asyncio
import bisect
import os
import random
import struct
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path
from unittest.mock import patch

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "bench"))

import load_test  # noqa: E402  (bench/, the script's folder)
import queue_sim  # noqa: E402
from capacity import cpu_seconds, server_pids  # noqa: E402
from class_cpu import route_of  # noqa: E402

PROBE = Path(__file__).resolve().parent / "probe"
OFFSETS_S = (0.0, 0.002, 0.004, 0.008)  # the second of a pair sent this long after the first
ROUTES = {"page": "GET /lab/sessions/{id}", "turn": "POST /lab/sessions/{id}/turn"}
CONDITIONS = ("alone", *OFFSETS_S)


@dataclass
class Cost:
    """One request's mean costs, as ``queue_sim`` takes them: (server CPU, database CPU,
    client CPU, SQLite calls, thread-pool trips, server CPU on the event loop, of it the
    request's own task's), s."""

    server: float
    client: float
    calls: float
    trips: float
    loop: float
    loop_own: float

    def as_costs(self) -> tuple[float, ...]:
        return (self.server, 0.0, self.client, self.calls, self.trips, self.loop, self.loop_own)


def modelled(route: str, cost: Cost, offset: float | None, seeds: int = 20) -> list[float]:
    """The model's mean latencies (s) of the request alone (``offset`` None) or of a pair's
    first and second, ``offset`` apart; inside the app, as the probe measures it."""
    costs = {route: cost.as_costs(), queue_sim.STREAM: cost.as_costs()}
    starts = [0.0] if offset is None else [0.0, offset]
    inside = []
    for seed in range(seeds):
        result = queue_sim.simulate(
            costs, len(starts), 1, 2.0, teacher=False, seed=seed,
            script=lambda: iter([("request", route)]), starts=starts,
        )  # fmt: skip
        rows = sorted(result["server"][route], key=lambda row: row[6])  # by when they came
        inside.append([row[0] + row[1] for row in rows])
    return [float(x) for x in np.mean(inside, axis=0)]


async def _send(base: str, route: str, assignment: int, reps: int, ready) -> tuple:
    """Two students log in (then ``ready()`` is called) and send the plan's requests:
    (each trial's condition and when it began, time.perf_counter; the load generator's CPU
    for the trials' requests; how many requests)."""
    students = []
    for index in (0, 1):
        client = load_test.browser(base)
        page = await client.get("/login")
        await client.post("/login", data={"username": f"s{index:03d}",
                                          "password": load_test.PASSWORD,
                                          "csrf_token": load_test.csrf(page.text)})  # fmt: skip
        home = await client.get("/lab")
        created = await client.post("/lab/sessions", data={
            "assignment_id": str(assignment), "csrf_token": load_test.csrf(home.text)})  # fmt: skip
        session = load_test.session_id_of(created)
        page = await client.get(f"/lab/sessions/{session}")
        client.headers["X-CSRF-Token"] = load_test.csrf(page.text)
        students.append((client, session, [2]))

    async def one(student, delay: float) -> None:
        client, session, position = student
        if delay:
            await asyncio.sleep(delay)
        if route == ROUTES["turn"]:  # to and fro: each one a turn the server writes
            position[0] = 5 - position[0]
            body = {"part": "heading", "position": position[0]}
            answer = await client.post(f"/lab/sessions/{session}/turn", json=body)
        else:
            answer = await client.get(f"/lab/sessions/{session}")
        answer.raise_for_status()

    plan = list(CONDITIONS) * reps
    random.Random(1).shuffle(plan)
    ready()
    trials = []
    cpu, sent = time.process_time(), 0
    for condition in plan:
        trials.append((condition, time.perf_counter()))
        if condition == "alone":
            await one(students[0], 0.0)
            sent += 1
        else:
            await asyncio.gather(one(students[0], 0.0), one(students[1], condition))
            sent += 2
        await asyncio.sleep(0.03)
    cpu = time.process_time() - cpu
    for client, _, _ in students:
        await client.aclose()
    return trials, cpu, sent


def measure(route: str, reps: int) -> tuple[dict, Cost]:
    """The server's time inside the app per condition (ms: alone; a pair's first, second)
    and the route's mean costs, from one quiet server."""
    with tempfile.TemporaryDirectory(prefix="gyrolab-pairs-") as var:
        var_dir = Path(var)
        counts, waits = var_dir / "counts.bin", var_dir / "waits.txt"
        counts.write_bytes(bytes(16))
        env = {**os.environ, "GYROLAB_VAR_DIR": var,
               "GYROLAB_DATABASE_URL": f"sqlite:///{var_dir / 'gyrolab.db'}"}  # fmt: skip
        _, assignment = load_test.seed(env, 2)
        probed = {"PYTHONPATH": str(PROBE), "GYROLAB_BENCH_PROBE": str(counts),
                  "GYROLAB_BENCH_REQUEST_WAITS": str(waits)}  # fmt: skip
        with (
            patch.dict(os.environ, probed),  # the server's, then as it was
            load_test.running_server(var_dir, "--no-demo", "--no-access-log") as server,
        ):
            pids = server_pids(server.process.pid)
            before: list = []

            def ready() -> None:  # the trials' costs from here
                before[:] = [struct.unpack("<2q", counts.read_bytes()), cpu_seconds(pids)]

            trials, client_cpu, sent = asyncio.run(
                _send(server.url, route, assignment, reps, ready)
            )
            used = cpu_seconds(pids) - before[1]
            made = np.subtract(struct.unpack("<2q", counts.read_bytes()), before[0])
        lines = waits.read_text().splitlines()
    starts = [began for _, began in trials]
    by_trial: dict[int, list] = {}
    for row in (line.split() for line in lines):
        if len(row) != 14 or route_of(row[0], row[1]) != route:
            continue
        trial = bisect.bisect_right(starts, float(row[12])) - 1
        if trial >= 0:  # not the students' own first visits
            by_trial.setdefault(trial, []).append(row)
    by_condition: dict = {condition: [] for condition in CONDITIONS}
    for trial, trial_rows in by_trial.items():
        condition = trials[trial][0]
        if len(trial_rows) == (1 if condition == "alone" else 2):
            trial_rows.sort(key=lambda row: float(row[12]))
            by_condition[condition].append([float(row[2]) for row in trial_rows])
    rows = [row for trial_rows in by_trial.values() for row in trial_rows]
    own = np.array([[float(row[4]), float(row[7])] for row in rows]) / 1000  # loop, threads
    loop_own, threads = own.mean(axis=0)
    unseen = max(used / sent - loop_own - threads, 0.0)  # sockets, the framework's outside
    cost = Cost(server=loop_own + threads + unseen, client=client_cpu / sent,
                calls=made[0] / sent, trips=made[1] / sent, loop=loop_own + unseen,
                loop_own=loop_own)  # fmt: skip
    return {c: np.mean(v, axis=0) for c, v in by_condition.items() if v}, cost


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--route", choices=sorted(ROUTES), default="page")
    parser.add_argument("--reps", type=int, default=60, help="times each condition is sent")
    args = parser.parse_args()
    route = ROUTES[args.route]
    measured, cost = measure(route, args.reps)
    print(f"{route}: per request {cost.server * 1000:.2f} ms of server CPU (of it"
          f" {cost.loop * 1000:.2f} on the event loop, {cost.loop_own * 1000:.2f} in its own"
          f" task), {cost.client * 1000:.2f} ms of the load generator's, {cost.calls:.1f}"
          f" SQLite calls, {cost.trips:.1f} thread-pool trips")  # fmt: skip
    print("inside the app, mean ms: model | measured (alone; a pair's first, second)")
    for condition in CONDITIONS:
        if condition not in measured:
            continue
        model = modelled(route, cost, None if condition == "alone" else condition)
        name = "alone" if condition == "alone" else f"second {condition * 1000:.0f} ms after"
        cells = " / ".join(f"{m * 1000:5.2f}" for m in model)
        seen = " / ".join(f"{s:5.2f}" for s in measured[condition])
        print(f"  {name:22s} {cells:>15s} | {seen}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
