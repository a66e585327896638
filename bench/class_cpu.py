"""Each request's CPU as a class spent it, from the probe's lines in a load test
(``bench/probe/sitecustomize.py``: ``GYROLAB_BENCH_REQUEST_CPU``, ``GYROLAB_BENCH_SERVER_TIMES``),
and the queueing model's costs per request made from them."""

from __future__ import annotations

import re
from collections import Counter, defaultdict
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from queue_sim import STREAM, STREAM_SAVE, STREAM_SPLIT, STREAM_START

ID_IN_PATH = re.compile(r"/\d+")
WEBSOCKET = "WS"  # a server-times line's method where a WebSocket connected
# the stream's functions in the thread pool (app.lab.stream), by the part of a position
# they belong to: the connection's and each position's checks and mark (a write), the
# gyro's take made ready (no write), each position's save (a write) -- the rest, too
MARKING = {"_owner", "_mark_started"}
MAKING_READY = {"SimulatedTake"}


def route_of(method: str, path: str) -> str:
    """The load test's name of a request (ids replaced; the teacher's page by its role)."""
    if path.startswith("/courses/"):
        return "GET dashboard (teacher)"
    return f"{method} {ID_IN_PATH.sub('/{id}', path)}"


@dataclass
class ClassCpu:
    """What the probe saw of a class: per route the mean CPU seconds (on the event loop,
    in the thread pool) of its own task (the stream: per frame of samples), how many, and
    their sum; and per HTTP route each request's own (loop, threads) CPU seconds."""

    means: dict[str, tuple[float, float]]
    counts: dict[str, int]
    total_s: float
    each: dict[str, list[tuple[float, float]]] = field(default_factory=dict)
    # the streams' thread CPU by part -- marking, making the take ready, saving -- as
    # shares of it, where the probe's lines name the functions
    stream_split: tuple[float, float, float] | None = None
    # the streams' thread CPU by function, s (all of the class's WebSockets)
    stream_functions: dict[str, float] = field(default_factory=dict)


def attributed_costs(text: str) -> ClassCpu:
    """From the probe's per-request lines (``GYROLAB_BENCH_REQUEST_CPU``): per route the
    mean CPU seconds (on the event loop, in the thread pool) of its own task; for the
    stream, per frame of samples sent (the WebSockets' whole CPU over their frames)."""
    spent: dict[str, list[tuple[float, float]]] = defaultdict(list)
    stream = np.zeros(3)
    parts = np.zeros(3)  # the streams' thread CPU marking, making ready, saving (ms)
    functions: dict[str, float] = defaultdict(float)
    for line in text.splitlines():
        kind, method, path, loop_ms, threads_ms, frames, *by_function = line.split()
        cpu = (float(loop_ms) / 1000, float(threads_ms) / 1000)
        if kind == "websocket":
            stream += (*cpu, int(frames))
            for pair in ",".join(by_function).split(","):
                if "=" in pair:
                    name, ms = pair.split("=")
                    part = 0 if name in MARKING else 1 if name in MAKING_READY else 2
                    parts[part] += float(ms)
                    functions[name] += float(ms) / 1000
        else:
            spent[route_of(method, path)].append(cpu)
    means = {route: tuple(np.mean(values, axis=0)) for route, values in spent.items()}
    counts = {route: len(values) for route, values in spent.items()}
    total = sum(float(np.sum(values)) for values in spent.values()) + stream[0] + stream[1]
    if stream[2]:
        means[STREAM] = (stream[0] / stream[2], stream[1] / stream[2])
        counts[STREAM] = int(stream[2])
    split = tuple(float(part) for part in parts / parts.sum()) if parts.sum() else None
    return ClassCpu(means, counts, float(total), dict(spent), split, dict(functions))


def lock_trace_by_route(trace: str) -> dict[str, np.ndarray]:
    """Per write route, one row per write transaction of the probe's
    ``GYROLAB_BENCH_LOCK_TRACE`` lines (``wall_ms cpu_ms kind method path function
    [turn_ms]``): its wait for the writers' turn (NaN where the line has none), its hold
    of the lock and its CPU meanwhile, ms; the stream's writes named as in
    :func:`locked_shares`."""
    rows: dict[str, list[tuple[float, float, float]]] = defaultdict(list)
    for line in trace.splitlines():
        fields = line.split()
        if len(fields) < 6 or fields[2] == "-":
            continue  # start-up, the CLI, or a trace without the requests' names
        if fields[2] == "websocket":
            route = STREAM_START if fields[5] in MARKING else STREAM_SAVE
        else:
            route = route_of(fields[3], fields[4])
        turn = float(fields[6]) if len(fields) > 6 and fields[6] != "-" else float("nan")
        rows[route].append((turn, float(fields[0]), float(fields[1])))
    return {route: np.array(values) for route, values in rows.items()}


