"""Single sign-on with an OpenID Connect provider (a university's identity service).

Configured by environment (``GYROLAB_OIDC_DISCOVERY_URL``, ``…_CLIENT_ID``,
``…_CLIENT_SECRET``; see the README), next to local passwords.  authlib does the protocol:
discovery, the authorization-code flow with ``state`` and ``nonce``, the token exchange,
and the ID token's checks (signature against the provider's keys, issuer, audience,
expiry, nonce).  This module only maps a verified identity to an account:

* an identity is the provider's ``iss`` and ``sub`` (never the e-mail address, which a
  provider may let people change): the first log-in creates a GyroLab account with no
  usable password, later ones find it again;
* a new account is a student unless ``GYROLAB_OIDC_ROLE_CLAIM`` holds one of
  ``GYROLAB_OIDC_TEACHER_VALUES``; an existing account keeps the role an administrator
  gave it;
* its username comes from ``preferred_username`` (or the e-mail's local part), made
  unique -- it never takes over an existing local account of the same name.
"""

from __future__ import annotations

import hashlib
import re
import secrets
from functools import lru_cache

from sqlmodel import Session, select

from app.accounts.security import hash_password, normalise_username
from app.config import Settings
from app.core.text_files import shown_name
from app.models import ExternalIdentity, Role, User, utcnow

USERNAME_CHARS = re.compile(r"[^a-z0-9._-]+")


def sso_enabled(settings: Settings) -> bool:
    return bool(settings.oidc_discovery_url and settings.oidc_client_id)


@lru_cache
def provider_client(discovery_url: str, client_id: str, client_secret: str):
    """The provider as an authlib client (its metadata and keys fetched when first used).

    authlib makes an httpx client for each call to the provider, and httpx a TLS context
    for each client, loading the CA bundle each time (≈ 20 ms of CPU, twice a log-in):
    one context, made here as httpx makes it (``SSL_CERT_FILE``/``SSL_CERT_DIR`` or
    certifi's bundle), serves them all."""
    import httpx
    from authlib.integrations.starlette_client import OAuth

    oauth = OAuth()
    oauth.register(
        "sso",
        server_metadata_url=discovery_url,
        client_id=client_id,
        client_secret=client_secret,
        client_kwargs={"scope": "openid email profile", "verify": httpx.create_ssl_context()},
    )
    return oauth.create_client("sso")


def client_for(settings: Settings):
    return provider_client(
        settings.oidc_discovery_url, settings.oidc_client_id, settings.oidc_client_secret
    )


def role_from_claims(claims: dict, settings: Settings) -> Role:
    """Teacher when the configured claim holds one of the teacher values, else student."""
    if not settings.oidc_role_claim:
        return Role.student
    value = claims.get(settings.oidc_role_claim)
    held = {str(v).strip().lower() for v in (value if isinstance(value, list) else [value])}
    teacher = {v.strip().lower() for v in settings.oidc_teacher_values.split(",") if v.strip()}
    return Role.teacher if held & teacher else Role.student


def free_username(db: Session, claims: dict) -> str:
    """A username from ``preferred_username`` (or the e-mail's local part), made unique."""
    wanted = str(claims.get("preferred_username") or "")
    if not wanted and isinstance(claims.get("email"), str):
        wanted = claims["email"].split("@", 1)[0]
    base = USERNAME_CHARS.sub("-", normalise_username(wanted)).strip("-.")[:48]
    if not base:
        base = "sso-" + hashlib.sha256(str(claims.get("sub")).encode()).hexdigest()[:8]
    candidate, number = base, 1
    while db.exec(select(User.id).where(User.username == candidate)).first() is not None:
        number += 1
        candidate = f"{base}-{number}"
    return candidate


def account_for(db: Session, claims: dict, new_role: Role) -> User:
    """The account of a verified identity (``iss``, ``sub``), created on its first log-in
    with ``new_role``; its name and e-mail follow the provider's.  The caller commits.

    Used by single sign-on and by LTI launches (the LMS is then the identity provider)."""
    issuer, subject = str(claims["iss"]), str(claims["sub"])
    identity = db.exec(
        select(ExternalIdentity).where(
            ExternalIdentity.issuer == issuer, ExternalIdentity.subject == subject
        )
    ).first()
    name = shown_name(str(claims.get("name") or claims.get("preferred_username") or ""))[:128]
    email = claims.get("email") if isinstance(claims.get("email"), str) else None
    email = email if email and len(email) <= 254 else None
    if identity is not None:
        user = db.get(User, identity.user_id)
        if name and user.display_name != name:
            user.display_name = name
        if email and user.email != email:
            user.email = email
        db.add(user)
    else:
        user = User(
            username=free_username(db, claims),
            display_name=name or subject[:128],
            email=email,
            role=new_role.value,
            # a password nobody knows: this account logs in through the provider
            password_hash=hash_password(secrets.token_urlsafe(32)),
        )
        db.add(user)
        db.flush()
        identity = ExternalIdentity(user_id=user.id, issuer=issuer[:500], subject=subject[:255])
    identity.last_login_at = utcnow()
    db.add(identity)
    return user


def signs_in_elsewhere(db: Session, user: User) -> bool:
    """Whether the account logs in through an identity provider (it has no password)."""
    found = db.exec(select(ExternalIdentity.id).where(ExternalIdentity.user_id == user.id))
    return found.first() is not None
