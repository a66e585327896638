"""Bearer tokens for the API: personal access tokens and short-lived log-in tokens.

Tokens look like ``gl_<43 random characters>``; only their SHA-256 is stored.  Each token
has a fixed one-minute request window kept in the database, so the limit holds across
restarts and several server processes.
"""

from __future__ import annotations

import secrets
from dataclasses import dataclass
from datetime import timedelta

from sqlalchemy import case, or_, update
from sqlmodel import Session, select

from app.models import ApiToken, User, utcnow
from app.security import token_digest

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


def check_token(db: Session, raw: str, rate_per_minute: int) -> TokenCheck:
    """Find a live token and count this request in its one-minute window (caller commits).

    One ``UPDATE ... RETURNING`` statement: atomic on its own (a row lock on PostgreSQL),
    so it needs no serialised write transaction -- every SET expression reads the row as it
    was, whichever request gets there first."""
    now = utcnow()
    window_over = or_(
        ApiToken.window_start.is_(None), ApiToken.window_start <= now - timedelta(minutes=1)
    )
    counted = db.execute(
        update(ApiToken)
        .where(
            ApiToken.token_hash == token_digest(raw),
            ApiToken.revoked_at.is_(None),
            or_(ApiToken.expires_at.is_(None), ApiToken.expires_at > now),
        )
        .values(
            window_start=case((window_over, now), else_=ApiToken.window_start),
            window_count=case((window_over, 1), else_=ApiToken.window_count + 1),
            last_used_at=now,
        )
        .returning(
            ApiToken.id,
            ApiToken.user_id,
            ApiToken.scopes,
            ApiToken.window_start,
            ApiToken.window_count,
        )
    ).first()
    if counted is None:
        return TokenCheck(None, "invalid")
    token = TokenUse(counted.id, counted.user_id, counted.scopes)
    if counted.window_count > rate_per_minute:
        wait = 60 - int((now - counted.window_start).total_seconds())
        return TokenCheck(token, "rate", max(wait, 1))
    return TokenCheck(token)


def user_tokens(db: Session, user: User) -> list[ApiToken]:
    return list(
        db.exec(
            select(ApiToken)
            .where(ApiToken.user_id == user.id, ApiToken.kind == "personal")
            .order_by(ApiToken.created_at.desc())
        ).all()
    )
