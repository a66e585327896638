"""A session's results, solved once per change of its data.

The key is everything a result depends on, read from the database: each
current take (id, position, dial angle, source, sample count, trim), the session's columns
(station, schedule, simulator -- not those that only follow the recording, such as the
virtual table's position) and its assignment's (the characterised station noise).  Any
change the database sees gives a new key, so a cached result can never be stale, and
several worker processes (or hosts) need no invalidation: each keeps its own bounded cache
of immutable entries and solves a given key at most once.  Reading the key costs one small
query (no samples); a miss loads the samples and solves.

Entries hold slim results (position summaries, no samples), the REST payload already
serialised, and the plotly figures per language as the page embeds them.
"""

from __future__ import annotations

import functools
import operator
import threading
from collections import OrderedDict
from collections.abc import Callable
from dataclasses import dataclass, field

from markupsafe import Markup
from sqlalchemy import bindparam
from sqlmodel import Session, select

from app.lab.lru import LruCache
from app.lab.results import PartResult, session_results
from app.models import Assignment, LabSession, Take

DataKey = tuple  # (take rows, session row, assignment row): see digest_rows

MAX_ENTRIES = 512  # slim results: a few kB each
MAX_FIGURE_BYTES = 32 * 2**20  # the figures' JSON of all entries, both languages


@dataclass
class CachedResults:
    key: DataKey
    parts: dict[str, PartResult]
    payload: bytes | None = None  # the REST results body (set by the API on first use)
    # language → (each figure's text alternative by name, the figures' JSON as embedded)
    figures: dict[str, tuple[dict[str, dict], Markup]] = field(default_factory=dict)
    # (language, editable) → each part's rendered results block (app/lab/pages.py)
    blocks: dict[tuple[str, bool], dict[str, Markup]] = field(default_factory=dict)


class ResultCache:
    """A thread-safe LRU of :class:`CachedResults`, bounded in entries and figure bytes.

    The figure bytes held are kept as a running total (adding up every entry's on each
    addition cost ≈ 0.1 ms with the cache full, 6 % of a new session's first page)."""

    def __init__(self, max_entries: int = MAX_ENTRIES, max_figure_bytes: int = MAX_FIGURE_BYTES):
        self.max_entries = max_entries
        self.max_figure_bytes = max_figure_bytes
        self._entries: OrderedDict[DataKey, CachedResults] = OrderedDict()
        self._bytes = 0  # figure_bytes of the entries held
        self._lock = threading.Lock()
        self.hits = 0
        self.misses = 0

    def get(self, key: DataKey) -> CachedResults | None:
        with self._lock:
            entry = self._entries.get(key)
            if entry is None:
                self.misses += 1
                return None
            self._entries.move_to_end(key)
            self.hits += 1
            return entry

    def put(self, entry: CachedResults) -> CachedResults:
        with self._lock:
            kept = self._entries.setdefault(entry.key, entry)  # a racing solve: keep one
            if kept is entry:
                self._bytes += figure_bytes(entry)
            self._entries.move_to_end(entry.key)
            self._trim()
            return kept

    def add_figures(
        self, entry: CachedResults, language: str, figures: tuple[dict[str, dict], Markup]
    ) -> None:
        self._add(entry, entry.figures, language, figures)

    def add_blocks(
        self, entry: CachedResults, language: str, editable: bool, blocks: dict[str, Markup]
    ) -> None:
        self._add(entry, entry.blocks, (language, editable), blocks)

    def _add(self, entry: CachedResults, kept: dict, key, value) -> None:
        """``kept[key] = value`` in one of ``entry``'s dicts, the running total adjusted
        while the entry is held (a request may add to one already dropped)."""
        with self._lock:
            held = self._entries.get(entry.key) is entry
            if held:
                self._bytes -= figure_bytes(entry)
            kept[key] = value
            if held:
                self._bytes += figure_bytes(entry)
                self._trim()

    def clear(self) -> None:
        with self._lock:
            self._entries.clear()
            self._bytes = 0

    @property
    def held_bytes(self) -> int:
        """The figure bytes of the entries held (the running total)."""
        return self._bytes

    def _trim(self) -> None:
        while len(self._entries) > self.max_entries:
            self._drop_oldest()
        while len(self._entries) > 1 and self._bytes > self.max_figure_bytes:
            self._drop_oldest()

    def _drop_oldest(self) -> None:
        _, dropped = self._entries.popitem(last=False)
        self._bytes -= figure_bytes(dropped)


def figure_bytes(entry: CachedResults) -> int:
    """The characters of an entry's figures' JSON and rendered blocks (the byte bound's
    measure)."""
    return sum(len(f) for _, f in entry.figures.values()) + sum(
        len(html) for parts in entry.blocks.values() for html in parts.values()
    )


CACHE = ResultCache()


# the class dashboard's data flags and fingerprints of a session's current data, keyed
# like results
SUMMARIES = LruCache(8192)


# Session columns that change while recording or submitting but never enter a result
# (every other column does, including any added later: a new column is safe by default).
NOT_IN_RESULTS = frozenset(
    {
        "title",
        "status",
        "created_at",
        "updated_at",
        "stream_part",
        "stream_position",
        "sim_table_heading",
        "sim_table_latitude",
        "sim_turns",
        "sim_clock_s",
        "sim_clock_at",
        "partner_code",
    }
)


