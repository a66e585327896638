"""Where a class's threads waited for a core, from the kernel's scheduler trace: each wait
from the moment a thread was woken (or preempted) to the moment it was put on a core,
by what the cores were doing when it began -- its core idle, its core busy and the other
idle, both busy -- or because it was preempted; and how many cores were busy while some
thread waited (a core left idle meanwhile is one the queueing model's cores would have
used); each group's time run and waited by the class's time; and what the cores ran while
a group waited (both busy, or one idle beside the wait).  run_queue.py measures the sums
(schedstat); this says which kind of wait they are made of, for the queueing model.

Record while a load test runs, as root, then write the events out as text::

    perf sched record -a -o perf.data -- sleep 75 &
    .venv/bin/python bench/load_test.py --backend postgresql --students 60
    perf script -i perf.data -F comm,pid,tid,cpu,time,event,trace > sched.txt
    .venv/bin/python bench/sched_trace.py sched.txt --server PID PID --client PID

(the server's worker processes and the load generator's, by process id; PostgreSQL's
processes by their name)."""

from __future__ import annotations

import argparse
import re
from collections import defaultdict
from collections.abc import Callable, Iterable, Iterator
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

LINE = re.compile(r"^\s*(\S.*?)\s+(\d+)/(\d+)\s+\[(\d+)\]\s+([\d.]+):\s+sched:(\w+):\s+(.*)$")
FIELD = re.compile(r"(\w+)=(\S+)")
IDLE = 0  # the idle task's pid
KINDS = ("woken, its core idle", "woken, its core busy, another idle", "woken, every core busy",
         "preempted")  # fmt: skip
WAKES = ("sched_waking", "sched_wakeup_new")


@dataclass(frozen=True)
class Event:
    """One scheduler event: when (s), on which core, its name, the task that ran it (thread
    id, process id, name) and its fields (``next_pid=…``)."""

    time: float
    cpu: int
    name: str
    tid: int
    pid: int
    comm: str
    fields: dict[str, str]


def events_of(lines: Iterable[str]) -> Iterator[Event]:
    """The ``sched:`` events of ``perf script -F comm,pid,tid,cpu,time,event,trace``."""
    for line in lines:
        match = LINE.match(line)
        if match:
            comm, pid, tid, cpu, time, name, rest = match.groups()
            fields = dict(FIELD.findall(rest))
            yield Event(float(time), int(cpu), name, int(tid), int(pid), comm, fields)


def waits_by_kind(
    events: Iterable[Event], group_of: Callable[[int, str], str | None]
) -> dict[tuple[str, str], list[float]]:
    """Each wait for a core (s) of every thread ``group_of(process id, process name)``
    names, by (group, kind): from its wake-up or its preemption to its next time on a core.
    A thread's process is known from the events it ran; one woken before it ran any is
    placed by the name the wake-up gives."""
    process: dict[int, tuple[int, str]] = {}  # thread id → (process id, name)
    running: dict[int, int] = {}  # core → thread id on it (IDLE: none)
    waiting: dict[int, tuple[float, str]] = {}  # thread id → (since, kind)
    waits: dict[tuple[str, str], list[float]] = defaultdict(list)

    def group(tid: int, comm: str = "") -> str | None:
        pid, name = process.get(tid, (tid, comm))
        return group_of(pid, name)

    for event in events:
        process[event.tid] = (event.pid, event.comm)
        if event.name == "sched_switch":
            before, after = int(event.fields["prev_pid"]), int(event.fields["next_pid"])
            if before != IDLE and event.fields["prev_state"].startswith("R") and group(before):
                waiting[before] = (event.time, KINDS[3])
            if after in waiting:
                since, kind = waiting.pop(after)
                name = group(after, event.fields.get("next_comm", ""))
                if name:
                    waits[name, kind].append(event.time - since)
            running[event.cpu] = after
        elif event.name in WAKES:
            woken = int(event.fields["pid"])
            if woken in waiting or not group(woken, event.fields.get("comm", "")):
                continue
            target = int(event.fields["target_cpu"])
            if running.get(target, IDLE) == IDLE:
                kind = KINDS[0]
            elif any(tid == IDLE for core, tid in running.items() if core != target):
                kind = KINDS[1]
            else:
                kind = KINDS[2]
            waiting[woken] = (event.time, kind)
    return dict(waits)


