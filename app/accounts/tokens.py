"""Bearer tokens for the API: personal access tokens and short-lived log-in tokens.

Tokens look like ``gl_<43 random characters>``; only their SHA-256 is stored.  Each token
has a fixed one-minute request window kept in the database, so the limit holds across
restarts and several server processes.
"""

from __future__ import annotations

import secrets
from dataclasses import dataclass
from datetime import timedelta

from sqlalchemy import and_, case, or_, update
from sqlmodel import Session, select

from app.accounts.security import token_digest
from app.models import ApiToken, AuthSession, User, utcnow

LOGIN_TOKEN_LIFETIME = timedelta(hours=1)
SCOPES = ("read", "upload")


def new_token(
    db: Session,
    user: User,
    *,
    kind: str,
    name: str = "",
    scopes: tuple[str, ...] = SCOPES,
    lifetime: timedelta | None = None,
) -> tuple[str, ApiToken]:
    raw = "gl_" + secrets.token_urlsafe(32)
    record = ApiToken(
        user_id=user.id,
        kind=kind,
        name=name[:100],
        token_hash=token_digest(raw),
        prefix=raw[:10],
        scopes=",".join(s for s in SCOPES if s in scopes),
        expires_at=utcnow() + lifetime if lifetime else None,
    )
    db.add(record)
    db.flush()
    return raw, record


@dataclass
class TokenUse:
    id: int
    user_id: int
    scopes: str


@dataclass
class TokenCheck:
    token: TokenUse | None
    problem: str | None = None  # "invalid" | "rate"
    retry_after: int = 0


def _counted(model, condition, now):
    """``UPDATE model SET <this request counted in its one-minute window> WHERE condition
    RETURNING ...``: atomic on its own (a row lock on PostgreSQL), so it needs no
    serialised write transaction -- every SET expression reads the row as it was."""
    window_over = or_(
        model.window_start.is_(None), model.window_start <= now - timedelta(minutes=1)
    )
    return (
        update(model)
        .where(condition)
        .values(
            window_start=case((window_over, now), else_=model.window_start),
            window_count=case((window_over, 1), else_=model.window_count + 1),
        )
        .returning(model.id, model.user_id, model.window_start, model.window_count)
    )


def _retry_after(row, now) -> int:
    return max(60 - int((now - row.window_start).total_seconds()), 1)


def check_token(db: Session, raw: str, rate_per_minute: int) -> TokenCheck:
    """Find a live token and count this request in its one-minute window (caller commits)."""
    now = utcnow()
    live = and_(
        ApiToken.token_hash == token_digest(raw),
        ApiToken.revoked_at.is_(None),
        or_(ApiToken.expires_at.is_(None), ApiToken.expires_at > now),
    )
    counted = db.execute(
        _counted(ApiToken, live, now).values(last_used_at=now).returning(ApiToken.scopes)
    ).first()
    if counted is None:
        return TokenCheck(None, "invalid")
    token = TokenUse(counted.id, counted.user_id, counted.scopes)
    if counted.window_count > rate_per_minute:
        return TokenCheck(token, "rate", _retry_after(counted, now))
    return TokenCheck(token)


def count_cookie_request(db: Session, auth_session_id: int, rate_per_minute: int) -> int:
    """Count an API call made with a browser session; 0, or seconds to wait past the rate."""
    now = utcnow()
    counted = db.execute(_counted(AuthSession, AuthSession.id == auth_session_id, now)).first()
    if counted is not None and counted.window_count > rate_per_minute:
        return _retry_after(counted, now)
    return 0


def user_tokens(db: Session, user: User) -> list[ApiToken]:
    return list(
        db.exec(
            select(ApiToken)
            .where(ApiToken.user_id == user.id, ApiToken.kind == "personal")
            .order_by(ApiToken.created_at.desc())
        ).all()
    )
