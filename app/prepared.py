"""One SQL statement compiled once and run on a pooled driver connection.

SQLAlchemy builds a cache key for every statement it executes (a walk of the whole
expression tree), runs events around every transaction and wraps every row; for the
hottest read (``lab.results_read``: a device polling for results) that cost several times
the query itself (issue 32: 261 µs a request in process, of which 22 µs in SQLite).  A
:class:`Prepared` statement is compiled once per dialect and keeps the bind and result
processors of its types, so a call is a pool checkout, the driver's ``execute`` and the
same conversions SQLAlchemy applies: its rows equal ``connection.execute(statement)``'s,
value for value (``tests/test_prepared.py``, on SQLite and PostgreSQL).

``prepared.rows(engine)`` runs one statement in a transaction of its own (an
``UPDATE … RETURNING`` is atomic and committed); ``driver_transaction(engine,
snapshot=True)`` runs several in one transaction that sees one snapshot, begun by itself
(not by the engine's events, which SQLAlchemy fires only for its own connections).  Driver errors
are raised as SQLAlchemy's (``DBAPIError``), so "database is locked" still answers 503.
Expanding (``IN``) parameters are not supported.
"""

from __future__ import annotations

import threading
from collections import namedtuple
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from typing import Any

from sqlalchemy import Engine
from sqlalchemy.engine import Dialect
from sqlalchemy.exc import DBAPIError
from sqlalchemy.sql.expression import Executable


@dataclass
class _Plan:
    sql: str
    positions: tuple[str, ...] | None  # bind names in order, for positional drivers
    defaults: dict[str, Any]  # the statement's own bound values (literals in it)
    binds: dict[str, Callable[[Any], Any]]  # bind processors, where the type has one
    columns: tuple  # the statement's columns, whose types convert what the driver returns
    row_type: type
    # (column index, processor) to apply; known after the first execution, because a
    # driver's processor may depend on the type the database reports for the column
    results: tuple[tuple[int, Callable[[Any], Any]], ...] | None = None
    row_type: type


class Prepared:
    """A Core ``select`` (or DML with ``RETURNING``) without SQLAlchemy's per-execution
    work: see the module."""

    def __init__(self, statement: Executable) -> None:
        self.statement = statement
        self._plans: dict[tuple[str, str], _Plan] = {}
        self._lock = threading.Lock()

    def _plan(self, dialect: Dialect) -> _Plan:
        key = (dialect.name, dialect.driver)
        plan = self._plans.get(key)
        if plan is None:
            with self._lock:
                plan = self._plans.get(key) or self._compile(dialect)
                self._plans[key] = plan
        return plan

    def _compile(self, dialect: Dialect) -> _Plan:
        compiled = self.statement.compile(dialect=dialect)
        if any(bind.expanding for bind in compiled.binds.values()):
            raise ValueError("Prepared does not support expanding (IN) parameters")
        binds = {}
        for name, bind in compiled.binds.items():
            processor = bind.type.dialect_impl(dialect).bind_processor(dialect)
            if processor is not None:
                binds[name] = processor
        columns = list(self.statement.exported_columns)
        return _Plan(
            sql=compiled.string,
            positions=tuple(compiled.positiontup) if compiled.positional else None,
            defaults={
                name: bind.effective_value
                for name, bind in compiled.binds.items()
                if not bind.required
            },
            binds=binds,
            columns=tuple(columns),
            row_type=namedtuple("Row", [column.key for column in columns], rename=True),
        )

    def rows(self, engine: Engine, **params: Any) -> list:
        """Run the statement in a transaction of its own; its rows as named tuples with
        the statement's column keys."""
        with driver_transaction(engine) as transaction:
            return transaction.rows(self, **params)

    def first(self, engine: Engine, **params: Any):
        found = self.rows(engine, **params)
        return found[0] if found else None

    def _run(self, cursor, dialect: Dialect, params: dict[str, Any]) -> list:
        plan = self._plan(dialect)
        values = {**plan.defaults, **params}
        for name, processor in plan.binds.items():
            values[name] = processor(values[name])
        parameters = (
            [values[name] for name in plan.positions] if plan.positions is not None else values
        )
        try:
            cursor.execute(plan.sql, parameters)
            fetched = cursor.fetchall()
        except dialect.loaded_dbapi.Error as error:
            raise DBAPIError.instance(
                plan.sql, parameters, error, dialect.loaded_dbapi.Error
            ) from error
        if plan.results is None:
            plan.results = _result_processors(plan.columns, dialect, cursor.description)
        make = plan.row_type._make
        if not plan.results:
            return [make(row) for row in fetched]
        rows = []
        for raw in fetched:
            row = list(raw)
            for index, processor in plan.results:
                if row[index] is not None:
                    row[index] = processor(row[index])
            rows.append(make(row))
        return rows


def _result_processors(columns, dialect: Dialect, description) -> tuple:
    found = []
    for index, (column, described) in enumerate(zip(columns, description, strict=True)):
        processor = column.type.dialect_impl(dialect).result_processor(dialect, described[1])
        if processor is not None:
            found.append((index, processor))
    return tuple(found)


class DriverTransaction:
    """Prepared statements run on one pooled driver connection in one transaction."""

    def __init__(self, connection, dialect: Dialect) -> None:
        self._cursor = connection.cursor()
        self._dialect = dialect

    def rows(self, prepared: Prepared, **params: Any) -> list:
        return prepared._run(self._cursor, self._dialect, params)

    def first(self, prepared: Prepared, **params: Any):
        found = self.rows(prepared, **params)
        return found[0] if found else None


@contextmanager
def driver_transaction(engine: Engine, *, snapshot: bool = False) -> Iterator[DriverTransaction]:
    """A transaction on a pooled driver connection, committed at the end (rolled back on
    an error).  ``snapshot``: every statement in it sees one snapshot -- SQLite's deferred
    ``BEGIN`` (WAL: readers never wait), PostgreSQL's REPEATABLE READ -- as
    ``db.reader``'s transactions do; otherwise each statement is its own transaction on
    SQLite (autocommit) and sees its own snapshot on PostgreSQL (READ COMMITTED)."""
    dialect = engine.dialect
    connection = engine.raw_connection()
    try:
        transaction = DriverTransaction(connection, dialect)
        if snapshot:
            begin = "BEGIN" if dialect.name == "sqlite" else SNAPSHOT_ON_POSTGRESQL
            transaction._cursor.execute(begin)
        yield transaction
        connection.commit()
    except BaseException:
        connection.rollback()
        raise
    finally:
        connection.close()


SNAPSHOT_ON_POSTGRESQL = "SET TRANSACTION ISOLATION LEVEL REPEATABLE READ"
