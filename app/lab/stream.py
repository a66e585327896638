"""Live readings from the simulated gyro over a WebSocket, in batched frames.

Protocol (JSON text frames):
  client → {"action": "start", "part": "heading", "position": 2, "dwell_s": 30,
            "settle_s": 5, "speed": 10}
  server → {"type": "started", "rate_hz": 1.0, "total": 30, "dial_angle_deg": -90}
  server → {"type": "samples", "t": [...], "v": [...], "done": 12, "total": 30}
  client → {"action": "stop"}           (ends the dwell early; what was recorded is kept)
  server → {"type": "saved", "position": 2, "n": 30}  or  {"type": "error", "message": ...}

A frame that is not such an object (not JSON, not UTF-8, NaN, a number past 300 digits,
nesting too deep, an unknown action) is answered with an error between recordings and
ignored during one; the connection stays open either way.

Only measured readings leave the server: the run's true azimuth, biases and indexing
errors stay in the database.  A recording is saved in one transaction when it ends; a
dropped connection saves nothing and the page says the position must be recorded again.
"""

from __future__ import annotations

import asyncio
import math
from urllib.parse import urlsplit

import numpy as np
from fastapi import APIRouter, WebSocket, WebSocketDisconnect
from sqlalchemy.exc import DBAPIError
from starlette.concurrency import run_in_threadpool

from app.accounts.deps import login_for_cookie
from app.config import get_settings
from app.core.exceptions import UserError
from app.core.jsonsafe import loads_finite
from app.db import database_busy, read_session, write_session
from app.lab.service import locked_session, record_position, recordable_session
from app.lab.sim import (
    MAX_DWELL_S,
    MAX_SETTLE_S,
    SimulatedTake,
    position_count,
    set_gyro_clock,
)
from app.lab.store import PARTS, POSITIONS
from app.models import InputMethod, LabSession, User
from app.web.admission import write_slot
from app.web.deps import ObjectId
from app.web.errors import message_for
from app.web.render import SESSION_COOKIE, request_language

router = APIRouter(tags=["streams"])

FRAME_SECONDS = 0.2
MAX_SPEED = 60.0
INBOX_FRAMES = 64
# The largest client frame the server reads (``gyrolab serve`` gives it to uvicorn, which
# closes the socket with 1009 on a longer one): the page's frames are under 200 bytes, and a
# frame is parsed on the event loop every student's stream shares -- uvicorn's 16 MiB
# default let one student hold it 0.5 s a frame (12 MB of numbers), 64 KiB at most ≈ 3 ms.
MAX_FRAME_BYTES = 64 * 1024


def _same_origin(websocket: WebSocket) -> bool:
    origin = websocket.headers.get("origin")
    if not origin:
        return True  # not a browser (browsers always send Origin on WebSockets)
    host = websocket.headers.get("host", "")
    return urlsplit(origin).netloc == host


def _owner(websocket: WebSocket, session_id: int) -> tuple[User, LabSession] | None:
    """The cookie's user and their session, when it may be recorded from the simulator."""
    with read_session() as db:
        found = login_for_cookie(db, websocket.cookies.get(SESSION_COOKIE), get_settings())
        if found is None or found[0].must_change_password:
            return None
        try:
            session = recordable_session(db, found[0], session_id, InputMethod.simulator)
        except UserError:
            return None
        return found[0], session


def _locked(db, session_id: int) -> LabSession:
    """The session in a row writer's transaction, its rows locked (see own_session)."""
    session = locked_session(db, session_id)
    if session is None:  # deleted while streaming: the stream's write fails, not a 500
        raise UserError("lab.no_such_session", status=404)
    return session


def _mark_started(cookie: str | None, session_id: int, part: str, position: int) -> LabSession:
    """Mark the session as streaming ``part``'s ``position``, in one write transaction
    with the checks a recording needs each time it starts: the cookie's log-in still live
    and its user still the session's (a password changed or a log-out since the socket
    opened ends the stream), the assignment still allowing the simulator, the position on
    the schedule and the table turned to it."""
    with write_session(rows=True) as db:
        found = login_for_cookie(db, cookie, get_settings())
        if found is None or found[0].must_change_password:
            raise UserError("stream.gone")
        try:
            session = recordable_session(db, found[0], session_id, InputMethod.simulator)
        except UserError:
            raise UserError("stream.gone") from None
        if position > position_count(session):
            raise UserError("lab.needs_symmetric", position=position)
        if getattr(session, f"sim_table_{part}") != position:
            raise UserError("stream.turn_first", position=position)
        session.stream_part, session.stream_position = part, position
        db.add(session)
        return session


