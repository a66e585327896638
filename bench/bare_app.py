"""The framework's own ceiling: a bare FastAPI JSON endpoint and a bare Jinja page,
served by the same uvicorn, to compare GyroLab's routes against."""

from fastapi import FastAPI
from fastapi.responses import HTMLResponse
from jinja2 import Template

app = FastAPI()
PAGE = Template(
    "<!doctype html><html><body><h1>{{ title }}</h1>"
    "{% for i in range(rows) %}<p>{{ i }}</p>{% endfor %}</body></html>"
)
PAYLOAD = {
    "heading": {"azimuth_deg": 10.75, "theta_deg": -10.75, "values": list(range(16))},
    "latitude": {"latitude_deg": 40.73, "earth_rate_deg_h": 15.13},
}


@app.get("/json")
def bare_json() -> dict:
    return PAYLOAD


@app.get("/page", response_class=HTMLResponse)
def bare_page() -> str:
    return PAGE.render(title="bare", rows=40)
