"""A chart page's first view in Chromium: plotly.js as the package ships it against plotly as
GyroLab serves it (under V8's explicit compile hint), alternated in fresh browser contexts.

    python bench/bench_chart_page.py [--rounds 6]

Serves the demo (``gyrolab serve`` on a new var dir), signs in as the demo's student1 and
opens their submitted session, whose five charts are drawn as they come into view.  Each
round opens the page once per variant (the order swapped every round), in a context of its
own so that nothing is cached, with the plotly URL answered from memory for both, and
measures from the page's load to its last chart drawn:

- the page's main thread: its busy time (``TaskDuration``) and of that the JavaScript's
  (``ScriptDuration``), from the DevTools protocol's ``Performance.getMetrics``;
- the CPU of all of Chromium's processes (from /proc), background threads included.

Prints each variant's medians and the served variant's ratio to the package's.  Debian's
Chromium (``/usr/bin/chromium``), no flags beyond what a root container needs.
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

import httpx

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from bench_web import free_ports, wait_for  # noqa: E402

from app.main import PLOTLY_JS, PLOTLY_URL  # noqa: E402

CHROMIUM = "/usr/bin/chromium"
ARGS = ["--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage"]
TICKS = os.sysconf("SC_CLK_TCK")


def chromium_cpu_s() -> float:
    """The CPU (user + system, s) of every Chromium process now running."""
    total = 0.0
    for pid in filter(str.isdigit, os.listdir("/proc")):
        try:
            stat = Path(f"/proc/{pid}/stat").read_text()
        except OSError:
            continue
        if stat[stat.index("(") + 1 : stat.rindex(")")] == "chromium":
            fields = stat[stat.rindex(")") + 2 :].split()
            total += (int(fields[11]) + int(fields[12])) / TICKS
    return total


def serve(var_dir: Path) -> tuple[subprocess.Popen, str]:
    """The demo on a free port: (the server, its URL), once it answers."""
    [port] = free_ports(1)
    env = {**os.environ, "GYROLAB_VAR_DIR": str(var_dir)}
    server = subprocess.Popen(
        [sys.executable, "-m", "app.cli.main", "serve", "--port", str(port)],
        env=env, cwd=ROOT, stdout=subprocess.DEVNULL, stderr=subprocess.STDOUT,
    )  # fmt: skip
    url = f"http://127.0.0.1:{port}"
    try:
        wait_for(f"{url}/login", server)
    except RuntimeError:
        server.kill()
        raise
    return server, url


def main_thread(cdp) -> tuple[float, float]:
    metrics = {m["name"]: m["value"] for m in cdp.send("Performance.getMetrics")["metrics"]}
    return metrics["TaskDuration"], metrics["ScriptDuration"]


def first_view(browser, state: dict, page_url: str, script: bytes) -> tuple[float, float, float]:
    """(main thread busy s, of it JavaScript s, Chromium CPU s) from the page's load to its
    last chart drawn, plotly answered with ``script``."""
    context = browser.new_context(storage_state=state, viewport={"width": 1366, "height": 900})
    try:
        page = context.new_page()
        page.route(
            f"**{PLOTLY_URL}",
            lambda route: route.fulfill(
                body=script,
                content_type="text/javascript",
                headers={"Cache-Control": "public, max-age=31536000, immutable"},
            ),
        )
        cdp = context.new_cdp_session(page)
        cdp.send("Performance.enable")
        page.goto(page_url)
        page.wait_for_load_state("load")
        task_0, script_0 = main_thread(cdp)
        cpu_0 = chromium_cpu_s()
        charts = page.locator(".chart[data-figure]")
        for index in range(charts.count()):
            chart = charts.nth(index)
            chart.scroll_into_view_if_needed()
            chart.locator(".main-svg").first.wait_for(state="visible", timeout=60_000)
        page.wait_for_timeout(300)  # a redraw after the last one settles
        task_1, script_1 = main_thread(cdp)
        return task_1 - task_0, script_1 - script_0, chromium_cpu_s() - cpu_0
    finally:
        context.close()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--rounds", type=int, default=6)
    rounds = parser.parse_args().rounds
    from playwright.sync_api import sync_playwright

    with tempfile.TemporaryDirectory() as var_dir:
        server, url = serve(Path(var_dir))
        try:
            credentials = {
                line.split(",")[1]: line.split(",")[2]
                for line in (Path(var_dir) / "demo-credentials.txt").read_text().splitlines()
                if not line.startswith("#")
            }
            served = httpx.get(url + PLOTLY_URL, timeout=30).content
            variants = {"package": PLOTLY_JS.read_bytes(), "served": served}
            with sync_playwright() as playwright:
                browser = playwright.chromium.launch(
                    executable_path=CHROMIUM, headless=True, args=ARGS
                )
                context = browser.new_context()
                page = context.new_page()
                page.goto(f"{url}/login")
                page.fill("input[name=username]", "student1")
                page.fill("input[name=password]", credentials["student1"])
                with page.expect_navigation():
                    page.click("button[type=submit].primary")
                page.goto(f"{url}/lab")
                link = page.locator("#sessions a[href^='/lab/sessions/']").first
                page_url = url + link.get_attribute("href")
                state = context.storage_state()
                context.close()
                found: dict[str, list[tuple[float, float, float]]] = {k: [] for k in variants}
                for number in range(rounds):
                    order = list(variants) if number % 2 == 0 else list(variants)[::-1]
                    for name in order:
                        found[name].append(first_view(browser, state, page_url, variants[name]))
                browser.close()
        finally:
            server.terminate()
            server.wait(30)
    medians = {
        name: [statistics.median(column) for column in zip(*rows, strict=True)]
        for name, rows in found.items()
    }
    print(f"a chart page's first view, {rounds} rounds, medians (s)")
    print(f"{'plotly':10} {'main thread':>12} {'of it JS':>10} {'Chromium CPU':>13}")
    for name, (task, script, cpu) in medians.items():
        print(f"{name:10} {task:12.3f} {script:10.3f} {cpu:13.3f}")
    (task_p, script_p, cpu_p), (task_s, script_s, cpu_s) = medians.values()
    print(f"{'ratio':10} {task_s / task_p:12.2f} {script_s / script_p:10.2f} {cpu_s / cpu_p:13.2f}")


if __name__ == "__main__":
    main()
