"""The serial bridge: parsing, a pseudo-terminal written like a real FOG, retries."""

from __future__ import annotations

import os
import re
import threading
import time

import httpx
import numpy as np
import pytest
from sqlmodel import select

from app.bridge import BridgeError, LineParser, Uploader, run_bridge, serial_lines
from app.db import read_session
from app.lab.store import load_samples
from app.models import Take
from tests.factories import PRACTICE, token_for

FOG_LINE = re.compile(r"^\$FOG,\d+,(?P<value>[-+0-9.eE]+),")


def fog_lines(values, garbage_every=7):
    """What a FOG with an RS-232 output prints: a sentence per reading, some noise lines."""
    for index, value in enumerate(values):
        if index % garbage_every == 3:
            yield "$STATUS,OK,TEMP=24.1\r\n"
        yield f"$FOG,{index},{value / 3600:.9f},24.1*5A\r\n"


def test_line_parser():
    parser = LineParser(regex=FOG_LINE, scale=3600.0)
    assert parser.parse("$FOG,1,0.0029750,24.1*5A") == pytest.approx(10.71)
    assert parser.parse("$STATUS,OK") is None and parser.skipped == 1
    assert parser.parse("") is None and parser.skipped == 1
    by_column = LineParser(column=2)
    assert by_column.parse("12:00:01, 10.65, 24.0") == 10.65
    assert by_column.parse("12:00:01;  -8.83") == -8.83
    assert by_column.parse("only") is None
    assert LineParser(column=1).parse("nan") is None


@pytest.fixture
def api_session(client, student):
    headers = token_for(client, "student1")
    client.headers.update(headers)
    session_id = client.post("/api/v1/sessions", json=PRACTICE).json()["id"]
    return client, session_id


def stored_values(session_id) -> np.ndarray:
    with read_session() as db:
        take = db.exec(select(Take).where(Take.session_id == session_id)).one()
        return load_samples(db, take)[0]


def test_a_pseudo_terminal_stream_reaches_the_session(api_session):
    client, session_id = api_session
    master, slave = os.openpty()
    values = np.round(10.7 + 0.1 * np.sin(np.arange(120)), 4)

    def instrument():
        for line in fog_lines(values):
            os.write(master, line.encode("ascii"))
            time.sleep(0.002)

    port = serial_lines(os.ttyname(slave), 115200, timeout_s=0.2)  # open before it talks
    writer = threading.Thread(target=instrument, daemon=True)
    writer.start()
    parser = LineParser(regex=FOG_LINE, scale=3600.0)
    uploader = Uploader(client, session_id, "heading", 1, batch=25)
    sent = run_bridge(port, parser, uploader, max_samples=120, seconds=30, progress=None)
    writer.join(5)
    os.close(master)
    os.close(slave)
    assert sent == 120
    assert stored_values(session_id) == pytest.approx(values, abs=1e-5)
    assert parser.skipped > 0  # the status lines were passed over


class LosesAnswers(httpx.BaseTransport):
    """Delivers every request, but the answer of every third one is lost on the way back."""

    def __init__(self, inner: httpx.BaseTransport) -> None:
        self.inner = inner
        self.count = 0

    def handle_request(self, request: httpx.Request) -> httpx.Response:
        self.count += 1
        response = self.inner.handle_request(request)
        if self.count % 3 == 2:
            response.read()
            raise httpx.ReadError("connection reset", request=request)
        return response


def test_retries_never_duplicate_samples(api_session):
    client, session_id = api_session
    client._transport = LosesAnswers(client._transport)
    values = np.arange(100, dtype=float) / 10
    uploader = Uploader(client, session_id, "latitude", 2, batch=10, backoff_s=0.001)
    sent = run_bridge((f"{v}\n" for v in values), LineParser(column=1), uploader, progress=None)
    assert sent == 100 and uploader.attempts > 10  # some batches were sent twice
    assert stored_values(session_id).tolist() == values.tolist()


def test_refused_upload_is_reported(api_session):
    client, session_id = api_session
    uploader = Uploader(client, session_id, "heading", 1, unit="deg/s", batch=5)
    with pytest.raises(BridgeError, match="check the unit"):
        run_bridge(["10.7\n"] * 5, LineParser(column=1), uploader, progress=None)
