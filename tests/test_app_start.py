"""What a worker does at start-up before its first request."""

from __future__ import annotations

import pytest
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
    language's catalogue (≈ 40 ms): the start-up does, before its heap is frozen; and it
    sets the interpreter's switch interval (``GYROLAB_SWITCH_INTERVAL_MS``)."""
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
switch = sys.getswitchinterval()
with TestClient(create_app(migrate_on_start=True, freeze_heap=True)):
    print(switch, sys.getswitchinterval())
    after = [m in sys.modules for m in modules]
    pages = [n for n in templates.env.list_templates() if n.endswith(".html")]
    print(compiled, len(templates.env.cache) == len(pages) > 40)
    print(loaded, i18n.translations.cache_info().currsize, i18n._locale.cache_info().currsize)
print(before, after)
"""
    env = {**os.environ, "GYROLAB_VAR_DIR": str(tmp_path), "GYROLAB_SWITCH_INTERVAL_MS": "2"}
    env.pop("GYROLAB_DATABASE_URL", None)
    done = subprocess.run(
        [sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True
    )
    lines = done.stdout.split("\n")[-5:-1]
    # and it takes the interpreter's switch interval from the settings (Python's: 5 ms)
    assert lines == ["0.005 0.002", "0 True", "0 2 2", "[False, False] [True, True]"], done.stdout


@pytest.mark.parametrize("value", ["0", "0.05", "1000", "nan", "fast"])
def test_a_switch_interval_out_of_range_is_refused_at_start(monkeypatch, value):
    """``GYROLAB_SWITCH_INTERVAL_MS`` from 0.1 to 100 ms; anything else stops the start
    with the setting's name, not a worker that hands its interpreter on every microsecond."""
    from pydantic import ValidationError

    from app.config import Settings

    monkeypatch.setenv("GYROLAB_SWITCH_INTERVAL_MS", value)
    with pytest.raises(ValidationError, match="switch_interval_ms"):
        Settings()
    monkeypatch.setenv("GYROLAB_SWITCH_INTERVAL_MS", "2.5")
    assert Settings().switch_interval_ms == 2.5


@pytest.mark.parametrize("value", ["Mars/Olympus", "asia/shanghai", "", "../etc/passwd"])
def test_a_time_zone_that_is_not_iana_is_refused_at_start(monkeypatch, value):
    """``GYROLAB_TIMEZONE`` must name an IANA zone (the names read once, ``iana_zones``);
    anything else stops the start with the setting's name."""
    from pydantic import ValidationError

    from app.config import Settings

    monkeypatch.setenv("GYROLAB_TIMEZONE", value)
    with pytest.raises(ValidationError, match="GYROLAB_TIMEZONE"):
        Settings()
    monkeypatch.setenv("GYROLAB_TIMEZONE", "Europe/Berlin")
    assert Settings().timezone == "Europe/Berlin"
