"""How often a thread waiting for the interpreter is put on a core, and what that costs.

    .venv/bin/python bench/bench_gil_wakes.py [--seconds 2] [--interval-ms 1 5]

CPython's ``take_gil`` waits for the interpreter in timed waits of one switch interval: at
each timeout a waiting thread wakes, asks the holder to drop it and, unless it is handed
the interpreter, sleeps again.  So every waiting thread is put on a core about once an
interval -- 1,000 times a second at GyroLab's 1 ms (``app.main.set_switch_interval``) --
which the kernel counts in its ``schedstat`` slices.  Here ``N`` threads run pure-Python
loops in one process (all wanting the interpreter, one holding it), and for each ``N``:
each thread's times on a core a second, the run-queue waits (thread-seconds a second),
the cores used and the loops' throughput against one thread alone.  ``queue_model.py``
counts these wake-ups beside its others (``waiting wake-ups``); bench/README.md,
issue 32, twenty-ninth part.

``--beside``: a thread hashing passwords as a log-in does (argon2id at the app's cost,
outside the interpreter) beside ``N`` spinning threads: how much of its time on a core it
waits for one more (its ``schedstat``) -- beside one thread holding the interpreter the
cores suffice, beside threads taking turns at it the woken ones land on its core
(bench/README.md, issue 32, thirty-third part).
"""

from __future__ import annotations

import argparse
import os
import sys
import threading
import time
from dataclasses import dataclass

from run_queue import thread_stats, thread_switches  # bench/

THREADS = (1, 2, 4, 8, 16, 32)


@dataclass
class Contended:
    """``threads`` spinning threads over one watch: each thread's times on a core a
    second, of which the wake-ups from its own waits (``sleeps_per_thread_s``: voluntary
    switches, which a crowded host's preemptions do not add to), run-queue waits
    (thread-seconds a second), cores used and additions a second."""

    threads: int
    slices_per_thread_s: float
    sleeps_per_thread_s: float
    run_queue: float
    cores: float
    adds_per_s: float


def contended(threads: int, interval_s: float, seconds: float = 2.0) -> Contended:
    """Run ``threads`` pure-Python loops at the switch interval ``interval_s`` for
    ``seconds`` and watch them; the main thread sleeps meanwhile.

    The threads' counters are read before they start spinning and after they have
    stopped (parked, not yet ended): read beside them, each of the reads' system calls
    would wait its turn at the interpreter (seconds in all at 20 ms) and be one more
    thread wanting it."""
    before = sys.getswitchinterval()
    sys.setswitchinterval(interval_s)
    go, stop, release = threading.Event(), threading.Event(), threading.Event()
    parked, watched = threading.Barrier(threads + 1), False
    counts = [0] * threads

    def spin(index: int) -> None:
        go.wait()
        done = 0
        while not stop.is_set():
            for _ in range(1000):
                done += 1
            counts[index] += 1000
        try:
            parked.wait()  # stopped, not yet ended: its counters are still there to read
        except threading.BrokenBarrierError:
            return
        release.wait()

    workers = [threading.Thread(target=spin, args=(i,)) for i in range(threads)]
    try:
        for worker in workers:
            worker.start()
        first, first_switches = thread_stats(os.getpid()), thread_switches(os.getpid())
        began, cpu = time.perf_counter(), time.process_time()
        go.set()
        time.sleep(seconds)
        stop.set()
        wall = time.perf_counter() - began
        parked.wait()
        watched = True
        cpu = time.process_time() - cpu
        last, last_switches = thread_stats(os.getpid()), thread_switches(os.getpid())
        added = sum(counts)
    finally:
        stop.set()
        go.set()
        if not watched:  # the watch failed before the spinners parked
            parked.abort()
        release.set()
        for worker in workers:
            worker.join()
        sys.setswitchinterval(before)
    spinning = [tid for tid in first if tid != os.getpid()]
    slices = sum(last[tid][2] - first[tid][2] for tid in spinning if tid in last)
    waited = sum(last[tid][1] - first[tid][1] for tid in spinning if tid in last) / 1e9
    sleeps = sum(
        last_switches[tid][0] - first_switches[tid][0]
        for tid in spinning
        if tid in first_switches and tid in last_switches
    )
    per_thread = wall * threads
    return Contended(
        threads, slices / per_thread, sleeps / per_thread, waited / wall, cpu / wall, added / wall
    )