def _save(
    session_id: int, part: str, position: int, dial: float, values, times, end_s: float
) -> int:
    with write_session(rows=True) as db:
        session = _locked(db, session_id)
        session.stream_part = session.stream_position = None
        set_gyro_clock(session, end_s)  # the gyro ran through the recording
        record_position(
            db,
            session,
            part=part,
            position=position,
            values=np.asarray(values),
            times=np.asarray(times),
            angle_deg=dial,
            source=InputMethod.simulator,
        )
        return len(values)


def _clear_mark(session_id: int) -> None:
    with write_session(rows=True) as db:
        session = _locked(db, session_id)
        session.stream_part = session.stream_position = None
        db.add(session)


def _number(message: dict, name: str, default: float, low: float, high: float) -> float:
    value = message.get(name, default)
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise UserError("stream.bad_number", name=name)
    if isinstance(value, float) and not math.isfinite(value):
        raise UserError("stream.bad_number", name=name)
    if not low <= value <= high:  # (an int of any size compares; float() of one may overflow)
        raise UserError("stream.out_of_range", name=name, low=low, high=high)
    return float(value)


@router.websocket("/lab/sessions/{session_id}/stream")
async def stream(websocket: WebSocket, session_id: ObjectId) -> None:
    if not _same_origin(websocket):
        await websocket.close(code=4403)
        return
    found = await run_in_threadpool(_owner, websocket, session_id)
    if found is None:
        await websocket.close(code=4404)
        return
    language = request_language(websocket)
    await websocket.accept()
    inbox: asyncio.Queue = asyncio.Queue(maxsize=INBOX_FRAMES)  # a flood waits in the socket
    reader = asyncio.create_task(_read_into(websocket, inbox))
    try:
        while True:
            message = await inbox.get()
            if message is None:
                return
            try:
                if isinstance(message, UserError):
                    raise message
                if message.get("action") == "stop":
                    continue  # after the recording it ended (or a second click): nothing to do
                if message.get("action") != "start":
                    raise UserError("stream.bad_frame")
                await _record(websocket, session_id, message, inbox)
            except UserError as error:
                await websocket.send_json(
                    {
                        "type": "error",
                        "key": error.key,
                        "message": message_for(error, language),
                    }
                )
    except (WebSocketDisconnect, RuntimeError, _Closed):
        return
    finally:
        reader.cancel()


class _Closed(Exception):
    """The client went away during a recording: nothing is saved."""


async def _read_into(websocket: WebSocket, inbox: asyncio.Queue) -> None:
    """Read client frames into a queue (so waiting for a 'stop' never loses a frame): each
    a JSON object, or the ``UserError`` that says why it is none; ``None`` when the client
    has gone.  No frame ends the reading: a binary frame is read as UTF-8 text, and one
    that cannot be parsed is refused in words (``loads_finite``)."""
    try:
        while True:
            frame = await websocket.receive()
            if frame["type"] == "websocket.disconnect":
                break
            await inbox.put(_message(frame))
    except (WebSocketDisconnect, RuntimeError):
        pass
    await inbox.put(None)


def _message(frame: dict) -> dict | UserError:
    """A received frame as the client's JSON object, or the error that says why not."""
    text = frame.get("text")
    if text is None:
        text = frame.get("bytes") or b""
    try:
        message = loads_finite(text)
    except UserError as error:
        return UserError("stream.bad_frame") if error.key == "json.invalid" else error
    return message if isinstance(message, dict) else UserError("stream.bad_frame")


_TICK = object()  # FramePacer: the frame's time came first (no client frame)


