"""How long each group of processes waited for a core while a class ran: the kernel's
``/proc/PID/task/TID/schedstat`` (per thread: ns on a core, ns runnable but waiting on a
run queue, time slices), polled by a thread of the load generator so that threads born
and ended during the class are counted (a thread first seen after the start is counted
from zero; one that ends loses at most one poll's worth).

What the queueing model assumes about the scheduler -- cores shared in proportion among
whatever asks for them -- can then be held against what the scheduler did: the share of
each group's wanted time it spent waiting (``waited / (ran + waited)``), and each group's
autogroup (the kernel shares the cores between sessions' autogroups first when
``kernel.sched_autogroup_enabled`` is 1)."""

from __future__ import annotations

import os
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

POLL_S = 0.25


def _per_thread(pid: int, name: str, parse) -> dict:
    """``parse(text)`` of each thread's ``/proc/PID/task/TID/<name>`` file, by thread id
    (a thread that ends meanwhile, or whose file does not parse, left out)."""
    found: dict = {}
    try:
        tasks = list(Path(f"/proc/{pid}/task").iterdir())
    except OSError:
        return found
    for task in tasks:
        try:
            found[int(task.name)] = parse((task / name).read_text())
        except (OSError, ValueError, KeyError):
            continue  # ended meanwhile
    return found


def _schedstat(text: str) -> tuple[int, int, int]:
    ran, waited, slices = text.split()
    return int(ran), int(waited), int(slices)


def _switches(text: str) -> tuple[int, int]:
    fields = dict(line.split(":", 1) for line in text.splitlines())
    return int(fields["voluntary_ctxt_switches"]), int(fields["nonvoluntary_ctxt_switches"])


def thread_stats(pid: int) -> dict[int, tuple[int, int, int]]:
    """Per thread of ``pid``: (ns on a core, ns waiting on a run queue, times it was put
    on a core) so far."""
    return _per_thread(pid, "schedstat", _schedstat)


def thread_switches(pid: int) -> dict[int, tuple[int, int]]:
    """Per thread of ``pid``: (times it gave up its core to wait -- a sleep, a lock, a
    timed wait --, times the kernel took its core from it while it could run) so far:
    ``/proc/PID/task/TID/status``'s voluntary and nonvoluntary context switches."""
    return _per_thread(pid, "status", _switches)


def machine_times() -> tuple[float, ...]:
    """The whole machine so far, in core-seconds: (busy, of which steal, idle and waiting
    for I/O, and the kernel's CPU pressure: seconds in which at least one task waited for
    a core).  Busy is ``/proc/stat``'s user + nice + system + irq + softirq; steal is the
    time the hypervisor ran something else on a virtual core that wanted it."""
    ticks = int(os.sysconf("SC_CLK_TCK"))
    fields = [int(f) for f in Path("/proc/stat").read_text().split("\n", 1)[0].split()[1:9]]
    user, nice, system, idle, iowait, irq, softirq, steal = fields
    try:
        some = Path("/proc/pressure/cpu").read_text().split("\n", 1)[0]
        pressure = int(some.rsplit("total=", 1)[1]) / 1e6
    except (OSError, IndexError, ValueError):
        pressure = float("nan")
    busy = (user + nice + system + irq + softirq) / ticks
    return busy, steal / ticks, (idle + iowait) / ticks, pressure


def autogroup(pid: int) -> str:
    """The process's autogroup ("/autogroup-N"), or "" where the kernel has none."""
    try:
        return Path(f"/proc/{pid}/autogroup").read_text().split()[0]
    except (OSError, IndexError):
        return ""


@dataclass
class Waits:
    """One group's time over the watch: on a core and waiting for one (s), and how many
    times its threads were put on a core (each after a wait on the run queue: a wake-up,
    or a turn after being preempted)."""

    ran_s: float
    waited_s: float
    autogroups: tuple[str, ...]
    slices: int = 0

    @property
    def waited_share(self) -> float:
        """Of the time its threads wanted a core, the part spent waiting for one."""
        wanted = self.ran_s + self.waited_s
        return self.waited_s / wanted if wanted else 0.0


