"""Passwords (argon2id via pwdlib), server-side sessions, CSRF tokens and login throttling."""

from __future__ import annotations

import hashlib
import math
import secrets
import threading
from dataclasses import dataclass
from datetime import timedelta
from functools import lru_cache

from pwdlib import PasswordHash
from pwdlib.hashers.argon2 import Argon2Hasher
from sqlalchemy import and_, delete, or_, update
from sqlmodel import Session, select

from app.config import Settings
from app.core.text_files import plain_text
from app.db import give_way, lock_keys
from app.models import ApiToken, AuthSession, LoginFailure, User, utcnow
from app.web.signing import signed, token_digest, unsigned

# OWASP's minimum for argon2id, in the cheapest of its five equal settings (m=7 MiB, t=5,
# p=1; "equal level of defense", trading memory for passes): ≈ 16 ms per verify here,
# 20–25 % less than m=19 MiB, t=2 alone and with four at once (7 MiB stays in the cache;
# bench/README.md, issue 32), against ~250 ms for the library default, so a whole class
# can log in at once.  Hashes made with other parameters keep verifying (they carry them).
ARGON2_MEMORY_KIB = 7 * 1024
ARGON2_TIME_COST = 5
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
    """A username as stored and looked up: full-width forms as ASCII (a student number
    typed with a Chinese input method), no surrounding spaces, lower case."""
    return plain_text(username).strip().lower()


@lru_cache
def _dummy_hash() -> str:
    return hash_password(secrets.token_urlsafe(16))


def check_password(user: User | None, password: str) -> tuple[bool, str | None]:
    """Check a password without the database; one hash either way (no timing oracle).
    Returns whether it matches and, when the stored hash has other parameters than the
    app's, the password hashed with the app's (to store: every hash converges on one cost)."""
    if user is None:
        verify_password(password, _dummy_hash())
        return False, None
    return password_hasher().verify_and_update(password, user.password_hash)


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


# --- login throttling (in the database: survives restarts, shared by workers) --------------
#
# Failures are counted in four ways, so that an attacker cannot turn the throttle against
# the user it protects (OWASP's "device cookies"):
#   pair     account + client address: growing delays, then a pause (the user who mistypes);
#            an attempt being checked is "pending" and counts towards the pause only
#   account  all untrusted attempts at one account, from anywhere: brute force stays slow
#   address  all untrusted failures from one address: password spraying stays slow
#   device   attempts from a browser that logged in to this account before (a signed
#            cookie): they skip the account and address limits, so guesses from elsewhere
#            never lock the real user out, nor a class behind one NAT.
# Each attempt is charged before its password is hashed (outside the write lock), so
# guesses sent in parallel cannot slip past a limit; at most ``login_hash_slots`` hashes
# run at once per process (argon2id takes 7 MiB each).

HASH_WAIT_SECONDS = 5.0


@dataclass
class LoginOutcome:
    user: User | None
    problem: str | None = None  # "throttled" | "failed" | "busy"
    retry_after: int = 0  # seconds, for "throttled" and "busy"
    device_cookie: str | None = None  # on success: remember this browser for the account


@lru_cache
def _hash_slots(count: int) -> threading.BoundedSemaphore:
    return threading.BoundedSemaphore(count)


def _account_key(username: str) -> str:
    return normalise_username(username)[:128]


def _pair_key(account: str, address: str) -> str:
    return hashlib.sha256(f"{account}|{address}".encode()).hexdigest()


def device_cookie_value(account: str, secret: str) -> str:
    return signed(f"{account}:{secrets.token_urlsafe(12)}", secret, "device")


def trusted_device(cookie: str | None, account: str, secret: str) -> str | None:
    """The device key when the signed cookie was issued to this account, else None."""
    value = unsigned(cookie, secret, "device")
    if not isinstance(value, str) or ":" not in value:
        return None
    owner, nonce = value.rsplit(":", 1)
    return nonce[:64] if owner == account else None


def _wait_for_limit(times: list, limit: int, window: timedelta, now) -> float:
    """Seconds until fewer than ``limit`` failures are left in the window."""
    if len(times) < limit:
        return 0.0
    return (times[len(times) - limit] + window - now).total_seconds()


