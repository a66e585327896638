"""Probes for the benchmarks, loaded by a server only when this folder is on its
``PYTHONPATH`` and one of these names a file (never part of the app otherwise):

``GYROLAB_BENCH_PROBE`` (``queue_model.py``'s measuring run): a 16-byte file in which it
counts the places where a request's thread gives up the interpreter -- database calls
(SQLite's execute and fetch: each runs ``sqlite3_step`` with the GIL released;
PostgreSQL's round trips: psycopg's statements and its BEGIN, COMMIT and ROLLBACK) and
trips to the thread pool (anyio's ``to_thread.run_sync``).

``GYROLAB_BENCH_SQLITE_CALLS`` (a load test): a file to which each SQLite call that runs
the database with the GIL released (execute, executemany, fetch) appends the CPU its thread
spent in it, µs: how long the interpreter is left to others at each call (a waiting thread
is woken for it; ``bench_handoffs.py`` measures how long a call must last for it to run).

``GYROLAB_BENCH_LOCK_TRACE`` (a load test): a file to which each SQLite write transaction
appends one line, ``wall_ms cpu_ms kind method path function``: how long it held the write
lock (``BEGIN IMMEDIATE`` to the end of its commit or rollback), the CPU its thread spent
meanwhile, the request or WebSocket it was for and the function the thread pool ran it in
(``-`` where there was none: start-up, the CLI), and how long it waited for its turn
(``app.writer_turn``) before ``BEGIN IMMEDIATE``, ms (the wall from asking to being granted;
``-`` for a write that did not ask).

``GYROLAB_BENCH_SERVER_TIMES`` (a load test): a file to which each HTTP request appends
``method path ms waited_ms began_s pid``: from when the app is called (uvicorn has read
the request's head) to its answer's start -- the server's part of the latency the load
generator measures -- and of it the wait before the app proper began (the body, a work
place); when it was called (``time.perf_counter``, the machine's monotonic clock, the
same in every process); and which worker answered.  A WebSocket appends ``WS path - -
began_s pid`` when it connects: which worker its connection reached.

``GYROLAB_BENCH_REQUEST_CPU`` (a load test, or ``queue_model.py``'s measuring run): a
file to which each HTTP request and each WebSocket appends ``kind method path loop_ms
threads_ms frames``: the CPU its own task spent on the event loop (each step of the app's
coroutine, timed by the thread's CPU clock) and in the thread pool (each function it sent
there), and for a WebSocket the frames of samples it sent and its thread-pool CPU by
function (``name=ms,…``: the stream's marks, takes and saves).  What no request's task runs -- the
server reading and writing sockets, the collector, other threads -- is not in it.

``GYROLAB_BENCH_GC`` (a load test): a file to which each of the process's garbage
collections appends ``pid generation ms collected began`` (``began``: ``time.perf_counter``
at its start, the clock of ``GYROLAB_BENCH_CLIENT_TIMES``), and a full one also how many
objects the collector now keeps in its oldest generation, and of which types most
(``type:count``).

``GYROLAB_BENCH_PROFILE`` (a load test): a folder in which each worker keeps, rewritten
after every 100 profiled calls (a stopped server may not run its exit code), one
``cProfile`` file per route (``PID-ROUTE.prof``, for ``pstats``) of every
function the route's requests sent to the thread pool, timed by the thread's CPU clock --
where a class's thread-pool CPU goes (``GYROLAB_BENCH_REQUEST_CPU`` says how much).

``GYROLAB_BENCH_REQUEST_WAITS`` (a load test): a file to which each HTTP request appends
where its time inside the server went, ms: ``method path total admitted loop_cpu
loop_wall dispatch thread_cpu thread_wall thread_queued back trips began_s pid`` -- from
when the app is called to its end, of it the wait before the app proper began (the body,
a work place); its coroutine's steps on the event loop (CPU, and wall: a step that loses
the interpreter or its core takes longer); per function sent to the thread pool, from
sending it to its start (a thread woken, the interpreter taken), its CPU and wall in the
thread and of that wall the thread's wait for a core (the kernel's
``/proc/thread-self/schedstat``: the rest of the wall is waiting for the interpreter or
for the write lock), and from its end to the coroutine's next step (the loop woken, the
interpreter taken, the loop's other callbacks first); the trips to the thread pool; when
it was called (``time.perf_counter``) and which worker answered.  The probe's own reads
of ``schedstat`` are in the thread's CPU.

``GYROLAB_BENCH_GIL_WAITS`` (a load test): a file to which a thread of each process that
loads the probe (the server's workers, and the load generator when it has the probe on
its path) appends, every nap of 2 ms, ``began_s late_µs queued_µs pid``: how much later
than the nap's end the thread ran Python again, and of that how long it waited for a core
(``schedstat``) -- the rest is the wait for the interpreter.  A thread that wants the
interpreter at a moment chosen by nothing in the class: how crowded the interpreter and
the cores were, sampled 500 times a second.

``GYROLAB_BENCH_TRIPS`` (a load test): a file to which each trip to the thread pool, of an
HTTP request or a WebSocket (a stream's marks, takes and saves), appends ``kind method
path function sent began ended resumed pid``: when the coroutine sent the function, when a
thread began and ended it, and when the coroutine ran again (``time.perf_counter``, s) --
each trip's dispatch, its time in the thread and its way back, per request and per
position streamed.
"""