@functools.cache
def _result_columns(model: type) -> Callable[[object], tuple]:
    """A getter of the model's result columns' values, in table order (found once)."""
    names = [c.name for c in model.__table__.columns if c.name not in NOT_IN_RESULTS]
    getter = operator.attrgetter(*names)
    return getter if len(names) > 1 else lambda record: (getter(record),)


def _row(record) -> tuple:
    if record is None:
        return ()
    return _result_columns(type(record))(record)


KEY_COLUMNS = (
    Take.id,
    Take.part,
    Take.position,
    Take.angle_deg,
    Take.source,
    Take.n_samples,
    Take.trim_start,
)


def _digest(takes, session: LabSession, assignment_row: tuple) -> DataKey:
    return digest_rows(takes, _row(session), assignment_row)


def digest_rows(takes, session_row: tuple, assignment_row: tuple) -> DataKey:
    """The cache key: the takes' key columns, the session's and the assignment's result
    columns (in table order), as read by the ORM or by Core (``lab.results_read``).

    The values themselves, compared whole: the caches are each process's own, so nothing
    needs a text form, and a key a few hundred bytes long costs less to hash than a digest
    of its text cost to make (``repr`` of ≈ 40 values and BLAKE2: ≈ 15 µs a session, 300 a
    dashboard).  Never a hash alone: equal keys are equal data."""
    return (tuple(map(tuple, takes)), session_row, assignment_row)


def data_key(
    db: Session,
    session: LabSession,
    assignment: Assignment | None,
    takes: list[Take] | None = None,
) -> DataKey:
    """The digest of everything the session's results depend on (one query for the takes,
    none when the caller has the current ``takes`` already; the session and assignment
    rows are the caller's)."""
    if takes is None:
        rows = db.exec(CURRENT_TAKE_KEYS, params={"session_id": session.id}).all()
    else:
        rows = key_rows(takes)
    return _digest(rows, session, _row(assignment))


def key_rows(takes: list[Take]) -> list[tuple]:
    """:data:`KEY_COLUMNS` of loaded takes, as :data:`CURRENT_TAKE_KEYS` reads them (in
    its order, a take's source as the plain text stored)."""
    return [
        (t.id, t.part, t.position, t.angle_deg, str(t.source), t.n_samples, t.trim_start)
        for t in sorted(takes, key=lambda take: (take.part, take.position))
    ]


CURRENT_TAKE_KEYS = (  # built once: building it per call cost more than running it
    select(*KEY_COLUMNS)
    .where(Take.session_id == bindparam("session_id"), Take.superseded_at.is_(None))
    .order_by(Take.part, Take.position)
)


ASSIGNMENT_TAKE_KEYS = (  # every session's current takes in an assignment, built once
    select(Take.session_id, *KEY_COLUMNS)
    .join(LabSession, LabSession.id == Take.session_id)
    .where(LabSession.assignment_id == bindparam("assignment_id"), Take.superseded_at.is_(None))
    .order_by(Take.session_id, Take.part, Take.position)
)


def current_take_rows(
    db: Session, sessions: list[LabSession], assignment: Assignment | None
) -> dict[int, list[tuple]]:
    """Each session's current takes as rows of :data:`KEY_COLUMNS`, in part and position
    order, in one query (by the assignment when every session is one of its own: no list
    of ids to send)."""
    by_session: dict[int, list] = {session.id: [] for session in sessions}
    connection = db.connection()  # columns through Core: no ORM row processing
    if assignment is not None and all(s.assignment_id == assignment.id for s in sessions):
        rows = connection.execute(ASSIGNMENT_TAKE_KEYS, {"assignment_id": assignment.id})
    else:
        rows = connection.execute(
            select(Take.session_id, *KEY_COLUMNS)
            .where(Take.session_id.in_(list(by_session)), Take.superseded_at.is_(None))
            .order_by(Take.session_id, Take.part, Take.position)
        )
    for row in rows.all():
        kept = by_session.get(row[0])
        if kept is not None:
            kept.append(tuple(row[1:]))
    return by_session


def data_keys(
    db: Session,
    sessions: list[LabSession],
    assignment: Assignment | None,
    take_rows: dict[int, list[tuple]] | None = None,
) -> dict[int, DataKey]:
    """:func:`data_key` of many sessions of one assignment, in one query (none when the
    caller has their :func:`current_take_rows`)."""
    if take_rows is None:
        take_rows = current_take_rows(db, sessions, assignment)
    assignment_row = _row(assignment)
    return {s.id: _digest(take_rows[s.id], s, assignment_row) for s in sessions}


def cached_results(
    db: Session,
    session: LabSession,
    assignment: Assignment | None = None,
    *,
    on_miss: Callable[[dict[str, PartResult]], None] | None = None,
    takes: list[Take] | None = None,
) -> CachedResults:
    """The session's results for its current data, solved only when that data changed.

    ``assignment`` is the session's (looked up when not given).  ``on_miss`` sees the full
    results (with samples) when they had to be solved, e.g. to draw the figures at once.
    ``takes``: the session's current takes, where the caller has loaded them (the key is
    then made without a query)."""
    if assignment is None and session.assignment_id is not None:
        assignment = db.get(Assignment, session.assignment_id)
    key = data_key(db, session, assignment, takes)
    entry = CACHE.get(key)
    if entry is not None:
        return entry
    full = session_results(db, session)
    if on_miss is not None:
        on_miss(full)
    return CACHE.put(CachedResults(key, {part: r.slim() for part, r in full.items()}))


def results_of(db: Session, session: LabSession) -> dict[str, PartResult]:
    """The session's (slim) results: the cached path for every reader."""
    return cached_results(db, session).parts
