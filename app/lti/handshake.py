"""pylti1p3 on Starlette and the database: the OIDC login initiation and the launch.

The security checks of a launch (IMS Security Framework §5.1.3, LTI 1.3 §5.3), in order:

1. ``state``: the form's state equals the cookie set by ``/lti/login`` in this browser
   (no launch is ever re-validated from stored data);
2. the id_token is a JWT whose issuer and audience name a registered platform and client
   id (with several audiences, ``azp`` must be GyroLab's client id);
3. its RS256 signature verifies with the platform's published key (``kid``; the key set
   is fetched again once if the kid is unknown, for platforms that rotated);
4. ``exp`` and ``iat`` present, not expired, not issued in the future;
5. the deployment id is one registered for that platform;
6. the message is a valid LTI 1.3.0 resource-link or deep-linking request;
7. ``nonce``: the one this browser's login issued for this state, used once (deleted).
"""

from __future__ import annotations

import hmac
import json
import secrets
import time
from datetime import timedelta
from typing import Any

import requests
from pylti1p3.cookie import CookieService
from pylti1p3.exception import LtiException
from pylti1p3.launch_data_storage.base import LaunchDataStorage
from pylti1p3.message_launch import MessageLaunch
from pylti1p3.oidc_login import OIDCLogin
from pylti1p3.redirect import Redirect
from pylti1p3.request import Request as LtiRequest
from pylti1p3.service_connector import ServiceConnector
from pylti1p3.session import SessionService
from sqlalchemy import delete
from sqlmodel import col
from starlette.responses import RedirectResponse

from app.db import read_session, statement_session, write_session
from app.lti.frame_launch import PLATFORM_STATE, state_cookie_matches
from app.models import LtiLaunchValue, utcnow

COOKIE_PATH = "/lti/"
CLOCK_SKEW_S = 60
SERVICE_TIMEOUT_S = 10
KEY_SET_CACHE_S = 300


class LaunchRefused(Exception):
    """A login or launch that fails a check; ``reason`` says which, in English."""

    def __init__(self, reason: str):
        super().__init__(reason)
        self.reason = reason


class TimedSession(requests.Session):
    """requests with a timeout on every call (pylti1p3 sets none)."""

    def request(self, method, url, **kwargs):  # type: ignore[override]
        kwargs.setdefault("timeout", SERVICE_TIMEOUT_S)
        return super().request(method, url, **kwargs)


def http_session() -> requests.Session:
    session = TimedSession()
    session.headers["User-Agent"] = "GyroLab LTI tool"
    return session


class ServiceTokens(ServiceConnector):
    """Service calls (NRPS, AGS) with access tokens kept per process until they expire."""

    tokens: dict[str, tuple[str, float]] = {}

    def _get_cached_access_token(self, scope_key: str) -> str | None:
        token, until = self.tokens.get(scope_key, ("", 0.0))
        return token if until > time.time() + 30 else None

    def _cache_access_token(self, scope_key: str, access_token: str, expires_in: float) -> None:
        self.tokens[scope_key] = (access_token, time.time() + float(expires_in or 0))


class FormRequest(LtiRequest):
    """A Starlette request as pylti1p3 sees it: its parameters (query or form) and cookies."""

    def __init__(self, params: dict[str, str], cookies: dict[str, str], secure: bool):
        self.params, self.cookies, self.secure = params, cookies, secure

    @property
    def session(self):
        return None

    def is_secure(self) -> bool:
        return self.secure

    def get_param(self, key: str) -> str:
        return self.params.get(key)  # type: ignore[return-value]

    def get_cookie(self, key: str) -> str | None:
        return self.cookies.get(key)


class ResponseCookies(CookieService):
    """State cookies: read from the request, set on the response (``/lti/`` only).  In a
    secure context (HTTPS or loopback) they are ``SameSite=None; Secure; Partitioned``: a
    platform's cross-site form post carries them, and inside an LMS frame the browser keeps
    them for that LMS alone (CHIPS) instead of dropping them as third-party cookies."""

    def __init__(self, request: FormRequest):
        self.request = request
        self.pending: dict[str, tuple[str, int]] = {}

    def _key(self, name: str) -> str:
        return f"{self._cookie_prefix}-{name}"

    def get_cookie(self, name: str) -> str | None:
        return self.request.get_cookie(self._key(name))

    def set_cookie(self, name: str, value, exp: int | None = 3600) -> None:
        self.pending[self._key(name)] = (str(value), int(exp or 3600))

    def apply(self, response) -> None:
        secure = self.request.is_secure()
        for key, (value, max_age) in self.pending.items():
            response.set_cookie(
                key,
                value,
                max_age=max_age,
                path=COOKIE_PATH,
                httponly=True,
                secure=secure,
                samesite="none" if secure else "lax",
            )
            if secure:  # Python's http.cookies knows Partitioned only from 3.14
                name, value = response.raw_headers[-1]
                response.raw_headers[-1] = (name, value + b"; Partitioned")


