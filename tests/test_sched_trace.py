"""Where a class's threads waited for a core, from the scheduler's trace
(``bench/sched_trace.py``), on a trace written out by hand in ``perf script``'s format."""

from __future__ import annotations

import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "bench"))

import sched_trace  # noqa: E402  (bench/)


def switch(time: float, cpu: int, before: tuple[str, int, int], state: str, after: tuple) -> str:
    """A ``sched_switch`` line: ``before`` (name, process id, thread id) leaves the core in
    ``state`` for ``after`` (name, thread id)."""
    name, pid, tid = before
    return (
        f"{name:>16s} {pid}/{tid} [{cpu:03d}] {time:.6f}: sched:sched_switch: prev_comm={name}"
        f" prev_pid={tid} prev_prio=120 prev_state={state} ==> next_comm={after[0]}"
        f" next_pid={after[1]} next_prio=120"
    )


def waking(time: float, cpu: int, by: tuple[str, int, int], woken: tuple, target: int) -> str:
    name, pid, tid = by
    return (
        f"{name:>16s} {pid}/{tid} [{cpu:03d}] {time:.6f}: sched:sched_waking:"
        f" comm={woken[0]} pid={woken[1]} prio=120 target_cpu={target:03d}"
    )


IDLE0, IDLE1 = ("swapper/0", 0, 0), ("swapper/1", 0, 0)
SERVER, OTHER = ("python", 100, 101), ("python", 100, 102)  # two threads of a worker
CLIENT, DATABASE = ("python", 200, 200), ("postgres", 300, 300)

TRACE = [
    switch(9.990, 0, IDLE0, "R", ("python", 102)),
    switch(9.991, 0, OTHER, "S", ("python", 101)),  # both server threads have run
    switch(9.999, 1, IDLE1, "R", ("python", 200)),
    switch(10.000, 0, SERVER, "S", ("swapper/0", 0)),
    waking(10.001, 1, CLIENT, ("python", 101), 0),  # its core idle: 20 µs
    switch(10.001020, 0, IDLE0, "R", ("python", 101)),
    waking(10.0019, 0, SERVER, ("postgres", 300), 1),  # the other core busy, none idle
    switch(10.002, 1, CLIENT, "R+", ("postgres", 300)),  # the load generator preempted
    switch(10.002300, 1, DATABASE, "S", ("python", 200)),  # …for 300 µs
    waking(10.003, 1, CLIENT, ("python", 102), 0),  # every core busy: 500 µs
    switch(10.003500, 0, SERVER, "S", ("python", 102)),
    "          python 100/101 [000] 10.004: sched:sched_stat_runtime: comm=python pid=101",
]


def group_of(pid: int, name: str) -> str | None:
    return {100: "server", 200: "client"}.get(pid) or ("db" if name == "postgres" else None)


def test_each_wait_is_told_by_what_the_cores_were_doing_when_it_began():
    waits = sched_trace.waits_by_kind(sched_trace.events_of(TRACE), group_of)
    idle, busy, preempted = sched_trace.KINDS[0], sched_trace.KINDS[2], sched_trace.KINDS[3]
    assert set(waits) == {("server", idle), ("server", busy), ("client", preempted),
                          ("db", busy)}  # fmt: skip
    assert waits["server", idle] == [pytest.approx(20e-6, abs=1e-9)]
    assert waits["server", busy] == [pytest.approx(500e-6, abs=1e-9)]
    assert waits["client", preempted] == [pytest.approx(300e-6, abs=1e-9)]
    assert waits["db", busy] == [pytest.approx(100e-6, abs=1e-9)]


def test_the_report_sums_each_groups_waits():
    waits = sched_trace.waits_by_kind(sched_trace.events_of(TRACE), group_of)
    lines = sched_trace.report(waits)
    assert lines[0] == "client: waited 0.00 s in all" and "preempted" in lines[1]
    server = lines.index("server: waited 0.00 s in all")
    assert lines[server + 1].split()[:5] == ["woken,", "its", "core", "idle", "1"]


def test_threads_outside_the_groups_are_not_counted():
    waits = sched_trace.waits_by_kind(sched_trace.events_of(TRACE), lambda pid, name: None)
    assert waits == {}


def test_the_cores_busy_while_a_thread_waits():
    """A thread woken onto the idle core waits 20 µs with the other core busy; the three
    later waits (100, 300 and 500 µs) have both cores busy."""
    spent = sched_trace.busy_while_waiting(sched_trace.events_of(TRACE))
    assert spent == {1: pytest.approx(20e-6, abs=1e-9), 2: pytest.approx(900e-6, abs=1e-9)}
    assert sched_trace.busy_report(spent).endswith("(on average 1.98)")
    assert sched_trace.busy_report({}) == "no thread waited for a core"


