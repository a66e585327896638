"""How a class's students fall into step: the load test's students stream a position, turn
the table, stream the next, each cycle as long as the last (3 s of streaming and what the
server adds).  Two students whose cycles run a few ms apart meet in the server at each turn,
start and save; if the one behind is slowed less than the one ahead, they draw closer cycle
after cycle and ride together (a convoy), and each of their requests then waits for the
other's.  A run's records (load_test.py's ``GYROLAB_BENCH_CLIENT_TIMES`` and
``GYROLAB_BENCH_STREAM_TIMES``) and the queueing model's (``queue_sim.simulate``'s
"students") are read into the same shape here and compared: how close each turn's nearest
other turn was sent, and by how much the students of a close pair draw together in each
part of a cycle."""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from p95_interval import client_lines

TURN = "POST /lab/sessions/{id}/turn"
TURN_PATH = re.compile(r"/lab/sessions/(\d+)/turn$")
CLOSE_S = 0.010  # "close": the share of turns with another sent within 10 ms
PAIR_S = (0.010, 0.030)  # a pair whose turns were answered 10-30 ms apart: draws together?
PHASES = ("start", "stream", "save", "cycle")  # asked → started → last frame → saved; all


@dataclass
class Student:
    """One student's turns (sent, answered) and positions streamed (asked for, started,
    last frame of samples, saved), s, in the order they happened."""

    turns: list[tuple[float, float]] = field(default_factory=list)
    positions: list[tuple[float, float, float, float]] = field(default_factory=list)


def read_run(client_times: Path, stream_times: Path) -> list[Student]:
    """A run's students from its two records (``method path sent answered`` per HTTP
    request; ``session part position asked started first last saved`` per position): the
    turns and the positions of the session they streamed in."""
    by_session: dict[int, Student] = {}
    for line in stream_times.read_text().splitlines():
        fields = line.split()
        if len(fields) != 8:  # a line cut short
            continue
        asked, started, _first, last, saved = map(float, fields[3:])
        by_session.setdefault(int(fields[0]), Student()).positions.append(
            (asked, started, last, saved)
        )
    for method, url, sent, answered, _ in client_lines(client_times):
        turn = TURN_PATH.match(url) if method == "POST" else None
        if turn and int(turn.group(1)) in by_session:
            by_session[int(turn.group(1))].turns.append((sent, answered))
    return [_in_order(student) for student in by_session.values()]


def from_model(result: dict) -> list[Student]:
    """The model's students (``simulate``'s "students")."""
    return [
        _in_order(
            Student(
                [
                    (sent, sent + latency)
                    for route, sent, latency in record["requests"]
                    if route == TURN
                ],  # fmt: skip
                list(record["positions"]),
            )
        )
        for record in result["students"]
    ]


def _in_order(student: Student) -> Student:
    return Student(sorted(student.turns), sorted(student.positions))


def nearest_turns(students: list[Student]) -> list[tuple[float, float, int]]:
    """Per turn of the script (the k-th of each student's): the median time from one
    student's turn sent to the nearest other's (s), the share sent within ``CLOSE_S`` of
    another, and how many students had it."""
    rows = []
    for k in range(max((len(s.turns) for s in students), default=0)):
        sent = np.sort([s.turns[k][0] for s in students if len(s.turns) > k])
        if len(sent) < 2:
            break
        gaps = np.diff(sent)
        nearest = np.minimum(np.r_[np.inf, gaps], np.r_[gaps, np.inf])
        rows.append((float(np.median(nearest)), float(np.mean(nearest < CLOSE_S)), len(sent)))
    return rows


def cycles(student: Student) -> list[tuple[float, np.ndarray]]:
    """Each turn that is followed by one position and then by the next turn: (the turn's
    answer, the times from it spent in each of ``PHASES``: asked → started, started →
    last frame, last frame → saved, and the answer to the next turn sent), s.  The
    time from the answer to asking for the position (the client's) goes to no phase."""
    found = []
    for (_, answered), (next_sent, _) in zip(student.turns, student.turns[1:], strict=False):
        between = [p for p in student.positions if answered <= p[0] and p[3] <= next_sent]
        if len(between) != 1:  # none, or a part's last position and the next part's first
            continue
        (position,) = between
        asked, started, last, saved = position
        found.append(
            (
                answered,
                np.array([started - asked, last - started, saved - last, next_sent - answered]),
            )  # fmt: skip
        )
    return found


def drawing_together(students: list[Student], pair_s=PAIR_S) -> list[tuple[np.ndarray, int]]:
    """Per cycle of the script (the k-th cycle of each student's): for each pair of
    students whose turns were answered ``pair_s`` apart, how much shorter the one behind
    spent in each of ``PHASES`` than the one ahead (mean, s: negative, they drew
    together), and how many pairs."""
    per_student = [cycles(student) for student in students]
    rows = []
    for k in range(max((len(c) for c in per_student), default=0)):
        mine = [c[k] for c in per_student if len(c) > k]
        answered = np.array([answer for answer, _ in mine])
        phases = np.array([spent for _, spent in mine])
        behind = answered[None, :] - answered[:, None]  # [ahead, behind]
        ahead_index, behind_index = np.nonzero((behind >= pair_s[0]) & (behind < pair_s[1]))
        if not len(ahead_index):
            rows.append((np.full(len(PHASES), np.nan), 0))
            continue
        differences = phases[behind_index] - phases[ahead_index]
        rows.append((differences.mean(axis=0), len(ahead_index)))
    return rows


def compare(model: list[list[Student]], measured: list[Student]) -> None:
    """The model's classes (one per seed) beside a run's: how close each turn was sent to
    another's, and how the students of a close pair drew together in each cycle."""
    model_near = [nearest_turns(students) for students in model]
    seen_near = nearest_turns(measured)
    print("  turns, by their place in the script: median ms to the nearest other's sent,"
          f" share within {CLOSE_S * 1000:.0f} ms (model | measured)")  # fmt: skip
    for k, (median, close, _) in enumerate(seen_near):
        rows = [near[k] for near in model_near if len(near) > k]
        if not rows:
            continue
        print(f"    turn {k + 1}: {np.mean([r[0] for r in rows]) * 1000:5.1f} ms"
              f" {np.mean([r[1] for r in rows]):4.0%} | {median * 1000:5.1f} ms"
              f" {close:4.0%}")  # fmt: skip
    low, high = (bound * 1000 for bound in PAIR_S)
    print(
        f"  a pair whose turns were answered {low:.0f}-{high:.0f} ms apart: ms the one"
        " behind spent less than the one ahead, by phase (model | measured)"
    )
    print("    cycle " + "".join(f"{phase:>17s}" for phase in PHASES) + "    pairs")
    model_rows = [drawing_together(students) for students in model]
    for k, (seen, pairs) in enumerate(drawing_together(measured)):
        rows = [row[k] for row in model_rows if len(row) > k and row[k][1]]
        if not rows or not pairs:
            continue
        weights = np.array([count for _, count in rows], dtype=float)
        mean = np.average(np.array([d for d, _ in rows]), axis=0, weights=weights)
        cells = "".join(
            f"  {-m * 1000:6.2f} | {-s * 1000:6.2f}" for m, s in zip(mean, seen, strict=True)
        )
        print(f"    {k + 1:5d} {cells}  {weights.sum() / len(rows):5.0f} | {pairs}")
