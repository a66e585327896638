"""Charts beside the data evidence at the grading desk: a part's readings beside readings
the station's gyro makes at the same counts (``app.core.expected_readings``), and the
last typed digits beside the uniform share honest typing gives."""

from __future__ import annotations

import math

import numpy as np

from app.core.data_copies import typed_step
from app.core.expected_readings import MAX_READINGS, expected_readings
from app.core.reading_moments import expected_variance
from app.lab.charts import LAYOUT, PALETTE, SYMBOLS, titled
from app.lab.copy_index import own_positions
from app.lab.planner import gyro_model


def _lag1(deviations: list[np.ndarray]) -> float | None:
    """r₁ of the readings about each position's mean, pooled."""
    top = sum(float(np.sum(d[1:] * d[:-1])) for d in deviations if d.size > 1)
    bottom = sum(float(np.sum(d * d)) for d in deviations)
    return top / bottom if bottom > 0 else None


def _pooled_sd(deviations: list[np.ndarray]) -> float | None:
    dof = sum(d.size - 1 for d in deviations if d.size > 1)
    if dof <= 0:
        return None
    return math.sqrt(sum(float(np.sum(d * d)) for d in deviations if d.size > 1) / dof)


def _traces(deviations: list[np.ndarray], positions: list[int], axis: str, _) -> list[dict]:
    traces, start = [], 1
    for k, values in zip(positions, deviations, strict=True):
        number = np.arange(start, start + values.size)
        start += values.size
        traces.append(
            {
                "type": "scatter",
                "mode": "lines+markers",
                "name": _("chart.position", n=k),
                "legendgroup": str(k),
                "showlegend": axis == "x",
                "x": number.tolist(),
                "y": np.round(values, 5).tolist(),
                "xaxis": axis,
                "yaxis": "y" if axis == "x" else "y2",
                "line": {"color": PALETTE[(k - 1) % len(PALETTE)], "width": 1},
                "marker": {"symbol": SYMBOLS[(k - 1) % len(SYMBOLS)], "size": 5},
            }
        )
    return traces


def beside_figure(part: str, own, noise, rate_hz: float, seed: int, _) -> tuple[dict, dict]:
    """The group's readings about each position's mean (left) beside one draw of the
    station's gyro at the same counts and typed step (right), on one scale; and the
    chart's sentence and table."""
    positions = [item.take.position for item in own]
    values = [np.asarray(item.values, float) for item in own]
    shown = [v[:MAX_READINGS] - v[:MAX_READINGS].mean() if v.size else v for v in values]
    step = typed_step(np.concatenate(values)) if values else None
    grid = 3600.0 * noise.angle_lsb_deg * rate_hz
    expected = expected_readings(noise, rate_hz, [v.size for v in shown], step or grid, seed)
    expected = [e - e.mean() if e.size else e for e in expected]
    reach = max([float(np.max(np.abs(v))) for v in shown + expected if v.size] + [1e-9])
    axis = {"range": [-1.1 * reach, 1.1 * reach], "zeroline": True}
    title_left, title_right = _("evidence.chart_group"), _("evidence.chart_gyro")
    figure = {
        "data": _traces(shown, positions, "x", _) + _traces(expected, positions, "x2", _),
        "layout": {
            **LAYOUT,
            "title": titled(_("evidence.chart_title", part=_(f"lab.part_short_{part}"))),
            "xaxis": {
                "domain": [0, 0.48],
                "title": {"text": _("chart.reading_number"), "standoff": 8},
                "automargin": True,
            },
            "xaxis2": {
                "domain": [0.52, 1],
                "title": {"text": _("chart.reading_number"), "standoff": 8},
                "automargin": True,
            },
            "yaxis": {**axis, "title": {"text": _("evidence.chart_deviation")}},
            # one scale for both: the right one's numbers are the left one's
            "yaxis2": {**axis, "anchor": "x2", "matches": "y", "showticklabels": False},
            "annotations": [
                {
                    "text": text,
                    "x": x,
                    "xref": "paper",
                    "y": 1.0,
                    "yref": "paper",
                    "xanchor": "center",
                    "yanchor": "bottom",
                    "showarrow": False,
                }
                for text, x in ((title_left, 0.235), (title_right, 0.765))
            ],
        },
    }
    counts = [v.size for v in values]
    sd_group, r_group = _pooled_sd(shown), _lag1(shown)
    sd_model = math.sqrt(expected_variance(noise, rate_hz, int(np.median(counts)), step))
    r_model = _lag1(expected)

    def number(value, digits=3):
        return "—" if value is None else f"{value:.{digits}g}"

    summary = _(
        "evidence.chart_summary",
        sd=number(sd_group),
        r1=number(r_group, 2),
        expected_sd=number(sd_model),
        expected_r1=number(r_model, 2),
    )
    if any(v.size > MAX_READINGS for v in values):
        summary += " " + _("evidence.chart_first", n=MAX_READINGS)
    rows = [
        [
            str(k),
            str(v.size),
            number(float(np.std(s, ddof=1)) if s.size > 1 else None),
            number(float(np.std(e, ddof=1)) if e.size > 1 else None),
        ]
        for k, v, s, e in zip(positions, values, shown, expected, strict=True)
    ]
    table = {
        "columns": [
            _("evidence.chart_position"),
            "n",
            _("evidence.chart_group_sd"),
            _("evidence.chart_gyro_sd"),
        ],
        "rows": rows,
    }
    return figure, {"summary": summary, "table": table}


def digits_figure(part: str, counts: list[int], _) -> tuple[dict, dict]:
    """How often each last typed digit was typed, beside the uniform share (n/10)."""
    total = sum(counts)
    figure = {
        "data": [
            {
                "type": "bar",
                "name": _("evidence.chart_typed"),
                "x": list(range(10)),
                "y": counts,
                "marker": {"color": PALETTE[0]},
            },
            {
                "type": "scatter",
                "mode": "lines",
                "name": _("evidence.chart_uniform"),
                "x": [-0.5, 9.5],
                "y": [total / 10, total / 10],
                "line": {"color": PALETTE[1], "dash": "dash", "width": 2},
            },
        ],
        "layout": {
            **LAYOUT,
            "title": titled(_("evidence.digits_title", part=_(f"lab.part_short_{part}"))),
            "xaxis": {"title": {"text": _("evidence.chart_last_digit")}, "dtick": 1},
            "yaxis": {"title": {"text": _("evidence.chart_count")}},
        },
    }
    text = {
        "summary": _("evidence.digits_summary", n=total, expected=f"{total / 10:.1f}"),
        "table": {
            "columns": [_("evidence.chart_last_digit"), _("evidence.chart_count")],
            "rows": [[str(d), str(c)] for d, c in enumerate(counts)],
        },
    }
    return figure, text


def evidence_figures(assignment, session, data: dict, findings: list[dict], _) -> dict:
    """key → (figure, text) for each part with findings: its readings beside the gyro's,
    and its last digits when that is a finding."""
    noise, rate_hz, _source = gyro_model(assignment, session.simulator_preset)
    parts = {f["part"] for f in findings}
    out = {}
    for part in sorted(parts):
        own = own_positions(data.get(part, {}))
        if not own:
            continue
        seed = (session.id or 0) * 2 + (part == "latitude")
        out[f"evidence-{part}"] = beside_figure(part, own, noise, rate_hz, seed, _)
        for finding in findings:
            if finding["part"] == part and finding["check"] == "digits" and "counts" in finding:
                out[f"evidence-digits-{part}"] = digits_figure(part, finding["counts"], _)
    return out
