"""Where a request's time inside the server goes, measured beside the queueing model's.

The probe's ``GYROLAB_BENCH_REQUEST_WAITS`` (``bench/probe/sitecustomize.py``) splits each
HTTP request of a load test into its wait for a work place and, holding the place, its
CPU, its threads' waits off a core (for the interpreter, for the write lock or
PostgreSQL's answers, for the thread pool to take the function and the event loop to take
the answer back) and its threads' waits on the run queue (the kernel's ``schedstat``).
``queue_sim.simulate`` reports the same split for each simulated request ("server"), and
:func:`compare` prints the two side by side per route, :func:`compare_windows` by the
class's time (start, each part's streams, burst); :func:`place_queue` says how crowded the
work places were.  :func:`outside_the_app` sets the load generator's times of each request
(``GYROLAB_BENCH_CLIENT_TIMES``) beside the server's: the time before the app is called and
after it has answered, which :func:`compare_outside` prints beside the model's."""

from __future__ import annotations

from collections import defaultdict
from collections.abc import Iterable
from pathlib import Path

import numpy as np
from class_cpu import WEBSOCKET, route_of
from connections import matched_requests

# the columns of ``read``'s arrays, ms (began: s, the probe's clock)
PLACE, INSIDE, CPU, OFF_CORE, RUN_QUEUE, BEGAN = range(6)


def read(path: Path) -> dict[str, np.ndarray]:
    """Per route, one row per request: waited for a work place, inside (from the place to
    the app's end), CPU (event loop and threads), waits off a core, waits on the run
    queue (ms), and when it came (s)."""
    rows: dict[str, list[list[float]]] = defaultdict(list)
    for line in path.read_text().splitlines():
        fields = line.split()
        if len(fields) < 12:
            continue  # a line cut short by a stopped server
        method, route = fields[:2]
        total, place, loop_cpu, loop_wall, dispatch, cpu, wall, queued, back = map(
            float, fields[2:11]
        )
        began = float(fields[12]) if len(fields) > 12 else 0.0
        off_core = dispatch + back + (loop_wall - loop_cpu) + max(wall - cpu - queued, 0.0)
        rows[route_of(method, route)].append(
            [place, total - place, loop_cpu + cpu, off_core, queued, began]
        )
    return {route: np.array(values) for route, values in rows.items()}


def modelled(result: dict) -> dict[str, np.ndarray]:
    """``queue_sim.simulate``'s (or ``combine``'s) "server" tuples in ``read``'s columns
    (ms).  As the probe counts them: CPU the server's own inside the place (the request's
    drawn CPU); on the run queue its threads' waits for a core (and for a hand-off of the
    interpreter); off a core everything else inside -- the interpreter's queue, the write
    lock or the database, and the event loop's part of the hops (its queue of callbacks).
    Tuples without the drawn CPU (before 2026-12-05): CPU is what is left of the time
    inside, the model's waits for the event loop with it."""
    table = {}
    for route, rows in result["server"].items():
        values = np.array(rows, dtype=float)
        if values.shape[1] < 7:
            continue
        place, asked_to_answer = values[:, 0], values[:, 1]
        inside = asked_to_answer - place
        run_queue = values[:, 3] + values[:, 4]  # being handed the interpreter, a core
        if values.shape[1] >= 8:
            cpu = np.clip(values[:, 7], 0.0, np.maximum(inside - run_queue, 0.0))
            off_core = np.maximum(inside - cpu - run_queue, 0.0)
        else:
            off_core = values[:, 2] + values[:, 5]  # the interpreter's queue, lock or database
            cpu = np.maximum(inside - off_core - run_queue, 0.0)
        table[route] = np.column_stack(
            [place * 1000, inside * 1000, cpu * 1000, off_core * 1000, run_queue * 1000,
             values[:, 6]]
        )  # fmt: skip
    return table