@dataclass
class Cores:
    """What the cores run and which threads wait in whose queue, event by event: a thread
    woken waits on its wake-up's ``target_cpu``, one preempted on its core, and a
    ``sched_migrate_task`` moves it; a thread seen running an event of its own waits no
    longer, even if its switch to a core was not in the trace."""

    running: dict[int, int] = field(default_factory=dict)  # core → thread id (IDLE: none)
    waiting: dict[int, int] = field(default_factory=dict)  # thread id → the core it waits on

    def apply(self, event: Event) -> tuple[str, str]:
        """Take ``event`` in; returns what it may have begun (a thread preempted or woken
        onto a busy core, a core gone idle) and what it may have ended (a waiting thread
        run on its own core or moved, the idle core given other work), "" for none."""
        cause, ended = "", ""
        if event.tid != IDLE:
            self.waiting.pop(event.tid, None)  # on a core: it runs this event
        if event.name == "sched_switch":
            before, after = int(event.fields["prev_pid"]), int(event.fields["next_pid"])
            if before != IDLE and event.fields["prev_state"].startswith("R"):
                self.waiting[before] = event.cpu
                cause = "preempted"
            was_idle = self.running.get(event.cpu, IDLE) == IDLE
            queued_on = self.waiting.pop(after, None)
            if not was_idle:
                ended = "ran on its own core"
            elif queued_on is not None and queued_on != event.cpu:
                ended = "migrated"
            else:  # a thread woken onto the idle core, or one the trace did not see queued
                ended = "the idle core took other work"
            self.running[event.cpu] = after
            if after == IDLE:
                cause = "a core went idle"
        elif event.name in WAKES:
            woken = int(event.fields["pid"])
            if woken not in self.running.values():
                self.waiting[woken] = int(event.fields["target_cpu"])
                cause = "woken onto a busy core"
        elif event.name == "sched_migrate_task":
            moved = int(event.fields["pid"])
            if moved in self.waiting:
                self.waiting[moved] = int(event.fields["dest_cpu"])
                ended = "migrated"
        return cause, ended

    def busy(self) -> int:
        return sum(1 for tid in self.running.values() if tid != IDLE)

    def stranded(self) -> bool:
        """Whether some core is idle while a thread waits in another core's queue."""
        idle = {core for core, tid in self.running.items() if tid == IDLE}
        return bool(idle) and any(core not in idle for core in self.waiting.values())


def busy_while_waiting(events: Iterable[Event]) -> dict[int, float]:
    """The time (s) some thread -- any -- waited for a core, by how many cores were busy
    meanwhile: a scheduler that never leaves a core idle while a thread waits has it all
    under the full count (a thread woken onto an idle core waits there until the core is
    up, under one fewer).  The kernel's trace of a class on two cores: 1.46 cores busy on
    average while a thread waited (bench/README.md, fortieth part)."""
    cores = Cores()
    spent: dict[int, float] = defaultdict(float)
    last = None
    for event in events:
        if last is not None and cores.waiting:
            spent[cores.busy()] += event.time - last
        last = event.time
        cores.apply(event)
    return dict(spent)


def busy_report(spent: dict[int, float] | dict[float, float]) -> str:
    """``busy_while_waiting``'s (or the model's "busy while waiting") in a line."""
    total = sum(spent.values())
    if not total:
        return "no thread waited for a core"
    mean = sum(busy * time for busy, time in spent.items()) / total
    cells = ", ".join(f"{busy:g}: {time:.2f} s" for busy, time in sorted(spent.items()))
    return (
        f"some thread waited for a core during {total:.2f} s; the cores busy then {cells}"
        f" (on average {mean:.2f})"
    )


@dataclass(frozen=True)
class Episode:
    """A time some core was idle while a thread waited in another core's queue: when it
    began (s), how long it lasted (s), what began it and what ended it."""

    began: float
    length: float
    began_by: str  # "a core went idle", "woken onto a busy core", "preempted"
    ended_by: str  # "migrated", "ran on its own core", "the idle core took other work"


def idle_episodes(events: Iterable[Event]) -> list[Episode]:
    """Each time some core idled while a thread waited on another's queue (``Cores``): the
    kernel leaves a thread where it was queued unless a balancing moves it (a core newly
    idle pulls only a thread that has not run in the last ``migration_cost_ns``, 0.5 ms,
    and otherwise waits for a tick), so such times end either by a migration or by the
    thread's own core coming free."""
    cores = Cores()
    episodes: list[Episode] = []
    since: tuple[float, str] | None = None
    for event in events:
        cause, ended = cores.apply(event)
        now = cores.stranded()
        if now and since is None:
            since = (event.time, cause or "a core went idle")
        elif not now and since is not None:
            began, began_by = since
            episodes.append(Episode(began, event.time - began, began_by, ended or "migrated"))
            since = None
    return episodes


