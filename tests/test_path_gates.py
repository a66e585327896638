"""Each router sits behind a gate on the request's path (``app.routes.PathGate``): a gate
may turn a request away only when none of its routes could match it."""

from __future__ import annotations

import re

import pytest

from app.routes import ROUTERS, PathGate, iter_routes

GATES = [PathGate(router) for router in ROUTERS]
PARAMETER = re.compile(r"\{[^}]*\}")


def concrete_paths() -> list[str]:
    """Every route's path with its parameters filled in, with and without a trailing
    slash, and a few that match nothing."""
    paths = set()
    for router in ROUTERS:
        for route in iter_routes(router.routes):
            path = PARAMETER.sub("7", route.path)
            paths |= {path, path.rstrip("/") or "/", f"{path}/"}
    return sorted(paths | {"/", "/nothing", "/lab/nothing/7", "/api/v2/sessions"})


def scope(path: str, kind: str = "http") -> dict:
    return {"type": kind, "method": "GET", "path": path, "root_path": ""}


@pytest.mark.parametrize("kind", ["http", "websocket"])
def test_a_gate_turns_away_only_paths_none_of_its_routes_match(kind):
    for gate, router in zip(GATES, ROUTERS, strict=True):
        patterns = [route.path_regex for route in iter_routes(router.routes)]
        for path in concrete_paths():
            if any(pattern.match(path) for pattern in patterns):
                assert gate.admits(scope(path, kind)), (router.prefix, path)


def test_a_lab_page_reaches_only_the_lab_s_routers():
    admitted = [gate for gate in GATES if gate.admits(scope("/lab/sessions/7/results.json"))]
    assert 1 <= len(admitted) <= 6 < len(GATES)
    assert not any(gate.admits(scope("/nothing")) for gate in GATES)
    assert all(gate.admits({**scope("/nothing"), "gyrolab.every_router": True}) for gate in GATES)


def test_every_route_is_still_reached_through_the_gates(client):
    """A route behind its gate answers as before: pages, the API and the redirect of a
    path spelt with a trailing slash."""
    assert client.get("/login").status_code == 200
    assert client.get("/api/v1/me").status_code == 401
    assert client.get("/lab", follow_redirects=False).status_code in (303, 307)
    assert client.get("/login/", follow_redirects=False).status_code in (307, 308)
    assert client.get("/nothing").status_code == 404


def test_a_router_with_a_route_matched_otherwise_than_by_its_pattern_is_not_gated():
    """A mount matches every path under it (its own path has no parameter to show that):
    a router holding one is let through whatever the path."""
    from fastapi import APIRouter

    async def files(scope, receive, send) -> None:  # an ASGI app, never called here
        raise AssertionError

    router = APIRouter()
    router.mount("/files", files)
    gate = PathGate(router)
    assert gate.admits(scope("/files/report.pdf")) and gate.admits(scope("/elsewhere"))
