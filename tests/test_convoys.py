"""bench/convoys.py: how a class's students fall into step -- read from a run's records and
from the queueing model's, and measured on classes built by hand."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "bench"))

import convoys  # noqa: E402  (bench/)
import queue_sim  # noqa: E402

MS = 1e-3


def student(offset: float, start_ms: float = 5.0, cycles: int = 3, shrink_ms: float = 0.0):
    """A student whose turns come every 3 s from ``offset``: each cycle a position asked
    for at the turn's answer, started ``start_ms`` later (less ``shrink_ms`` a cycle),
    streamed 3 s, saved 5 ms after its last frame, and the next turn sent at once."""
    made = convoys.Student()
    sent = offset
    for k in range(cycles + 1):
        answered = sent + 10 * MS
        made.turns.append((sent, answered))
        if k == cycles:
            break
        started = answered + (start_ms - shrink_ms * k) * MS
        last = started + 3.0
        saved = last + 5 * MS
        made.positions.append((answered, started, last, saved))
        sent = saved
    return made


def test_a_pair_whose_one_behind_starts_faster_draws_together_by_that_much():
    """The one 20 ms behind starts 2 ms faster each cycle than the one ahead: its cycle is
    2 ms shorter, cycle after cycle; a student far off (1 s) is in no pair."""
    ahead = student(0.0)
    behind = student(0.020, start_ms=3.0)
    rows = convoys.drawing_together([ahead, behind, student(1.0)])
    assert len(rows) == 3
    for k, (differences, pairs) in enumerate(rows):
        assert pairs == 1
        start, stream, save, cycle = differences
        assert start == pytest.approx(-2 * MS)
        assert stream == pytest.approx(0.0, abs=1e-9) and save == pytest.approx(0.0, abs=1e-9)
        assert cycle == pytest.approx(-2 * MS), k
    # drawn together, the gap at the next turn is the smaller by the cycle's difference
    assert behind.turns[1][0] - ahead.turns[1][0] == pytest.approx(0.018)


def test_the_nearest_others_turn_closes_as_the_class_falls_into_step():
    """Students 20 ms apart, every second one starting 4 ms faster each cycle than the one
    before it: each turn's nearest other comes closer (20, 16, 12, 8 ms), and at the last
    turn every student has one within 10 ms."""
    students = [student(i * 0.020, start_ms=10.0 - 4.0 * (i % 2)) for i in range(10)]
    rows = convoys.nearest_turns(students)
    assert [count for _, _, count in rows] == [10] * 4
    medians = [median for median, _, _ in rows]
    assert medians == pytest.approx([0.020, 0.016, 0.012, 0.008])
    assert [share for _, share, _ in rows] == [0.0, 0.0, 0.0, 1.0]


def test_a_runs_records_are_read_per_session(tmp_path):
    """The load generator's two files: turns by their session's path, positions by their
    session; other requests and a line cut short are left out."""
    client = tmp_path / "client.txt"
    client.write_text(
        "GET /lab/sessions/7 1.000000 1.010000\n"
        "POST /lab/sessions/7/turn 4.000000 4.012000\n"
        "POST /lab/sessions/8/turn 4.005000 4.020000\n"
        "POST /lab/sessions/7/turn 7.100000 7.111000\n"
        "POST /lab/sess\n"
    )
    streams = tmp_path / "stream.txt"
    streams.write_text(
        "7 heading 1 1.02 1.03 1.23 4.03 4.035\n"
        "7 heading 2 4.012 4.02 4.22 7.02 7.03\n"
        "8 heading 1 1.05 1.06 1.26 4.06\n"
    )
    read = convoys.read_run(client, streams)
    assert len(read) == 1  # session 8's one position was cut short: no student
    (seven,) = read
    assert seven.turns == [(4.0, 4.012), (7.1, 7.111)]
    assert seven.positions == [(1.02, 1.03, 4.03, 4.035), (4.012, 4.02, 7.02, 7.03)]
    ((answered, spent),) = convoys.cycles(seven)
    assert answered == 4.012
    assert spent == pytest.approx([0.008, 3.0, 0.01, 7.1 - 4.012])


def test_the_models_students_are_recorded_as_a_runs_are():
    """``simulate``'s "students": each of the class's students with every request of the
    script (its turns among them) and every position, in the order of a cycle."""
    costs = {route: (2 * MS, 0.0, 1 * MS, 2.0, 2.0, 0.5 * MS)
             for kind, route in queue_sim.student_script() if kind == "request"}  # fmt: skip
    costs[queue_sim.STREAM] = (1 * MS, 0.0, 0.5 * MS, 1.0, 0.2, 0.4 * MS)
    result = queue_sim.simulate(costs, 4, 1, 2.0, teacher=False)
    script = [route for kind, route in queue_sim.student_script() if kind == "request"]
    students = convoys.from_model(result)
    assert len(students) == len(result["students"]) == 4
    for record, made in zip(result["students"], students, strict=True):
        assert [route for route, _, _ in record["requests"]] == script
        assert len(made.turns) == script.count(convoys.TURN) == 6
        assert len(made.positions) == 8
        for asked, started, last, saved in made.positions:
            assert asked < started < last < saved
            assert last - started == pytest.approx(3.0, abs=0.05)  # 15 frames of 0.2 s
        assert len(convoys.cycles(made)) == 4  # the two parts' turns after their first
    near = convoys.nearest_turns(students)
    assert len(near) == 6 and all(np.isfinite(median) for median, _, _ in near)
