"""Translations are complete; the language follows the user; static assets are served."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from app.paths import PROJECT_ROOT, TEMPLATES_DIR
from app.web.i18n import catalogue, messages, negotiate, translate
from tests.factories import login, post_form

MESSAGES = messages()
KEY_IN_TEMPLATE = re.compile(r"""_\(\s*["']([a-z_]+\.[a-z_]+)["']""")
PREFIXES = "|".join(sorted({key.split(".")[0] for key in MESSAGES}))
KEY_IN_PYTHON = re.compile(rf"""["']((?:{PREFIXES})\.[a-z_]+)["']""")


def test_every_message_has_both_languages():
    for key, entry in MESSAGES.items():
        assert entry.get("en", "").strip(), key
        assert entry.get("zh-CN", "").strip(), key
        placeholders_en = set(re.findall(r"{(\w+)}", entry["en"]))
        placeholders_zh = set(re.findall(r"{(\w+)}", entry["zh-CN"]))
        assert placeholders_en == placeholders_zh, key


def test_both_catalogues_hold_the_same_keys_with_plural_forms_where_needed():
    english, chinese = catalogue("en"), catalogue("zh-CN")
    keys = {m.id if isinstance(m.id, str) else m.id[0] for m in english if m.id}
    assert keys == {m.id if isinstance(m.id, str) else m.id[0] for m in chinese if m.id}
    assert english.num_plurals == 2 and chinese.num_plurals == 1
    assert translate("admin.pruned", "en", n=1, days=30, mb=2).startswith(
        "Removed 1 old recording "
    )
    assert translate("admin.pruned", "en", n=2, days=30, mb=2).startswith(
        "Removed 2 old recordings"
    )
    assert translate("admin.pruned", "zh-CN", n=2, days=30, mb=2).startswith("已删除 2 条")


def test_every_key_the_code_writes_is_in_both_catalogues():
    """The keys pybabel extracts (babel.cfg) from the code and the templates."""
    import io

    from babel.messages.extract import extract_from_dir
    from babel.messages.frontend import parse_mapping_cfg

    method_map, options_map = parse_mapping_cfg(
        io.StringIO((PROJECT_ROOT / "babel.cfg").read_text())
    )
    keywords = {"_": None, "translate": (1,), "UserError": (1,), "flash": (3,)}
    extracted = {
        message if isinstance(message, str) else message[0]
        for _file, _line, message, _comments, _context in extract_from_dir(
            str(PROJECT_ROOT), method_map, options_map, keywords=keywords
        )
    }
    # one dot: a key ("a.b"); conditional keys ("a.b" if x else "a.c") extract joined
    keys = {m for m in extracted if m and re.fullmatch(r"[a-z_0-9]+\.[a-z0-9_]+", m)}
    assert len(keys) > 400
    assert not sorted(keys - set(MESSAGES))


def test_every_key_used_exists():
    used: set[str] = set()
    for path in TEMPLATES_DIR.rglob("*.html"):
        used |= set(KEY_IN_TEMPLATE.findall(path.read_text()))
    for path in (PROJECT_ROOT / "app").rglob("*.py"):
        used |= set(KEY_IN_PYTHON.findall(path.read_text()))
    not_messages = {"course.id", "assignment.id", "error.html", "join.html"}  # not keys
    # keys completed at run time ("lab.part_" ~ part) are prefixes of real keys
    missing = sorted(
        key
        for key in used - not_messages
        if key not in MESSAGES
        and not (key.endswith("_") and any(k.startswith(key) for k in MESSAGES))
    )
    assert not missing, missing
    assert len(used) > 50


@pytest.mark.parametrize(
    ("header", "expected"),
    [
        (None, "en"),
        ("zh-CN,zh;q=0.9,en;q=0.8", "zh-CN"),
        ("en-US,en;q=0.9,zh;q=0.8", "en"),
        ("fr-FR, zh-TW;q=0.5", "zh-CN"),
        ("de", "en"),
        ("en;q=0.1, zh;q=0.9", "zh-CN"),
    ],
)
def test_accept_language(header, expected):
    assert negotiate(header) == expected


def test_translate_formats_parameters():
    assert translate("roster.line", "zh-CN", line=3) == "第 3 行"
    assert translate("no.such.key", "en") == "no.such.key"


def test_pages_follow_accept_language(client):
    page = client.get("/login", headers={"Accept-Language": "zh-CN,zh;q=0.9"})
    assert '<html lang="zh-CN">' in page.text and "用户名或学号" in page.text


def test_language_switch_is_remembered_per_user(client, teacher, app):
    from fastapi.testclient import TestClient

    login(client, "teacher1")
    response = post_form(client, "/lang", {"lang": "zh-CN", "next": "/"})
    assert response.status_code == 303
    assert "我的课程" in client.get("/").text
    with TestClient(app, follow_redirects=False) as other_browser:  # no cookie, same user
        login(other_browser, "teacher1")
        assert "我的课程" in other_browser.get("/", headers={"Accept-Language": "en"}).text


def test_plotly_is_served_from_the_installed_package(client):
    from app.main import PLOTLY_JS, PLOTLY_URL

    plain = client.get(PLOTLY_URL, headers={"Accept-Encoding": "identity"})
    assert plain.status_code == 200 and "content-encoding" not in plain.headers
    assert plain.headers["content-type"].startswith("text/javascript")
    assert "max-age=31536000" in plain.headers["cache-control"]
    # the package's file byte for byte, under V8's compile hint: a comment line of its own
    hint, script = plain.content.split(b"\n", 1)
    assert hint == b"//# allFunctionsCalledOnLoad"
    assert script == Path(PLOTLY_JS).read_bytes() and len(script) > 1_000_000
    # compressed for browsers: under a third of the bytes on the wire, the same script
    packed = client.get(PLOTLY_URL, headers={"Accept-Encoding": "gzip, deflate, br"})
    assert packed.headers["content-encoding"] == "gzip"
    assert packed.headers["vary"] == "Accept-Encoding"
    assert int(packed.headers["content-length"]) < len(plain.content) / 3
    assert packed.content == plain.content  # httpx decodes it


def test_api_docs_link_back_to_the_app(client):
    assert '<a href="/"' in client.get("/docs").text


def test_no_page_loads_anything_from_the_internet():
    for path in list(TEMPLATES_DIR.rglob("*.html")) + list((PROJECT_ROOT / "static").rglob("*")):
        if path.is_file() and path.suffix in {".html", ".css", ".js"}:
            text = path.read_text()
            assert not re.search(r"""(src|href)=["']https?://""", text), path
            assert "@import url(http" not in text, path


def test_unknown_page_is_a_friendly_404(client):
    response = client.get("/nowhere", headers={"Accept-Language": "zh-CN"})
    assert response.status_code == 404 and "页面不存在" in response.text


def test_security_headers(client):
    response = client.get("/login")
    csp = response.headers["content-security-policy"]
    assert "script-src 'self'" in csp and "frame-ancestors 'none'" in csp
    assert response.headers["x-content-type-options"] == "nosniff"
    assert response.headers["referrer-policy"] == "same-origin"
    assert "strict-transport-security" not in response.headers  # plain http here
    secure = client.get("https://testserver/login")
    assert secure.headers["strict-transport-security"].startswith("max-age=")


def test_no_inline_scripts_in_templates():
    for path in TEMPLATES_DIR.rglob("*.html"):
        for tag in re.findall(r"<script[^>]*>", path.read_text()):
            assert "src=" in tag or 'type="application/json"' in tag, (path, tag)


def user_errors_in_the_code():
    """Every ``UserError(...)`` call in app/: (place, key or None when computed, keyword
    names or None when they are passed as ``**params``, positional argument count)."""
    import ast

    for path in (PROJECT_ROOT / "app").rglob("*.py"):
        tree = ast.parse(path.read_text())
        for node in ast.walk(tree):
            name = getattr(node, "func", None)
            if not isinstance(node, ast.Call) or getattr(name, "id", None) != "UserError":
                continue
            first = node.args[0] if node.args else None
            key = first.value if isinstance(first, ast.Constant) else None
            names = {k.arg for k in node.keywords}
            yield f"{path.name}:{node.lineno}", key, None if None in names else names, node.args


def test_user_errors_carry_a_key_and_every_parameter_of_its_words():
    """The words come from the catalogue only (no English copy beside the key to drift),
    and each placeholder of the message in either language gets a value (a missing one
    would show "{position}" or fail)."""
    placeholders = {
        key: set(re.findall(r"{(\w+)", " ".join(entry.values()))) for key, entry in MESSAGES.items()
    }
    checked = 0
    for place, key, names, args in user_errors_in_the_code():
        assert len(args) == 1, f"{place}: a key only (the catalogue has the words)"
        if key is None or names is None:
            continue
        assert key in MESSAGES, f"{place}: {key} is in neither catalogue"
        missing = placeholders[key] - names
        assert not missing, f"{place}: {key} needs {sorted(missing)}"
        checked += 1
    assert checked > 200


def test_no_words_in_two_languages_are_kept_in_python():
    """The catalogues are the one source of words: no ``{"en": ..., "zh-CN": ...}`` left in
    the code (the language list itself, app/web/i18n.py, names each language once)."""
    import ast

    found = []
    for path in (PROJECT_ROOT / "app").rglob("*.py"):
        if path.name == "i18n.py":
            continue
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.Dict):
                keys = {k.value for k in node.keys if isinstance(k, ast.Constant)}
                if {"en", "zh-CN"} <= keys:
                    found.append(f"{path.name}:{node.lineno}")
    assert not found


def test_a_time_shown_names_its_zone_in_the_readers_language():
    from datetime import UTC, datetime
    from zoneinfo import ZoneInfo

    from app.web.i18n import format_datetime

    moment = datetime(2026, 12, 1, 10, 0, tzinfo=UTC)
    shanghai = ZoneInfo("Asia/Shanghai")
    assert format_datetime(moment, "en", "yMMMd", "Hm", shanghai) == "Dec 1, 2026 18:00 China Time"
    assert (
        format_datetime(moment, "zh-CN", "yMMMd", "Hm", shanghai) == "2026年12月1日 18:00 中国时间"
    )
    assert format_datetime(moment, "en", None, "Hms", ZoneInfo("UTC")) == "10:00:00 UTC"
    assert format_datetime(moment, "en", "yMMMd", None, shanghai) == "Dec 1, 2026"  # a date alone


@pytest.mark.parametrize("control", ["\u202e", "\u202d", "\u2066", "\u2067", "\u2069"])
def test_a_value_quoted_in_a_message_cannot_reorder_it(control, student_client):
    """A cell quoted back ("'…' is not a number") keeps its text but not a bidirectional
    control, which would show the rest of the message reversed (the lab page's own
    messages: tests/e2e/test_editing_flow.py)."""
    said = translate("csv.not_a_number", "en", line=2, column="position_1", value=f"{control}°/s")
    assert said == "Line 2, column position_1: '°/s' is not a number."
    assert control not in translate("csv.not_a_number", "zh-CN", line=2, column="c", value=control)
    from tests.factories import new_session, post_json

    session_id = new_session(student_client)
    page = f"/lab/sessions/{session_id}"
    text = f"P1,P2,P3,P4\n{control}°/s,x,°/s,°/s\n1,2,3,4\n"
    refused = post_json(
        student_client,
        f"{page}/csv/preview",
        {"part": "heading", "unit": "deg/h", "text": text},
        page,
    )
    assert refused.status_code == 400
    assert refused.json()["detail"] == "Line 2, column position_1: '°/s' is not a number."