class DatabaseStorage(LaunchDataStorage):
    """Handshake values in ``lti_launch_value`` (any worker can finish a launch)."""

    def can_set_keys_expiration(self) -> bool:
        return True

    def get_session_cookie_name(self) -> str | None:
        return None  # keys are random and short-lived; no per-browser prefix

    def get_value(self, key: str) -> Any:
        key = self._prepare_key(key)
        with read_session() as db:
            row = db.get(LtiLaunchValue, key)
            if row is None or row.expires_at <= utcnow():
                return None
            return json.loads(row.value)

    def set_value(self, key: str, value: Any, exp: int | None = None) -> None:
        key = self._prepare_key(key)
        expires = utcnow() + timedelta(seconds=exp or 3600)
        with write_session() as db:
            db.exec(delete(LtiLaunchValue).where(col(LtiLaunchValue.expires_at) <= utcnow()))
            row = db.get(LtiLaunchValue, key) or LtiLaunchValue(
                key=key, value="", expires_at=expires
            )
            row.value, row.expires_at = json.dumps(value), expires
            db.add(row)

    def check_value(self, key: str) -> bool:
        return self.get_value(key) is not None

    def consume(self, key: str) -> bool:
        """Delete the value; whether it was there and alive (exactly one caller wins)."""
        key = self._prepare_key(key)
        with statement_session() as db:
            result = db.exec(
                delete(LtiLaunchValue).where(
                    LtiLaunchValue.key == key, col(LtiLaunchValue.expires_at) > utcnow()
                )
            )
            db.commit()
            return result.rowcount == 1


class OneTimeSessions(SessionService):
    """pylti1p3's session service with nonces used once and no re-validation by state."""

    def __init__(self, request: FormRequest, storage: DatabaseStorage):
        super().__init__(request)
        self.storage = storage
        self.set_data_storage(storage)
        self._launch_data_lifetime = 3600

    def check_nonce(self, nonce: str) -> bool:
        return self.storage.consume(self._get_key("nonce", nonce))

    def set_state_valid(self, state: str, id_token_hash: str) -> None:
        return None

    def check_state_is_valid(self, state: str, id_token_hash: str) -> bool:
        return False


class CookieRedirect(Redirect):
    def __init__(self, location: str, cookies: ResponseCookies):
        self.location, self.cookies = location, cookies

    def do_redirect(self):
        response = RedirectResponse(self.location, status_code=302)
        self.cookies.apply(response)
        return response

    def do_js_redirect(self):
        return self.do_redirect()

    def set_redirect_url(self, location: str) -> None:
        self.location = location

    def get_redirect_url(self) -> str:
        return self.location


class Login(OIDCLogin):
    """The third-party login initiation: checks the platform, sets the state cookie,
    stores the nonce with the state, redirects to the platform's authorization endpoint."""

    def __init__(self, request: FormRequest, tool_config):
        storage = DatabaseStorage()
        cookies = ResponseCookies(request)
        super().__init__(
            request,
            tool_config,
            session_service=OneTimeSessions(request, storage),
            cookie_service=cookies,
        )
        self.cookies = cookies

    def _get_request_param(self, key: str) -> str:
        return self._request.get_param(key)

    def _generate_nonce(self) -> str:
        nonce = secrets.token_urlsafe(24)
        self.pass_params_to_launch({"nonce": nonce})  # kept with the state, checked at launch
        return nonce

    def get_redirect(self, url: str) -> CookieRedirect:
        return CookieRedirect(url, self.cookies)

    def registration_urls(self) -> list[str]:
        """The platform's issuer and authorization endpoint (once the login is checked):
        the origins that may frame the login page and answer its platform-storage calls."""
        registration = self._registration
        return [registration.get_issuer(), registration.get_auth_login_url()]