def place_queue(requests: Iterable[tuple[float, float, float]]) -> tuple[float, float]:
    """Of the time at least one request asked for or held a work place, the share in which
    some waited for one, and how many waited then on average; ``requests``: (asked,
    waited, inside) each, in the same unit (one worker's)."""
    events: list[tuple[float, int, int]] = []
    for asked, waited, inside in requests:
        events += [(asked, 1, 0), (asked + waited, -1, 1), (asked + waited + inside, 0, -1)]
    events.sort()
    waiting = holding = 0
    busy = crowded = waited_area = 0.0
    last = events[0][0] if events else 0.0
    for when, wait_change, hold_change in events:
        span = when - last
        if waiting or holding:
            busy += span
        if waiting:
            crowded += span
            waited_area += waiting * span
        waiting += wait_change
        holding += hold_change
        last = when
    if not busy:
        return 0.0, 0.0
    return crowded / busy, (waited_area / crowded if crowded else 0.0)


def compare(model: dict[str, np.ndarray], measured: dict[str, np.ndarray]) -> None:
    """Per route the time inside the server holding a place (mean, p95) and of it the
    waits off a core and on the run queue (p95), model beside measurement."""
    print("  inside the server holding a work place, ms: mean / p95 (model | measured);"
          " p95 of the waits off a core (interpreter, write lock or database, thread hops)"
          " and on the run queue")  # fmt: skip
    print(f"  {'route':42s} {'inside':>17s} {'off a core':>13s} {'run queue':>13s}")
    for route in sorted(set(model) & set(measured)):
        m, s = model[route], measured[route]
        inside = " | ".join(
            f"{t[:, INSIDE].mean():3.0f}/{np.percentile(t[:, INSIDE], 95):3.0f}" for t in (m, s)
        )
        cells = [
            f"{np.percentile(m[:, k], 95):5.1f} | {np.percentile(s[:, k], 95):5.1f}"
            for k in (OFF_CORE, RUN_QUEUE)
        ]
        print(f"  {route:42s} {inside:>17s} {cells[0]:>13s} {cells[1]:>13s}")


# The load test's class by its time from the first request (s), its default scenario at 60
# students (60 s a position at 20×): the log-ins and first pages; the first part's streams
# and turns; the second part's (the model's turns there wait 2-3× too little off a core
# while the first part's match, bench/README.md, thirty-first part); the CSV saves, results
# and submits
WINDOWS = (
    ("start", 0.0, 5.0),
    ("part A", 5.0, 13.0),
    ("part B", 13.0, 24.0),
    ("burst", 24.0, float("inf")),
)


def by_window(table: dict[str, np.ndarray]) -> dict[str, tuple[int, np.ndarray]]:
    """Per window of the class's time (``WINDOWS``, from the table's first request), how
    many requests came and their mean wait for a work place, time inside holding one, CPU,
    waits off a core and on the run queue (ms), all routes together."""
    rows = np.concatenate([rows for rows in table.values() if len(rows)])
    when = rows[:, BEGAN] - rows[:, BEGAN].min()
    out = {}
    columns = [PLACE, INSIDE, CPU, OFF_CORE, RUN_QUEUE]
    for name, start, end in WINDOWS:
        inside = rows[(when >= start) & (when < end)][:, columns]
        out[name] = (len(inside), inside.mean(axis=0) if len(inside) else np.full(5, np.nan))
    return out


THREAD_GROUPS = ("server", "hash", "client", "db")


def threads_by_window(
    bins: dict[tuple[int, str], tuple[float, ...]], bin_s: float
) -> dict[tuple[str, str], tuple[float, ...]]:
    """Per (window of ``WINDOWS``, group), the sums of ``bins``' columns: per (bin of
    ``bin_s`` from the class's start, group), the time the group's threads ran and waited
    for a core, s (``queue_sim.simulate``'s "threads by time"), and from a trace the part
    of the wait before work (``sched_trace.threads_by_time``)."""
    width = max((len(cell) for cell in bins.values()), default=2)
    out: dict[tuple[str, str], tuple[float, ...]] = {}
    for name, start, end in WINDOWS:
        for group in THREAD_GROUPS:
            cells = [cell for (index, of), cell in bins.items()
                     if of == group and start <= index * bin_s < end]  # fmt: skip
            out[name, group] = tuple(sum(cell[i] for cell in cells) for i in range(width))
    return out