class RunQueueWatch:
    """``with RunQueueWatch({"server": lambda: pids, …}) as watch: …`` then
    ``watch.waits()``: each group's :class:`Waits` between entering and leaving.  Each
    group's processes are asked for at every poll (PostgreSQL starts a process per
    connection)."""

    def __init__(
        self,
        groups: dict[str, Callable[[], list[int]]],
        poll_s: float = POLL_S,
        main_threads: dict[str, str] | None = None,
    ):
        """``main_threads``: for a group's name, the name under which its processes' main
        threads are also counted on their own (a uvicorn worker's event loop)."""
        self.groups, self.poll_s = groups, poll_s
        self.main_threads = main_threads or {}
        self._first: dict[str, dict[tuple[int, int], tuple[int, int, int]]] = {}
        self._last: dict[str, dict[tuple[int, int], tuple[int, int, int]]] = {}
        self._autogroups: dict[str, set[str]] = {name: set() for name in groups}
        self._machine: list[tuple[float, ...]] = []
        # at each poll: (time.perf_counter(), per group its threads' time on a core so far, s)
        self._series: list[tuple[float, dict[str, float]]] = []
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._watch, name="run-queue-watch", daemon=True)

    def _poll(self, first: bool) -> None:
        for name, pids_of in self.groups.items():
            seen = self._last.setdefault(name, {})
            start = self._first.setdefault(name, {})
            for pid in pids_of():
                if group := autogroup(pid):
                    self._autogroups[name].add(group)
                for tid, stats in thread_stats(pid).items():
                    key = (pid, tid)
                    if key not in start:  # born during the watch: from zero
                        start[key] = stats if first else (0, 0, 0)
                    seen[key] = stats
        self._series.append((time.perf_counter(), {
            name: sum(stats[0] - self._first[name][key][0]
                      for key, stats in self._last[name].items()) / 1e9
            for name in self.groups
        }))  # fmt: skip

    def _watch(self) -> None:
        while not self._stop.wait(self.poll_s):
            self._poll(first=False)

    def __enter__(self) -> RunQueueWatch:
        self._poll(first=True)
        self._machine = [machine_times()]
        self._thread.start()
        return self

    def __exit__(self, *exc) -> None:
        self._stop.set()
        self._thread.join()
        self._poll(first=False)
        self._machine.append(machine_times())

    def machine(self) -> tuple[float, ...]:
        """The whole machine over the watch: (busy, steal, idle, CPU pressure) in
        core-seconds (:func:`machine_times`)."""
        first, last = self._machine
        return tuple(b - a for a, b in zip(first, last, strict=True))

    def ran_by_time(self, since: float, bin_s: float = POLL_S) -> dict[str, list[float]]:
        """Per group, its threads' time on a core in each ``bin_s`` from ``since`` (a
        ``time.perf_counter()``: the class's first request) to the last poll, s
        (:func:`binned`)."""
        return binned(self._series, since, bin_s)

    def waits(self) -> dict[str, Waits]:
        result = {}
        for name in self.groups:
            start, last = self._first.get(name, {}), self._last.get(name, {})
            groups = tuple(sorted(self._autogroups[name]))
            result[name] = _summed(start, last, list(last), groups)
            if name in self.main_threads:
                mains = [(pid, tid) for pid, tid in last if pid == tid]
                result[self.main_threads[name]] = _summed(start, last, mains, groups)
        return result


def binned(
    series: list[tuple[float, dict[str, float]]], since: float, bin_s: float
) -> dict[str, list[float]]:
    """Per group, the growth of its running total in each ``bin_s`` from ``since`` to the
    last sample: ``series`` is (time, per group a total so far), in time order; the total
    at a bin's edge is interpolated linearly between the samples around it (before the
    first sample: the first's).  A poll every ``POLL_S`` puts each bin's CPU within a poll
    of when it was spent."""
    if not series:
        return {}
    times = np.array([when for when, _ in series])
    bins = int((times[-1] - since) // bin_s) if times[-1] > since else 0
    edges = since + bin_s * np.arange(bins + 1)
    out = {}
    for name in series[0][1]:
        totals = np.array([values.get(name, 0.0) for _, values in series])
        at_edges = np.interp(edges, times, totals)
        out[name] = [round(float(x), 4) for x in np.diff(at_edges)]
    return out


def _summed(start: dict, last: dict, keys: list, groups: tuple[str, ...]) -> Waits:
    ran, waited, slices = (sum(last[key][i] - start[key][i] for key in keys) for i in range(3))
    return Waits(ran / 1e9, waited / 1e9, groups, slices)
