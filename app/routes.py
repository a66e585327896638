"""Every router of GyroLab, in the order requests are matched, and what the app checks of
them when it is built (each route declares at most one locking: ``web.deps``)."""

from __future__ import annotations

from collections.abc import Iterable, Iterator

from fastapi import APIRouter, FastAPI
from fastapi.routing import APIRoute, APIWebSocketRoute
from starlette.routing import Match, get_route_path
from starlette.types import Scope

from app.accounts import admin_pages, sso_pages, token_pages
from app.accounts import api as account_api
from app.accounts import pages as account_pages
from app.courses import assignment_pages, join_pages
from app.courses import pages as course_pages
from app.explore import pages as explore_pages
from app.home import pages as home
from app.lab import admin_pages as lab_admin_pages
from app.lab import api as lab_api
from app.lab import file_pages, partner_pages, record_pages, stream
from app.lab import home_pages as lab_home_pages
from app.lab import pages as lab_pages
from app.lti import admin_pages as lti_admin_pages
from app.lti import course_pages as lti_course_pages
from app.lti import pages as lti_pages
from app.reports import api as report_api
from app.reports import pages as report_pages
from app.review import api as review_api
from app.review import archive_pages, board_pages, desk_pages
from app.review import pages as review_pages
from app.web.deps import Locking, declared_locking, lockings_declared

# The REST API first: its requests (devices, scripts, the bridge) are matched against its
# few routes before the pages' many (paths never overlap: /api/v1/...).
ROUTERS: tuple[APIRouter, ...] = (
    account_api.router,
    lab_api.router,
    review_api.router,
    report_api.router,
    account_pages.router,
    sso_pages.router,
    lti_pages.router,
    lti_admin_pages.router,
    lti_course_pages.router,
    home.router,
    course_pages.router,
    join_pages.router,
    admin_pages.router,
    lab_admin_pages.router,
    assignment_pages.router,
    lab_home_pages.router,
    lab_pages.router,
    record_pages.router,
    file_pages.router,
    partner_pages.router,
    review_pages.router,
    board_pages.router,
    desk_pages.router,
    archive_pages.router,
    report_pages.router,
    stream.router,
    token_pages.router,
    explore_pages.router,
)


def iter_routes(routes: Iterable) -> Iterator:
    """Every route, looking inside included routers."""
    for route in routes:
        inner = getattr(route, "original_router", None)
        if inner is not None:
            yield from iter_routes(inner.routes)
        else:
            yield route


def api_routes() -> Iterator[APIRoute]:
    """Every HTTP route of the routers."""
    for router in ROUTERS:
        for route in iter_routes(router.routes):
            if isinstance(route, APIRoute):
                yield route


def check_locking_declarations(routes: Iterable) -> None:
    """Refuse routes that declare two lockings, or a locking on a route that only reads
    (GET): a declaration that never takes effect is a mistake."""
    for route in iter_routes(routes):
        if not isinstance(route, APIRoute):
            continue
        declared = lockings_declared(route)
        if len(declared) > 1:
            raise RuntimeError(f"{route.path} declares {len(declared)} lockings")
        if declared and not route.methods - {"GET", "HEAD", "OPTIONS"}:
            raise RuntimeError(f"{route.path} declares a locking but changes nothing")


def read_only_routes() -> list[APIRoute]:
    """The POST routes declared ``ReadOnlySession`` (no write slot: web.admission)."""
    return [route for route in api_routes() if declared_locking(route) is Locking.none]


# A scope with this key set passes every gate (``app.main.build_routes``).
EVERY_ROUTER = "gyrolab.every_router"


class PathGate(APIRouter):
    """One router behind a check of the request's path: a request whose path none of its
    routes can match -- not one of its fixed paths, not starting with the fixed part of any
    of its paths with parameters -- is not matched against its routes at all.

    FastAPI matches a request against the routes of every included router in turn until
    one matches (a page of the lab went through ≈ 90 routes in 18 routers; bench/README.md,
    fifteenth part); behind gates it reaches only the routers under its own path.  A
    route's regular expression begins with that fixed part, so no match is lost and the
    order of the routes that can match is kept."""

    def __init__(self, router: APIRouter) -> None:
        super().__init__()
        self.include_router(router)
        routes = list(iter_routes(router.routes))
        paths = [route.path for route in routes if isinstance(route, APIRoute | APIWebSocketRoute)]
        # a mount or anything else matched otherwise than by its path's pattern: no gate
        self.open = len(paths) < len(routes)
        fixed = {path for path in paths if "{" not in path}
        # with and without a trailing slash: the redirect to the other spelling looks too
        self.fixed = frozenset(
            fixed | {path.rstrip("/") or "/" for path in fixed} | {f"{path}/" for path in fixed}
        )
        self.starts = tuple(sorted({path.split("{", 1)[0] for path in paths} - fixed))

    def admits(self, scope: Scope) -> bool:
        """Whether a route of this router may match the request's path."""
        if self.open or scope.get(EVERY_ROUTER):
            return True
        path = get_route_path(scope)
        return path in self.fixed or path.startswith(self.starts)

    def matches(self, scope: Scope) -> tuple[Match, Scope]:
        if not self.admits(scope):
            return Match.NONE, {}
        return super().matches(scope)


def include_routers(app: FastAPI) -> None:
    """Wire every router into ``app``, each behind its :class:`PathGate`, after checking
    their locking declarations."""
    check_locking_declarations(api_routes())
    for router in ROUTERS:
        app.include_router(PathGate(router))
