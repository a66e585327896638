"""The LTI endpoints an LMS calls, and the pages around them.

``/lti/login`` (third-party login initiation) → the platform's authorization endpoint →
``/lti/launch`` (the id_token, checked by ``handshake.Launch``) → the person's page:
a student's lab session, a teacher's assignment dashboard, or the deep-linking picker.
``/lti/jwks.json`` publishes GyroLab's keys; ``/lti/register`` is dynamic registration.

Inside an LMS frame, GyroLab's own pages cannot work (its session cookie would be a
third-party cookie and its pages refuse framing): a framed launch shows a button that
opens GyroLab in a new window through a one-time ``/lti/continue`` link.  The deep-linking
picker needs no cookie -- the launch id it carries is its credential, used once.
"""

from __future__ import annotations

import secrets
from datetime import timedelta

import jwt
import requests
from fastapi import APIRouter, BackgroundTasks, Request
from fastapi.responses import JSONResponse
from pylti1p3.deep_link_resource import DeepLinkResource
from pylti1p3.exception import LtiException, OIDCException, ToolConfException
from sqlmodel import select
from starlette.concurrency import run_in_threadpool

from app.accounts.pages import safe_next
from app.accounts.security import create_session
from app.config import get_settings
from app.core.exceptions import UserError
from app.courses.assignment_form import form_values, parse_assignment_form
from app.db import read_session, write_session
from app.lti import keys, provisioning, roster
from app.lti.frame_launch import (
    PLATFORM_STATE,
    check_page,
    login_page,
    secure_context,
    state_cookie_matches,
    storage_target,
    unverified_claims,
)
from app.lti.framing import framed_csp, origin
from app.lti.grades import line_item
from app.lti.handshake import (
    DatabaseStorage,
    FormRequest,
    Launch,
    LaunchRefused,
    Login,
    stored_launch,
)
from app.lti.platforms import DatabaseToolConf, find_platform
from app.lti.registration import link_is_live, register
from app.models import Assignment, Course, LtiContext, LtiPlatform, User
from app.web.i18n import translator
from app.web.render import SESSION_COOKIE, redirect, render, request_language, set_cookie

router = APIRouter(prefix="/lti", tags=["pages: lti"], include_in_schema=False)
MAX_PARAM = 20_000  # an id_token is a few kB
CONTINUE_LIFETIME = timedelta(minutes=2)
REFUSALS = (
    LtiException,
    OIDCException,
    ToolConfException,
    LaunchRefused,
    jwt.PyJWTError,
    requests.RequestException,
    ValueError,
    KeyError,
    TypeError,
    AssertionError,
    LookupError,
)


def public_base(request: Request) -> str:
    return get_settings().public_url.rstrip("/") or str(request.base_url).rstrip("/")


def is_secure(request: Request) -> bool:
    """Whether cookies may be ``Secure`` (and so cross-site and partitioned)."""
    return secure_context(public_base(request))


def in_frame(request: Request) -> bool:
    return request.headers.get("sec-fetch-dest") == "iframe"


async def _params(request: Request) -> dict[str, str]:
    params = {k: v for k, v in request.query_params.items() if len(v) <= MAX_PARAM}
    if request.method == "POST":
        form = await request.form()
        params.update({k: v for k, v in form.items() if isinstance(v, str) and len(v) <= MAX_PARAM})
    return params


def refused(request: Request, reason: str, status: int = 401, frame_urls=()):
    response = render(request, "lti/refused.html", {"reason": reason}, status)
    response.headers["Content-Security-Policy"] = framed_csp(list(frame_urls))
    return response


@router.get("/jwks.json")
def jwks_json() -> JSONResponse:
    """GyroLab's public keys (the current and recently retired), for platforms."""
    keys.ensure_key()
    with read_session() as db:
        body = keys.jwks(db)
    return JSONResponse(body, headers={"Cache-Control": "public, max-age=300"})


@router.api_route("/login", methods=["GET", "POST"])
async def login_initiation(request: Request):
    """Third-party initiated login: check the platform, set the state, send the browser to
    the platform's authorization endpoint with a nonce."""
    params = await _params(request)
    lti_request = FormRequest(params, dict(request.cookies), is_secure(request))
    launch_url = public_base(request) + "/lti/launch"

    def start():
        keys.ensure_key()
        with read_session() as db:
            login = Login(lti_request, DatabaseToolConf(db))
            return login.get_redirect_object(launch_url), login.registration_urls()

    try:
        redirection, platform_urls = await run_in_threadpool(start)
    except REFUSALS as error:
        return refused(request, str(error) or type(error).__name__, 400)
    if not storage_target(params) and not in_frame(request):
        return redirection.do_redirect()
    # in an LMS frame: the page ties the login to this browser (frame_launch), then goes on
    page = login_page(redirection.get_redirect_url(), params)
    response = render(request, "lti/frame_launch.html", page)
    response.headers["Content-Security-Policy"] = framed_csp(platform_urls)
    response.headers["Cache-Control"] = "no-store"
    redirection.cookies.apply(response)
    return response


