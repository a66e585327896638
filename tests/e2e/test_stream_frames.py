"""The live stream's frame limit, which only a real server has: uvicorn reads no client
frame longer than ``app.lab.stream.MAX_FRAME_BYTES`` (its own default, 16 MiB, let one
student hold every stream of the worker's event loop for 0.5 s with each frame of
numbers), closing that socket alone."""

from __future__ import annotations

import json

import pytest
from websockets.exceptions import ConnectionClosedError
from websockets.sync.client import connect

from app.lab.stream import MAX_FRAME_BYTES
from tests.e2e.conftest import STUDENT_PASSWORD, LiveServer
from tests.e2e.test_concurrency import cookie_login

pytestmark = pytest.mark.e2e


def test_a_frame_past_the_limit_closes_its_socket_alone(live_server: LiveServer):
    browser, csrf = cookie_login(live_server.url, "student", STUDENT_PASSWORD)
    reply = browser.post("/lab/sessions", data={"station": "handout", "csrf_token": csrf})
    session_id = int(reply.headers["location"].rsplit("/", 1)[1])
    url = live_server.url.replace("http", "ws", 1) + f"/lab/sessions/{session_id}/stream"
    headers = {
        "Cookie": "; ".join(f"{name}={value}" for name, value in browser.cookies.items()),
        "Origin": live_server.url,
    }

    def padded(size: int) -> str:  # a JSON object of exactly ``size`` bytes
        return json.dumps({"pad": ""})[:-2] + "x" * (size - 11) + '"}'

    with (
        connect(url, additional_headers=headers) as near,
        connect(url, additional_headers=headers) as far,
    ):
        near.send(padded(MAX_FRAME_BYTES))
        assert json.loads(near.recv(timeout=10))["key"] == "stream.bad_frame"
        far.send(padded(MAX_FRAME_BYTES + 1))
        with pytest.raises(ConnectionClosedError) as closed:
            far.recv(timeout=10)
        assert closed.value.rcvd.code == 1009  # "message too big"
        near.send(json.dumps({"action": "start", "part": "heading", "position": 9}))
        assert json.loads(near.recv(timeout=10))["key"] == "stream.bad_position"
