"""The ASGI application: ``create_app()`` wires middleware, static files, routers, errors."""

from __future__ import annotations

import asyncio
import gc
import gzip
import hashlib
import sys
from contextlib import asynccontextmanager
from functools import lru_cache
from pathlib import Path

import plotly
from fastapi import FastAPI, Request, Response
from fastapi.responses import HTMLResponse
from fastapi.staticfiles import StaticFiles
from starlette.middleware.sessions import SessionMiddleware
from starlette.types import ASGIApp, Receive, Scope, Send
from swagger_ui_bundle import swagger_ui_path

from app import __version__
from app.config import Settings, get_settings
from app.lab.copy_index import index_earlier_attempts
from app.lti import grades as lms_grades
from app.paths import STATIC_DIR
from app.routes import EVERY_ROUTER, include_routers, read_only_routes
from app.serving_lock import hold_while_serving, release
from app.web.admission import Admission
from app.web.errors import register_error_handlers
from app.web.headers import SecurityHeaders
from app.web.i18n import load_languages
from app.web.local_time import zone as local_zone
from app.web.render import compile_templates

API_DESCRIPTION = """REST API of GyroLab, the FOG north-finding teaching lab.

Authenticate with `Authorization: Bearer <token>`: a personal access token (page *API
tokens*; scopes `read` and `upload`) or a one-hour token from `POST /api/v1/auth/token`.
Rates are °/h unless a unit is given; angles are degrees.  Errors are
`{"detail": "..."}` with a 4xx status.  Limits: request bodies up to 64 MiB, at most
1,000,000 samples per position, 600 requests per minute per token.
"""
SWAGGER_PAGE = """<!doctype html>
<html lang="en"><head><meta charset="utf-8"><title>GyroLab API</title>
<link rel="icon" href="/static/favicon.svg" type="image/svg+xml">
<link rel="stylesheet" href="/vendor/swagger-ui/swagger-ui.css"></head>
<body data-schema="/docs/openapi.json">
<nav style="font:15px system-ui,sans-serif;padding:10px 20px;background:#13263a">
<a href="/" style="color:#fff;text-decoration:none">&larr; GyroLab</a></nav>
<div id="swagger-ui"></div>
<script src="/vendor/swagger-ui/swagger-ui-bundle.js"></script>
<script src="/vendor/swagger-ui/swagger-ui-standalone-preset.js"></script>
<script src="/static/js/swagger-init.js"></script></body></html>
"""
PLOTLY_JS = Path(plotly.__file__).parent / "package_data" / "plotly.min.js"
PLOTLY_URL = f"/vendor/plotly-{plotly.__version__}.min.js"
# V8's explicit compile hint (Chromium 136 on; a comment to other browsers): every function
# of plotly compiled on a background thread while the script streams in, not on the page's
# main thread as the first chart calls it -- the main thread's script time on a chart
# page's first view 0.81 -> 0.51 s, the browser's CPU no higher (bench/bench_chart_page.py)
PLOTLY_COMPILE_HINT = b"//# allFunctionsCalledOnLoad\n"


def plotly_script() -> bytes:
    """plotly.min.js as served: the installed package's, under the compile hint."""
    return PLOTLY_COMPILE_HINT + PLOTLY_JS.read_bytes()


@lru_cache(maxsize=1)
def plotly_gzip() -> bytes:
    """The gzip of the served plotly.min.js (made on the first request, then kept)."""
    return gzip.compress(plotly_script(), compresslevel=6, mtime=0)


class SsoSessionCookie:
    """Starlette's SessionMiddleware on single sign-on's own paths only: every other
    request passes untouched (no cookie parsed or signature checked on the hot paths).  The
    cookie is signed with a key derived from the settings' secret key when the request is
    served (one app serves whatever settings are in force: a test's own var dir)."""

    def __init__(self, app: ASGIApp, **options) -> None:
        self.app = app
        self.options = options
        self.prefix = options["path"]
        self._by_secret: dict[str, SessionMiddleware] = {}

    def _with_session(self) -> SessionMiddleware:
        secret = hashlib.sha256(f"sso:{get_settings().secret_key}".encode()).hexdigest()
        middleware = self._by_secret.get(secret)
        if middleware is None:
            if len(self._by_secret) >= 4:  # one key in a deployment; a few in tests
                self._by_secret.clear()
            middleware = SessionMiddleware(self.app, secret_key=secret, **self.options)
            self._by_secret[secret] = middleware
        return middleware

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] == "http" and scope["path"].startswith(self.prefix):
            await self._with_session()(scope, receive, send)
        else:
            await self.app(scope, receive, send)


def set_switch_interval(settings: Settings) -> None:
    """How long a served worker's thread may keep the interpreter while another waits for
    it: ``GYROLAB_SWITCH_INTERVAL_MS`` (1 ms; CPython's default is 5).

    A request's thread keeps the interpreter through most of its SQLite calls (a call is
    over before a waiting thread reaches a core), so a thread that waits -- the event loop
    with the next request to admit and the stream's frames, or another request -- waits
    for the holder's whole interval.  At 5 ms a request's waits off a core reached 6-44 ms
    at p95 in a class's burst.  At 1 ms, alternated pairs of load tests (bench/README.md,
    issue 32, twentieth part): the burst's p95 about halved at 60 students on SQLite and on
    PostgreSQL, 5-40 % lower at 120, the server's CPU a class unchanged or lower."""
    sys.setswitchinterval(settings.switch_interval_ms / 1000)