import os

_COUNTS = os.environ.get("GYROLAB_BENCH_PROBE")
_LOCKS = os.environ.get("GYROLAB_BENCH_LOCK_TRACE")
_TIMES = os.environ.get("GYROLAB_BENCH_SERVER_TIMES")
_GC = os.environ.get("GYROLAB_BENCH_GC")
_CPU = os.environ.get("GYROLAB_BENCH_REQUEST_CPU")
_PROFILE = os.environ.get("GYROLAB_BENCH_PROFILE")
_CALLS = os.environ.get("GYROLAB_BENCH_SQLITE_CALLS")
_WAITS = os.environ.get("GYROLAB_BENCH_REQUEST_WAITS")
_GIL = os.environ.get("GYROLAB_BENCH_GIL_WAITS")
_TRIPS = os.environ.get("GYROLAB_BENCH_TRIPS")

if _GC:
    import gc as _gc
    import time as _gc_time

    _gc_file = os.open(_GC, os.O_WRONLY | os.O_APPEND | os.O_CREAT)
    _gc_began = [0.0]

    def _gc_timed(phase, info):
        if phase == "start":
            _gc_began[0] = _gc_time.perf_counter()
            return
        took = (_gc_time.perf_counter() - _gc_began[0]) * 1000
        line = (
            f"{os.getpid()} {info['generation']} {took:.3f} {info['collected']} {_gc_began[0]:.6f}"
        )
        if info["generation"] == 2:
            from collections import Counter

            kept = _gc.get_objects(2)
            kinds = Counter(type(o).__qualname__ for o in kept).most_common(8)
            line += f" {len(kept)} " + " ".join(f"{k}:{n}" for k, n in kinds)
        os.write(_gc_file, (line + "\n").encode())

    _gc.callbacks.append(_gc_timed)

