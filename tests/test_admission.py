"""A worker's requests run a few at a time, waiting on the event loop (web.admission):
work places for every request until its response starts, write places for state-changing
ones; a body arrives before either is taken."""

from __future__ import annotations

import asyncio
from concurrent.futures import ThreadPoolExecutor

import anyio.to_thread
import httpx

from app.config import get_settings
from app.db import give_way
from app.routes import read_only_routes
from app.web.admission import Admission


class Inside:
    """An ASGI app that counts the requests inside it at once (until their answer starts)
    and echoes the body size; ``/stream`` answers at once, then sends its body late."""

    def __init__(self) -> None:
        self.now = self.most = 0
        self.release = asyncio.Event()

    async def __call__(self, scope, receive, send) -> None:
        body = b""
        while True:
            message = await receive()
            body += message.get("body", b"")
            if not message.get("more_body"):
                break
        if scope["path"] == "/heavy":  # a long job that has taken a pool slot of its own
            await anyio.to_thread.run_sync(give_way)
            await self.release.wait()
            await send({"type": "http.response.start", "status": 200, "headers": []})
            await send({"type": "http.response.body", "body": b"done"})
            return
        if scope["path"] == "/stream":
            await send({"type": "http.response.start", "status": 200, "headers": []})
            await self.release.wait()
            await send({"type": "http.response.body", "body": b"late"})
            return
        self.now += 1
        self.most = max(self.most, self.now)
        await self.release.wait()
        self.now -= 1
        await send({"type": "http.response.start", "status": 200, "headers": []})
        await send({"type": "http.response.body", "body": str(len(body)).encode()})


def places(monkeypatch, work: int, write: int) -> None:
    monkeypatch.setattr(get_settings(), "request_concurrency", work)
    monkeypatch.setattr(get_settings(), "write_concurrency", write)


def run(requests, late=()) -> tuple[Inside, list[httpx.Response]]:
    """``requests`` at once, released after 0.2 s; ``late``: sent after 0.1 s."""
    inside = Inside()
    app = Admission(inside, max_body=1 << 20, read_only_routes=read_only_routes())

    async def main():
        transport = httpx.ASGITransport(app=app)
        async with httpx.AsyncClient(transport=transport, base_url="http://t") as client:
            tasks = [asyncio.create_task(client.request(m, p, content=b)) for m, p, b in requests]
            await asyncio.sleep(0.1)
            tasks += [asyncio.create_task(client.request(m, p, content=b)) for m, p, b in late]
            await asyncio.sleep(0.1)
            inside.before_release = inside.now  # in the app before anything is answered
            inside.release.set()
            return await asyncio.gather(*tasks)

    # a loop of its own in a thread of its own: a session-wide Playwright browser may keep
    # an event loop running in this thread (asyncio.run refuses to nest)
    with ThreadPoolExecutor(1) as pool:
        return inside, pool.submit(asyncio.run, main()).result()


def test_writes_are_admitted_a_few_at_a_time_with_their_whole_body(monkeypatch):
    places(monkeypatch, work=10, write=2)
    inside, replies = run([("POST", "/lab/sessions/1/csv", b"x" * 1000)] * 6)
    assert inside.most == 2
    assert [r.text for r in replies] == ["1000"] * 6


def test_reads_and_posts_declared_read_only_take_no_write_place(monkeypatch):
    places(monkeypatch, work=10, write=2)
    requests = [("GET", "/lab", b"")] * 4 + [("POST", "/lab/sessions/3/csv/preview", b"{}")] * 2
    inside, replies = run(requests)
    assert inside.most == 6
    assert all(r.status_code == 200 for r in replies)


def test_every_request_waits_for_a_work_place(monkeypatch):
    places(monkeypatch, work=2, write=8)
    requests = [("GET", "/lab", b"")] * 3 + [("POST", "/lab/sessions/1/csv", b"x")] * 3
    inside, replies = run(requests)
    assert inside.most == 2
    assert [r.status_code for r in replies] == [200] * 6


def test_a_place_is_given_back_when_the_answer_starts_not_when_its_body_ends(monkeypatch):
    """A streamed export's body goes on without a place: the requests after it run."""
    places(monkeypatch, work=1, write=8)
    inside, replies = run([("GET", "/stream", b"")], late=[("GET", "/lab", b"")] * 3)
    assert inside.before_release == 1 and inside.most == 1
    assert replies[0].text == "late" and [r.text for r in replies[1:]] == ["0"] * 3


def test_a_long_job_with_a_slot_of_its_own_steps_aside(monkeypatch):
    """A PDF render or an Allan analysis is bounded by its own pool (web.work_slots): once
    it has its slot, the requests after it run."""
    places(monkeypatch, work=1, write=8)
    inside, replies = run([("GET", "/heavy", b"")], late=[("GET", "/lab", b"")] * 3)
    assert inside.before_release == 1 and inside.most == 1
    assert replies[0].text == "done" and [r.text for r in replies[1:]] == ["0"] * 3


def test_routes_that_wait_on_another_server_take_no_work_place(monkeypatch):
    places(monkeypatch, work=1, write=8)
    requests = [("GET", "/login/sso/callback", b""), ("POST", "/lti/launch", b"x")]
    requests += [("POST", "/courses/1/lti/sync", b""), ("GET", "/lab", b"")]
    inside, replies = run(requests)
    assert inside.most == 4
    assert all(r.status_code == 200 for r in replies)


def test_a_slow_body_holds_no_place(monkeypatch):
    """Places are taken once the body has arrived: a client still sending does not keep
    the worker's other requests out."""
    places(monkeypatch, work=1, write=1)
    inside = Inside()
    app = Admission(inside, max_body=1 << 20)
    sent: list[str] = []

    async def main():
        started = asyncio.Event()

        async def slow_body():
            yield b"x"
            started.set()
            await asyncio.sleep(0.3)  # the rest of the upload is slow
            yield b"y"

        transport = httpx.ASGITransport(app=app)
        async with httpx.AsyncClient(transport=transport, base_url="http://t") as client:
            slow = asyncio.create_task(client.post("/lab/sessions/1/csv", content=slow_body()))
            await started.wait()
            quick = asyncio.create_task(client.post("/lab/sessions/2/csv", content=b"z"))
            await asyncio.sleep(0.1)
            sent.append(f"inside while the slow body is sent: {inside.now}")
            inside.release.set()
            return await asyncio.gather(slow, quick)

    with ThreadPoolExecutor(1) as pool:
        replies = pool.submit(asyncio.run, main()).result()
    assert sent == ["inside while the slow body is sent: 1"]  # the quick one, not blocked
    assert [r.text for r in replies] == ["2", "1"]
