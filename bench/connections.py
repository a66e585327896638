"""Which worker each browser's connections reached in a load test: its HTTP connection (the
load generator's times of its requests matched with the server probe's, which name the
worker that answered) and its WebSocket (the probe's line for each that connected, by the
session it streamed).  With two workers the kernel's accept race decides it, and a run's
p95 depends on how the class's streams and requests fell (queue_model.py)."""

from __future__ import annotations

import re
from collections import Counter, defaultdict
from collections.abc import Iterable, Iterator
from dataclasses import dataclass
from pathlib import Path

from class_cpu import WEBSOCKET
from p95_interval import client_lines

SESSION_IN_PATH = re.compile(r"^/lab/sessions/(\d+)(?:/|$)")
TEACHER = "teacher"  # the load generator's name of the teacher's browser


@dataclass
class Connections:
    """Per browser (the load generator's name: a student's number, or "teacher"), the
    worker its HTTP connection reached and the worker its WebSocket reached (0: the worker
    that answered the most requests)."""

    http: dict[str, int]
    websocket: dict[str, int]
    workers: int

    def of_students(self, students: int) -> list[tuple[int, int]] | None:
        """(HTTP, WebSocket) worker of each student 0 … students-1, or None unless every
        student's two are known."""
        try:
            return [(self.http[str(i)], self.websocket[str(i)]) for i in range(students)]
        except KeyError:
            return None

    def shares(self, of: dict[str, int]) -> list[float]:
        """Each worker's share of the students' connections of one kind."""
        counts = Counter(worker for who, worker in of.items() if who != TEACHER)
        total = sum(counts.values()) or 1
        return [counts[worker] / total for worker in range(self.workers)]


def matched_requests(
    client_times: Path, requests: Iterable[list[str]]
) -> Iterator[tuple[tuple[str, str, float, float, str | None], list[str]]]:
    """Each request the load generator timed (``GYROLAB_BENCH_CLIENT_TIMES``: ``method path
    sent_s answered_s [who]``) with the server probe's line for it (``requests``: the
    ``GYROLAB_BENCH_SERVER_TIMES`` lines of HTTP requests, split: ``method path ms waited_ms
    began_s [pid]``), on one clock: the first not yet matched of its method and path that
    the server began while it was on its way.  Requests without a line are left out."""
    began: dict[tuple[str, str], list[tuple[float, list[str]]]] = defaultdict(list)
    for fields in requests:
        began[(fields[0], fields[1])].append((float(fields[4]), fields))
    for calls in began.values():
        calls.sort(key=lambda call: call[0])
    matched: dict[tuple[str, str], int] = defaultdict(int)  # the next not yet matched
    for request in client_lines(client_times):
        method, url, sent, answered, _who = request
        key = (method, url)
        calls, index = began.get(key, []), matched[key]
        while index < len(calls) and calls[index][0] < sent:
            index += 1  # answered to nobody the load generator timed (the teacher's page)
        if index == len(calls) or calls[index][0] > answered:
            continue
        matched[key] = index + 1
        yield request, calls[index][1]


def connections_of(server_times: Path, client_times: Path) -> Connections | None:
    """The workers each browser's connections reached, from the probe's
    ``GYROLAB_BENCH_SERVER_TIMES`` lines (``method path ms waited_ms began_s pid``; ``WS path
    - - began_s pid`` where a WebSocket connected) and the load generator's
    ``GYROLAB_BENCH_CLIENT_TIMES`` lines (``method path sent_s answered_s who``), on one
    clock.  Requests are matched as :func:`matched_requests` does; a browser's HTTP worker
    is the one that answered most of its requests.  None where the lines do not name the
    worker or the browser."""
    requests: list[list[str]] = []
    streamed: list[tuple[str, str]] = []  # (path, pid) of each WebSocket
    answered_by: Counter[str] = Counter()
    for line in server_times.read_text().splitlines():
        fields = line.split()
        if len(fields) < 6:
            return None
        if fields[0] == WEBSOCKET:
            streamed.append((fields[1], fields[5]))
        else:
            requests.append(fields)
            answered_by[fields[5]] += 1
    worker_of_pid = {pid: index for index, (pid, _) in enumerate(answered_by.most_common())}
    for _, pid in streamed:
        worker_of_pid.setdefault(pid, len(worker_of_pid))

    browser_of_session: dict[str, str] = {}
    for _method, url, _sent, _answered, who in client_lines(client_times):
        if who is None:
            return None
        session = SESSION_IN_PATH.match(url)
        if session and who != TEACHER:
            browser_of_session.setdefault(session.group(1), who)
    pids_of: dict[str, Counter[str]] = defaultdict(Counter)
    for (*_, who), fields in matched_requests(client_times, requests):
        pids_of[who][fields[5]] += 1
    http = {who: worker_of_pid[pids.most_common(1)[0][0]] for who, pids in pids_of.items()}
    websocket = {}
    for path, pid in streamed:
        session = SESSION_IN_PATH.match(path)
        if session and session.group(1) in browser_of_session:
            websocket[browser_of_session[session.group(1)]] = worker_of_pid[pid]
    return Connections(http, websocket, len(worker_of_pid))