def freeze_start_up_heap() -> None:
    """Keep what start-up made out of the cyclic garbage collector's full passes.

    A served worker holds ≈ 190,000 objects after start-up (the framework, SQLAlchemy, the
    templates, the catalogues, SciPy's filters), and every full collection walked them all
    with every thread stopped: 50-80 ms, several times a minute under a class's load (12 ms
    of the 50 ms the dashboard of 300 spent in process).  ``gc.freeze`` moves them to a
    generation the collector never walks; objects made later are collected as before.
    SciPy's signal and stats modules (the simulated gyro's filters, Student's t of every
    result; otherwise imported by the first stream and the first result: ≈ 1 s and
    ≈ 0.6 s inside a student's request) are imported first, the page templates
    compiled (``compile_templates``) and the languages' catalogues and locale data
    loaded (``load_languages``), so that they are frozen too."""
    import scipy.signal  # noqa: F401
    import scipy.stats  # noqa: F401

    compile_templates()
    load_languages(local_zone(None))
    gc.collect()
    gc.freeze()
    gc.set_threshold(*YOUNG_COLLECTIONS)


# The collector's first threshold: container objects allocated (net) between collections of
# the young generation.  Python's 700 suits small scripts; a request of a class's pages
# keeps tens of thousands alive while it runs (the dashboard of 300: ≈ 34,000), so at 700
# every one was walked ≈ 48 times a request and the survivors promoted until a full
# collection (13 ms of the dashboard's ≈ 90).  At 50,000 a young collection comes every
# few requests and walks what is alive then (≈ 20 ms, under the frame budget); the other
# two thresholds are Python's.  bench/README.md, issue 32.
YOUNG_COLLECTIONS = (50_000, 10, 10)


def build_routes(app: FastAPI) -> None:
    """Have FastAPI build every included router's routes now, at start-up.

    FastAPI builds an included router's routes (their dependencies, their models) when a
    request first reaches it: ≈ 100 ms for all of GyroLab's, paid by a worker's first
    requests and left out of the frozen start-up heap.  A path that matches nothing,
    let through every router's gate, reaches every router."""
    scope = {
        "type": "http",
        "method": "GET",
        "path": "/-/build-routes",
        "root_path": "",
        EVERY_ROUTER: True,
    }
    for route in app.router.routes:
        route.matches(scope)


def create_app(*, migrate_on_start: bool = True, freeze_heap: bool = False) -> FastAPI:
    """The app; ``freeze_heap`` for a served worker (:func:`freeze_start_up_heap`)."""

    @asynccontextmanager
    async def lifespan(_app: FastAPI):
        if migrate_on_start:
            from app.migrate import upgrade_to_head

            upgrade_to_head()
        index_earlier_attempts()
        build_routes(_app)
        if freeze_heap:
            set_switch_interval(get_settings())
            freeze_start_up_heap()
        # restore refuses while this lock is held (app/serving_lock.py)
        serving = hold_while_serving(get_settings().database_url)
        # grades released for an LMS are posted (and retried) by every worker
        sender = asyncio.create_task(lms_grades.run_sender())
        try:
            yield
        finally:
            sender.cancel()
            release(serving)

    app = FastAPI(
        title="GyroLab",
        version=__version__,
        description=API_DESCRIPTION,
        lifespan=lifespan,
        docs_url=None,
        redoc_url=None,
        max_body_size=get_settings().max_body_bytes,
    )
    app.add_middleware(
        Admission,
        max_body=get_settings().max_body_bytes,
        read_only_routes=read_only_routes(),
    )
    # single sign-on's state and nonce between /login/sso and its callback (a signed cookie
    # for those two paths only, ten minutes)
    app.add_middleware(
        SsoSessionCookie,
        session_cookie="gyrolab_sso",
        path="/login/sso",
        max_age=600,
        same_site="lax",
    )
    app.add_middleware(SecurityHeaders)
    app.mount("/static", StaticFiles(directory=str(STATIC_DIR)), name="static")
    app.mount("/vendor/swagger-ui", StaticFiles(directory=swagger_ui_path), name="swagger-ui")

    @app.get("/docs", include_in_schema=False)
    def api_docs() -> HTMLResponse:
        """The API reference: Swagger UI from the installed swagger-ui-bundle, started by a
        script file of ours (no inline script, so the CSP holds here too)."""
        return HTMLResponse(SWAGGER_PAGE)

    @app.get("/docs/openapi.json", include_in_schema=False)
    def docs_schema() -> dict:
        """The schema labelled 3.0 for the packaged Swagger UI 4, which predates OpenAPI 3.1
        (the real schema, 3.1, is /openapi.json)."""
        return {**app.openapi(), "openapi": "3.0.3"}

    @app.get(PLOTLY_URL, include_in_schema=False)
    def plotly_js(request: Request) -> Response:
        """plotly.js from the installed plotly package, gzip-compressed once per process
        (4.8 MB → 1.4 MB) for browsers that accept it, and cached for a year; the rare
        client without gzip is sent the file read again (not kept in every worker)."""
        headers = {
            "Cache-Control": "public, max-age=31536000, immutable",
            "Vary": "Accept-Encoding",
        }
        if "gzip" in request.headers.get("accept-encoding", ""):
            return Response(
                plotly_gzip(),
                media_type="text/javascript",
                headers={**headers, "Content-Encoding": "gzip"},
            )
        return Response(plotly_script(), media_type="text/javascript", headers=headers)

    app.state.plotly_url = PLOTLY_URL

    register_error_handlers(app)
    include_routers(app)
    return app


app = create_app(freeze_heap=True)  # what ``gyrolab serve`` runs