if _TIMES:
    import time as _time

    from fastapi import applications as _applications
    from starlette.middleware import exceptions as _exceptions

    _times = os.open(_TIMES, os.O_WRONLY | os.O_APPEND | os.O_CREAT)
    _call = _applications.FastAPI.__call__

    async def _timed_call(self, scope, receive, send):
        if scope["type"] == "websocket":  # which worker the connection reached
            line = f"WS {scope['path']} - - {_time.perf_counter():.6f} {os.getpid()}\n"
            os.write(_times, line.encode())
        if scope["type"] != "http":
            return await _call(self, scope, receive, send)
        began = _time.perf_counter()
        scope["bench.admitted"] = None

        async def timed_send(message):
            if message["type"] == "http.response.start":
                took = (_time.perf_counter() - began) * 1000
                admitted = scope["bench.admitted"]
                waited = (admitted - began) * 1000 if admitted else took
                line = (
                    f"{scope['method']} {scope['path']} {took:.3f} {waited:.3f} {began:.6f}"
                    f" {os.getpid()}\n"
                )
                os.write(_times, line.encode())
            await send(message)

        return await _call(self, scope, receive, timed_send)

    _applications.FastAPI.__call__ = _timed_call
    _inner = _exceptions.ExceptionMiddleware.__call__  # the next app inside the admission

    async def _admitted(self, scope, receive, send):
        if "bench.admitted" in scope and scope["bench.admitted"] is None:
            scope["bench.admitted"] = _time.perf_counter()
        return await _inner(self, scope, receive, send)

    _exceptions.ExceptionMiddleware.__call__ = _admitted

if _COUNTS or _LOCKS or _CALLS:
    import sqlite3
    import sqlite3.dbapi2
    import struct
    import threading
    import time

    if _COUNTS:
        import mmap

        _file = open(_COUNTS, "r+b")  # noqa: SIM115 (held for the process's life)
        _counts = mmap.mmap(_file.fileno(), 16)

        def _add(slot: int) -> None:
            (value,) = struct.unpack_from("<q", _counts, slot * 8)
            struct.pack_into("<q", _counts, slot * 8, value + 1)

    else:

        def _add(slot: int) -> None:
            pass

    _trace = os.open(_LOCKS, os.O_WRONLY | os.O_APPEND | os.O_CREAT) if _LOCKS else None
    if _LOCKS:
        import contextvars as _lock_contextvars

        # set by the thread-pool function (below); the request by _request_for
        _lock_in = _lock_contextvars.ContextVar("gyrolab_bench_lock_in", default="-")
        # the wait for the writers' turn of the write this thread is about to begin
        _turn_waited = threading.local()

        from app import writer_turn as _writer_turn

        _turn_acquire = _writer_turn.WriterTurn.acquire

        def _timed_acquire(self, *args, **kwargs):
            asked = time.perf_counter()
            try:
                return _turn_acquire(self, *args, **kwargs)
            finally:
                _turn_waited.ms = (time.perf_counter() - asked) * 1000

        _writer_turn.WriterTurn.acquire = _timed_acquire

    if _CALLS:
        _calls = os.open(_CALLS, os.O_WRONLY | os.O_APPEND | os.O_CREAT)

        def _sqlite_call(call, *args, **kwargs):
            began = time.thread_time_ns()
            try:
                return call(*args, **kwargs)
            finally:
                os.write(_calls, f"{(time.thread_time_ns() - began) / 1000:.1f}\n".encode())

    else:

        def _sqlite_call(call, *args, **kwargs):
            return call(*args, **kwargs)

    class _CountingCursor(sqlite3.Cursor):
        def execute(self, sql, *args, **kwargs):
            _add(0)
            if _trace is not None and sql.startswith("BEGIN IMMEDIATE"):
                self.connection.began = (time.perf_counter(), time.thread_time())
            return _sqlite_call(super().execute, sql, *args, **kwargs)

        def executemany(self, *args, **kwargs):
            _add(0)
            return _sqlite_call(super().executemany, *args, **kwargs)

        def fetchone(self):
            _add(0)
            return _sqlite_call(super().fetchone)

        def fetchmany(self, *args, **kwargs):
            _add(0)
            return _sqlite_call(super().fetchmany, *args, **kwargs)

        def fetchall(self):
            _add(0)
            return _sqlite_call(super().fetchall)

    class _CountingConnection(sqlite3.Connection):
        began = None

        def cursor(self, factory=_CountingCursor):
            return super().cursor(factory)

        def execute(self, sql, *args, **kwargs):  # the app begins on the connection itself
            _add(0)
            if _trace is not None and sql.startswith("BEGIN IMMEDIATE"):
                self.began = (time.perf_counter(), time.thread_time())
            return _sqlite_call(super().execute, sql, *args, **kwargs)

        def _ended(self) -> None:
            if self.began is not None and _trace is not None:
                wall, cpu = time.perf_counter() - self.began[0], time.thread_time() - self.began[1]
                where = f"{_request_for.get()} {_lock_in.get()}"
                turn = getattr(_turn_waited, "ms", None)
                _turn_waited.ms = None
                waited = "-" if turn is None else f"{turn:.3f}"
                os.write(_trace, f"{wall * 1000:.3f} {cpu * 1000:.3f} {where} {waited}\n".encode())
            self.began = None

        def commit(self):
            try:
                return super().commit()
            finally:
                self._ended()

        def rollback(self):
            try:
                return super().rollback()
            finally:
                self._ended()

    _connect = sqlite3.connect

    def _counting_connect(*args, **kwargs):
        kwargs.setdefault("factory", _CountingConnection)
        return _connect(*args, **kwargs)

    sqlite3.connect = sqlite3.dbapi2.connect = _counting_connect  # SQLAlchemy uses dbapi2

    import anyio.to_thread

    _run_sync = anyio.to_thread.run_sync

    async def _counting_run_sync(*args, **kwargs):
        _add(1)
        return await _run_sync(*args, **kwargs)

    anyio.to_thread.run_sync = _counting_run_sync

    try:  # PostgreSQL: each round trip to the server (statements, and BEGIN/COMMIT/ROLLBACK)
        import psycopg
        from psycopg import _connection_base
    except ImportError:
        psycopg = None
    if psycopg is not None and _COUNTS:

        def _counting(method):
            def counted(*args, **kwargs):
                _add(0)
                return method(*args, **kwargs)

            return counted

        for _name in ("execute", "executemany"):
            setattr(psycopg.Cursor, _name, _counting(getattr(psycopg.Cursor, _name)))
        _base = _connection_base.BaseConnection
        _base._exec_command = _counting(_base._exec_command)

