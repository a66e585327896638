"""bench/bench_pairs.py: the queueing model's answer for two requests sent a set time
apart (the real server's side needs a server: run the script)."""

from __future__ import annotations

import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "bench"))

import bench_pairs  # noqa: E402  (bench/)

MS = 1e-3
PAGE = bench_pairs.ROUTES["page"]


def test_a_pair_far_apart_is_two_requests_alone_and_a_pair_at_once_shares_the_interpreter():
    """5 ms of server CPU, 3.5 ms of it holding the interpreter in threads and on the event
    loop: a pair sent together takes longer than one alone, each less than both in a row;
    sent 8 ms apart (after the first has finished), each as long as one alone."""
    cost = bench_pairs.Cost(server=5 * MS, client=2 * MS, calls=10.0, trips=2.0,
                            loop=1.5 * MS, loop_own=1.0 * MS)  # fmt: skip
    (alone,) = bench_pairs.modelled(PAGE, cost, None, seeds=4)
    together = bench_pairs.modelled(PAGE, cost, 0.0, seeds=4)
    apart = bench_pairs.modelled(PAGE, cost, 0.008, seeds=4)
    assert 3.5 * MS <= alone < 8 * MS
    assert all(alone < t < 2 * alone for t in together) and len(together) == 2
    assert apart == pytest.approx([alone, alone], rel=0.02)