def threads_report(
    bins: dict[tuple[int, str], tuple[float, ...]], bin_s: float, whose: str
) -> list[str]:
    """``threads_by_window`` in lines: per window, each group's time run / waited for a
    core (s; a trace's, then the part of it before work) and the waiting threads on
    average (waited over the window's length)."""
    windows = threads_by_window(bins, bin_s)
    last = max((index for index, _ in bins), default=-1) + 1
    three = any(len(cell) > 2 for cell in bins.values())
    what = "s run / s waited for a core" + (" / of it before work" if three else "")
    lines = [f"  {whose} by the class's time, {what} (threads waiting on average):"
             f" {' · '.join(THREAD_GROUPS)}"]  # fmt: skip
    for name, start, end in WINDOWS:
        length = min(end, last * bin_s) - start
        if length <= 0:
            continue
        span = f"{start:g}-{end:g} s" if end < float("inf") else f"from {start:g} s"
        cells = " · ".join(
            " / ".join(f"{value:5.2f}" for value in windows[name, group])
            + f" ({windows[name, group][1] / length:4.2f})"
            for group in THREAD_GROUPS
        )
        lines.append(f"  {name:6s} {span:10s} {cells}")
    return lines


def ran_report(
    bins: dict[tuple[int, str], tuple[float, ...]], bin_s: float,
    measured: dict[str, list[float]], measured_bin_s: float,
) -> list[str]:  # fmt: skip
    """Per window of ``WINDOWS``, each group's CPU, s: the model's (its "threads by time",
    the hashes folded into the server) beside what the run's threads ran in the same window
    (``measured``: per group "server", "db", "client", its time on a core in each
    ``measured_bin_s`` from the class's first request, as ``load_test.py --run-queue``
    prints it), and the two added up -- where the model spends the class's CPU at other
    times than the run did."""
    windows = threads_by_window(bins, bin_s)
    groups = ("server", "db", "client")
    last = min(
        (max((index for index, _ in bins), default=-1) + 1) * bin_s,
        max((len(series) for series in measured.values()), default=0) * measured_bin_s,
    )
    lines = ["  CPU run by the class's time, s, model | run (schedstat): "
             + " · ".join(groups) + " · in all"]  # fmt: skip
    for name, start, end in WINDOWS:
        end = min(end, last)
        if end <= start:
            continue
        model = {group: windows[name, group][0] for group in groups}
        model["server"] += windows[name, "hash"][0]
        run = {
            group: sum(measured.get(group, [])[int(round(start / measured_bin_s)):
                                               int(round(end / measured_bin_s))])
            for group in groups
        }  # fmt: skip
        cells = " · ".join(f"{model[group]:5.2f} | {run[group]:5.2f}" for group in groups)
        total = f"{sum(model.values()):5.2f} | {sum(run.values()):5.2f}"
        lines.append(f"  {name:6s} {start:g}-{end:g} s  {cells} · {total}")
    return lines


def compare_windows(model: dict[str, np.ndarray], measured: dict[str, np.ndarray]) -> None:
    """``by_window`` of the model beside the measurement: where the class's time inside the
    server goes at its start, between and in its burst (``modelled``'s columns: the
    model's "CPU" is the CPU its requests drew)."""
    print("  the server by the class's time, mean ms a request: waited for a place / inside"
          " / CPU / off a core / run queue (model | measured)")  # fmt: skip
    modelled_windows, measured_windows = by_window(model), by_window(measured)
    for name, start, end in WINDOWS:
        span = f"{start:g}-{end:g} s" if end < float("inf") else f"from {start:g} s"
        cells = " | ".join(
            " / ".join(f"{value:4.1f}" for value in windows[name][1])
            for windows in (modelled_windows, measured_windows)
        )
        print(f"  {name:6s} {span:10s} {cells}")