if _CPU or _PROFILE or _WAITS or _LOCKS or _TRIPS:
    import contextvars
    import types
    from collections import defaultdict

    import anyio.to_thread as _to_thread

    @types.coroutine
    def _each_step(awaitable, before, after):
        """Drive ``awaitable`` step by step: ``after(before())`` around each step (what the
        coroutine does between two of its awaits, on the event loop)."""
        steps = awaitable.__await__()
        value, error = None, None
        while True:
            mark = before()
            try:
                yielded = steps.throw(error) if error is not None else steps.send(value)
            except StopIteration as stop:
                after(mark)
                return stop.value
            after(mark)
            try:
                value, error = (yield yielded), None
            except BaseException as raised:  # noqa: BLE001 (handed on to the coroutine)
                value, error = None, raised

    def _function_name(func) -> str:
        """The name of the function a thread-pool call runs, through starlette's partial and
        the other probes' wrappers."""
        while True:
            inner = getattr(func, "__wrapped__", None) or getattr(func, "func", None)
            if inner is None:
                return getattr(func, "__name__", "?")
            func = inner

    def _wrap_thread_pool(wrap) -> None:
        """Send every function a request gives the thread pool through ``wrap(func)``: the
        function to run instead, or None to run it as it is."""
        original = _to_thread.run_sync

        async def run_sync(func, *args, **kwargs):
            return await original(wrap(func) or func, *args, **kwargs)

        _to_thread.run_sync = run_sync