EPISODE_BINS_MS = (0.0, 0.05, 0.2, 0.5, 1.0, 2.0, 4.0, 8.0)


def episodes_report(episodes: list[Episode]) -> list[str]:
    """How many such times and how long in all, by length (ms), and by what began and
    ended them."""
    if not episodes:
        return ["no core idled while a thread waited on another's queue"]
    lengths = np.array([episode.length for episode in episodes]) * 1000
    lines = [f"a core idle while a thread waited on another's queue: {len(episodes)} times,"
             f" {lengths.sum() / 1000:.2f} s in all"]  # fmt: skip
    edges = [*EPISODE_BINS_MS, np.inf]
    for low, high in zip(edges, edges[1:], strict=False):
        inside = (lengths >= low) & (lengths < high)
        if inside.any():
            span = f"{low:g}-{high:g} ms" if np.isfinite(high) else f"{low:g} ms and more"
            lines.append(
                f"  {span:>14s}: {int(inside.sum()):6d} times, {lengths[inside].sum():8.1f} ms"
            )
    for label, key in (("began by", "began_by"), ("ended by", "ended_by")):
        spent: dict[str, list[float]] = defaultdict(list)
        for episode in episodes:
            spent[getattr(episode, key)].append(episode.length)
        cells = "; ".join(f"{name}: {len(values)} times, {sum(values) * 1000:.0f} ms"
                          for name, values in sorted(spent.items()))  # fmt: skip
        lines.append(f"  {label} -- {cells}")
    return lines


HASH_CPU_S = (0.015, 0.045)  # a worker's thread on a core this long between sleeps: a hash
CLASS_LEAD_S = 0.1  # the class's start, before its first hash (the model's first: ≈ 0.1 s)


WORK_AFTER_S = 100e-6  # a thread that runs this long after a wait did work with its core


def class_groups(
    events: list[Event], group_of: Callable[[int, str], str | None], start: float | None = None
) -> tuple[Callable[[int, float], str | None], float]:
    """Each thread's group at a time -- ``group_of(process id, name)``'s, or "hash" while a
    worker's thread other than its main one hashes a log-in's password (between a wake-up
    and its next sleep it ran ``HASH_CPU_S`` of CPU) -- and the class's start: ``start``,
    or ``CLASS_LEAD_S`` before the first hash (``threads_by_time``)."""
    process: dict[int, tuple[int, str]] = {}

    def group(tid: int) -> str | None:
        pid, name = process.get(tid, (tid, ""))
        return group_of(pid, name) if tid != IDLE else None

    # each server thread's times between a wake-up and its next sleep, and the CPU it ran
    # in each; the long ones are hashes
    hashes: dict[int, list[tuple[float, float]]] = defaultdict(list)
    awake: dict[int, list[float]] = {}  # thread id → [woken at, CPU so far, on a core since]
    low, high = HASH_CPU_S
    for event in events:
        process[event.tid] = (event.pid, event.comm)
        if event.name in WAKES:
            awake.setdefault(int(event.fields["pid"]), [event.time, 0.0, -1.0])
        elif event.name == "sched_switch":
            before, after = int(event.fields["prev_pid"]), int(event.fields["next_pid"])
            run = awake.get(before)
            if run is not None and run[2] >= 0:
                run[1] += event.time - run[2]
                run[2] = -1.0
                if not event.fields["prev_state"].startswith("R"):
                    del awake[before]
                    main = process.get(before, (before, ""))[0] == before
                    if low <= run[1] <= high and not main and group(before) == "server":
                        hashes[before].append((run[0], event.time))
            if after in awake:
                awake[after][2] = event.time
    firsts = [spans[0][0] for spans in hashes.values()]
    if start is None:
        start = (min(firsts) - CLASS_LEAD_S) if firsts else (events[0].time if events else 0.0)

    def group_at(tid: int, time: float) -> str | None:
        name = group(tid)
        if name == "server" and any(a <= time <= b for a, b in hashes.get(tid, ())):
            return "hash"
        return name

    return group_at, start