def test_a_thread_seen_running_no_longer_waits_though_its_switch_was_not_traced():
    """A thread woken, then seen running an event of its own with no ``sched_switch`` to it
    in the trace (lost, or before the trace began): it waited until then, not for good."""
    lines = [
        switch(1.000, 0, IDLE0, "R", ("python", 101)),
        switch(1.000, 1, IDLE1, "R", ("python", 200)),
        waking(1.001, 1, CLIENT, ("python", 102), 0),  # both cores busy
        "          python 100/102 [000] 1.002: sched:sched_stat_runtime: comm=python pid=102",
        switch(1.010, 0, SERVER, "S", ("swapper/0", 0)),
    ]
    spent = sched_trace.busy_while_waiting(sched_trace.events_of(lines))
    assert spent == {2: pytest.approx(1e-3, abs=1e-9)}


def migrate(time: float, cpu: int, moved: tuple[str, int], source: int, target: int) -> str:
    return (
        f"     migration/{cpu} 18/18 [{cpu:03d}] {time:.6f}: sched:sched_migrate_task:"
        f" comm={moved[0]} pid={moved[1]} prio=120 orig_cpu={source} dest_cpu={target}"
    )


def test_a_core_idle_while_a_thread_waits_on_the_others_queue():
    """Three times one core idles while a thread waits in the other's queue: until the
    waiter's own core comes free (300 µs), until it is moved (100 µs), until the idle core
    takes a thread woken onto it (600 µs) -- the waiter still waiting then, on a busy
    core.  A thread woken while both cores are busy, or onto the idle core, is no such
    time."""
    lines = [
        switch(1.000, 0, IDLE0, "R", ("python", 101)),
        switch(1.000, 1, IDLE1, "R", ("python", 200)),
        waking(1.0005, 1, CLIENT, ("python", 102), 0),  # both cores busy: none
        switch(1.001, 1, CLIENT, "S", ("swapper/1", 0)),  # core 1 idle, 102 waits on 0
        switch(1.0013, 0, SERVER, "S", ("python", 102)),  # …until its own core is free
        waking(1.002, 0, OTHER, ("python", 200), 0),  # onto busy core 0, core 1 idle
        migrate(1.0021, 0, ("python", 200), 0, 1),  # …until moved
        switch(1.0022, 1, IDLE1, "R", ("python", 200)),
        switch(1.003, 1, CLIENT, "S", ("swapper/1", 0)),  # nothing waits: none
        waking(1.0035, 0, OTHER, ("python", 101), 1),  # onto the idle core: none
        switch(1.0036, 1, IDLE1, "R", ("python", 101)),
        switch(1.0038, 1, SERVER, "S", ("swapper/1", 0)),
        waking(1.004, 0, OTHER, ("postgres", 300), 0),  # onto busy core 0, core 1 idle
        waking(1.0044, 0, OTHER, ("python", 200), 1),
        switch(1.0046, 1, IDLE1, "R", ("python", 200)),  # …until core 1 takes another
    ]
    episodes = sched_trace.idle_episodes(sched_trace.events_of(lines))
    assert [(e.began, e.began_by, e.ended_by) for e in episodes] == [
        (1.001, "a core went idle", "ran on its own core"),
        (1.002, "woken onto a busy core", "migrated"),
        (1.004, "woken onto a busy core", "the idle core took other work"),
    ]
    assert [e.length for e in episodes] == pytest.approx([300e-6, 100e-6, 600e-6], abs=1e-9)
    report = sched_trace.episodes_report(episodes)
    assert report[0] == (
        "a core idle while a thread waited on another's queue: 3 times, 0.00 s in all"
    )
    bins = [line.split()[:3] for line in report[1:4]]
    assert bins == [["0.05-0.2", "ms:", "1"], ["0.2-0.5", "ms:", "1"], ["0.5-1", "ms:", "1"]]
    assert sched_trace.episodes_report([])[0].startswith("no core idled")


MAIN, HASHER = ("python", 100, 100), ("python", 100, 102)
SHORT, WORKER = ("python", 100, 103), ("python", 100, 104)
# a log-in's hash on core 0, put off it for 1 ms by the worker's main thread; the
# database and the load generator on core 1, then two short threads of the worker
A_HASH = [
    switch(0.950, 1, IDLE1, "R", ("python", 200)),
    waking(1.000, 1, CLIENT, ("python", 102), 0),
    switch(1.000, 0, IDLE0, "R", ("python", 102)),
    waking(1.005, 1, CLIENT, ("python", 100), 0),
    switch(1.005, 0, HASHER, "R", ("python", 100)),  # the hash put off its core…
    switch(1.006, 0, MAIN, "S", ("python", 102)),  # …for 1 ms
    waking(1.011, 0, HASHER, ("postgres", 300), 1),
    switch(1.012, 1, CLIENT, "R", ("postgres", 300)),  # the database waited 1 ms
    switch(1.0125, 1, DATABASE, "S", ("python", 200)),  # the client 0.5 ms
    switch(1.025, 0, HASHER, "S", ("swapper/0", 0)),  # 24 ms of CPU: a hash
    waking(1.030, 1, CLIENT, ("python", 103), 0),
    switch(1.0302, 0, IDLE0, "R", ("python", 103)),
    switch(1.03025, 0, SHORT, "S", ("swapper/0", 0)),  # woken for nothing
    waking(1.040, 1, CLIENT, ("python", 104), 0),
    switch(1.0403, 0, IDLE0, "R", ("python", 104)),
    switch(1.0423, 0, WORKER, "S", ("swapper/0", 0)),  # 2 ms of work
    switch(1.050, 1, CLIENT, "S", ("swapper/1", 0)),
]