@router.get("/state-check")
def state_check(request: Request, state: str = "") -> JSONResponse:
    """Whether this browser sent the state cookie of ``state`` (the framed login page asks,
    to choose between going on and offering a new window)."""
    arrived = state_cookie_matches(dict(request.cookies), state[:200])
    return JSONResponse({"cookie": arrived}, headers={"Cache-Control": "no-store"})


@router.post("/launch")
async def launch(request: Request, background: BackgroundTasks):
    """The platform's form post with the id_token: checked, then the person lands."""
    params = await _params(request)
    lti_request = FormRequest(params, dict(request.cookies), is_secure(request))
    _ = translator(request_language(request))
    if needs_platform_storage(params, dict(request.cookies)):
        return await run_in_threadpool(_storage_check_page, request, params)

    def check() -> tuple[dict, int, str]:
        keys.ensure_key()
        with read_session() as db:
            message = Launch(lti_request, DatabaseToolConf(db))
            body = dict(message.get_launch_data())
            platform = find_platform(db, body["iss"], message.get_client_id())
            return body, platform.id, message.get_launch_id()

    try:
        body, platform_id, launch_id = await run_in_threadpool(check)
    except REFUSALS as error:
        return refused(request, str(error) or type(error).__name__)
    settings = get_settings()
    framed = in_frame(request)

    def arrive():
        with write_session() as db:
            platform = db.get(LtiPlatform, platform_id)
            landing = provisioning.land(db, platform, body, launch_id, _("lab.practice_title"))
            if landing.url.startswith("/lti/deep-link/"):
                return landing, None, picker_context(db, landing.course, launch_id, body)
            if framed:  # the session is made when the new window opens
                return landing, None, None
            return landing, create_session(db, landing.user, settings), None

    try:
        landing, cookie, picker = await run_in_threadpool(arrive)
    except UserError as problem:
        frames = _platform_urls(body)
        response = render(request, "lti/refused.html", {"problem": problem}, problem.status)
        response.headers["Content-Security-Policy"] = framed_csp(frames)
        return response
    if landing.teacher:  # the roster follows the LMS's, fetched after the response
        background.add_task(roster.sync_roster, landing.context_row_id)
    if picker is not None:
        response = render(request, "lti/deep_link.html", picker)
        response.headers["Content-Security-Policy"] = framed_csp(_platform_urls(body))
        return response
    if framed:
        token = await run_in_threadpool(_continue_token, landing.user.id, landing.url)
        response = render(request, "lti/new_window.html", {"token": token})
        response.headers["Content-Security-Policy"] = framed_csp(_platform_urls(body))
        return response
    response = redirect(landing.url)
    set_cookie(response, request, SESSION_COOKIE, cookie, settings.session_lifetime_hours * 3600)
    return response


def needs_platform_storage(params: dict[str, str], cookies: dict[str, str]) -> bool:
    """A launch whose state only the LMS's platform storage can confirm: no state cookie
    came, the LMS offers storage, and GyroLab's page has not read it back yet."""
    return (
        bool(storage_target(params))
        and not params.get(PLATFORM_STATE)
        and not state_cookie_matches(cookies, params.get("state", ""))
    )


def _storage_check_page(request: Request, params: dict[str, str]):
    """The page that reads the state back from platform storage and posts the launch
    again (``frame_launch``); the platform is the one the unverified token names."""
    claims = unverified_claims(params.get("id_token", ""))
    with read_session() as db:
        platform = find_platform(db, str(claims.get("iss") or ""), _client_of(claims))
    if platform is None:
        return refused(request, "The id_token names no registered platform (iss, aud).")
    page = check_page(params, origin(platform.auth_login_url) or "")
    response = render(request, "lti/frame_launch.html", page)
    response.headers["Content-Security-Policy"] = framed_csp(
        [platform.issuer, platform.auth_login_url]
    )
    response.headers["Cache-Control"] = "no-store"
    return response


def _platform_urls(body: dict) -> list[str]:
    presentation = body.get(provisioning.CLAIM + "launch_presentation") or {}
    settings = body.get(DEEP_LINK_SETTINGS) or {}
    return [body.get("iss"), presentation.get("return_url"), settings.get("deep_link_return_url")]


def _continue_token(user_id: int, url: str) -> str:
    token = secrets.token_urlsafe(24)
    DatabaseStorage().set_value(
        f"lti1p3-continue-{token}",
        {"user": user_id, "url": url},
        int(CONTINUE_LIFETIME.total_seconds()),
    )
    return token


@router.get("/continue/{token}")
def continue_in_new_window(request: Request, token: str):
    """A framed launch's one-time link: the session cookie, set first-party, then the page."""
    storage = DatabaseStorage()
    key = f"lti1p3-continue-{token[:64]}"
    value = storage.get_value(key)
    if not isinstance(value, dict) or not storage.consume(key):
        return refused(request, "This link was used already or has expired.", 410)
    settings = get_settings()
    with write_session() as db:
        user = db.get(User, int(value["user"]))
        if user is None:
            return refused(request, "This account no longer exists.", 410)
        cookie = create_session(db, user, settings)
    response = redirect(safe_next(str(value.get("url") or "/")))
    set_cookie(response, request, SESSION_COOKIE, cookie, settings.session_lifetime_hours * 3600)
    return response