def threads_by_time(
    events: list[Event],
    group_of: Callable[[int, str], str | None],
    bin_s: float,
    start: float | None = None,
    length: float = float("inf"),
) -> tuple[dict[tuple[int, str], tuple[float, ...]], float]:
    """Per (bin of ``bin_s`` from the class's start, group), the time the group's threads
    ran, waited for a core (from a wake-up or a preemption to the next time on a core),
    and of that wait, the part after which the thread ran ``WORK_AFTER_S`` or more before
    leaving the core again, s -- as ``queue_sim.simulate``'s "threads by time", whose
    threads wait only to work (a thread of the machine's is often woken to find the
    interpreter taken, and sleeps again within microseconds).

    ``group_of(process id, name)`` names "server", "client" or "db".  A server thread
    other than a worker's main one (its event loop) that ran between ``HASH_CPU_S`` of CPU
    from a wake-up to its next sleep was hashing a log-in's password (argon2id keeps its
    thread on a core 15-25 ms without the interpreter; a thread holding the interpreter
    lets it go at each database call, and every millisecond when another waits), and
    counts as "hash" from that wake-up to that sleep: in a 60-student class, 61 such
    times for 61 log-ins.  ``start``: the class's, on the trace's clock; by default
    ``CLASS_LEAD_S`` before the first hash (a class begins with its log-ins); ``length``:
    the class's (the load test's wall time), the trace after it left out.  Returns the
    bins and the start taken."""
    group_at, start = class_groups(events, group_of, start)

    bins: dict[tuple[int, str], list[float]] = defaultdict(lambda: [0.0, 0.0, 0.0])

    def spread(name: str | None, since: float, until: float, column: int) -> None:
        if name is None:
            return
        since, until = max(since, start), min(until, start + length)
        while since < until:
            index = int((since - start) // bin_s)
            end = start + (index + 1) * bin_s
            if end <= since:  # on a bin's edge, as floats round it
                index += 1
                end = start + (index + 1) * bin_s
            end = min(until, end)
            bins[index, name][column] += end - since
            since = end

    running: dict[int, tuple[int, float]] = {}  # core → (thread id, on it since)
    ready: dict[int, float] = {}  # thread id → waiting for a core since
    waited: dict[int, tuple[str | None, float, float]] = {}  # on a core now: its last wait
    for event in events:
        if event.name in WAKES:
            ready.setdefault(int(event.fields["pid"]), event.time)
        elif event.name == "sched_switch":
            before, after = int(event.fields["prev_pid"]), int(event.fields["next_pid"])
            if event.cpu in running:
                tid, since = running[event.cpu]
                spread(group_at(tid, event.time), since, event.time, 0)
                wait = waited.pop(tid, None)
                if wait is not None and event.time - since >= WORK_AFTER_S:
                    spread(*wait, 2)
            running[event.cpu] = (after, event.time)
            if before != IDLE and event.fields["prev_state"].startswith("R"):
                ready[before] = event.time
            if after in ready:
                wait = (group_at(after, event.time), ready.pop(after), event.time)
                spread(*wait, 1)
                waited[after] = wait
    return {key: tuple(cell) for key, cell in bins.items()}, start


@dataclass
class Beside:
    """A group's time waiting for a core (thread-seconds) and, over the same time, what the
    core it waited on ran ("own") and what the other cores ran ("other"), by group ("idle":
    nothing; "other": a thread of no group's), s."""

    waited: float = 0.0
    own: dict[str, float] = field(default_factory=lambda: defaultdict(float))
    other: dict[str, float] = field(default_factory=lambda: defaultdict(float))


def waits_beside(
    events: list[Event],
    group_of: Callable[[int, str], str | None],
    windows: Iterable[tuple[str, float, float]],
    start: float | None = None,
) -> dict[tuple[str, str], Beside]:
    """Per (window of the class, group), its threads' waits for a core and what ran
    beside them (``Beside``): whether a thread waited because both cores had work, or
    while a core idled.  ``windows``: (name, from, to), s from the class's start (by
    default ``CLASS_LEAD_S`` before its first hash, as ``threads_by_time``); a thread
    waits as ``Cores`` follows it, on the core it was woken onto or preempted on, and
    its group is the one it had when it began to wait."""
    group_at, start = class_groups(events, group_of, start)
    spans = [(name, start + low, start + high) for name, low, high in windows]
    cores = Cores()
    cells: dict[tuple[str, str], Beside] = {}
    waiting: dict[int, tuple[str, int]] = {}  # thread id → (its group, the core it waits on)
    on_core: dict[int, str] = {}  # core → its thread's group ("idle", "other")
    last = None
    for event in events:
        if last is not None and event.time > last and waiting:
            span = next((name for name, low, high in spans if low <= last < high), None)
            if span is not None:
                step = event.time - last
                for name, core in waiting.values():
                    cell = cells.get((span, name))
                    if cell is None:
                        cell = cells[span, name] = Beside()
                    cell.waited += step
                    for other, group in on_core.items():
                        (cell.own if other == core else cell.other)[group] += step
                    if core not in on_core:  # a core the trace has not seen switch yet
                        cell.own["idle"] += step
        last = event.time
        cores.apply(event)
        if event.name == "sched_switch":
            after = int(event.fields["next_pid"])
            on_core[event.cpu] = "idle" if after == IDLE else (
                group_at(after, event.time) or "other")  # fmt: skip
        for tid in [tid for tid in waiting if tid not in cores.waiting]:
            del waiting[tid]
        for tid, core in cores.waiting.items():
            known = waiting.get(tid)
            if known is None:
                name = group_at(tid, event.time)
                if name is not None:
                    waiting[tid] = (name, core)
            elif known[1] != core:
                waiting[tid] = (known[0], core)
    return cells


def beside_report(cells: dict[tuple[str, str], Beside], windows) -> list[str]:
    """``waits_beside`` in lines: per window and group, the time waited and the shares of
    it that its own core and the other cores ran each group, or idled."""
    lines = ["what ran beside a group's waits for a core: s waited; its own core's share by"
             " group | the other cores' (idle: nothing ran)"]  # fmt: skip
    for window, _, _ in windows:
        for (span, name), cell in sorted(cells.items()):
            if span != window or cell.waited <= 0:
                continue

            def shares(spent: dict[str, float], of: float) -> str:
                return " ".join(f"{group} {value / of:.0%}" for group, value in
                                sorted(spent.items(), key=lambda item: -item[1])
                                if value / of >= 0.005)  # fmt: skip

            own = shares(cell.own, cell.waited)
            other = shares(cell.other, sum(cell.other.values()) or 1.0)
            lines.append(f"  {window:6s} {name:7s} {cell.waited:6.2f} s: {own} | {other}")
    return lines


def report(waits: dict[tuple[str, str], list[float]]) -> list[str]:
    """Per group and kind: how many waits, their sum (s), mean, p50, p90 and p99 (µs)."""
    lines = []
    for name in sorted({group for group, _ in waits}):
        total = sum(sum(values) for (group, _), values in waits.items() if group == name)
        lines.append(f"{name}: waited {total:.2f} s in all")
        for kind in KINDS:
            values = np.array(waits.get((name, kind), [])) * 1e6
            if len(values):
                p50, p90, p99 = np.percentile(values, [50, 90, 99])
                lines.append(
                    f"  {kind:36s} {len(values):7d} waits {values.sum() / 1e6:6.2f} s,"
                    f" mean {values.mean():5.0f} µs, p50 {p50:5.0f}, p90 {p90:5.0f}, p99 {p99:5.0f}"
                )
    return lines


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("trace", type=Path, help="perf script's text of a perf sched record")
    parser.add_argument("--server", type=int, nargs="+", default=[], help="worker process ids")
    parser.add_argument("--client", type=int, nargs="+", default=[], help="load generator's")
    parser.add_argument("--database", default="postgres", help="the database's process name")
    parser.add_argument(
        "--class-start", type=float, default=None,
        help="the class's start on the trace's clock (default: just before its first hash)",
    )  # fmt: skip
    parser.add_argument(
        "--class-length", type=float, default=float("inf"),
        help="the class's length, s (the load test's wall time; default: to the trace's end)",
    )  # fmt: skip
    args = parser.parse_args()
    server, client = set(args.server), set(args.client)
    from queue_sim import TIMELINE_BIN_S  # the model's bins (imported here: a heavy module)
    from request_waits import WINDOWS, threads_report

    def group_of(pid: int, name: str) -> str | None:
        if pid in server:
            return "server"
        if pid in client:
            return "load generator"
        return "database" if name == args.database else None

    with args.trace.open() as lines:
        print("\n".join(report(waits_by_kind(events_of(lines), group_of))))
    with args.trace.open() as lines:
        print(busy_report(busy_while_waiting(events_of(lines))))
    with args.trace.open() as lines:
        print("\n".join(episodes_report(idle_episodes(events_of(lines)))))
    groups = {"server": "server", "load generator": "client", "database": "db"}
    with args.trace.open() as lines:
        bins, start = threads_by_time(
            list(events_of(lines)),
            lambda pid, name: groups.get(group_of(pid, name) or ""),
            TIMELINE_BIN_S,
            args.class_start,
            args.class_length,
        )
    print(f"the class from {start:.3f} s on the trace's clock")
    print("\n".join(threads_report(bins, TIMELINE_BIN_S, "the kernel's threads")))
    windows = [(name, low, min(high, args.class_length)) for name, low, high in WINDOWS]
    with args.trace.open() as lines:
        cells = waits_beside(
            list(events_of(lines)),
            lambda pid, name: groups.get(group_of(pid, name) or ""),
            windows,
            args.class_start,
        )
    print("\n".join(beside_report(cells, windows)))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
