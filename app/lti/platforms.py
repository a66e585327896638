"""The LMSs GyroLab trusts (``LtiPlatform`` rows) and pylti1p3's view of them.

A platform is known by its issuer and the client id it gave GyroLab (one issuer may
register GyroLab more than once); a launch must come from one of its deployment ids.
"""

from __future__ import annotations

from dataclasses import dataclass
from urllib.parse import urlsplit

from pylti1p3.deployment import Deployment
from pylti1p3.registration import Registration
from pylti1p3.tool_config.abstract import ToolConfAbstract
from sqlmodel import Session, select

from app.core.exceptions import UserError
from app.lti import keys
from app.models import LtiPlatform

MAX_DEPLOYMENTS = 100


@dataclass
class PlatformFields:
    """What an administrator (or dynamic registration) tells GyroLab about an LMS."""

    name: str
    issuer: str
    client_id: str
    auth_login_url: str
    auth_token_url: str
    key_set_url: str
    deployment_ids: list[str]
    auth_audience: str | None = None


def _url(value: str, field: str) -> str:
    value = value.strip()
    parts = urlsplit(value)
    if parts.scheme not in ("https", "http") or not parts.netloc or len(value) > 1000:
        raise UserError("lti.bad_url", status=400, field=field)
    return value


def checked(fields: PlatformFields) -> PlatformFields:
    """The fields trimmed and checked; a UserError names the first wrong one."""
    name = fields.name.strip()[:200]
    issuer = fields.issuer.strip()
    client_id = fields.client_id.strip()
    if not issuer or len(issuer) > 500:
        raise UserError("lti.bad_issuer", status=400)
    if not client_id or len(client_id) > 255:
        raise UserError("lti.bad_client_id", status=400)
    deployments = sorted({d.strip() for d in fields.deployment_ids if d.strip()})
    if len(deployments) > MAX_DEPLOYMENTS or any(len(d) > 255 for d in deployments):
        raise UserError("lti.bad_deployments", status=400)
    return PlatformFields(
        name=name or urlsplit(issuer).netloc or issuer[:200],
        issuer=issuer,
        client_id=client_id,
        auth_login_url=_url(fields.auth_login_url, "auth_login_url"),
        auth_token_url=_url(fields.auth_token_url, "auth_token_url"),
        key_set_url=_url(fields.key_set_url, "key_set_url"),
        deployment_ids=deployments,
        auth_audience=(fields.auth_audience or "").strip()[:1000] or None,
    )


def add_platform(db: Session, fields: PlatformFields, registered_by: str = "admin") -> LtiPlatform:
    """Register (or update, same issuer and client id) a platform; the caller commits."""
    fields = checked(fields)
    row = db.exec(
        select(LtiPlatform).where(
            LtiPlatform.issuer == fields.issuer, LtiPlatform.client_id == fields.client_id
        )
    ).first() or LtiPlatform(issuer=fields.issuer, client_id=fields.client_id, name=fields.name)
    if row.id is not None:  # deployments add up; one registration, several placements
        fields.deployment_ids = sorted(set(fields.deployment_ids) | set(deployments_of(row)))
    row.name = fields.name
    row.auth_login_url = fields.auth_login_url
    row.auth_token_url = fields.auth_token_url
    row.auth_audience = fields.auth_audience
    row.key_set_url = fields.key_set_url
    row.deployment_ids = "\n".join(fields.deployment_ids)
    row.registered_by = registered_by
    db.add(row)
    db.flush()
    return row


def deployments_of(platform: LtiPlatform) -> list[str]:
    return [line for line in platform.deployment_ids.splitlines() if line]


def find_platform(db: Session, issuer: str, client_id: str | None) -> LtiPlatform | None:
    """The platform of an issuer and client id; without a client id, the issuer's only one."""
    rows = db.exec(select(LtiPlatform).where(LtiPlatform.issuer == issuer)).all()
    if client_id is not None:
        rows = [row for row in rows if row.client_id == client_id]
    return rows[0] if len(rows) == 1 else None


class DatabaseToolConf(ToolConfAbstract):
    """pylti1p3's tool configuration, read from the database (many client ids per issuer)."""

    def __init__(self, db: Session):
        super().__init__()
        self.db = db

    def check_iss_has_one_client(self, iss: str) -> bool:
        return False

    def check_iss_has_many_clients(self, iss: str) -> bool:
        return True

    def find_registration_by_issuer(self, iss: str, *args, **kwargs) -> Registration | None:
        return self.find_registration_by_params(iss, None)

    def find_registration_by_params(
        self, iss: str, client_id: str | None, *args, **kwargs
    ) -> Registration | None:
        platform = find_platform(self.db, iss, client_id)
        return registration_of(self.db, platform) if platform is not None else None

    def find_deployment(self, iss: str, deployment_id: str) -> Deployment | None:
        return None

    def find_deployment_by_params(
        self, iss: str, deployment_id: str, client_id: str, *args, **kwargs
    ) -> Deployment | None:
        platform = find_platform(self.db, iss, client_id)
        if platform is None or deployment_id not in deployments_of(platform):
            return None
        return Deployment().set_deployment_id(deployment_id)


def registration_of(db: Session, platform: LtiPlatform) -> Registration:
    """A platform as pylti1p3 sees it, signing with GyroLab's current key."""
    key = keys.signing_key(db)
    registration = (
        Registration()
        .set_issuer(platform.issuer)
        .set_client_id(platform.client_id)
        .set_auth_login_url(platform.auth_login_url)
        .set_auth_token_url(platform.auth_token_url)
        .set_key_set_url(platform.key_set_url)
        .set_tool_private_key(key.private_pem)
        .set_tool_public_key(keys.public_pem(key))
    )
    if platform.auth_audience:
        registration.set_auth_audience(platform.auth_audience)
    return registration
