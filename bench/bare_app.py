"""The framework's own ceiling: a bare FastAPI JSON endpoint and a bare Jinja page,
served by the same uvicorn, to compare GyroLab's routes against.

``/page/{size}`` is a bare Jinja page *of a given size*: a table whose rows each carry
three escaped values, as many rows as make ``size`` bytes -- the lab page's own size is
what ``bench_web.py`` asks for, so the two pages cost the same to send and to escape
row by row."""

from functools import lru_cache

from fastapi import FastAPI
from fastapi.responses import HTMLResponse
from jinja2 import Environment

app = FastAPI()
ENV = Environment(autoescape=True)
PAGE = ENV.from_string(
    "<!doctype html><html><body><h1>{{ title }}</h1>"
    "{% for i in range(rows) %}<p>{{ i }}</p>{% endfor %}</body></html>"
)
SIZED = ENV.from_string(
    "<!doctype html><html><head><title>{{ title }}</title></head><body><table>"
    "{% for i in range(rows) %}"
    '<tr><td class="n">{{ i }}</td><td>{{ label }} {{ i }}</td><td>{{ value }}</td></tr>\n'
    "{% endfor %}</table></body></html>"
)
PAYLOAD = {
    "heading": {"azimuth_deg": 10.75, "theta_deg": -10.75, "values": list(range(16))},
    "latitude": {"latitude_deg": 40.73, "earth_rate_deg_h": 15.13},
}
SIZED_CONTEXT = {"title": "bare", "label": "Position <1>", "value": "10.7500 °/h"}


@app.get("/json")
def bare_json() -> dict:
    return PAYLOAD


@app.get("/page", response_class=HTMLResponse)
def bare_page() -> str:
    return PAGE.render(title="bare", rows=40)


@lru_cache
def rows_for(size: int) -> int:
    """The number of rows whose page is closest to ``size`` bytes (UTF-8)."""

    def length(rows: int) -> int:
        return len(SIZED.render(rows=rows, **SIZED_CONTEXT).encode())

    low, high = 0, 1
    while length(high) < size:
        low, high = high, high * 2
    while high - low > 1:
        middle = (low + high) // 2
        low, high = (middle, high) if length(middle) < size else (low, middle)
    return min((low, high), key=lambda rows: abs(length(rows) - size))


@app.get("/page/{size}", response_class=HTMLResponse)
def bare_page_of_size(size: int) -> str:
    return SIZED.render(rows=rows_for(min(size, 10_000_000)), **SIZED_CONTEXT)
