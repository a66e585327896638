"""LTI Dynamic Registration (IMS LTI-DR 1.0): an LMS administrator pastes one URL.

The URL is a one-time registration link an administrator of GyroLab makes (admin page or
``gyrolab lti registration-link``): without it anybody could register a "platform" of
their own and launch into GyroLab as its instructors.  The LMS opens the link with its
``openid_configuration`` URL and a ``registration_token``; pylti1p3 fetches the
configuration, posts GyroLab's tool configuration to the LMS's registration endpoint, and
the answer (client id, deployment id) becomes an ``LtiPlatform``.
"""

from __future__ import annotations

import secrets
from datetime import timedelta

import requests
from pylti1p3.dynamic_registration import DynamicRegistration
from pylti1p3.exception import LtiException
from sqlmodel import Session

from app.core.exceptions import UserError
from app.db import write_session
from app.lti.handshake import DatabaseStorage, http_session
from app.lti.platforms import PlatformFields, add_platform
from app.models import LtiLaunchValue, LtiPlatform, utcnow

LINK_LIFETIME = timedelta(days=1)
PLATFORM_CONFIGURATION = "https://purl.imsglobal.org/spec/lti-platform-configuration"
TOOL_CONFIGURATION = "https://purl.imsglobal.org/spec/lti-tool-configuration"
SCOPES = [
    "https://purl.imsglobal.org/spec/lti-ags/scope/lineitem",
    "https://purl.imsglobal.org/spec/lti-ags/scope/lineitem.readonly",
    "https://purl.imsglobal.org/spec/lti-ags/scope/score",
    "https://purl.imsglobal.org/spec/lti-nrps/scope/contextmembership.readonly",
]


def new_registration_link(db: Session) -> str:
    """A one-time token for ``/lti/register?token=…`` (valid a day); the caller commits."""
    token = secrets.token_urlsafe(24)
    db.add(
        LtiLaunchValue(key=_key(token), value='"registration"', expires_at=utcnow() + LINK_LIFETIME)
    )
    return token


def _key(token: str) -> str:
    return f"lti1p3-registration-{token[:64]}"


def link_is_live(token: str) -> bool:
    with write_session() as db:
        row = db.get(LtiLaunchValue, _key(token))
        return row is not None and row.expires_at > utcnow()


class GyroLabRegistration(DynamicRegistration):
    client_name = "GyroLab"
    description = "FOG north-finding teaching lab: heading, latitude and Earth rate."

    def __init__(self, base_url: str, configuration_url: str, registration_token: str | None):
        self.base_url = base_url.rstrip("/")
        self.configuration_url = configuration_url
        self.registration_token = registration_token
        self.platform: LtiPlatform | None = None

    def get_request_session(self) -> requests.Session:
        return http_session()

    def get_initiate_login_uri(self) -> str:
        return f"{self.base_url}/lti/login"

    def get_jwks_uri(self) -> str:
        return f"{self.base_url}/lti/jwks.json"

    def get_redirect_uris(self) -> list[str]:
        return [f"{self.base_url}/lti/launch"]

    def get_target_link_uri(self) -> str:
        return f"{self.base_url}/lti/launch"

    def get_domain(self) -> str:
        return self.base_url.split("://", 1)[-1]

    def get_logo_uri(self) -> str:
        return f"{self.base_url}/static/favicon.svg"

    def get_scopes(self) -> list[str]:
        return SCOPES

    def get_claims(self) -> list[str]:
        return ["iss", "sub", "name", "given_name", "family_name", "email"]

    def get_messages(self) -> list[dict]:
        return [
            {
                "type": "LtiDeepLinkingRequest",
                "target_link_uri": f"{self.base_url}/lti/launch",
                "label": "GyroLab",
                "placements": ["ContentArea"],
            }
        ]

    def get_openid_configuration_endpoint(self) -> str:
        return self.configuration_url

    def get_registration_token(self) -> str:
        return self.registration_token  # type: ignore[return-value]

    def complete_registration(self, configuration: dict, registration: dict) -> LtiPlatform:
        tool = registration.get(TOOL_CONFIGURATION) or {}
        platform = configuration.get(PLATFORM_CONFIGURATION) or {}
        fields = PlatformFields(
            name=str(platform.get("product_family_code") or configuration.get("issuer") or ""),
            issuer=str(configuration.get("issuer") or ""),
            client_id=str(registration.get("client_id") or ""),
            auth_login_url=str(configuration.get("authorization_endpoint") or ""),
            auth_token_url=str(configuration.get("token_endpoint") or ""),
            key_set_url=str(configuration.get("jwks_uri") or ""),
            deployment_ids=[str(tool["deployment_id"])] if tool.get("deployment_id") else [],
            auth_audience=configuration.get("authorization_server"),
        )
        with write_session() as db:
            self.platform = add_platform(db, fields, registered_by="dynamic")
        return self.platform


def register(token: str, base_url: str, configuration_url: str, registration_token: str | None):
    """Run the registration for a live link (used once); a UserError says what failed."""
    if not DatabaseStorage().consume(_key(token)):
        raise UserError("lti.registration_link_used", status=403)
    try:
        return GyroLabRegistration(base_url, configuration_url, registration_token).register()
    except (LtiException, requests.RequestException, ValueError, KeyError, AssertionError) as e:
        restore_link(token)
        raise UserError("lti.registration_failed", status=502, reason=str(e)[:200]) from e
    except UserError:
        restore_link(token)
        raise


def restore_link(token: str) -> None:
    """Give a link back after a failed attempt (the admin may retry from the LMS)."""
    with write_session() as db:
        db.merge(
            LtiLaunchValue(
                key=_key(token), value='"registration"', expires_at=utcnow() + LINK_LIFETIME
            )
        )
