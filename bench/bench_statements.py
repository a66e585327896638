"""The hot paths' statements built once against built on every call (issue 32).

    .venv/bin/python bench/bench_statements.py

Each hot-path select that a page, a write or the stream runs per request, on a file SQLite
database of the app's schema with one student's rows: the CPU of building the select and
running it (what the code did) beside running the one built at import with bound parameters
(what it does now: SQLAlchemy keys its compiled-statement cache by the statement, and a
statement built once keeps its key).  Best of five batches of 500 calls, thread CPU.
"""

from __future__ import annotations

import tempfile
import time
from pathlib import Path

from sqlmodel import Session, SQLModel, create_engine, select

from app.accounts.deps import SESSION_AND_USER
from app.lab.attempts import ATTEMPTS_OF_SESSION
from app.lab.result_cache import CURRENT_TAKE_KEYS, KEY_COLUMNS
from app.lab.store import CURRENT_TAKES, TAKE_HISTORY
from app.models import (
    Attempt,
    AuthSession,
    InputMethod,
    LabSession,
    Role,
    Take,
    User,
    utcnow,
)

CALLS, BATCHES = 500, 5


def cpu_per_call(function) -> float:
    """Best batch's thread CPU per call (µs)."""
    for _ in range(50):
        function()
    best = float("inf")
    for _ in range(BATCHES):
        began = time.thread_time()
        for _ in range(CALLS):
            function()
        best = min(best, (time.thread_time() - began) / CALLS * 1e6)
    return best


def main() -> None:
    from datetime import timedelta

    from sqlmodel import func

    folder = Path(tempfile.mkdtemp())
    engine = create_engine(f"sqlite:///{folder / 'bench.db'}")
    SQLModel.metadata.create_all(engine)
    with Session(engine) as db:
        user = User(username="s1", display_name="S", role=Role.student, password_hash="x")
        db.add(user)
        db.flush()
        now = utcnow()
        db.add(
            AuthSession(
                user_id=user.id,
                token_hash="d" * 64,
                csrf_token="c",
                created_at=now,
                last_seen_at=now,
                expires_at=now + timedelta(hours=8),
            )
        )
        session = LabSession(owner_id=user.id, title="t", latitude_deg=39.93)
        db.add(session)
        db.flush()
        for position in range(1, 5):
            db.add(
                Take(
                    session_id=session.id,
                    part="heading",
                    position=position,
                    angle_deg=90.0 * (position - 1),
                    source=InputMethod.manual,
                    n_samples=10,
                )
            )
        db.commit()
        sid = session.id
    cases = {
        "caller (session + user)": (
            lambda: (
                select(AuthSession, User)
                .join(User, User.id == AuthSession.user_id)
                .where(AuthSession.token_hash == "d" * 64)
            ),
            SESSION_AND_USER,
            {"digest": "d" * 64},
        ),
        "current takes": (
            lambda: (
                select(Take)
                .where(Take.session_id == sid, Take.superseded_at.is_(None))
                .order_by(Take.part, Take.position)
            ),
            CURRENT_TAKES,
            {"session_id": sid},
        ),
        "results' key (take columns)": (
            lambda: (
                select(*KEY_COLUMNS)
                .where(Take.session_id == sid, Take.superseded_at.is_(None))
                .order_by(Take.part, Take.position)
            ),
            CURRENT_TAKE_KEYS,
            {"session_id": sid},
        ),
        "recording history": (
            lambda: (
                select(Take, func.count().over())
                .where(Take.session_id == sid)
                .order_by(Take.created_at.desc(), Take.id.desc())
                .limit(50)
            ),
            TAKE_HISTORY,
            {"session_id": sid, "limit": 50},
        ),
        "attempts": (
            lambda: select(Attempt).where(Attempt.session_id == sid).order_by(Attempt.number),
            ATTEMPTS_OF_SESSION,
            {"session_id": sid},
        ),
    }
    print("| statement | built per call (µs) | built once (µs) |")
    print("|---|---:|---:|")
    with Session(engine) as db:
        for name, (build, built, params) in cases.items():
            per_call = cpu_per_call(lambda build=build: db.exec(build()).all())
            once = cpu_per_call(
                lambda built=built, params=params: db.exec(built, params=params).all()
            )
            print(f"| {name} | {per_call:.0f} | {once:.0f} |")


if __name__ == "__main__":
    main()
