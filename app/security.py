"""Passwords (argon2id via pwdlib), server-side sessions, CSRF tokens and login throttling."""

from __future__ import annotations

import hashlib
import hmac
import secrets
from datetime import timedelta
from functools import lru_cache

from pwdlib import PasswordHash
from pwdlib.hashers.argon2 import Argon2Hasher
from sqlalchemy import delete, func, update
from sqlmodel import Session, select

from app.config import Settings
from app.models import ApiToken, AuthSession, LoginFailure, User, utcnow

# OWASP's minimum for argon2id (m=19 MiB, t=2, p=1): ~30 ms per verify on 2 cores,
# against ~250 ms for the library default, so a whole class can log in at once.
ARGON2_MEMORY_KIB = 19 * 1024
ARGON2_TIME_COST = 2
ARGON2_PARALLELISM = 1
MIN_PASSWORD_LENGTH = 8


@lru_cache
def password_hasher() -> PasswordHash:
    return PasswordHash(
        (
            Argon2Hasher(
                memory_cost=ARGON2_MEMORY_KIB,
                time_cost=ARGON2_TIME_COST,
                parallelism=ARGON2_PARALLELISM,
            ),
        )
    )


def hash_password(password: str) -> str:
    return password_hasher().hash(password)


def verify_password(password: str, password_hash: str) -> bool:
    return password_hasher().verify(password, password_hash)


def normalise_username(username: str) -> str:
    return username.strip().lower()


@lru_cache
def _dummy_hash() -> str:
    return hash_password(secrets.token_urlsafe(16))


def password_matches(user: User | None, password: str) -> bool:
    """Check a password without the database; one hash either way (no timing oracle)."""
    if user is None:
        verify_password(password, _dummy_hash())
        return False
    return verify_password(password, user.password_hash)


def generate_password(length: int = 12) -> str:
    """A readable one-time password (no 0/O/1/l confusion)."""
    alphabet = "abcdefghjkmnpqrstuvwxyzABCDEFGHJKMNPQRSTUVWXYZ23456789"
    return "".join(secrets.choice(alphabet) for _ in range(length))


def password_problem(password: str, username: str = "") -> str | None:
    """A message key describing why a new password is unacceptable, or None."""
    if len(password) < MIN_PASSWORD_LENGTH:
        return "password.too_short"
    if len(password) > 256:
        return "password.too_long"
    if username and password.strip().lower() == username.strip().lower():
        return "password.same_as_username"
    return None


# --- sessions -----------------------------------------------------------------------------


def token_digest(token: str) -> str:
    return hashlib.sha256(token.encode()).hexdigest()


def create_session(db: Session, user: User, settings: Settings) -> str:
    """Store a new session for ``user``; returns the raw token for the cookie."""
    token = secrets.token_urlsafe(32)
    db.add(
        AuthSession(
            token_hash=token_digest(token),
            user_id=user.id,
            csrf_token=secrets.token_urlsafe(32),
            expires_at=utcnow() + timedelta(hours=settings.session_lifetime_hours),
        )
    )
    return token


def session_is_live(record: AuthSession, settings: Settings) -> bool:
    now = utcnow()
    if record.revoked_at is not None or record.expires_at <= now:
        return False
    return now - record.last_seen_at <= timedelta(minutes=settings.session_idle_minutes)


def revoke_sessions(db: Session, user_id: int, keep_id: int | None = None) -> None:
    """Revoke every live session of a user (all but ``keep_id``)."""
    records = db.exec(
        select(AuthSession).where(AuthSession.user_id == user_id, AuthSession.revoked_at.is_(None))
    ).all()
    for record in records:
        if record.id != keep_id:
            record.revoked_at = utcnow()
            db.add(record)


def revoke_credentials(db: Session, user_id: int, keep_session_id: int | None = None) -> None:
    """Credentials changed: end every login session (but ``keep_session_id``) and revoke
    every API token -- personal and one-hour -- of the user."""
    revoke_sessions(db, user_id, keep_session_id)
    db.exec(
        update(ApiToken)
        .where(ApiToken.user_id == user_id, ApiToken.revoked_at.is_(None))
        .values(revoked_at=utcnow())
    )


def tokens_match(expected: str | None, given: str | None) -> bool:
    return bool(expected) and bool(given) and hmac.compare_digest(expected, given)


def signed(value: str, secret: str) -> str:
    mac = hmac.new(secret.encode(), value.encode(), hashlib.sha256).hexdigest()[:32]
    return f"{value}.{mac}"


def unsigned(value: str | None, secret: str) -> str | None:
    if not value or "." not in value:
        return None
    raw = value.rsplit(".", 1)[0]
    return raw if hmac.compare_digest(signed(raw, secret), value) else None


# --- login throttling (in the database: survives restarts, shared by workers) --------------


def _recent_failures(db: Session, scope: str, key: str, settings: Settings) -> int:
    since = utcnow() - timedelta(minutes=settings.login_window_minutes)
    return db.exec(
        select(func.count())
        .select_from(LoginFailure)
        .where(LoginFailure.scope == scope, LoginFailure.key == key, LoginFailure.at >= since)
    ).one()


def _account_key(username: str) -> str:
    return username.strip().lower()[:128]


def login_throttled(db: Session, username: str, address: str, settings: Settings) -> bool:
    account = _account_key(username)
    return (
        _recent_failures(db, "account", account, settings)
        >= settings.login_max_failures_per_account
        or _recent_failures(db, "address", address, settings)
        >= settings.login_max_failures_per_address
    )


def log_in(
    db: Session, username: str, password: str, address: str, settings: Settings
) -> tuple[User | None, str | None]:
    """Check a log-in: ``(user, None)`` when the password matches (the account's failures
    are cleared; the caller adds its session or token and commits), otherwise
    ``(None, "throttled" | "failed")`` with the failure already committed.

    The attempt is charged to the *account* before the password is checked, so that
    guesses at one account sent in parallel cannot slip past its limit while the slow hash
    runs -- outside the write lock, after a commit.  The *address* is charged only for a
    wrong password: a class logging in at once from behind one address must not be
    throttled by its own log-ins in flight."""
    if login_throttled(db, username, address, settings):
        return None, "throttled"
    db.add(LoginFailure(scope="account", key=_account_key(username)))
    user = db.exec(select(User).where(User.username == normalise_username(username))).first()
    db.commit()
    if not password_matches(user, password):
        db.add(LoginFailure(scope="address", key=address[:128]))
        db.commit()
        return None, "failed"
    clear_login_failures(db, user.username)
    return user, None


def clear_login_failures(db: Session, username: str) -> None:
    db.exec(
        delete(LoginFailure).where(
            LoginFailure.scope == "account", LoginFailure.key == _account_key(username)
        )
    )
