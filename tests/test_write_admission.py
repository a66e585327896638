"""State-changing requests queue on the event loop, a few at a time, once their body has
arrived; reads and read-only POSTs pass straight through."""

from __future__ import annotations

import asyncio
from concurrent.futures import ThreadPoolExecutor

import httpx
import pytest

from app.config import get_settings
from app.routes import read_only_routes
from app.web.write_admission import WriteAdmission


class Inside:
    """An ASGI app that counts the requests inside it at once and echoes the body size."""

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
        self.now += 1
        self.most = max(self.most, self.now)
        await self.release.wait()
        self.now -= 1
        await send({"type": "http.response.start", "status": 200, "headers": []})
        await send({"type": "http.response.body", "body": str(len(body)).encode()})


@pytest.fixture
def limit(monkeypatch) -> int:
    monkeypatch.setattr(get_settings(), "write_concurrency", 2)
    return 2


def run(requests) -> tuple[Inside, list[httpx.Response]]:
    inside = Inside()
    app = WriteAdmission(inside, max_body=1 << 20, read_only_routes=read_only_routes())

    async def main():
        transport = httpx.ASGITransport(app=app)
        async with httpx.AsyncClient(transport=transport, base_url="http://t") as client:
            tasks = [asyncio.create_task(client.request(m, p, content=b)) for m, p, b in requests]
            await asyncio.sleep(0.2)
            inside.release.set()
            return await asyncio.gather(*tasks)

    # a loop of its own in a thread of its own: a session-wide Playwright browser may keep
    # an event loop running in this thread (asyncio.run refuses to nest)
    with ThreadPoolExecutor(1) as pool:
        return inside, pool.submit(asyncio.run, main()).result()


def test_writes_are_admitted_a_few_at_a_time_with_their_whole_body(limit):
    inside, replies = run([("POST", "/lab/sessions/1/csv", b"x" * 1000)] * 6)
    assert inside.most == limit
    assert [r.text for r in replies] == ["1000"] * 6


def test_reads_and_posts_declared_read_only_are_not_held_back(limit):
    requests = [("GET", "/lab", b"")] * 4 + [("POST", "/lab/sessions/3/csv/preview", b"{}")] * 2
    inside, replies = run(requests)
    assert inside.most == 6
    assert all(r.status_code == 200 for r in replies)