if _LOCKS or _TRIPS:
    from fastapi import applications as _request_applications

    # ``kind method path`` of the request or WebSocket whose task runs now (the lock trace's
    # and the trips' lines name it)
    _request_for = contextvars.ContextVar("gyrolab_bench_request_for", default="- - -")
    _request_call = _request_applications.FastAPI.__call__

    async def _request_noted_call(self, scope, receive, send):
        if scope["type"] not in ("http", "websocket"):
            return await _request_call(self, scope, receive, send)
        noted = f"{scope['type']} {scope.get('method', 'WS')} {scope['path']}"
        token = _request_for.set(noted)
        try:
            return await _request_call(self, scope, receive, send)
        finally:
            _request_for.reset(token)

    _request_applications.FastAPI.__call__ = _request_noted_call

if _LOCKS:

    def _lock_named(func):
        name = _function_name(func)

        def named(*call_args):
            token = _lock_in.set(name)
            try:
                return func(*call_args)
            finally:
                _lock_in.reset(token)

        named.__wrapped__ = func  # for the next wrapper's _function_name
        return named

    _wrap_thread_pool(_lock_named)

if _CPU:
    import time as _cpu_time

    from fastapi import applications as _cpu_applications

    _cpu_file = os.open(_CPU, os.O_WRONLY | os.O_APPEND | os.O_CREAT)
    _SAMPLES = '"type":"samples"'  # how the stream's frames of samples begin
    _spent = contextvars.ContextVar("gyrolab_bench_spent", default=None)

    def _timed_steps(awaitable, spent):
        """``awaitable`` with each step's CPU (this thread's clock) added to ``spent[0]``."""

        def after(began: float) -> None:
            spent[0] += _cpu_time.thread_time() - began

        return _each_step(awaitable, _cpu_time.thread_time, after)

    _cpu_call = _cpu_applications.FastAPI.__call__

    async def _cpu_timed_call(self, scope, receive, send):
        if scope["type"] not in ("http", "websocket"):
            return await _cpu_call(self, scope, receive, send)
        spent = [0.0, 0.0, 0, defaultdict(float)]
        token = _spent.set(spent)

        async def counting_send(message):
            if message["type"] == "websocket.send" and _SAMPLES in (message.get("text") or "")[:32]:
                spent[2] += 1  # a frame of samples (not "started" or "saved")
            await send(message)

        try:
            return await _timed_steps(_cpu_call(self, scope, receive, counting_send), spent)
        finally:
            _spent.reset(token)
            line = (
                f"{scope['type']} {scope.get('method', 'WS')} {scope['path']}"
                f" {spent[0] * 1000:.3f} {spent[1] * 1000:.3f} {spent[2]}"
            )
            if scope["type"] == "websocket":  # its thread CPU by function, ms
                line += " " + ",".join(f"{k}={v * 1000:.3f}" for k, v in spent[3].items())
            line += "\n"
            os.write(_cpu_file, line.encode())

    _cpu_applications.FastAPI.__call__ = _cpu_timed_call

    def _timed(func):
        spent = _spent.get()
        if spent is None:
            return None

        name = _function_name(func)

        def timed(*call_args):
            began = _cpu_time.thread_time()
            try:
                return func(*call_args)
            finally:
                took = _cpu_time.thread_time() - began
                spent[1] += took
                spent[3][name] += took

        timed.__wrapped__ = func  # for the next wrapper's _function_name
        return timed

    _wrap_thread_pool(_timed)

