"""Bearer tokens for the API: personal access tokens and short-lived log-in tokens.

Tokens look like ``gl_<43 random characters>``; only their SHA-256 is stored.  Each token
has a fixed one-minute request window kept in the database, so the limit holds across
restarts and several server processes; workers lease requests of it a few at a time
(``rate_leases``), so most requests only read.
"""

from __future__ import annotations

import secrets
from dataclasses import dataclass
from datetime import timedelta

from sqlalchemy import bindparam, or_
from sqlmodel import Session, select

from app.accounts.rate_leases import LEASES, lease_parameters, lease_update
from app.models import ApiToken, AuthSession, User, utcnow
from app.web.signing import token_digest

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
    user: User | None  # the token's owner (None: no live token)
    scopes: set[str]
    problem: str | None = None  # "invalid" | "rate"
    retry_after: int = 0


def check_token(db: Session, raw: str, rate_per_minute: int) -> TokenCheck:
    """Find a live token and its owner (one read) and admit this request within the
    token's per-minute rate (a database write once per lease, see ``rate_leases``)."""
    now = utcnow()
    digest = token_digest(raw)
    found = db.exec(
        select(ApiToken.id, ApiToken.scopes, User)
        .join(User, User.id == ApiToken.user_id)
        .where(
            ApiToken.token_hash == digest,
            ApiToken.revoked_at.is_(None),
            or_(ApiToken.expires_at.is_(None), ApiToken.expires_at > now),
        )
    ).first()
    if found is None:
        return TokenCheck(None, set(), "invalid")
    token_id, scopes, user = found
    admission = LEASES.admit(digest, rate_per_minute, _leaser(db, ApiToken, token_id, touch=True))
    if not admission.admitted:
        return TokenCheck(user, set(), "rate", admission.retry_after)
    return TokenCheck(user, set(scopes.split(",")))


def count_cookie_request(db: Session, auth: AuthSession, rate_per_minute: int) -> int:
    """Count an API call made with a browser session; 0, or seconds to wait past the rate."""
    admission = LEASES.admit(auth.token_hash, rate_per_minute, _leaser(db, AuthSession, auth.id))
    return 0 if admission.admitted else admission.retry_after


def _leaser(db: Session, model, row_id: int, *, touch: bool = False):
    """Lease ``size`` requests of the row's window in its own short statement."""

    def lease(size: int, now):
        # End the read first: on SQLite a read transaction cannot become a write once
        # another writer has committed ("database is locked" at once, no busy wait).
        db.commit()
        statement = lease_update(model)
        if touch:
            statement = statement.values(last_used_at=bindparam("now"))
        # Core on the session's connection: no ORM bulk-update work for a counter
        counted = db.connection().execute(statement, lease_parameters(row_id, size, now)).first()
        db.commit()
        return None if counted is None else (counted.window_start, counted.window_count)

    return lease


def user_tokens(db: Session, user: User) -> list[ApiToken]:
    return list(
        db.exec(
            select(ApiToken)
            .where(ApiToken.user_id == user.id, ApiToken.kind == "personal")
            .order_by(ApiToken.created_at.desc())
        ).all()
    )