def login_wait(
    db: Session, account: str, address: str, device: str | None, settings: Settings
) -> tuple[int, bool]:
    """(seconds this attempt must wait, whether it counts as from a trusted device)."""
    now = utcnow()
    window = timedelta(minutes=settings.login_window_minutes)
    since = now - window
    key = _pair_key(account, address)
    # every count in ONE statement (one round trip; a class logs in at once), and the
    # completed failures with the attempts being checked right now in the same snapshot:
    # an attempt that completes (pending → pair) between two statements would otherwise be
    # counted in neither (READ COMMITTED on PostgreSQL) and let one guess too many through
    wanted = [(("pair", "pending"), key), (("account",), account), (("address",), address)]
    if device is not None:
        wanted.append((("device",), device))
    rows = db.exec(
        select(LoginFailure.scope, LoginFailure.at)
        .where(
            or_(*(and_(LoginFailure.scope.in_(s), LoginFailure.key == k) for s, k in wanted)),
            LoginFailure.at >= since,
        )
        .order_by(LoginFailure.at)
    ).all()
    times: dict[str, list] = {"pair": [], "pending": [], "account": [], "address": [], "device": []}
    for scope, at in rows:
        times[scope].append(at)
    pair = times["pair"]
    tries = sorted(pair + times["pending"])
    waits = [_wait_for_limit(tries, settings.login_max_failures_per_pair, window, now)]
    if 2 <= len(pair) < settings.login_max_failures_per_pair:  # 2 s, 4 s, 8 s, ...
        delay = timedelta(seconds=2 ** (len(pair) - 1))
        waits.append((pair[-1] + delay - now).total_seconds())
    trusted = device is not None and len(times["device"]) < settings.login_max_failures_per_pair
    if not trusted:
        waits.append(
            _wait_for_limit(times["account"], settings.login_max_failures_per_account, window, now)
        )
        waits.append(
            _wait_for_limit(times["address"], settings.login_max_failures_per_address, window, now)
        )
    wait = max(waits)
    return (math.ceil(wait) if wait > 0 else 0), trusted


def log_in(
    db: Session,
    username: str,
    password: str,
    address: str,
    settings: Settings,
    device_cookie: str | None = None,
) -> LoginOutcome:
    """Check a log-in.  On success the caller adds its session or token and commits (and
    sets ``device_cookie`` where it can): the attempt's charges go in that transaction;
    every failure is already committed."""
    account = _account_key(username)
    address = address[:128]
    device = trusted_device(device_cookie, account, settings.secret_key)
    # the throttle is a read-check-write (count, then charge): one at a time per account
    # (PostgreSQL row writers; SQLite's single writer needs nothing).  Everything charged
    # here is the account's: its pair (account + address), its account count, or its
    # device (a device cookie names its account).  The address and the device are not
    # locked: an address's failures are written after the hash, never here, and a class
    # behind one address -- or every browser without a device cookie -- would otherwise
    # check its passwords one log-in at a time
    lock_keys(db, f"account:{account}")
    wait, trusted = login_wait(db, account, address, device, settings)
    if wait:
        return LoginOutcome(None, "throttled", wait)
    # In flight, an attempt counts against the limits (so parallel guesses cannot pass
    # them) but not towards the growing delay, which follows failures only: log-ins of one
    # account from one address at once (scripts, a device's workers) all get through.
    charges = [LoginFailure(scope="pending", key=_pair_key(account, address))]
    charges.append(
        LoginFailure(scope="device", key=device)
        if trusted
        else LoginFailure(scope="account", key=account)
    )
    db.add_all(charges)
    user = db.exec(select(User).where(User.username == normalise_username(username))).first()
    db.commit()
    # argon2id runs outside the interpreter lock, bounded by its own slots: the request's
    # work place (``web.admission``) goes to another request meanwhile
    give_way()
    slots = _hash_slots(settings.login_hash_slots)
    if not slots.acquire(timeout=HASH_WAIT_SECONDS):
        _uncharge(db, charges)
        return LoginOutcome(None, "busy", 1)
    try:
        matches, rehashed = check_password(user, password)
    finally:
        slots.release()
    if not matches:
        pending = db.get(LoginFailure, charges[0].id)
        if pending is not None:  # the attempt is now a failure of this account and address
            pending.scope = "pair"
            db.add(pending)
        if not trusted:
            db.add(LoginFailure(scope="address", key=address))
        db.commit()
        return LoginOutcome(None, "failed")
    # the attempt is uncharged and the pair's failures forgiven (and a hash of other
    # parameters replaced) in the transaction that the caller commits with its session
    # row: one transaction after the hash
    if rehashed is not None and user is not None:
        user.password_hash = rehashed
        db.add(user)
    db.exec(
        delete(LoginFailure).where(
            or_(
                LoginFailure.id.in_([c.id for c in charges]),
                and_(LoginFailure.scope == "pair", LoginFailure.key == charges[0].key),
            )
        )
    )
    return LoginOutcome(user, device_cookie=device_cookie_value(account, settings.secret_key))


def _uncharge(db: Session, charges: list[LoginFailure]) -> None:
    db.exec(delete(LoginFailure).where(LoginFailure.id.in_([c.id for c in charges])))
    db.commit()