if _PROFILE:
    import atexit
    import cProfile
    import pstats
    import re
    import threading
    import time as _profile_time

    from fastapi import applications as _profile_applications

    _route = contextvars.ContextVar("gyrolab_bench_route", default=None)
    _profiles: dict[str, pstats.Stats] = {}
    _profiled_calls = [0]
    _profile_clock = _profile_time.thread_time  # CPU: not the waits for the interpreter or a lock
    _profiles_lock = threading.Lock()
    _profile_call = _profile_applications.FastAPI.__call__

    async def _routed_call(self, scope, receive, send):
        if scope["type"] in ("http", "websocket"):
            name = f"{scope.get('method', 'WS')} {re.sub(r'/[0-9]+', '/{id}', scope['path'])}"
            token = _route.set(name)
            try:
                return await _profile_call(self, scope, receive, send)
            finally:
                _route.reset(token)
        return await _profile_call(self, scope, receive, send)

    _profile_applications.FastAPI.__call__ = _routed_call

    def _profiled(func):
        route = _route.get()
        if route is None:
            return None

        def profiled(*call_args):
            profile = cProfile.Profile(_profile_clock)
            try:
                return profile.runcall(func, *call_args)
            finally:
                profile.create_stats()
                with _profiles_lock:
                    if route in _profiles:
                        _profiles[route].add(profile)
                    else:
                        _profiles[route] = pstats.Stats(profile)
                    _profiled_calls[0] += 1
                    if _profiled_calls[0] % 100 == 0:
                        _write_profiles()

        profiled.__wrapped__ = func  # for the next wrapper's _function_name
        return profiled

    _wrap_thread_pool(_profiled)

    def _write_profiles() -> None:
        for route, stats in _profiles.items():
            name = re.sub(r"[^A-Za-z0-9]+", "_", route).strip("_")
            stats.dump_stats(os.path.join(_PROFILE, f"{os.getpid()}-{name}.prof"))

    @atexit.register
    def _write_at_exit() -> None:
        with _profiles_lock:
            _write_profiles()


if _WAITS:
    import time as _w_time

    from fastapi import applications as _w_applications
    from starlette.middleware import exceptions as _w_exceptions

    _w_file = os.open(_WAITS, os.O_WRONLY | os.O_APPEND | os.O_CREAT)
    _w_state = contextvars.ContextVar("gyrolab_bench_waits", default=None)
    # began, admitted, loop cpu, loop wall, dispatch, thread cpu, thread wall, thread queued,
    # back, trips, a function's end (until the coroutine's next step)
    _BEGAN, _ADMITTED, _LOOP_CPU, _LOOP_WALL, _DISPATCH = range(5)
    _T_CPU, _T_WALL, _T_QUEUED, _BACK, _TRIP_COUNT, _ENDED = range(5, 11)

    def _queued_s() -> float:
        """This thread's time ready to run but waiting for a core so far (the kernel's)."""
        handle = os.open("/proc/thread-self/schedstat", os.O_RDONLY)
        try:
            return int(os.read(handle, 96).split()[1]) / 1e9
        finally:
            os.close(handle)

    def _waited_steps(awaitable, state):
        """``awaitable`` with each step's CPU and wall on the loop added to ``state``, and
        the time from a thread-pool function's end to the step after it."""

        def before() -> tuple[float, float]:
            wall = _w_time.perf_counter()
            if state[_ENDED]:
                state[_BACK] += wall - state[_ENDED]
                state[_ENDED] = 0.0
            return wall, _w_time.thread_time()

        def after(began: tuple[float, float]) -> None:
            state[_LOOP_CPU] += _w_time.thread_time() - began[1]
            state[_LOOP_WALL] += _w_time.perf_counter() - began[0]

        return _each_step(awaitable, before, after)

    _w_call = _w_applications.FastAPI.__call__

    async def _waits_call(self, scope, receive, send):
        if scope["type"] != "http":
            return await _w_call(self, scope, receive, send)
        state = [_w_time.perf_counter(), 0.0, *([0.0] * 9)]
        token = _w_state.set(state)
        try:
            return await _waited_steps(_w_call(self, scope, receive, send), state)
        finally:
            _w_state.reset(token)
            total = _w_time.perf_counter() - state[_BEGAN]
            admitted = state[_ADMITTED] - state[_BEGAN] if state[_ADMITTED] else total
            parts = (total, admitted, *state[_LOOP_CPU:_TRIP_COUNT])
            line = f"{scope['method']} {scope['path']} " + " ".join(
                f"{part * 1000:.3f}" for part in parts
            )
            line += f" {int(state[_TRIP_COUNT])} {state[_BEGAN]:.6f} {os.getpid()}\n"
            os.write(_w_file, line.encode())

    _w_applications.FastAPI.__call__ = _waits_call
    _w_inner = _w_exceptions.ExceptionMiddleware.__call__

    async def _w_admitted(self, scope, receive, send):
        state = _w_state.get()
        if state is not None and not state[_ADMITTED]:
            state[_ADMITTED] = _w_time.perf_counter()
        return await _w_inner(self, scope, receive, send)

    _w_exceptions.ExceptionMiddleware.__call__ = _w_admitted

    def _waited(func):
        state = _w_state.get()
        if state is None:
            return None
        sent = _w_time.perf_counter()

        def waited(*call_args):
            began, cpu, queued = _w_time.perf_counter(), _w_time.thread_time(), _queued_s()
            state[_DISPATCH] += began - sent
            try:
                return func(*call_args)
            finally:
                state[_T_QUEUED] += _queued_s() - queued
                state[_T_CPU] += _w_time.thread_time() - cpu
                ended = _w_time.perf_counter()
                state[_T_WALL] += ended - began
                state[_TRIP_COUNT] += 1
                state[_ENDED] = ended

        waited.__wrapped__ = func  # for the next wrapper's _function_name
        return waited

    _wrap_thread_pool(_waited)