def beside(threads: int, interval_s: float, hashes: int = 60) -> tuple[float, float, int]:
    """``hashes`` argon2id hashes at the app's cost, one after another on a thread of their
    own, beside ``threads`` pure-Python loops at the switch interval ``interval_s``: the
    hash thread's (time on a core s, time waiting for one s, times put on one)."""
    from argon2.low_level import Type, hash_secret_raw

    from app.accounts.security import ARGON2_MEMORY_KIB, ARGON2_PARALLELISM, ARGON2_TIME_COST

    before = sys.getswitchinterval()
    sys.setswitchinterval(interval_s)
    stop = threading.Event()
    seen: list[tuple[float, float, int]] = []

    def spin() -> None:
        while not stop.is_set():
            for _ in range(1000):
                pass

    def hash_all() -> None:
        tid = threading.get_native_id()
        first = thread_stats(os.getpid())[tid]
        for index in range(hashes):
            hash_secret_raw(
                b"password %d" % index, b"a salt of 16 by", ARGON2_TIME_COST,
                ARGON2_MEMORY_KIB, ARGON2_PARALLELISM, 32, Type.ID,
            )  # fmt: skip
        last = thread_stats(os.getpid())[tid]
        seen.append(((last[0] - first[0]) / 1e9, (last[1] - first[1]) / 1e9, last[2] - first[2]))

    spinners = [threading.Thread(target=spin) for _ in range(threads)]
    hasher = threading.Thread(target=hash_all)
    try:
        for thread in spinners:
            thread.start()
        time.sleep(0.1)
        hasher.start()
        hasher.join()
    finally:
        stop.set()
        for thread in spinners:
            thread.join()
        sys.setswitchinterval(before)
    return seen[0]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--seconds", type=float, default=2.0)
    parser.add_argument("--interval-ms", type=float, nargs="+", default=[1.0, 5.0])
    parser.add_argument("--beside", action="store_true", help="a hashing thread beside them")
    args = parser.parse_args()
    print(f"{os.cpu_count()} cores, Python {sys.version.split()[0]}")
    if args.beside:
        for interval_ms in args.interval_ms:
            print(f"\nswitch interval {interval_ms:g} ms: a thread hashing passwords beside"
                  " N pure-Python threads; its time on a core, its wait for one")  # fmt: skip
            for threads in (0, 1, 2, 4):
                ran, waited, slices = beside(threads, interval_ms / 1000)
                print(f"  N = {threads}: ran {ran:.2f} s, waited {waited:.2f} s"
                      f" ({waited / ran:.0%} of its run), put on a core {slices:,} times"
                      f" ({waited / max(slices, 1) * 1e6:.0f} µs a time)")  # fmt: skip
        return
    for interval_ms in args.interval_ms:
        print(f"\nswitch interval {interval_ms:g} ms")
        print(f"  {'threads':>7s} {'on a core /s each':>18s} {'of which woken':>15s}"
              f" {'run queue':>10s} {'cores':>6s} {'throughput':>11s}")  # fmt: skip
        alone = None
        for threads in THREADS:
            seen = contended(threads, interval_ms / 1000, args.seconds)
            alone = alone or seen.adds_per_s
            print(f"  {threads:7d} {seen.slices_per_thread_s:18,.0f}"
                  f" {seen.sleeps_per_thread_s:15,.0f} {seen.run_queue:10.2f}"
                  f" {seen.cores:6.2f} {seen.adds_per_s / alone:10.0%}")  # fmt: skip


if __name__ == "__main__":
    main()
