"""Settings from environment variables prefixed ``GYROLAB_`` (pydantic-settings).

| variable | default |
|---|---|
| GYROLAB_DATABASE_URL | ``sqlite:///<var dir>/gyrolab.db`` |
| GYROLAB_VAR_DIR | ``./var`` (database, secret key, demo credentials) |
| GYROLAB_SECRET_KEY | generated on first run and kept in ``<var dir>/secret_key`` |
| GYROLAB_SESSION_IDLE_MINUTES | 120 |
| GYROLAB_SESSION_LIFETIME_HOURS | 12 |
| GYROLAB_HOST / GYROLAB_PORT | 127.0.0.1 / 8000 |
| GYROLAB_TIMEZONE | ``Asia/Shanghai`` (a course's default zone for due dates) |
| GYROLAB_PUBLIC_URL | the request's address (LTI registration behind a proxy) |
"""

from __future__ import annotations

import os
import secrets
from functools import cache, lru_cache
from pathlib import Path

from pydantic import Field, field_validator
from pydantic_settings import BaseSettings, SettingsConfigDict


class Settings(BaseSettings):
    model_config = SettingsConfigDict(env_prefix="GYROLAB_", extra="ignore")

    var_dir: Path = Path("var")
    database_url: str = ""
    secret_key: str = ""
    session_idle_minutes: int = Field(default=120, ge=1)
    session_lifetime_hours: int = Field(default=12, ge=1)
    host: str = "127.0.0.1"
    port: int = Field(default=8000, ge=1, le=65535)
    login_max_failures_per_pair: int = Field(default=5, ge=2)
    login_max_failures_per_account: int = Field(default=10, ge=1)
    login_max_failures_per_address: int = Field(default=100, ge=1)
    login_window_minutes: int = Field(default=15, ge=1)
    login_hash_slots: int = Field(default=4, ge=1)
    report_renders: int = Field(default=2, ge=1)  # PDF renders at once per process
    report_cache_mb: int = Field(default=64, ge=0)  # rendered PDFs kept per process
    api_rate_per_minute: int = Field(default=600, ge=1)
    student_storage_mb: int = Field(default=200, ge=1)
    max_body_bytes: int = Field(default=64 * 1024 * 1024, ge=1024)
    # OpenID Connect single sign-on (accounts/sso.py): on when a discovery URL is set
    oidc_discovery_url: str | None = None  # …/.well-known/openid-configuration
    oidc_client_id: str = ""
    oidc_client_secret: str = ""
    oidc_name: str = ""  # the button's words, e.g. "University ID" (default: "single sign-on")
    oidc_role_claim: str = ""  # a claim naming the person's roles or groups, e.g. "groups"
    oidc_teacher_values: str = ""  # comma-separated values of that claim that mean teacher
    # the address people and LMSs reach GyroLab at (LTI registration, behind a proxy);
    # default: the address of the request
    public_url: str = ""
    # requests of one worker running at once, and state-changing ones (web/admission.py)
    request_concurrency: int = Field(default=2, ge=1, le=64)
    write_concurrency: int = Field(default=8, ge=1, le=32)
    # how long a served worker's thread keeps the interpreter while another waits for it
    # (sys.setswitchinterval; CPython's default is 5 ms): main.set_switch_interval
    switch_interval_ms: float = Field(default=1.0, ge=0.1, le=100.0)
    timezone: str = "Asia/Shanghai"  # a course's default zone for due dates and times

    @field_validator("timezone")
    @classmethod
    def _known_zone(cls, value: str) -> str:
        if value not in iana_zones():
            raise ValueError(f"GYROLAB_TIMEZONE {value!r} is not an IANA time zone")
        return value

    @field_validator("secret_key")
    @classmethod
    def _no_placeholder(cls, value: str) -> str:
        if value and (len(value) < 16 or value.lower() in {"changeme", "secret", "change-me"}):
            raise ValueError("GYROLAB_SECRET_KEY must be a random string of at least 16 characters")
        return value

    def resolved(self) -> Settings:
        """Fill in the database URL and secret key defaults that depend on the var dir."""
        var_dir = self.var_dir.resolve()
        var_dir.mkdir(parents=True, exist_ok=True)
        url = self.database_url or f"sqlite:///{var_dir / 'gyrolab.db'}"
        key = self.secret_key or _persisted_secret(var_dir / "secret_key")
        return self.model_copy(update={"var_dir": var_dir, "database_url": url, "secret_key": key})


@cache
def iana_zones() -> frozenset[str]:
    """The IANA time zone names this machine knows, read once: ``available_timezones`` walks
    the whole zone database on every call (≈ 6 ms), and settings and course pages ask often."""
    from zoneinfo import available_timezones

    return frozenset(available_timezones())


def _persisted_secret(path: Path) -> str:
    if path.exists():
        return path.read_text().strip()
    key = secrets.token_urlsafe(48)
    try:
        fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600)
    except FileExistsError:  # another worker wrote it first
        return path.read_text().strip()
    with os.fdopen(fd, "w") as handle:
        handle.write(key)
    return key


@lru_cache
def get_settings() -> Settings:
    return Settings().resolved()
