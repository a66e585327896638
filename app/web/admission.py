"""A worker's requests admitted into the app a few at a time, waiting on the event loop.

Why: the worker's threads share one interpreter.  When a class's requests all run at once
(60 students saving and reading within a few seconds) each gets a sliver of it, and the
request holding SQLite's write lock gets a sliver too: a CSV save held the lock 17 ms for
4 ms of its own work, and the writes queued for the lock for most of a second
(bench/README.md, issue 32).  So:

- **work places**: at most ``GYROLAB_REQUEST_CONCURRENCY`` (default 2) HTTP requests of a
  worker run at once, the rest wait their turn on the event loop, where waiting costs no
  thread and no interpreter.  A place is held until the response *starts*: a streamed
  export or report body goes on without one.  Routes that mostly wait on another server
  (single sign-on, LTI launches and registration, an LMS roster or grade) do not take one.
  A request gives its place back (``db.give_way``) when it must wait for a lock another
  holds -- a write's ``BEGIN IMMEDIATE`` on SQLite, or its turn, once slow to come; the
  writers' advisory lock on PostgreSQL (tried first: a row writer's shared lock is almost
  always free at once) -- so that writers waiting on a backup, another process or each
  other never keep the worker's reads out; when a log-in hashes its password (outside the
  interpreter, bounded by its own slots); and when a long job takes a slot of a pool of its
  own (``web.work_slots``: PDF reports, the class zip, an Allan analysis).  The lock holder
  thus shares the interpreter with at most the few admitted requests.
- **write places**: at most ``GYROLAB_WRITE_CONCURRENCY`` (default 8) state-changing
  requests or stream saves hold threads at once (:func:`write_slot`).  Before, a queue of
  writers filled every thread of the pool, each waiting for the write lock, and the writer
  holding the lock waited for a free thread to finish: nothing moved until SQLite's busy
  timeout (10 s) failed them all (seen in the 60-student load test).

A request with a body takes its places once the body has arrived (a slow upload holds
none), bounded by ``max_body`` (past it, the app's own body limit answers).  Neither kind
of place is taken inside a thread, so a request that holds SQLite's lock always finds a
thread to finish on.
"""

from __future__ import annotations

import asyncio
import re
import weakref
from collections.abc import AsyncIterator, Sequence
from contextlib import asynccontextmanager

from starlette.types import ASGIApp, Message, Receive, Scope, Send

from app.config import get_settings
from app.db import give_way_hook

SAFE_METHODS = {"GET", "HEAD", "OPTIONS"}
# routes whose time is spent waiting on another server: they take no work place
WAITING_ON_OTHERS = re.compile(r"^/login/sso(/|$)|/lti(/|$)")
_write_places: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()
_work_places: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def _semaphore(places: weakref.WeakKeyDictionary, size: int) -> asyncio.Semaphore:
    """This event loop's semaphore (a worker has one loop; tests may run several)."""
    loop = asyncio.get_running_loop()
    semaphore = places.get(loop)
    if semaphore is None:
        semaphore = places[loop] = asyncio.Semaphore(size)
    return semaphore


@asynccontextmanager
async def write_slot() -> AsyncIterator[None]:
    """One of the worker's places for a state-changing operation (waits on the loop)."""
    async with _semaphore(_write_places, get_settings().write_concurrency):
        yield


class Admission:
    """ASGI middleware: HTTP requests wait for a work place (released when the response
    starts), and state-changing ones for a write place too (held to the end), each once
    its body has been received.  ``read_only_routes``: the routes that declare
    ``web.deps.ReadOnlySession`` (``app.routes.read_only_routes``), which take no write
    place."""

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
        if scope["type"] != "http":
            await self.app(scope, receive, send)
            return
        writes = scope["method"] not in SAFE_METHODS and not self.reads_only(scope)
        if scope["method"] not in SAFE_METHODS:
            receive = await self._whole_body(receive)
        if WAITING_ON_OTHERS.search(scope["path"]):
            await self._write_place(writes, scope, receive, send)
            return
        work = _semaphore(_work_places, get_settings().request_concurrency)
        await work.acquire()
        holding = True
        loop = asyncio.get_running_loop()

        def give_back() -> None:  # on the loop only
            nonlocal holding
            if holding:
                holding = False
                work.release()

        # from any thread; nothing to schedule once the place is back
        give_way_hook.set(lambda: holding and loop.call_soon_threadsafe(give_back))

        async def send_then_give_back(message: Message) -> None:
            if message["type"] == "http.response.start":
                give_back()  # the answer is ready: what follows is its body
            await send(message)

        try:
            await self._write_place(writes, scope, receive, send_then_give_back)
        finally:
            give_back()

    async def _write_place(self, writes: bool, scope: Scope, receive: Receive, send: Send):
        if not writes:
            await self.app(scope, receive, send)
            return
        async with write_slot():
            await self.app(scope, receive, send)

    async def _whole_body(self, receive: Receive) -> Receive:
        """Receive the body (up to ``max_body``) now; the app reads it from memory."""
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

        return replay