def locked_shares(trace: str, seen: ClassCpu) -> dict[str, float]:
    """Per write route, the share of its thread CPU spent holding SQLite's write lock: the
    CPU of its write transactions (the probe's ``GYROLAB_BENCH_LOCK_TRACE`` lines, ``wall_ms
    cpu_ms kind method path function``) over its requests' thread CPU (``seen``, the CPU
    probe of the same run); for the stream, its mark's (``_mark_started`` over the marking
    functions) and its save's.  A write parses, checks and packs before ``BEGIN
    IMMEDIATE`` (issue 32, item 2): the model holds the lock for this share alone."""
    locked = {
        route: float(np.sum(rows[:, 2])) / 1000
        for route, rows in lock_trace_by_route(trace).items()
    }
    threads = {route: float(np.sum(cpus, axis=0)[1]) for route, cpus in seen.each.items()}
    functions = seen.stream_functions
    threads[STREAM_START] = sum(functions.get(name, 0.0) for name in MARKING)
    threads[STREAM_SAVE] = sum(
        cpu for name, cpu in functions.items() if name not in MARKING | MAKING_READY
    )
    return {
        route: min(cpu / threads[route], 1.0)
        for route, cpu in locked.items()
        if threads.get(route, 0.0) > 0
    }


# what the probe sees of a request's CPU is part of what the server's process used (its
# threads' clocks against the process's): beyond this much more, the probe's file is not
# the run's alone (a second run appended to it: a class's requests counted twice)
SEEN_BEYOND_USED = 1.05


def in_class(
    costs, own, seen: ClassCpu, used: dict[str, float] | None = None, each=False,
    frame_weight: float = 1.0, client_floor_s: float = 0.0,
):  # fmt: skip
    """The costs per request as a class spent them.  Each route's own CPU (its task's,
    ``seen`` by the probe in a load test) replaces one student's alone (``own``).  What the
    probe does not see -- the server's socket work, the collector; per frame of a lone
    stream, most of its cost -- is shared out in a class; with ``used`` (the CPU the same
    run used: "server", "client"[, "db"] seconds) each route's unseen part is scaled so
    that the class's requests and frames add up to the server's CPU, the load generator's
    per request to its own, and the database server's (PostgreSQL's, measured alone) to
    what its processes used in the run.  Routes the class run did not see keep one
    student's costs.

    ``each``: a route's costs are a list, one per request the class made (its own task's
    CPU as the probe saw it, the unseen part as above), for the simulation to draw from:
    a route's CPU varies (a dashboard redoing many sessions, a results read that solves, a
    young collection run inside a request) and a p95 depends on it, not on the mean.

    ``frame_weight``: with ``used``, the load generator's CPU per stream frame counts this
    many times its share beside the requests' (1: each as one student's alone, scaled
    alike), the total still the run's; ``client_floor_s``: of the load generator's CPU in
    ``used``, what it spent whatever it sent (``fitted_client_cpu``'s floor times the
    class's time), left out of its requests' and frames' (the model runs it apart).

    Raises ValueError where the probe saw more of the server's CPU than ``used`` says the
    run used (``SEEN_BEYOND_USED``): the probe's file holds more than that run."""
    shared = routes = [r for r in costs if r in seen.means and r in own]
    unseen = {r: costs[r][0] - sum(own[r]) for r in routes}
    scale = client_scale = db_scale = 1.0
    if used and seen.total_s > SEEN_BEYOND_USED * used["server"]:
        raise ValueError(
            f"the probe saw {seen.total_s:.1f} s of the server's CPU in the class's requests,"
            f" more than the {used['server']:.1f} s the run used: its file holds more than"
            " that run (the probe appends to its files: give each run a new one)"
        )
    if used:
        alone_unseen = sum(seen.counts[r] * max(unseen[r], 0.0) for r in shared)
        if alone_unseen > 0:
            scale = max(used["server"] - seen.total_s, 0.0) / alone_unseen
        asked = sum(seen.counts[r] * costs[r][2] * (frame_weight if r == STREAM else 1.0)
                    for r in shared)  # fmt: skip
        sent = max(used["client"] - client_floor_s, 0.0)
        client_scale = sent / asked if asked > 0 else 1.0
        asked_of_db = sum(seen.counts[r] * costs[r][1] for r in shared)
        if used.get("db") and asked_of_db > 0:
            db_scale = used["db"] / asked_of_db
    adjusted = dict(costs)
    for route in routes:
        server, db, client, calls, trips, loop = costs[route]
        loop_unseen = max(loop - own[route][0], 0.0)
        unseen_now = (scale * loop_unseen, scale * max(unseen[route] - loop_unseen, 0.0))
        weight = frame_weight if route == STREAM and used else 1.0
        rest = (db * db_scale, client * client_scale * weight, calls, trips)
        requests = seen.each.get(route) if each else None
        mine = requests or [seen.means[route]]
        made = [_with_own_cpu(rest, unseen_now, *cpu) for cpu in mine]
        adjusted[route] = made if requests else made[0]
    if seen.stream_split:
        adjusted[STREAM_SPLIT] = seen.stream_split
    return adjusted, scale, client_scale


