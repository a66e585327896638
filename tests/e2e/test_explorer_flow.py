"""The explorer in a real browser: pick the paper's 10° tilt, then compare four positions."""

from __future__ import annotations

import pytest
from playwright.sync_api import expect

from tests.e2e.conftest import STUDENT_PASSWORD, expect_chart_drawn, log_in

pytestmark = pytest.mark.e2e


def trace_names(page) -> list[str]:
    return page.evaluate(
        "() => document.getElementById('heading-chart').data.map(trace => trace.name)"
    )


def first_y(page) -> float:
    return page.evaluate("() => document.getElementById('heading-chart').data[1].y[3]")


@pytest.mark.parametrize("locale", ["en-US", "zh-CN"])
def test_slider_and_scenarios_update_the_chart(live_server, new_page, locale):
    page = new_page(locale=locale)
    log_in(page, live_server.url, "student", STUDENT_PASSWORD)
    page.goto(f"{live_server.url}/explore")
    expect(page.locator("#run-info")).not_to_be_empty()
    page.locator("#heading-chart").scroll_into_view_if_needed()  # drawn once in view
    page.select_option("#scenario", "indexing-tilt-10")
    expect(page.locator("#scenario-text")).not_to_be_empty()
    # the chart is drawn once plotly has arrived (static/js/charts.js): until then no .data
    page.wait_for_function(
        "() => (document.getElementById('heading-chart').data || []).length === 2"
    )
    before = first_y(page)
    assert before == pytest.approx(0.15, abs=0.2)  # ≈ δ/2 = 0.125° with a ripple
    slider = page.locator("#indexing_arcsec")
    slider.fill("1800")  # a bigger indexing error: the curve must move
    page.wait_for_function(
        f"() => (document.getElementById('heading-chart').data || [])[1]?.y[3] > {before} * 1.5"
    )
    page.locator("input[name=method][value=both]").check()
    page.wait_for_function(
        "() => (document.getElementById('heading-chart').data || []).length === 4"
    )
    names = trace_names(page)
    assert any("四位置法" in n or "four-position" in n for n in names)
    expect_chart_drawn(page.locator("#dwell-chart"))
