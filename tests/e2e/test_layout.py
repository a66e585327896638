"""Every page as people meet it: no page scrolls sideways at 320 px (WCAG 2.2's reflow
width), 390 px or 1366 px, in either language, for a student, a teacher or an
administrator (the class dashboard's table fits at 1366 px); and every page passes
axe-core's WCAG 2.0/2.1/2.2 A and AA rules with no serious or critical violation, in the
light and the dark theme."""

from __future__ import annotations

import pytest

from tests.e2e.conftest import axe_problems, log_in

pytestmark = pytest.mark.e2e

# the page's width beyond the viewport, and the first elements sticking out (outside the
# containers that scroll on purpose: tables, the grid, plotly's own layers)
OVERFLOW = """() => {
  const width = document.documentElement.clientWidth;
  const out = [];
  if (document.documentElement.scrollWidth > width + 1) {
    for (const element of document.querySelectorAll("body *")) {
      const box = element.getBoundingClientRect();
      if (box.width > 0 && box.right > width + 1
          && !element.closest(".table-scroll, .grid-wrap, .js-plotly-plot, pre")) {
        out.push(`${element.tagName.toLowerCase()}.${element.className}`);
      }
    }
  }
  return {scroll: document.documentElement.scrollWidth, width, out: out.slice(0, 5)};
}"""


ADMIN = ("admin1", "admin-e2e-pass-1")
WIDTHS = (320, 390, 1366)  # WCAG 2.2 1.4.10 reflow, a phone, a laptop


@pytest.fixture(scope="session")
def admin_password(demo_server) -> str:
    """An administrator in the demo installation (the demo itself has none)."""
    server, _credentials = demo_server
    server.gyrolab("create-user", "--role", "admin", "--username", ADMIN[0], "--password", ADMIN[1])
    return ADMIN[1]


def pages_of(page, url: str, role: str) -> list[str]:
    """Every kind of page the role sees, found by following the app's own links."""
    paths = ["/", "/lab", "/explore", "/account/tokens", "/account/password"]
    if role == "admin":
        return ["/", "/admin/accounts", "/admin/lti", "/account/tokens", "/no-such-page"]
    if role == "teacher":
        page.goto(f"{url}/courses")
        course = page.locator("main a[href^='/courses/']").first.get_attribute("href")
        page.goto(url + course)
        demo = page.locator("main a[href*='/assignments/']", has_text="Four-position north finding")
        assignment = demo.first.get_attribute("href")
        page.goto(url + assignment)
        review = page.locator("#class-table a[href^='/review/']").first.get_attribute("href")
        paths += ["/courses", course, assignment, review, "/review/archives"]
    else:
        page.goto(f"{url}/lab")
        paths += [page.locator("main a[href^='/lab/sessions/']").first.get_attribute("href")]
        paths += ["/join?code=ABCDEFGH"]
    return paths


@pytest.mark.parametrize(
    ("locale", "theme"), [("en-US", "light"), ("zh-CN", "dark")], ids=["en-light", "zh-dark"]
)
@pytest.mark.parametrize("role", ["student1", "teacher", "admin"])
def test_every_page_fits_the_screen_and_passes_axe(
    demo_server, browser, request, role, locale, theme
):
    server, credentials = demo_server
    if role == "admin":
        credentials = {**credentials, "admin": request.getfixturevalue("admin_password")}
    problems, inaccessible = [], {}
    context = browser.new_context(
        locale=locale, color_scheme=theme, viewport={"width": 1366, "height": 900}
    )
    page = context.new_page()
    if role == "student1":  # the log-in page, before anyone is logged in
        for width in WIDTHS:
            page.set_viewport_size({"width": width, "height": 900})
            page.goto(f"{server.url}/login")
            found = page.evaluate(OVERFLOW)
            if found["scroll"] > width + 1:
                problems.append((locale, width, "/login", found))
        if found_axe := axe_problems(page):
            inaccessible["/login"] = found_axe
    log_in(page, server.url, ADMIN[0] if role == "admin" else role, credentials[role])
    kind = {"student1": "student", "teacher": "teacher", "admin": "admin"}[role]
    paths = pages_of(page, server.url, kind)
    # each page loaded once at 320 px, then widened to 390 and 1366 px (plotly resizes its
    # charts a moment after the window does: they grow late, never too wide)
    for path in paths:
        page.set_viewport_size({"width": WIDTHS[0], "height": 900})
        page.goto(server.url + path)
        page.wait_for_load_state("load")
        for width in WIDTHS:
            page.set_viewport_size({"width": width, "height": 900})
            found = page.evaluate(OVERFLOW)
            if found["scroll"] > width + 1:
                problems.append((locale, width, path, found))
            if width == 1366 and "/assignments/" in path:
                table = page.evaluate(
                    "() => { const s = document.querySelector('#class-table').parentElement;"
                    " return [s.scrollWidth, s.clientWidth]; }"
                )
                if table[0] > table[1] + 1:
                    problems.append((locale, width, path, {"class table": table}))
        if found_axe := axe_problems(page):
            inaccessible[path] = found_axe
    context.close()
    assert problems == []
    assert inaccessible == {}
