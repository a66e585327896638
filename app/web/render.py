"""Page rendering: one Jinja environment, a shared base context, and flash messages."""

from __future__ import annotations

import secrets
from typing import Any

from fastapi import Request
from fastapi.responses import HTMLResponse, RedirectResponse
from fastapi.templating import Jinja2Templates

from app import __version__
from app.config import get_settings
from app.paths import TEMPLATES_DIR
from app.web.i18n import (
    LANGUAGE_NAMES,
    LANGUAGES,
    format_datetime,
    format_number,
    negotiate,
    normalise,
    translator,
    zone_label,
)
from app.web.local_time import zone as zone_of
from app.web.signing import signed, unsigned
from app.web.template_cache import use_code_cache

SESSION_COOKIE = "gyrolab_session"
CSRF_COOKIE = "gyrolab_csrf"
# Over https the pre-login CSRF cookie carries the __Host- prefix: browsers accept it only
# from this very host (Secure, Path=/, no Domain), so a sibling subdomain cannot plant a
# known token for a log-in CSRF.  Plain http (development) keeps the plain name.
HOST_CSRF_COOKIE = "__Host-" + CSRF_COOKIE
FLASH_COOKIE = "gyrolab_flash"
LANG_COOKIE = "gyrolab_lang"

templates = Jinja2Templates(directory=str(TEMPLATES_DIR))
# The templates are part of the installed app: compiled once, never re-checked on disk
# (an auto-reloading environment stats every template a page includes on every render).
templates.env.auto_reload = False
# gettext extraction (pybabel, babel.cfg) reads the templates' _("key") calls through
# Jinja's i18n extension; each page's _ is the reader's translator (render()).
templates.env.add_extension("jinja2.ext.i18n")
templates.env.globals["version"] = __version__
templates.env.globals["LANGUAGE_NAMES"] = LANGUAGE_NAMES
templates.env.globals["LANGUAGES"] = LANGUAGES
# their compiled code kept on disk between starts (app/web/template_cache.py)
use_code_cache(templates.env, __version__)


def compile_templates() -> int:
    """Compile every page template now (a served worker's start-up: ≈ 0.3 s for all of
    them, which the first view of each page otherwise pays -- 30-60 ms for the lab page
    and its includes, inside the first students' requests; ≈ 20 ms from the code cache of
    an earlier start, ``template_cache``).  Returns how many."""
    names = [name for name in templates.env.list_templates() if name.endswith(".html")]
    for name in names:
        templates.env.get_template(name)
    return len(names)


def request_language(request: Request) -> str:
    user = getattr(request.state, "user", None)
    return (
        (user and normalise(user.language))
        or normalise(request.cookies.get(LANG_COOKIE))
        or negotiate(request.headers.get("accept-language"))
    )


def is_https(request: Request) -> bool:
    return request.url.scheme == "https"


def csrf_cookie_name(request: Request) -> str:
    return HOST_CSRF_COOKIE if is_https(request) else CSRF_COOKIE


def set_cookie(response, request: Request, name: str, value: str, max_age: int | None = None):
    response.set_cookie(
        name,
        value,
        max_age=max_age,
        httponly=True,
        samesite="lax",
        secure=is_https(request),
        path="/",
    )


# --- flash messages: a signed cookie read once by the next page -----------------------------


def flash(response, request: Request, key: str, kind: str = "info", **params: Any) -> None:
    pending = list(getattr(request.state, "flashes_out", []))
    pending.append({"key": key, "kind": kind, "params": params})
    request.state.flashes_out = pending
    value = signed(pending, get_settings().secret_key, "flash")
    set_cookie(response, request, FLASH_COOKIE, value, 300)


def _take_flashes(request: Request) -> list[dict]:
    items = unsigned(request.cookies.get(FLASH_COOKIE), get_settings().secret_key, "flash")
    if not isinstance(items, list):
        return []
    return [item for item in items if isinstance(item, dict) and "key" in item]


def redirect(url: str) -> RedirectResponse:
    return RedirectResponse(url, status_code=303)


def csrf_token_for(request: Request) -> str:
    """The session's CSRF token, or for a visitor not logged in a double-submit cookie value."""
    auth = getattr(request.state, "auth", None)
    if auth is not None:
        return auth.csrf_token
    existing = getattr(request.state, "anon_csrf", None) or request.cookies.get(
        csrf_cookie_name(request)
    )
    if not existing:
        existing = request.state.anon_csrf = secrets.token_urlsafe(32)
    return existing


def time_formatter(language: str, timezone: str | None):
    """A page's ``when(value, date="yMMMd", time="Hm", tz=None, zone=True)``: a stored
    (UTC) time in the reader's locale, on the wall clock of ``timezone`` (the page's
    course's), else the server's -- never "UTC" to a user; ``zone=False`` leaves the
    zone's name out (a table's column names it once, in its heading)."""
    shown_zone = zone_of(timezone)
    return lambda value, date="yMMMd", time="Hm", tz=None, zone=True: format_datetime(
        value, language, date, time, zone_of(tz) if tz else shown_zone, zone
    )


def render(
    request: Request, template: str, context: dict[str, Any] | None = None, status_code: int = 200
) -> HTMLResponse:
    language = request_language(request)
    _ = translator(language)
    timezone = (context or {}).get("timezone")
    shown_zone = zone_of(timezone)
    flashes = [
        {"kind": item.get("kind", "info"), "text": _(item["key"], **item.get("params", {}))}
        for item in _take_flashes(request)
    ]
    base = {
        "request": request,
        "_": _,
        "lang": language,
        "when": time_formatter(language, timezone),
        "zone_text": zone_label(shown_zone, language),
        "zone_name": shown_zone.key,
        "num": lambda value, digits=3: format_number(value, language, digits),
        "user": getattr(request.state, "user", None),
        "csrf_token": csrf_token_for(request),
        "flashes": flashes,
        "base_url": str(request.base_url),
    }
    response = templates.TemplateResponse(
        request, template, {**base, **(context or {})}, status_code=status_code
    )
    response.headers["Cache-Control"] = "no-store"
    if flashes:
        response.delete_cookie(FLASH_COOKIE, path="/")
    anon = getattr(request.state, "anon_csrf", None)
    if anon and request.cookies.get(csrf_cookie_name(request)) != anon:
        set_cookie(response, request, csrf_cookie_name(request), anon)
    return response