def test_the_threads_time_run_and_waited_is_told_by_the_classs_time_and_a_hash_by_its_length():
    """``threads_by_time``: a worker's pool thread runs 24 ms between its wake-up and its
    sleep, put off its core once for 1 ms by the worker's main thread -- a log-in's hash;
    the class begins 0.1 s before it.  Two short threads wait 0.2 ms (then run 50 µs: a
    thread woken for nothing) and 0.3 ms (then run 2 ms: before work); the load generator
    is put off its core for 0.5 ms by the database, which waited 1 ms for it."""
    events = list(sched_trace.events_of(A_HASH))
    bins, start = sched_trace.threads_by_time(events, group_of, 0.01)
    assert start == pytest.approx(0.900)
    cell = {key: pytest.approx(value, abs=1e-9) for key, value in {
        (10, "hash"): (0.009, 0.001, 0.001), (11, "hash"): (0.010, 0.0, 0.0),
        (12, "hash"): (0.005, 0.0, 0.0), (10, "server"): (0.001, 0.0, 0.0),
        (13, "server"): (0.00005, 0.0002, 0.0), (14, "server"): (0.002, 0.0003, 0.0003),
        (11, "db"): (0.0005, 0.001, 0.001), (11, "client"): (0.0095, 0.0005, 0.0005),
    }.items()}  # fmt: skip
    assert {key: bins[key] for key in cell} == cell
    assert not [key for key in bins if key[1] == "hash" and key not in cell]
    assert sum(bins[key][0] for key in bins if key[1] == "client") == pytest.approx(0.0995)
    # the class's start given: the same time, other bins
    later, start = sched_trace.threads_by_time(events, group_of, 0.01, start=1.0)
    assert start == 1.0 and later[0, "hash"] == bins[10, "hash"]
    assert sum(later[key][0] for key in later if key[1] == "client") == pytest.approx(0.0495)
    # and its length: nothing after it
    cut, _ = sched_trace.threads_by_time(events, group_of, 0.01, start=1.0, length=0.0121)
    assert sum(cut[key][0] for key in cut if key[1] == "client") == pytest.approx(0.012)
    assert cut[1, "db"] == pytest.approx((0.0001, 0.001, 0.001))  # its wait before it ends


def test_what_ran_beside_a_groups_waits_tells_a_full_machine_from_an_idle_core():
    """``waits_beside``: the hash waited 1 ms on its core while the worker's main thread
    ran there and the load generator on the other; the database 1 ms behind the load
    generator, beside the hash; the load generator 0.5 ms behind the database; the two
    short threads 0.5 ms on core 0 while it was idle (woken, not yet on it)."""
    events = list(sched_trace.events_of(A_HASH))
    windows = [("early", 0.0, 0.12), ("late", 0.12, 1.0)]  # the class from 0.9 s
    cells = sched_trace.waits_beside(events, group_of, windows)
    seen = {key: (round(cell.waited * 1e6), {k: round(v * 1e6) for k, v in cell.own.items()},
                  {k: round(v * 1e6) for k, v in cell.other.items()})
            for key, cell in cells.items()}  # fmt: skip
    assert seen == {
        ("early", "hash"): (1000, {"server": 1000}, {"client": 1000}),
        ("early", "db"): (1000, {"client": 1000}, {"hash": 1000}),
        ("early", "client"): (500, {"db": 500}, {"hash": 500}),
        ("late", "server"): (500, {"idle": 500}, {"client": 500}),
    }
    report = sched_trace.beside_report(cells, windows)
    assert "  early  hash      0.00 s: server 100% | client 100%" in report
    assert "  late   server    0.00 s: idle 100% | client 100%" in report
    # the class's start given: every wait in the second window
    later = sched_trace.waits_beside(events, group_of, windows, start=0.88)
    assert {key: cell.waited for key, cell in later.items()} == pytest.approx(
        {
            ("late", "hash"): 0.001,
            ("late", "db"): 0.001,
            ("late", "client"): 0.0005,
            ("late", "server"): 0.0005,
        }  # fmt: skip
    )