class FramePacer:
    """When a recording's next frame of samples is due, and how many samples are due by
    then: a frame every ``FRAME_SECONDS`` of the event loop's clock, or at once when the
    client says stop.  The server alone paces a recording -- samples are due by the clock
    (``samples_per_s`` × the time since the start) -- so frames a client sends in between
    change nothing.

    The timer's firing is the tick.  uvicorn runs on uvloop, whose clock counts whole
    milliseconds and whose timers are set in whole milliseconds: a timer can fire while
    ``loop.time()`` still reads up to 1 ms before its deadline.  Waiting again until the
    clock agrees would spin the event loop through that millisecond: dozens of wake-ups a
    frame on a quiet server, about four in a class of 60 (bench/README.md, part 48).  A
    tick's samples are those due by the tick's own time (ticks multiplied out, not summed,
    and 1 µs allowed for rounding): the time since the start falls a rounding error short
    of a sample due exactly at a tick more often than not, and that sample would wait a
    frame."""

    def __init__(
        self, inbox: asyncio.Queue, samples_per_s: float, frame_s: float = FRAME_SECONDS
    ) -> None:
        self.inbox = inbox
        self.samples_per_s = samples_per_s
        self.frame_s = frame_s
        self.loop = asyncio.get_running_loop()
        self.started = self.anchor = self.loop.time()
        self.ticks = 1  # the next tick: anchor + ticks × frame_s

    @property
    def next_tick(self) -> float:
        return self.anchor + self.ticks * self.frame_s

    async def due(self) -> tuple[int, bool]:
        """Wait for the next frame: (how many samples are due since the start, whether the
        client stopped).  Raises ``_Closed`` when the client went away."""
        while True:
            deadline = self.next_tick
            try:  # (asyncio.timeout_at, not wait_for: no task made per frame, ≈ 60 µs less)
                async with asyncio.timeout_at(deadline):
                    incoming = await self.inbox.get()
            except TimeoutError:
                incoming = _TICK
            if incoming is None:
                raise _Closed()
            now = self.loop.time()
            ticked = incoming is _TICK
            stopped = isinstance(incoming, dict) and incoming.get("action") == "stop"
            if ticked or stopped or now >= deadline:
                break
            # any other client frame before the tick: not a reason to send samples
        due_at = max(now, deadline) if ticked else now
        if now < deadline + self.frame_s:
            self.ticks += 1
        else:  # a frame or more late: the next frame at once, and the ticks counted anew
            self.anchor, self.ticks = now, 0
        # (+1 µs: the clock's arithmetic is exact to a few ns; no sample waits for it)
        return int(self.samples_per_s * (due_at - self.started + 1e-6)), stopped


async def _record(
    websocket: WebSocket, session_id: int, message: dict, inbox: asyncio.Queue
) -> None:
    part, position = message.get("part"), message.get("position")
    if (
        part not in PARTS
        or isinstance(position, bool)  # JSON's true is no position (Python's int 1)
        or not isinstance(position, int)
        or not 1 <= position <= POSITIONS
    ):
        raise UserError("stream.bad_position")
    dwell = _number(message, "dwell_s", 30.0, 1.0, MAX_DWELL_S)
    settle = _number(message, "settle_s", 0.0, 0.0, MAX_SETTLE_S)
    speed = _number(message, "speed", 1.0, 0.1, MAX_SPEED)
    cookie = websocket.cookies.get(SESSION_COOKIE)
    async with write_slot():
        session = await run_in_threadpool(_mark_started, cookie, session_id, part, position)
    # the take replays the gyro's noise since switch-on (up to 6 h: 216,000 samples at
    # 10 Hz, ≈ 60 ms) and makes the recording's: in the pool, so that the other students'
    # frames are not held up
    take = await run_in_threadpool(SimulatedTake, session, part, position, settle, dwell_s=dwell)
    total = take.samples_in(dwell)
    await websocket.send_json(
        {
            "type": "started",
            "rate_hz": take.rate_hz,
            "total": total,
            "dial_angle_deg": take.dial_angle_deg,
            "part": part,
            "position": position,
        }
    )
    values, times = [], []
    pacer = FramePacer(inbox, take.rate_hz * speed)
    stopped = False
    while len(values) < total and not stopped:
        due, stopped = await pacer.due()
        count = min(total, due) - len(values)
        if stopped and not values:
            count = max(count, 1)
        if count <= 0:
            continue
        batch, batch_times = take.next(count)
        values.extend(batch.tolist())
        times.extend(batch_times.tolist())
        await websocket.send_json(
            {
                "type": "samples",
                "t": batch_times.tolist(),
                "v": batch.tolist(),
                "done": len(values),
                "total": total,
            }
        )
    try:
        async with write_slot():
            saved = await run_in_threadpool(
                _save, session_id, part, position, take.dial_angle_deg, values, times, take.end_s
            )
    except UserError:  # e.g. stopped before the minimum number of readings
        async with write_slot():
            await run_in_threadpool(_clear_mark, session_id)
        raise
    except DBAPIError as error:  # the write lock stayed taken past the busy timeout
        if not database_busy(error):
            raise
        raise UserError("error.busy") from error  # nothing was saved: the client says so
    await websocket.send_json({"type": "saved", "part": part, "position": position, "n": saved})
