"""The tables' clock: every stored time is UTC.  Every change here needs an Alembic migration
(tests check it)."""

from __future__ import annotations

from datetime import UTC, datetime


def utcnow() -> datetime:
    return datetime.now(UTC)
