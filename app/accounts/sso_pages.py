"""The single sign-on round trip: ``/login/sso`` sends the browser to the provider, which
sends it back to ``/login/sso/callback`` with a code (see ``accounts/sso.py``).

The two steps are ``async`` because authlib talks to the provider with httpx's async
client; the database work runs on the thread pool, as everywhere else."""

from __future__ import annotations

import logging

from fastapi import APIRouter, Request
from sqlmodel import select
from starlette.concurrency import run_in_threadpool

from app.accounts.pages import login_view, safe_next
from app.accounts.security import create_session
from app.accounts.sso import account_for, client_for, role_from_claims, sso_enabled
from app.config import Settings, get_settings
from app.core.exceptions import UserError
from app.db import write_session
from app.models import LtiPlatform
from app.web.i18n import translator
from app.web.render import SESSION_COOKIE, redirect, render, request_language, set_cookie

log = logging.getLogger("gyrolab.sso")

router = APIRouter(tags=["pages: account"], include_in_schema=False)
NEXT_KEY = "sso_next"


def provider_problems() -> tuple[type[Exception], ...]:
    """What the round trip can meet: the provider's errors and refusals (authlib), an ID
    token that fails its checks (joserfc's JoseError: signature, algorithm, issuer,
    audience, expiry, nonce), the network (httpx).  Imported here, when single sign-on is
    used (0.2 s at start-up)."""
    import httpx
    from authlib.common.errors import AuthlibBaseError
    from authlib.integrations.base_client import OAuthError
    from joserfc.errors import JoseError

    return (OAuthError, AuthlibBaseError, JoseError, httpx.HTTPError, OSError, ValueError, KeyError)


class NotAnIdentity(Exception):
    """The provider's answer names nobody GyroLab may log in: no ID token, or one whose
    issuer is not the discovered provider's."""

    def __init__(self, key: str, **params) -> None:
        super().__init__(key)
        self.key, self.params = key, params


def token_reason(error: Exception) -> tuple[str, dict] | None:
    """An ID token's failed check as a message key and its parameters (None: not a token
    check, e.g. the provider's own refusal)."""
    from joserfc import errors

    if isinstance(error, NotAnIdentity):
        return error.key, error.params
    if isinstance(error, errors.UnsupportedAlgorithmError):
        return "sso.reason.algorithm", {}
    if isinstance(error, errors.BadSignatureError | errors.InvalidKeyIdError):
        return "sso.reason.signature", {}
    if isinstance(error, errors.ExpiredTokenError):
        return "sso.reason.expired", {}
    if isinstance(error, errors.ClaimError):
        claim = getattr(error, "claim", None) or str(error).rsplit(":", 1)[-1].strip(" '")
        key = (
            "sso.reason.missing_claim"
            if isinstance(error, errors.MissingClaimError)
            else ("sso.reason.invalid_claim")
        )
        return key, {"claim": claim}
    if isinstance(error, errors.JoseError):
        return "sso.reason.token", {}
    return None


def _enabled() -> Settings:
    settings = get_settings()
    if not sso_enabled(settings):
        raise UserError("error.not_found", status=404)
    return settings


@router.get("/login/sso")
async def sso_start(request: Request, next: str = "/"):
    settings = _enabled()
    request.session[NEXT_KEY] = safe_next(next)
    try:
        return await client_for(settings).authorize_redirect(
            request, str(request.url_for("sso_callback"))
        )
    except provider_problems() as error:  # the provider is unreachable or misconfigured
        return _failed(request, settings, error)


@router.get("/login/sso/callback", name="sso_callback")
async def sso_callback(request: Request):
    settings = _enabled()
    client = client_for(settings)
    try:
        token = await client.authorize_access_token(request)
        claims = await _verified_identity(client, token)
    except (*provider_problems(), NotAnIdentity) as error:  # denied, bad token, unreachable…
        return _failed(request, settings, error)
    try:
        cookie = await run_in_threadpool(_log_in, dict(claims), settings)
    except NotAnIdentity as error:
        return _failed(request, settings, error)
    response = redirect(request.session.pop(NEXT_KEY, "/"))
    set_cookie(response, request, SESSION_COOKIE, cookie, settings.session_lifetime_hours * 3600)
    return response


async def _verified_identity(client, token: dict) -> dict:
    """The identity of a verified ID token of the discovered issuer, and nothing else.

    authlib verifies an ``id_token`` (signature against the provider's keys, algorithm,
    issuer, audience and azp, expiry, nonce) into ``token["userinfo"]``; without an
    ``id_token`` a ``userinfo`` in the token response is the provider's unsigned word --
    and it could name an LTI platform's user, whose identities share the table -- so it is
    refused.  The issuer is checked once more against the discovery document."""
    if not token.get("id_token"):
        raise NotAnIdentity("sso.reason.no_id_token")
    claims = dict(token.get("userinfo") or {})
    issuer = (await client.load_server_metadata()).get("issuer")
    if not issuer or claims.get("iss") != issuer:
        raise NotAnIdentity("sso.reason.invalid_claim", claim="iss")
    if not claims.get("sub"):
        raise NotAnIdentity("sso.reason.missing_claim", claim="sub")
    return claims


def _log_in(claims: dict, settings: Settings) -> str:
    """The account of a verified identity, logged in.  An issuer that is also a registered
    LTI platform's is refused: its subjects are that platform's users, whose identities
    share the table, and only the platform's own signed launch may speak for them."""
    with write_session() as db:
        platform = db.exec(select(LtiPlatform.id).where(LtiPlatform.issuer == claims["iss"]))
        if platform.first() is not None:
            raise NotAnIdentity("sso.reason.lti_issuer")
        user = account_for(db, claims, role_from_claims(claims, settings))
        return create_session(db, user, settings)


def _failed(request: Request, settings: Settings, error: Exception):
    """The log-in page, 400, saying why in the reader's language; nobody is logged in."""
    found = token_reason(error)
    if found is not None:
        reason = translator(request_language(request))(found[0], **found[1])
    else:
        reason = getattr(error, "description", None) or getattr(error, "error", None) or error
    # an error without words (a network time-out) is named by its kind, on the page and in
    # the log, where an administrator looks when sign-in stops working
    reason = str(reason) or type(error).__name__
    log.warning("single sign-on failed: %s: %s", type(error).__name__, reason)
    context = login_view(settings, error="sso.failed", reason=reason[:200])
    return render(request, "auth/login.html", context, 400)