def _with_own_cpu(rest, unseen, loop_own: float, threads_own: float) -> tuple[float, ...]:
    """A request's costs (server, db, client, calls, trips, loop, its own task's loop
    part) from its own task's CPU on the loop and in threads, and the unseen parts."""
    db, client, calls, trips = rest
    loop_now = loop_own + unseen[0]
    server_now = max(loop_now + threads_own + unseen[1], 1e-6)
    return (server_now, db, client, calls, trips, loop_now, loop_own)


def server_times(path: Path) -> dict[str, np.ndarray]:
    """Per route, each request's (waited for a work place, server time) in ms, from the
    probe's ``GYROLAB_BENCH_SERVER_TIMES`` lines (``method path ms waited_ms [began_s pid]``)."""
    rows: dict[str, list[tuple[float, float]]] = defaultdict(list)
    for line in path.read_text().splitlines():
        method, route, took, waited, *_when_and_where = line.split()
        if method != WEBSOCKET:
            rows[route_of(method, route)].append((float(waited), float(took)))
    return {route: np.array(values) for route, values in rows.items()}


def worker_shares(path: Path) -> list[float] | None:
    """Each worker's share of the HTTP requests in the probe's ``GYROLAB_BENCH_SERVER_TIMES``
    lines (largest first), or None where the lines do not say which worker answered.  The
    kernel hands each new connection to whichever worker accepts it first, and a browser
    keeps its connection: not an even split (33 % / 67 % of a 60-student run's requests)."""
    served: Counter[str] = Counter()
    for line in path.read_text().splitlines():
        fields = line.split()
        if len(fields) < 6:
            return None
        if fields[0] != WEBSOCKET:
            served[fields[5]] += 1
    total = sum(served.values())
    return sorted((count / total for count in served.values()), reverse=True) if total else None


@dataclass(frozen=True)
class ClientFit:
    """The load generator's CPU as a run spent it, fitted by the bin
    (``fitted_client_cpu``): ``requests`` and ``frames``, its CPU per request and per
    frame against one student's alone; ``floor``, the share of a core it spent whatever it
    sent (its event loop's timers, its collector)."""

    requests: float
    frames: float
    floor: float
    span_s: float  # the class's time the bins covered, s

    @property
    def floor_s(self) -> float:
        """What it spent whatever it sent over the class, CPU s."""
        return self.floor * self.span_s

    @property
    def frame_weight(self) -> float:
        """Its CPU per frame against its requests' (``in_class``'s ``frame_weight``)."""
        return self.frames / self.requests


def fitted_client_cpu(
    client_ran: list[float], bin_s: float, requests: list[tuple[str, float, float]],
    spans: list[tuple[float, float]], frames: int, costs: dict,
) -> ClientFit | None:  # fmt: skip
    """The load generator's CPU per request, per frame and whatever it sends, as a run
    spent them, from when it spent it.

    ``client_ran``: its CPU in each ``bin_s`` from the class's first request
    (``load_test.py --run-queue``); ``requests``: the run's (route, sent, answered);
    ``spans``: each position's (first sample, last sample); ``frames``: the run's stream
    frames; ``costs``: one student's alone, per route (its third field the load
    generator's CPU).  In each bin,

        ran_b = k_r · R_b + k_f · F_b + k_0,

    where R_b is the alone CPU of the requests sent or answered in it (half each) and F_b
    that of the frames streamed in it (a position's spread evenly from its first sample to
    its last), solved for k ≥ 0 by non-negative least squares.  Returns k_r, k_f,
    k_0 / ``bin_s`` (the floor, a share of a core) and the bins' time, or None where the
    bins do not tell it (no requests' CPU fitted)."""
    from scipy.optimize import nnls

    if not requests or not spans or not client_ran or STREAM not in costs:
        return None
    start = min(sent for _, sent, _ in requests)
    end = max(answered for _, _, answered in requests)
    bins = min(len(client_ran), int((end - start) // bin_s) + 1)
    asked = np.zeros((bins, 3))
    asked[:, 2] = 1.0

    def add(when: float, column: int, amount: float) -> None:
        index = int((when - start) // bin_s)
        if 0 <= index < bins:
            asked[index, column] += amount

    for route, sent, answered in requests:
        if route in costs:
            add(sent, 0, costs[route][2] / 2)
            add(answered, 0, costs[route][2] / 2)
    per_position = frames / len(spans)
    count = max(int(round(per_position)), 1)
    frame_cost = costs[STREAM][2] * per_position / count
    for first, last in spans:
        for when in np.linspace(first, last, count):
            add(float(when), 1, frame_cost)
    (requests_k, frames_k, floor_k), _ = nnls(asked, np.asarray(client_ran[:bins], dtype=float))
    if requests_k <= 0:
        return None
    return ClientFit(float(requests_k), float(frames_k), float(floor_k) / bin_s, bins * bin_s)
