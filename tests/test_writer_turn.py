"""SQLite's writers of one process take turns in the order they asked (app.writer_turn):
handed on at commit or rollback, never left taken, and never more than a wait."""

from __future__ import annotations

import threading
import time

import pytest
from sqlalchemy import text
from sqlalchemy.exc import OperationalError

from app.db import make_engine, write_session, writer_turn
from app.writer_turn import WriterTurn

pytestmark = pytest.mark.sqlite_only


def wait_until(condition, timeout: float = 5.0) -> None:
    deadline = time.monotonic() + timeout
    while not condition():
        assert time.monotonic() < deadline, "timed out"
        time.sleep(0.001)


def test_the_turn_goes_to_writers_in_the_order_they_asked():
    turn = WriterTurn()
    assert turn.acquire(timeout=1)
    order: list[int] = []

    def writer(number: int) -> None:
        assert turn.acquire(timeout=5)
        order.append(number)
        turn.release()

    threads = []
    for number in range(6):
        thread = threading.Thread(target=writer, args=(number,))
        thread.start()
        threads.append(thread)
        wait_until(lambda n=number: turn.queued == n + 1)  # asked strictly one after another
    turn.release()
    for thread in threads:
        thread.join(5)
    assert order == list(range(6))
    assert turn.acquire(timeout=0)  # free again


def test_a_writer_that_waited_too_long_leaves_the_queue():
    turn = WriterTurn()
    assert turn.acquire(timeout=1)
    waited: list[tuple[bool, float]] = []

    def writer() -> None:
        started = time.monotonic()
        waited.append((turn.acquire(timeout=0.05), time.monotonic() - started))

    thread = threading.Thread(target=writer)
    thread.start()
    thread.join(5)
    assert waited and waited[0][0] is False and waited[0][1] >= 0.05
    assert turn.queued == 0
    turn.release()
    assert turn.acquire(timeout=0)  # the one who gave up is not handed the turn


def test_a_writer_inside_a_write_of_its_own_thread_does_not_wait_for_its_own_turn():
    turn = WriterTurn()
    assert turn.acquire(timeout=1)
    started = time.monotonic()
    assert not turn.acquire(timeout=5)  # at once: it would wait for itself
    assert time.monotonic() - started < 1
    other: list[bool] = []
    thread = threading.Thread(target=lambda: other.append(turn.acquire(timeout=5)))
    thread.start()
    wait_until(lambda: turn.queued == 1)  # another thread still queues
    turn.release()
    thread.join(5)
    assert other == [True]


@pytest.fixture
def file_engine(tmp_path):
    engine = make_engine(f"sqlite:///{tmp_path / 'turns.db'}")
    with engine.begin() as connection:
        connection.exec_driver_sql("CREATE TABLE note (id INTEGER PRIMARY KEY, text TEXT)")
    yield engine
    engine.dispose()


def test_a_second_writer_queues_for_the_turn_and_goes_on_at_the_first_ones_commit(file_engine):
    turn = writer_turn(file_engine)
    assert turn is not None
    first_wrote, second_done = threading.Event(), threading.Event()
    go_on = threading.Event()

    def first() -> None:
        with write_session(file_engine) as db:
            db.exec(text("INSERT INTO note (text) VALUES ('first')"))
            first_wrote.set()
            go_on.wait(5)

    def second() -> None:
        with write_session(file_engine) as db:
            db.exec(text("INSERT INTO note (text) VALUES ('second')"))
        second_done.set()

    one = threading.Thread(target=first)
    one.start()
    assert first_wrote.wait(5)
    two = threading.Thread(target=second)
    two.start()
    wait_until(lambda: turn.queued == 1)  # waiting in the queue, not in SQLite's busy handler
    assert not second_done.is_set()
    go_on.set()
    one.join(5)
    two.join(5)
    assert second_done.is_set()
    with file_engine.connect() as connection:
        rows = connection.exec_driver_sql("SELECT text FROM note ORDER BY id").all()
    assert [row[0] for row in rows] == ["first", "second"]
    assert turn.acquire(timeout=0)
    turn.release()


def test_the_turn_is_handed_on_after_a_rollback_and_a_failed_statement(file_engine):
    turn = writer_turn(file_engine)
    with pytest.raises(RuntimeError), write_session(file_engine) as db:
        db.exec(text("INSERT INTO note (text) VALUES ('rolled back')"))
        raise RuntimeError("the request failed")
    with pytest.raises(OperationalError), write_session(file_engine) as db:
        db.exec(text("INSERT INTO no_such_table VALUES (1)"))
    for _ in range(3):  # each would wait for ever if a turn had been kept
        with write_session(file_engine) as db:
            db.exec(text("INSERT INTO note (text) VALUES ('kept')"))
    assert turn.queued == 0
    assert turn.acquire(timeout=0)
    turn.release()
    with file_engine.connect() as connection:
        assert connection.exec_driver_sql("SELECT count(*) FROM note").scalar() == 3


def test_readers_and_memory_databases_take_no_turn(file_engine):
    turn = writer_turn(file_engine)
    assert turn.acquire(timeout=0)  # a writer holds the turn: readers are not held up
    try:
        with file_engine.connect() as connection:
            assert connection.exec_driver_sql("SELECT count(*) FROM note").scalar() == 0
    finally:
        turn.release()
    assert writer_turn(make_engine("sqlite://")) is None


def test_an_impatient_writer_is_told_once_and_keeps_its_place_in_the_queue():
    """After ``patience`` the waiter's callback runs (its request gives its place back,
    web.admission) while it still waits; it still gets the turn before those who asked
    after it.  The turn is released only once the callback has run, so the test holds on
    a crowded machine, where a thread may start or wake a tenth of a second late (a
    fresh run once saw the callback 0.21 s after the first thread was started)."""
    turn = WriterTurn()
    assert turn.acquire(1.0)
    order: list[str] = []
    told: dict[str, float] = {}

    def waiter(name: str, patience: float) -> None:
        asked = time.perf_counter()

        def impatient() -> None:
            told[name] = time.perf_counter() - asked

        assert turn.acquire(5.0, patience, impatient)
        order.append(name)
        turn.release()

    first = threading.Thread(target=waiter, args=("first", 0.05))
    first.start()
    wait_until(lambda: turn.queued >= 1)
    second = threading.Thread(target=waiter, args=("second", 0.0))
    second.start()
    wait_until(lambda: turn.queued >= 2)
    wait_until(lambda: "first" in told)
    assert order == [] and turn.queued == 2  # told while it waits, its place kept
    turn.release()
    first.join(10)
    second.join(10)
    assert order == ["first", "second"]
    assert list(told) == ["first"] and told["first"] >= 0.04, told