if _GIL:
    import atexit as _g_atexit
    import threading as _g_threading
    import time as _g_time

    _GIL_NAP_S = 0.002
    _g_lines: list[str] = []
    _g_naps = [0]  # naps made so far (a test waits for enough of them)
    _g_file = os.open(_GIL, os.O_WRONLY | os.O_APPEND | os.O_CREAT)

    def _g_queued_ns(schedstat: int) -> int:
        return int(os.pread(schedstat, 100, 0).split()[1])

    def _g_write() -> None:
        lines, _g_lines[:] = _g_lines[:], []
        if lines:
            os.write(_g_file, "".join(lines).encode())

    def _gil_sampler() -> None:
        """Nap ``_GIL_NAP_S`` again and again; each time, how much later than that the
        thread ran Python again, and of it how long it waited for a core (schedstat):
        the rest is the wait for the interpreter of a thread that wants it at a random
        moment.  The clock starts before the first read of ``schedstat``: a read lets the
        interpreter go, and a thread that took it meanwhile (a route that keeps it for
        90 ms) delays the nap there as much as after the sleep."""
        schedstat = os.open("/proc/thread-self/schedstat", os.O_RDONLY)  # this thread's
        while True:
            began = _g_time.perf_counter()
            queued = _g_queued_ns(schedstat)
            _g_time.sleep(_GIL_NAP_S)
            queued = _g_queued_ns(schedstat) - queued
            late = _g_time.perf_counter() - began - _GIL_NAP_S
            _g_lines.append(f"{began:.6f} {late * 1e6:.0f} {queued / 1000:.0f} {os.getpid()}\n")
            _g_naps[0] += 1
            if len(_g_lines) >= 100:
                _g_write()

    _g_atexit.register(_g_write)
    _g_threading.Thread(target=_gil_sampler, daemon=True, name="gil-sampler").start()

if _TRIPS:
    import time as _t_time

    _t_file = os.open(_TRIPS, os.O_WRONLY | os.O_APPEND | os.O_CREAT)
    _t_original = _to_thread.run_sync

    async def _t_run_sync(func, *args, **kwargs):
        times = [0.0, 0.0]

        def timed(*call_args):
            times[0] = _t_time.perf_counter()
            try:
                return func(*call_args)
            finally:
                times[1] = _t_time.perf_counter()

        timed.__wrapped__ = func
        sent = _t_time.perf_counter()
        try:
            return await _t_original(timed, *args, **kwargs)
        finally:
            line = (
                f"{_request_for.get()} {_function_name(func)} {sent:.6f} {times[0]:.6f}"
                f" {times[1]:.6f} {_t_time.perf_counter():.6f} {os.getpid()}\n"
            )
            os.write(_t_file, line.encode())

    _to_thread.run_sync = _t_run_sync