def crowding(measured: dict[str, np.ndarray]) -> tuple[float, float]:
    """``place_queue`` of the requests ``read`` (all workers as one)."""
    rows = np.concatenate(list(measured.values()))
    return place_queue(
        zip(rows[:, BEGAN], rows[:, PLACE] / 1000, rows[:, INSIDE] / 1000, strict=True)
    )


def simulated_crowding(result: dict) -> tuple[float, float]:
    """``place_queue`` of one ``queue_sim.simulate``'s requests (all workers as one)."""
    rows = [row for rows in result["server"].values() for row in rows if len(row) > 6]
    return place_queue((row[6], row[0], row[1] - row[0]) for row in rows)


def compare_crowding(model: tuple[float, float], measured: dict[str, np.ndarray]) -> None:
    """How crowded the work places were, ``model`` (``simulated_crowding``, e.g. the median
    over seeds) beside the requests ``read`` (one worker's)."""
    share, queue = crowding(measured)
    print(f"  the work places: someone waited for one {model[0]:.0%} of the time they were"
          f" asked for or held (model), {share:.0%} (measured); then {model[1]:.1f} /"
          f" {queue:.1f} waited on average")  # fmt: skip


def outside_the_app(client_times: Path, server_times: Path) -> dict[str, tuple[int, float, float]]:
    """Per route: how many requests were matched, and their mean time before the app was
    called (sent, carried, read and parsed by the server) and after it answered (written,
    carried, read by the load generator), ms.  ``client_times``: the load generator's
    ``GYROLAB_BENCH_CLIENT_TIMES`` lines (``method path sent_s answered_s``);
    ``server_times``: the probe's ``GYROLAB_BENCH_SERVER_TIMES`` lines (``method path ms
    waited_ms began_s pid``), on the same clock (``time.perf_counter``), matched as
    :func:`connections.matched_requests` does."""
    fields = (line.split() for line in server_times.read_text().splitlines())
    requests = [row for row in fields if len(row) >= 5 and row[0] != WEBSOCKET]  # no WebSocket
    parts: dict[str, list[tuple[float, float]]] = defaultdict(list)
    for (method, url, sent, answered, _), row in matched_requests(client_times, requests):
        start, took = float(row[4]), float(row[2]) / 1000
        parts[route_of(method, url)].append((start - sent, answered - start - took))
    return {
        route: (len(values), *(float(mean) * 1000 for mean in np.mean(values, axis=0)))
        for route, values in parts.items()
    }


def modelled_outside(result: dict) -> dict[str, float]:
    """Per route, the model's mean time outside the app (ms): a request's latency less its
    time from asking for a place to the answer (``queue_sim.simulate``'s "server"; of
    ``combine``'s, its seeds' "mean" latency)."""
    means = result.get("mean") or {
        route: float(np.mean(values)) for route, values in result["latencies"].items()
    }
    return {
        route: (means[route] - float(np.mean(np.array(rows)[:, 1]))) * 1000
        for route, rows in result["server"].items()
        if route in means and len(rows)
    }


def compare_outside(result: dict, measured: dict[str, tuple[int, float, float]]) -> None:
    """``modelled_outside`` beside ``outside_the_app``'s."""
    print("  outside the app, mean ms a request: model | measured (before the app + after it)")
    model = modelled_outside(result)
    for route in sorted(set(model) & set(measured)):
        count, before, after = measured[route]
        print(f"  {route:42s} {model[route]:5.1f} | {before + after:5.1f}"
              f" ({before:4.1f} + {after:4.1f}, {count} requests)")  # fmt: skip
