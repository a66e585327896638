"""Bearer tokens for the API: personal access tokens and short-lived log-in tokens.

Tokens look like ``gl_<43 random characters>``; only their SHA-256 is stored.  Each token
has a fixed one-minute request window kept in the database, so the limit holds across
restarts and several server processes.
"""

from __future__ import annotations

import secrets
from dataclasses import dataclass
from datetime import timedelta

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
class TokenCheck:
    token: ApiToken | None
    problem: str | None = None  # "invalid" | "rate"
    retry_after: int = 0


def check_token(db: Session, raw: str, rate_per_minute: int) -> TokenCheck:
    """Find a live token, count this request in its window (caller commits)."""
    record = db.exec(select(ApiToken).where(ApiToken.token_hash == token_digest(raw))).first()
    now = utcnow()
    if (
        record is None
        or record.revoked_at is not None
        or (record.expires_at is not None and record.expires_at <= now)
    ):
        return TokenCheck(None, "invalid")
    if record.window_start is None or now - record.window_start >= timedelta(minutes=1):
        record.window_start, record.window_count = now, 0
    record.window_count += 1
    record.last_used_at = now
    db.add(record)
    if record.window_count > rate_per_minute:
        wait = 60 - int((now - record.window_start).total_seconds())
        return TokenCheck(record, "rate", max(wait, 1))
    return TokenCheck(record)


def user_tokens(db: Session, user: User) -> list[ApiToken]:
    return list(
        db.exec(
            select(ApiToken)
            .where(ApiToken.user_id == user.id, ApiToken.kind == "personal")
            .order_by(ApiToken.created_at.desc())
        ).all()
    )
