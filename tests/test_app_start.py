"""What a worker does at start-up before its first request."""

from __future__ import annotations

from fastapi.routing import _IncludedRouter  # FastAPI's own (pinned); what it builds lazily
from fastapi.testclient import TestClient

from app.main import create_app


def unbuilt_routers(routes) -> int:
    """Included routers whose routes FastAPI has not built yet (it builds them when a
    request first reaches them)."""
    count = 0
    for route in routes:
        if isinstance(route, _IncludedRouter):
            if route._effective_candidates_version is None:
                count += 1
            count += unbuilt_routers(route._effective_candidates)
    return count


def test_every_router_is_built_at_start_up_not_by_the_first_request(var_dir):
    app = create_app(migrate_on_start=False)
    assert unbuilt_routers(app.router.routes) > 20  # built lazily unless started
    with TestClient(app) as client:
        assert unbuilt_routers(app.router.routes) == 0
        assert client.get("/login").status_code == 200


def test_a_served_worker_imports_what_the_first_result_needs_before_serving(tmp_path):
    """The first stream and the first result of a served worker do not pay SciPy's import
    (≈ 1 s and ≈ 0.6 s), nor its first pages their templates' compiling or their
    language's catalogue (≈ 40 ms): the start-up does, before its heap is frozen."""
    import os
    import subprocess
    import sys

    code = """
import sys
from fastapi.testclient import TestClient
from app.main import create_app
from app.web import i18n
from app.web.render import templates
modules = ("scipy.signal", "scipy.stats")
before = [m in sys.modules for m in modules]
compiled = len(templates.env.cache)
loaded = i18n.translations.cache_info().currsize
with TestClient(create_app(migrate_on_start=True, freeze_heap=True)):
    after = [m in sys.modules for m in modules]
    pages = [n for n in templates.env.list_templates() if n.endswith(".html")]
    print(compiled, len(templates.env.cache) == len(pages) > 40)
    print(loaded, i18n.translations.cache_info().currsize, i18n._locale.cache_info().currsize)
print(before, after)
"""
    env = {**os.environ, "GYROLAB_VAR_DIR": str(tmp_path)}
    env.pop("GYROLAB_DATABASE_URL", None)
    done = subprocess.run(
        [sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True
    )
    lines = done.stdout.split("\n")[-4:-1]
    assert lines == ["0 True", "0 2 2", "[False, False] [True, True]"], done.stdout
