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

from run_queue import thread_stats  # bench/

THREADS = (1, 2, 4, 8, 16, 32)


@dataclass
class Contended:
    """``threads`` spinning threads over one watch: each thread's times on a core a
    second, run-queue waits (thread-seconds a second), cores used and additions a second."""

    threads: int
    slices_per_thread_s: float
    run_queue: float
    cores: float
    adds_per_s: float


def contended(threads: int, interval_s: float, seconds: float = 2.0) -> Contended:
    """Run ``threads`` pure-Python loops at the switch interval ``interval_s`` for
    ``seconds`` (after 0.2 s to settle) and watch them; the main thread sleeps meanwhile."""
    before = sys.getswitchinterval()
    sys.setswitchinterval(interval_s)
    stop, settled = threading.Event(), threading.Event()
    counts = [0] * threads

    def spin(index: int) -> None:
        done = 0
        while not stop.is_set():
            for _ in range(1000):
                done += 1
            if settled.is_set():
                counts[index] += 1000
                done = 0

    workers = [threading.Thread(target=spin, args=(i,)) for i in range(threads)]
    try:
        for worker in workers:
            worker.start()
        time.sleep(0.2)
        first, began, cpu = thread_stats(os.getpid()), time.perf_counter(), time.process_time()
        settled.set()
        time.sleep(seconds)
        last, wall = thread_stats(os.getpid()), time.perf_counter() - began
        cpu = time.process_time() - cpu
        added = sum(counts)
    finally:
        stop.set()
        for worker in workers:
            worker.join()
        sys.setswitchinterval(before)
    spinning = [tid for tid in last if tid in first and tid != os.getpid()]
    slices = sum(last[tid][2] - first[tid][2] for tid in spinning)
    waited = sum(last[tid][1] - first[tid][1] for tid in spinning) / 1e9
    return Contended(threads, slices / wall / threads, waited / wall, cpu / wall, added / wall)


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
        print(f"  {'threads':>7s} {'on a core /s each':>18s} {'run queue':>10s}"
              f" {'cores':>6s} {'throughput':>11s}")  # fmt: skip
        alone = None
        for threads in THREADS:
            seen = contended(threads, interval_ms / 1000, args.seconds)
            alone = alone or seen.adds_per_s
            print(f"  {threads:7d} {seen.slices_per_thread_s:18,.0f} {seen.run_queue:10.2f}"
                  f" {seen.cores:6.2f} {seen.adds_per_s / alone:10.0%}")  # fmt: skip


if __name__ == "__main__":
    main()
