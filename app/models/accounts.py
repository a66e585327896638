"""Accounts: users, their log-in sessions, throttling, API tokens and external identities.
Every change here needs an Alembic migration (tests check it)."""

from __future__ import annotations

from datetime import datetime
from enum import StrEnum

from sqlalchemy import UniqueConstraint
from sqlmodel import Field, SQLModel

from app.models.clock import utcnow


class Role(StrEnum):
    admin = "admin"
    teacher = "teacher"
    student = "student"


class User(SQLModel, table=True):
    id: int | None = Field(default=None, primary_key=True)
    username: str = Field(max_length=64, unique=True, index=True)
    display_name: str = Field(max_length=128)
    email: str | None = Field(default=None, max_length=254)
    role: str = Field(max_length=16)
    password_hash: str = Field(max_length=255)
    must_change_password: bool = False
    language: str | None = Field(default=None, max_length=8)
    created_at: datetime = Field(default_factory=utcnow)
    # the teacher whose roster created this account (may reset its password); None for
    # accounts made by the CLI or an administrator
    created_by_id: int | None = Field(default=None, foreign_key="user.id", ondelete="SET NULL")


class AuthSession(SQLModel, table=True):
    """A server-side login session; the browser holds only a random token."""

    __tablename__ = "auth_session"
    id: int | None = Field(default=None, primary_key=True)
    token_hash: str = Field(max_length=64, unique=True, index=True)
    user_id: int = Field(foreign_key="user.id", index=True, ondelete="CASCADE")
    csrf_token: str = Field(max_length=64)
    created_at: datetime = Field(default_factory=utcnow)
    last_seen_at: datetime = Field(default_factory=utcnow)
    expires_at: datetime
    revoked_at: datetime | None = None
    window_start: datetime | None = None  # API calls with this cookie: one-minute windows
    window_count: int = 0


class LoginFailure(SQLModel, table=True):
    """One failed login, keyed by account or client address, for throttling."""

    __tablename__ = "login_failure"
    id: int | None = Field(default=None, primary_key=True)
    scope: str = Field(max_length=16)  # "account" | "address"
    key: str = Field(max_length=128, index=True)
    at: datetime = Field(default_factory=utcnow, index=True)


class ExternalIdentity(SQLModel, table=True):
    """An account's identity at an outside identity provider (OpenID Connect single
    sign-on): the provider's issuer and its stable subject id.  Such accounts have no
    usable password; they log in through the provider."""

    __tablename__ = "external_identity"
    __table_args__ = (UniqueConstraint("issuer", "subject"),)
    id: int | None = Field(default=None, primary_key=True)
    user_id: int = Field(foreign_key="user.id", index=True, ondelete="CASCADE")
    issuer: str = Field(max_length=500)
    subject: str = Field(max_length=255)
    created_at: datetime = Field(default_factory=utcnow)
    last_login_at: datetime | None = None


class ApiToken(SQLModel, table=True):
    """A bearer token: a personal access token (named, scoped, revocable) or a short-lived
    token from ``POST /api/v1/auth/token``.  Only its SHA-256 is stored."""

    __tablename__ = "api_token"
    id: int | None = Field(default=None, primary_key=True)
    user_id: int = Field(foreign_key="user.id", index=True, ondelete="CASCADE")
    kind: str = Field(max_length=8)  # personal | login
    name: str = Field(default="", max_length=100)
    token_hash: str = Field(max_length=64, unique=True, index=True)
    prefix: str = Field(max_length=12)  # the first characters, to recognise a token
    scopes: str = Field(max_length=32)  # "read" or "read,upload"
    created_at: datetime = Field(default_factory=utcnow)
    expires_at: datetime | None = None
    last_used_at: datetime | None = None
    revoked_at: datetime | None = None
    window_start: datetime | None = None  # per-token rate limit: fixed one-minute windows
    window_count: int = 0
