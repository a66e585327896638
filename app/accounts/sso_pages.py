"""The single sign-on round trip: ``/login/sso`` sends the browser to the provider, which
sends it back to ``/login/sso/callback`` with a code (see ``accounts/sso.py``).

The two steps are ``async`` because authlib talks to the provider with httpx's async
client; the database work runs on the thread pool, as everywhere else."""

from __future__ import annotations

from fastapi import APIRouter, Request
from starlette.concurrency import run_in_threadpool

from app.accounts.pages import login_view, safe_next
from app.accounts.security import create_session
from app.accounts.sso import account_for, client_for, role_from_claims, sso_enabled
from app.config import Settings, get_settings
from app.core.exceptions import UserError
from app.db import write_session
from app.web.render import SESSION_COOKIE, redirect, render, set_cookie

router = APIRouter(tags=["pages: account"], include_in_schema=False)
NEXT_KEY = "sso_next"


def provider_problems() -> tuple[type[Exception], ...]:
    """What the round trip can meet: the provider's errors and refusals (authlib), an ID
    token that fails its checks (joserfc/authlib: ValueError subclasses), the network
    (httpx).  Both are imported here, when single sign-on is used (0.2 s at start-up)."""
    import httpx
    from authlib.integrations.base_client import OAuthError

    return (OAuthError, httpx.HTTPError, OSError, ValueError, KeyError)


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
    try:
        token = await client_for(settings).authorize_access_token(request)
    except provider_problems() as error:  # denied, wrong state, bad token, unreachable…
        return _failed(request, settings, error)
    claims = token.get("userinfo") or {}
    if not claims.get("iss") or not claims.get("sub"):
        return _failed(request, settings, ValueError("no identity in the ID token"))
    cookie = await run_in_threadpool(_log_in, dict(claims), settings)
    response = redirect(request.session.pop(NEXT_KEY, "/"))
    set_cookie(response, request, SESSION_COOKIE, cookie, settings.session_lifetime_hours * 3600)
    return response


def _log_in(claims: dict, settings: Settings) -> str:
    with write_session() as db:
        user = account_for(db, claims, role_from_claims(claims, settings))
        return create_session(db, user, settings)


def _failed(request: Request, settings: Settings, error: Exception):
    reason = getattr(error, "description", None) or getattr(error, "error", None) or str(error)
    context = login_view(settings, error="sso.failed", reason=str(reason)[:200])
    return render(request, "auth/login.html", context, 400)
