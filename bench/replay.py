"""A run's arrivals, for the queueing model to replay (``queue_sim.simulate``'s
``arrivals``): every HTTP request the load generator sent and every position it asked to
stream, at the time it did, from the run's two records (load_test.py's
``GYROLAB_BENCH_CLIENT_TIMES`` and ``GYROLAB_BENCH_STREAM_TIMES``).

Open loop, each arrival is sent at its time whatever the model answered before it: the
model's server meets the class exactly as the run's did, its convoys included.  Paced,
each browser's steps go in order, each at its time in the run or, where the model answered
the step before later than the run did, as long after that answer as the run's browser took
(its "think"): no step is sent before the model could have sent it, and a model slower than
the run is not buried under a queue the run never had."""

from __future__ import annotations

import re
from pathlib import Path

from class_cpu import route_of
from p95_interval import client_lines
from queue_sim import STREAM

SESSION_IN_PATH = re.compile(r"/lab/sessions/(\d+)(?:/|$)")

# (time from the first arrival s, "request" or "stream", route, connection, browser or None,
# the browser's think before it s)
Arrival = tuple[float, str, str, object, object, float]


def arrivals_of(client_times: Path, stream_times: Path, paced: bool = False) -> list[Arrival]:
    """The run's arrivals in the order sent.  Open loop (``paced`` False): a session's HTTP
    requests share a connection, as do its positions streamed (its WebSocket), a request of
    no session has one of its own (None), and no arrival has a browser.  ``paced``: each
    request's browser (the client times' fifth field: load_test.py's since 2026-12-05; a
    position's, its session's) and its HTTP requests one connection; each step's think is
    the time from the browser's step before it ended (answered; a position: saved) to its
    own start, at least 0.  Lines cut short are left out."""
    steps: list[tuple[float, float, str, str, object, object]] = []
    browser_of_session: dict[int, str] = {}
    for method, url, sent, answered, who in client_lines(client_times):
        if paced and who is None:
            raise ValueError(f"{client_times} names no browser for its requests (pacing needs "
                             "load_test.py's client times of 2026-12-05 or later)")  # fmt: skip
        session = SESSION_IN_PATH.search(url)
        browser = who if paced else None
        if paced:
            connection: object = ("http", browser)
            if session:
                browser_of_session[int(session.group(1))] = browser
        else:
            connection = ("http", int(session.group(1))) if session else None
        steps.append((sent, answered, "request", route_of(method, url), connection, browser))
    for line in stream_times.read_text().splitlines():
        fields = line.split()
        if len(fields) != 8:
            continue
        session = int(fields[0])
        browser = browser_of_session.get(session) if paced else None
        if paced and browser is None:
            continue  # a session no request of the run's names
        asked, saved = float(fields[3]), float(fields[7])
        steps.append((asked, saved, "stream", STREAM, ("websocket", session), browser))
    if not steps:
        return []
    steps.sort(key=lambda step: step[0])
    first = steps[0][0]
    ended: dict[object, float] = {}  # each browser's step before: when it ended
    arrivals: list[Arrival] = []
    for sent, end, kind, route, connection, browser in steps:
        # a browser's first step: sent at its time, nothing before it to wait for
        think = max(sent - ended[browser], 0.0) if browser in ended else 0.0
        if browser is not None:
            ended[browser] = end
        arrivals.append((sent - first, kind, route, connection, browser, think))
    return arrivals
