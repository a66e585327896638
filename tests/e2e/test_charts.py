"""Issue 34 item 9: charts are drawn only when they come into view (plotly, 1.4 MB
compressed, is not fetched for a page whose charts are off screen), and a chart's legend
never sits on its x axis's title or tick labels, at 390 and 1366 px, in both languages."""

from __future__ import annotations

import pytest
from playwright.sync_api import expect

from app.cli.demo import DEMO_ASSIGNMENT
from tests.e2e.conftest import expect_chart_drawn, log_in

pytestmark = pytest.mark.e2e

# every overlap between a chart's legend and its x axis's title and tick labels, as text
OVERLAPS = """chart => {
  const boxes = (selector) => [...chart.querySelectorAll(selector)]
    .map(el => el.getBoundingClientRect()).filter(r => r.width > 0 && r.height > 0);
  const legend = boxes("g.legend .traces");
  const axis = boxes("g.g-xtitle text, g.xtick text");
  const meet = (a, b) => a.left < b.right && b.left < a.right
    && a.top < b.bottom && b.top < a.bottom;
  return legend.flatMap(a => axis.filter(b => meet(a, b))
    .map(b => `${a.top}-${a.bottom} / ${b.top}-${b.bottom}`));
}"""


def session_with_results(page, base_url: str) -> str:
    page.goto(f"{base_url}/lab")
    # the demo assignment's (the partners' flow may have given this student a newer one)
    demo = page.locator("#sessions a[href^='/lab/sessions/']", has_text=DEMO_ASSIGNMENT)
    href = demo.first.get_attribute("href")
    return f"{base_url}{href}"


@pytest.mark.parametrize("language", ["en", "zh-CN"])
def test_charts_are_drawn_as_they_come_into_view_with_legends_clear_of_the_axes(
    demo_server, new_page, language
):
    server, credentials = demo_server
    page = new_page()
    page.set_viewport_size({"width": 390, "height": 844})
    page.context.add_cookies([{"name": "gyrolab_lang", "value": language, "url": server.url}])
    log_in(page, server.url, "student1", credentials["student1"])
    fetched = []
    page.on("request", lambda r: fetched.append(r.url) if "plotly" in r.url else None)
    page.goto(session_with_results(page, server.url))

    charts = page.locator(".chart[data-figure]")
    assert charts.count() >= 4
    first_top = charts.first.bounding_box()["y"]
    assert first_top > 844 + 400, "the first chart is meant to start well below the fold"
    page.wait_for_timeout(500)
    assert fetched == [] and page.locator(".chart .main-svg").count() == 0

    for width in (390, 1366):  # a phone, then the same page widened (plotly redraws)
        page.set_viewport_size({"width": width, "height": 844})
        for index in range(charts.count()):
            chart = charts.nth(index)
            expect_chart_drawn(chart)
            page.wait_for_timeout(100 if width == 390 else 300)  # a resize redraw settles
            where = f"{chart.get_attribute('data-figure')}, {language}, {width} px"
            assert chart.evaluate(OVERLAPS) == [], f"legend on the x axis: {where}"
    assert len(fetched) == 1, "plotly is fetched once, however many charts"

    # the toolbar speaks the page's language once plotly has arrived
    download = "Download plot as a PNG" if language == "en" else "下载图表（PNG）"
    expect(page.locator(".modebar-btn[data-title]").first).to_have_attribute("data-title", download)


def test_a_chart_says_so_when_plotly_cannot_be_fetched(demo_server, new_page):
    server, credentials = demo_server
    page = new_page()
    log_in(page, server.url, "student1", credentials["student1"])
    page.route("**/vendor/plotly-*", lambda route: route.abort())
    page.goto(session_with_results(page, server.url))
    chart = page.locator(".chart[data-figure]").first
    chart.scroll_into_view_if_needed()
    expect(chart).to_have_attribute("data-chart-failed", "1")
    expect(chart).to_contain_text("could not be loaded")
