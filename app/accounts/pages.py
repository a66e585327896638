"""Login, logout, password change and the language switch."""

from __future__ import annotations

from typing import Annotated
from urllib.parse import urlsplit

from fastapi import APIRouter, Form, Request

from app.accounts.deps import CsrfProtected, CurrentUser, OptionalUser
from app.accounts.security import (
    MIN_PASSWORD_LENGTH,
    create_session,
    hash_password,
    log_in,
    password_problem,
    revoke_credentials,
    verify_password,
)
from app.accounts.sso import signs_in_elsewhere, sso_enabled
from app.config import Settings
from app.core.exceptions import UserError
from app.models import AuthSession, User, utcnow
from app.web.deps import RowWriteSession, SessionDep, SettingsDep
from app.web.i18n import normalise
from app.web.render import LANG_COOKIE, SESSION_COOKIE, flash, redirect, render, set_cookie

# A browser that logged in to an account before: its attempts skip the limits that
# strangers' guesses fill (app.accounts.security); a signed value, kept for 180 days.
DEVICE_COOKIE = "gyrolab_device"
DEVICE_COOKIE_SECONDS = 180 * 24 * 3600

router = APIRouter(tags=["pages: account"], include_in_schema=False)


def safe_next(target: str | None) -> str:
    """Only same-site relative paths may be redirect targets after login."""
    if not target:
        return "/"
    parts = urlsplit(target)
    if parts.scheme or parts.netloc or not target.startswith("/") or target.startswith("//"):
        return "/"
    return target


def client_address(request: Request) -> str:
    return request.client.host if request.client else "unknown"


def login_view(settings: Settings, **context) -> dict:
    """The log-in page's context: with a single sign-on button when a provider is set."""
    return {"sso": sso_enabled(settings), "sso_name": settings.oidc_name, **context}


@router.get("/login")
def login_page(request: Request, user: OptionalUser, settings: SettingsDep, next: str = "/"):
    if user is not None:
        return redirect(safe_next(next))
    return render(request, "auth/login.html", login_view(settings, next=safe_next(next)))


@router.post("/login", dependencies=[CsrfProtected, RowWriteSession])
def login(
    request: Request,
    db: SessionDep,
    settings: SettingsDep,
    username: Annotated[str, Form(max_length=200)] = "",
    password: Annotated[str, Form(max_length=1000)] = "",
    next: Annotated[str, Form(max_length=2000)] = "/",
):
    address = client_address(request)
    context = login_view(settings, next=safe_next(next), username=username)
    outcome = log_in(db, username, password, address, settings, request.cookies.get(DEVICE_COOKIE))
    if outcome.problem in ("throttled", "busy"):
        context.update(login_wait_message(outcome))
        status = 429 if outcome.problem == "throttled" else 503
        response = render(request, "auth/login.html", context, status)
        response.headers["Retry-After"] = str(outcome.retry_after)
        return response
    if outcome.user is None:
        context["error"] = "login.failed"
        return render(request, "auth/login.html", context, 401)
    user = outcome.user
    token = create_session(db, user, settings)
    db.commit()
    response = redirect("/account/password" if user.must_change_password else safe_next(next))
    set_cookie(response, request, SESSION_COOKIE, token, settings.session_lifetime_hours * 3600)
    set_cookie(response, request, DEVICE_COOKIE, outcome.device_cookie, DEVICE_COOKIE_SECONDS)
    return response


def login_wait_message(outcome) -> dict:
    """The log-in page's words for a refused attempt: how long to wait."""
    if outcome.problem == "busy":
        return {"error": "login.busy"}
    if outcome.retry_after < 120:
        return {"error": "login.slow_down", "seconds": outcome.retry_after}
    return {"error": "login.throttled", "minutes": -(-outcome.retry_after // 60)}


@router.post("/logout", dependencies=[CsrfProtected, RowWriteSession])
def logout(request: Request, db: SessionDep):
    auth: AuthSession | None = getattr(request.state, "auth", None)
    if auth is not None:
        auth.revoked_at = utcnow()
        db.add(auth)
        db.commit()
    response = redirect("/login")
    response.delete_cookie(SESSION_COOKIE, path="/")
    flash(response, request, "login.logged_out")
    return response


@router.get("/account/password")
def password_page(request: Request, user: CurrentUser, db: SessionDep, settings: SettingsDep):
    external = signs_in_elsewhere(db, user)
    return render(
        request,
        "auth/password.html",
        {
            "forced": user.must_change_password,
            "external": external,
            "sso_name": settings.oidc_name,
        },
    )


def password_form_problems(
    user: User, current: str, new: str, confirm: str
) -> dict[str, UserError]:
    """Every problem of the change-password form at once, by field (in the form's order)."""
    problems: dict[str, UserError] = {}
    if not verify_password(current, user.password_hash):
        problems["current_password"] = UserError("password.wrong_current")
    weakness = "password.unchanged" if new == current else password_problem(new, user.username)
    if weakness:
        problems["new_password"] = UserError(weakness, minimum=MIN_PASSWORD_LENGTH)
    if new != confirm:
        problems["confirm_password"] = UserError("password.mismatch")
    return problems


@router.post("/account/password", dependencies=[CsrfProtected])
def change_password(
    request: Request,
    user: CurrentUser,
    db: SessionDep,
    settings: SettingsDep,
    current_password: Annotated[str, Form(max_length=1000)] = "",
    new_password: Annotated[str, Form(max_length=1000)] = "",
    confirm_password: Annotated[str, Form(max_length=1000)] = "",
):
    problems = password_form_problems(user, current_password, new_password, confirm_password)
    if problems:  # every problem beside its field; the passwords are never sent back
        context = {"forced": user.must_change_password, "problems": problems}
        return render(request, "auth/password.html", context, 400)
    db_user = db.get(User, user.id)
    db_user.password_hash = hash_password(new_password)
    db_user.must_change_password = False
    db.add(db_user)
    revoke_credentials(db, user.id)  # every session and token; a fresh session follows
    token = create_session(db, db_user, settings)
    db.commit()
    response = redirect("/")
    set_cookie(response, request, SESSION_COOKIE, token, settings.session_lifetime_hours * 3600)
    flash(response, request, "password.changed", "success")
    return response


@router.post("/lang", dependencies=[CsrfProtected])
def switch_language(
    request: Request,
    user: OptionalUser,
    db: SessionDep,
    lang: Annotated[str, Form(max_length=16)] = "en",
    next: Annotated[str, Form(max_length=2000)] = "/",
):
    language = normalise(lang) or "en"
    if user is not None:
        db_user = db.get(User, user.id)
        db_user.language = language
        db.add(db_user)
        db.commit()
    response = redirect(safe_next(next))
    set_cookie(response, request, LANG_COOKIE, language, 365 * 24 * 3600)
    return response