# --- deep linking -----------------------------------------------------------------------------

DEEP_LINK_SETTINGS = "https://purl.imsglobal.org/spec/lti-dl/claim/deep_linking_settings"


def picker_context(db, course: Course, launch_id: str, body: dict, **extra) -> dict:
    assignments = db.exec(
        select(Assignment).where(Assignment.course_id == course.id).order_by(Assignment.id)
    ).all()
    return {"course": course, "assignments": assignments, "launch_id": launch_id, **extra}


def _launch_course(db, body: dict) -> Course:
    """The GyroLab course linked to a stored launch's LMS course."""
    platform = find_platform(db, body["iss"], _client_of(body))
    context = db.exec(
        select(LtiContext).where(
            LtiContext.platform_id == platform.id,
            LtiContext.context_id == provisioning.context_of(platform, body)[0],
        )
    ).one()
    return db.get(Course, context.course_id)


@router.post("/deep-link")
async def deep_link_response(request: Request):
    """The teacher's choice (an existing assignment, or a new one) signed and posted back
    to the LMS's deep-linking return URL.  The launch id is the credential, used once."""
    params = await _params(request)
    launch_id = params.get("launch_id", "")[:80]
    body = await run_in_threadpool(stored_launch, launch_id) if launch_id else None
    if not body or body.get(provisioning.CLAIM + "message_type") != provisioning.DEEP_LINKING:
        return refused(request, "This choice has expired; add the activity again.", 410)
    lti_request = FormRequest({}, {}, is_secure(request))
    base = public_base(request)

    def respond():
        with write_session() as db:
            course = _launch_course(db, body)
            if params.get("new"):
                assignment = _new_assignment(db, course, params)
            else:
                chosen = provisioning.assignment_in(db, course, params.get("assignment_id"))
                if chosen is None:
                    raise UserError("lti.choose_assignment", status=400)
                assignment = db.get(Assignment, chosen)
            message = Launch.restored(launch_id, body, lti_request, DatabaseToolConf(db))
            resource = (
                DeepLinkResource()
                .set_url(base + "/lti/launch")
                .set_title(assignment.title)
                .set_custom_params({provisioning.ASSIGNMENT_PARAMETER: str(assignment.id)})
                .set_lineitem(line_item(assignment.id, assignment.title, assignment.max_points))
            )
            token = message.get_deep_link().get_response_jwt([resource])
            return course, token

    try:
        course, token = await run_in_threadpool(respond)
    except UserError as problem:
        with read_session() as db:
            course = _launch_course(db, body)
            picker = picker_context(db, course, launch_id, body, problem=problem, form=params)
        response = render(request, "lti/deep_link.html", picker, problem.status)
        response.headers["Content-Security-Policy"] = framed_csp(_platform_urls(body))
        return response
    except REFUSALS as error:
        return refused(request, str(error) or type(error).__name__, 400, _platform_urls(body))
    await run_in_threadpool(DatabaseStorage().consume, launch_id)
    return_url = (body.get(DEEP_LINK_SETTINGS) or {}).get("deep_link_return_url")
    response = render(request, "lti/deep_link_return.html", {"url": return_url, "jwt": token})
    response.headers["Content-Security-Policy"] = framed_csp(_platform_urls(body), [return_url])
    return response


def _client_of(body: dict) -> str | None:
    audience = body.get("aud")
    if isinstance(audience, list):
        audience = audience[0] if audience else None
    return audience if isinstance(audience, str) else None


def _new_assignment(db, course: Course, params: dict[str, str]) -> Assignment:
    values = form_values()
    for name in ("title", "latitude_deg", "max_points"):
        if params.get(name, "").strip():
            values[name] = params[name]
    assignment = parse_assignment_form(values, course.timezone)
    assignment.course_id = course.id
    db.add(assignment)
    db.flush()
    return assignment


# --- dynamic registration ---------------------------------------------------------------------


@router.get("/register")
async def dynamic_registration(
    request: Request,
    token: str = "",
    openid_configuration: str = "",
    registration_token: str | None = None,
):
    """LTI Dynamic Registration, opened by the LMS with a one-time link of an admin's."""
    frames = [openid_configuration]
    try:
        if not token or not await run_in_threadpool(link_is_live, token):
            raise UserError("lti.registration_link_used", status=403)
        if not openid_configuration:
            raise UserError("lti.registration_needs_lms", status=400)
        platform = await run_in_threadpool(
            register, token, public_base(request), openid_configuration, registration_token
        )
    except UserError as problem:
        context = {"problem": problem, "title_key": "lti.registration_refused_title"}
        response = render(request, "lti/refused.html", context, problem.status)
    else:
        response = render(request, "lti/registered.html", {"platform": platform})
    response.headers["Content-Security-Policy"] = framed_csp(frames)
    return response