class Launch(MessageLaunch):
    """A launch checked as the module's docstring lists."""

    def __init__(self, request: FormRequest, tool_config):
        storage = DatabaseStorage()
        super().__init__(
            request,
            tool_config,
            session_service=OneTimeSessions(request, storage),
            cookie_service=ResponseCookies(request),
            requests_session=http_session(),
            service_connector_cls=ServiceTokens,
        )
        self.storage = storage
        self.set_public_key_caching(storage, KEY_SET_CACHE_S)
        self.set_jwt_verify_options({"verify_aud": False, "require": ["exp", "iat"]})

    def _get_request_param(self, key: str) -> str:
        return self._request.get_param(key)

    @classmethod
    def restored(cls, launch_id: str, body: dict, request: FormRequest, tool_config) -> Launch:
        """A launch checked earlier, from its stored claims (for its deep-linking answer)."""
        launch = cls(request, tool_config)
        launch.set_launch_id(launch_id).set_auto_validation(enable=False)
        launch.set_jwt({"body": body}).set_restored()
        launch.validate_registration()
        return launch

    def get_public_key(self):
        try:
            return super().get_public_key()
        except LtiException:  # unknown kid: the platform may have rotated; fetch once more
            assert self._registration is not None
            self._public_key_cache_data_storage = None
            self._registration.set_key_set(None)
            return super().get_public_key()

    def validate(self) -> Launch:
        if self._restored:
            raise LaunchRefused("A restored launch cannot be validated.")
        self._validated = True
        try:
            (
                self.validate_state()
                .validate_jwt_format()
                .validate_registration()
                .validate_audience()
                .validate_jwt_signature()
                .validate_times()
                .validate_deployment()
                .validate_message()
                .validate_nonce()
            )
        except Exception:
            self._validated = False
            raise
        self.get_session_service().save_launch_data(self.get_launch_id(), self._jwt["body"])
        return self

    def validate_state(self) -> Launch:
        """The state cookie this browser's login set -- or, inside an LMS frame with no
        cookies, the state read back from the LMS's platform storage by GyroLab's page
        (``frame_launch``), for a login GyroLab started whose nonce is still unused."""
        state = self._get_request_param("state") or ""
        confirmed = self._get_request_param(PLATFORM_STATE) or ""
        if state and confirmed:
            if not hmac.compare_digest(confirmed.encode(), state.encode()):
                raise LaunchRefused("The platform's storage holds another state.")
            if not self.get_params_from_login():
                raise LaunchRefused("This launch's login was not started by GyroLab.")
            return self
        if not state_cookie_matches(self._request.cookies, state):
            raise LaunchRefused(
                "The state is not this browser's (no state cookie, no platform storage)."
            )
        return self

    def validate_audience(self) -> Launch:
        body = self._jwt["body"]
        audience = body.get("aud")
        audiences = audience if isinstance(audience, list) else [audience]
        client_id = self._registration.get_client_id()
        if client_id not in audiences:
            raise LaunchRefused("The id_token is not addressed to GyroLab (aud).")
        if len(audiences) > 1 and body.get("azp") != client_id:
            raise LaunchRefused("The id_token has several audiences and azp is not GyroLab.")
        return self

    def validate_times(self) -> Launch:
        issued = self._jwt["body"].get("iat")
        if not isinstance(issued, int | float) or issued > time.time() + CLOCK_SKEW_S:
            raise LaunchRefused("The id_token was issued in the future (iat).")
        return self

    def validate_nonce(self) -> Launch:
        nonce = self._jwt["body"].get("nonce")
        expected = (self.get_params_from_login() or {}).get("nonce")
        if not nonce or nonce != expected:
            raise LaunchRefused("The nonce is not the one this login issued.")
        if not self._session_service.check_nonce(nonce):
            raise LaunchRefused("The nonce was used already (a replayed launch).")
        return self


def old_values_removed() -> int:
    """Delete expired handshake values (called now and then by the grade sender)."""
    with write_session() as db:
        result = db.exec(delete(LtiLaunchValue).where(col(LtiLaunchValue.expires_at) <= utcnow()))
        return result.rowcount or 0


def stored_launch(launch_id: str) -> dict | None:
    """The claims of a launch kept for its next step (deep linking), or None."""
    value = DatabaseStorage().get_value(launch_id)
    return value if isinstance(value, dict) else None


def service_connector(registration) -> ServiceTokens:
    """pylti1p3's connector to a platform's services (tokens by a JWT signed with
    GyroLab's key, RFC 7523), with timeouts."""
    return ServiceTokens(registration, requests_session=http_session())
