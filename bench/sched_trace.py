"""Where a class's threads waited for a core, from the kernel's scheduler trace: each wait
from the moment a thread was woken (or preempted) to the moment it was put on a core,
by what the cores were doing when it began -- its core idle, its core busy and the other
idle, both busy -- or because it was preempted; and how many cores were busy while some
thread waited (a core left idle meanwhile is one the queueing model's cores would have
used).  run_queue.py measures the sums (schedstat); this says which kind of wait they are
made of, for the queueing model.

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
    args = parser.parse_args()
    server, client = set(args.server), set(args.client)

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
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
