"""At most a few state-changing requests of a worker inside the app at once.

Why: every database call runs on the worker's thread pool (40 threads).  A write request
begins its transaction in one trip to the pool (the route's dependencies) and finishes it
in another (the handler).  When a queue of writers filled every thread, each waiting for
the write lock, the writer holding the lock waited for a free thread to finish: nothing
moved until SQLite's busy timeout (10 s) failed them all (seen in the 60-student load
test: every route, reads too, stalled for 8-10 s).  Writers now queue *here*, on the
event loop, where waiting costs no thread: at most ``GYROLAB_WRITE_CONCURRENCY`` of them
(default 8) hold threads, so the lock holder and readers always find one.

A request is admitted once its body has arrived (a slow upload does not hold a place);
the WebSocket stream's saves take a place the same way (:func:`write_slot`).
"""

from __future__ import annotations

import asyncio
import weakref
from collections.abc import AsyncIterator, Sequence
from contextlib import asynccontextmanager

from starlette.types import ASGIApp, Message, Receive, Scope, Send

from app.config import get_settings

SAFE_METHODS = {"GET", "HEAD", "OPTIONS"}
_semaphores: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def _semaphore() -> asyncio.Semaphore:
    """This event loop's semaphore (a worker has one loop; tests may run several)."""
    loop = asyncio.get_running_loop()
    semaphore = _semaphores.get(loop)
    if semaphore is None:
        semaphore = _semaphores[loop] = asyncio.Semaphore(get_settings().write_concurrency)
    return semaphore


@asynccontextmanager
async def write_slot() -> AsyncIterator[None]:
    """One of the worker's places for a state-changing operation (waits on the loop)."""
    async with _semaphore():
        yield


class WriteAdmission:
    """ASGI middleware: state-changing HTTP requests wait for a :func:`write_slot` once
    their body has been received (bounded by ``max_body``: past it, the app's own body
    limit answers).  ``read_only_routes``: the routes that declare
    ``web.deps.ReadOnlySession`` (``app.routes.read_only_routes``), which pass at once."""

    def __init__(self, app: ASGIApp, max_body: int, read_only_routes: Sequence = ()) -> None:
        self.app = app
        self.max_body = max_body
        self.read_only = [(route.path_regex, route.methods) for route in read_only_routes]

    def reads_only(self, scope: Scope) -> bool:
        """Whether the request is for a route declared read-only."""
        return any(
            scope["method"] in methods and pattern.match(scope["path"])
            for pattern, methods in self.read_only
        )

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] != "http" or scope["method"] in SAFE_METHODS or self.reads_only(scope):
            await self.app(scope, receive, send)
            return
        received: list[Message] = []
        size = 0
        while True:
            message = await receive()
            received.append(message)
            if message["type"] != "http.request":
                break  # the client went away
            size += len(message.get("body", b""))
            if not message.get("more_body", False) or size > self.max_body:
                break
        pending = iter(received)

        async def replay() -> Message:
            message = next(pending, None)
            return message if message is not None else await receive()

        async with write_slot():
            await self.app(scope, replay, send)
