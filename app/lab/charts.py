"""Plotly figures (plain plotly.js JSON) built from core results, labelled in either language.

Long records are downsampled on the server (min/max per bucket) so a page never ships
more than a few thousand points per trace.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from app.core.allan import allan_deviation
from app.core.exceptions import UserError
from app.core.record_checks import sample_rate_hz

MAX_POINTS = 2000
# Okabe & Ito's palette, told apart with every common colour-vision deficiency (its yellow
# swapped for a wine red, which keeps 3:1 against white); each series also has its own
# marker symbol, so no chart relies on colour alone
PALETTE = ["#0072B2", "#D55E00", "#009E73", "#CC79A7", "#E69F00", "#56B4E9", "#000000", "#882255"]
SYMBOLS = ["circle", "square", "triangle-up", "diamond", "triangle-down", "cross", "x", "star"]
LAYOUT = {
    # titles sit on the left, clear of plotly's toolbar at the top right
    "margin": {"l": 60, "r": 20, "t": 50, "b": 50},
    "height": 320,
    "font": {"family": "system-ui, 'PingFang SC', 'Noto Sans CJK SC', sans-serif"},
    # the legend at the foot of the whole figure (not of the plot area), so it never sits on
    # the x axis's title however narrow the screen; it pushes the bottom margin as it wraps
    "legend": {
        "orientation": "h",
        "x": 0,
        "xanchor": "left",
        "y": 0,
        "yref": "container",
        "yanchor": "bottom",
    },
}


def titled(text: str) -> dict:
    """A chart title, left-aligned so the toolbar (top right) never covers it."""
    return {"text": text, "x": 0.01, "xanchor": "left", "font": {"size": 14}}


def downsample(times: np.ndarray, values: np.ndarray, limit: int = MAX_POINTS):
    """Keep each bucket's minimum and maximum (in time order) so spikes stay visible."""
    if values.size <= limit:
        return times, values
    buckets = limit // 2
    edges = np.linspace(0, values.size, buckets + 1).astype(int)
    keep = []
    for lo, hi in zip(edges[:-1], edges[1:], strict=True):
        segment = values[lo:hi]
        pair = sorted({lo + int(np.argmin(segment)), lo + int(np.argmax(segment))})
        keep.extend(pair)
    index = np.array(keep)
    return times[index], values[index]


def readings_figure(part_result, _: Callable[..., str]) -> dict:
    """Each position's readings against time, or against the reading number when the
    readings have no times (typed or pasted)."""
    traces = []
    timed = all(item.times is not None for item in part_result.positions.values())
    for position, item in sorted(part_result.positions.items()):
        times = item.times if timed else np.arange(1, item.values.size + 1, dtype=float)
        t, v = downsample(times, item.values)
        traces.append(
            {
                "type": "scattergl" if t.size > 500 else "scatter",
                "mode": "lines+markers" if t.size <= 60 else "lines",
                "name": _("chart.position", n=position),
                "x": np.round(t, 3).tolist(),
                "y": np.round(v, 5).tolist(),
                "line": {"color": PALETTE[(position - 1) % len(PALETTE)], "width": 1},
                "marker": {"symbol": SYMBOLS[(position - 1) % len(SYMBOLS)], "size": 5},
            }
        )
    return {
        "data": traces,
        "layout": {
            **LAYOUT,
            "title": titled(_("chart.readings_title")),
            "xaxis": {
                "title": {"text": _("chart.time_s") if timed else _("chart.reading_number")},
                "automargin": True,
            },
            "yaxis": {"title": {"text": _("chart.rate_deg_h")}},
        },
    }


def fit_figure(part_result, _: Callable[..., str]) -> dict | None:
    result = part_result.result
    if result is None:
        return None
    fit = result.fit
    angles = fit.angles_deg
    # error bars: the 1σ of each mean that the result propagates (white, closure or Allan)
    sems = fit.position_sigmas or [0.0] * len(fit.stats)
    grid = (
        np.linspace(angles.min() - 20, angles.max() + 20, 241)
        if np.ptp(angles) < 360
        else np.linspace(angles.min(), angles.max(), 241)
    )
    curve = fit.a * np.cos(np.radians(grid)) + fit.c * np.sin(np.radians(grid)) + fit.b
    axis = _("chart.angle_heading") if part_result.part == "heading" else _("chart.angle_latitude")
    return {
        "data": [
            {
                "type": "scatter",
                "mode": "markers",
                "name": _("chart.means"),
                "x": angles.tolist(),
                "y": fit.means.tolist(),
                "error_y": {"type": "data", "array": sems, "visible": True},
                "marker": {"size": 9, "color": PALETTE[0]},
            },
            {
                "type": "scatter",
                "mode": "lines",
                "name": _("chart.fit"),
                "x": grid.tolist(),
                "y": np.round(curve, 5).tolist(),
                "line": {"color": PALETTE[1], "dash": "dot"},
            },
        ],
        "layout": {
            **LAYOUT,
            "title": titled(_("chart.fit_title")),
            "xaxis": {"title": {"text": axis}, "automargin": True},
            "yaxis": {"title": {"text": _("chart.rate_deg_h")}},
        },
    }


def compass_figure(heading_result, angles, _: Callable[..., str]) -> dict | None:
    """North up, clockwise: the found start azimuth, the other positions, and north."""
    if heading_result is None:
        return None
    start = heading_result.azimuth_deg
    first = float(angles[0]) if len(angles) else 0.0
    traces = [
        {
            "type": "scatterpolar",
            "mode": "lines+text",
            "r": [0, 1.05],
            "theta": [0, 0],
            "name": _("chart.north"),
            "text": ["", _("chart.north_short")],
            "textposition": "top center",
            "line": {"color": "#b3261e", "width": 4},
        }
    ]
    for index, angle in enumerate(angles, start=1):
        direction = (start + float(angle) - first) % 360
        traces.append(
            {
                "type": "scatterpolar",
                "mode": "lines+text",
                "r": [0, 0.85],
                "theta": [direction, direction],
                "text": ["", str(index)],
                "name": _("chart.position", n=index),
                "textposition": "top center",
                "line": {
                    "color": PALETTE[(index - 1) % len(PALETTE)],
                    "width": 3 if index == 1 else 1.5,
                },
            }
        )
    layout = {
        **LAYOUT,
        "height": 340,
        "showlegend": False,
        "title": titled(_("chart.compass_title", azimuth=f"{start:.2f}")),
        "polar": {
            "angularaxis": {"direction": "clockwise", "rotation": 90, "dtick": 30},
            "radialaxis": {"visible": False, "range": [0, 1.15]},
        },
    }
    return {"data": traces, "layout": layout}


def allan_figure(part_result, _: Callable[..., str], minimum_samples: int = 1000) -> dict | None:
    """Allan deviation of the longest position, when it is a long static record."""
    longest = max(part_result.positions.values(), key=lambda item: item.values.size, default=None)
    if longest is None or longest.values.size < minimum_samples:
        return None
    times = longest.times
    if times is None or times.size < 2:
        return None
    rate = sample_rate_hz(times)
    if not math.isfinite(rate) or rate <= 0:
        return None
    try:
        result = allan_deviation(longest.values, rate)
    except UserError:
        return None
    return {
        "data": [
            {
                "type": "scatter",
                "mode": "lines+markers",
                "name": "σ(τ)",
                "x": result.taus_s.tolist(),
                "y": result.adev_deg_h.tolist(),
                "error_y": {
                    "type": "data",
                    "array": result.adev_error_deg_h.tolist(),
                    "visible": True,
                },
            },
            {  # the IEEE 952 terms the curve carries (allan_fit): its own model line
                "type": "scatter",
                "mode": "lines",
                "name": _("chart.allan_model"),
                "x": result.taus_s.tolist(),
                "y": result.model_adev_deg_h.tolist(),
                "line": {"dash": "dash", "color": PALETTE[1]},
            },
        ],
        "layout": {
            **LAYOUT,
            "title": titled(_("chart.allan_title", n=longest.take.position)),
            "xaxis": {"type": "log", "title": {"text": "τ (s)"}, "automargin": True},
            "yaxis": {"type": "log", "title": {"text": _("chart.adev")}},
        },
    }


def class_error_figure(rows, _: Callable[..., str]) -> dict:
    """Each student's heading error (°) and latitude error (%) with 1σ error bars."""
    names, heading, heading_sigma, latitude, latitude_sigma = [], [], [], [], []
    for row in rows:
        if not row.attempts:
            continue
        names.append(row.student.display_name)
        head = row.results.get("heading") or {}
        lat = row.results.get("latitude") or {}
        heading.append(row.check_error("heading"))
        heading_sigma.append(head.get("azimuth_sigma_deg"))
        latitude.append(row.check_error("latitude"))
        sigma = lat.get("latitude_sigma_deg")
        truth = row.truth.latitude_deg if row.truth else None
        latitude_sigma.append(sigma / abs(truth) * 100 if sigma is not None and truth else None)
    return {
        "data": [
            {
                "type": "scatter",
                "mode": "markers",
                "name": _("review.heading_error"),
                "x": names,
                "y": heading,
                "error_y": {"type": "data", "array": heading_sigma, "visible": True},
                "marker": {"size": 10, "color": PALETTE[0]},
            },
            {
                "type": "scatter",
                "mode": "markers",
                "name": _("review.latitude_error"),
                "x": names,
                "y": latitude,
                "yaxis": "y2",
                "marker": {"size": 10, "symbol": "diamond", "color": PALETTE[1]},
                "error_y": {"type": "data", "array": latitude_sigma, "visible": True},
            },
        ],
        "layout": {
            **LAYOUT,
            "margin": {**LAYOUT["margin"], "r": 70},
            "title": titled(_("review.class_errors_title")),
            "xaxis": {"automargin": True, "tickangle": -30},
            "yaxis": {"title": {"text": _("review.heading_error")}, "zeroline": True},
            "yaxis2": {
                "title": {"text": _("review.latitude_error")},
                "overlaying": "y",
                "side": "right",
                "rangemode": "tozero",
                "showgrid": False,  # one grid (the left axis's); the right axis's ticks only
                "tickmode": "auto",  # not "sync" (plotly's default here): round numbers
                "nticks": 6,
                "tickformat": ".2~f",
            },
        },
    }


def class_histogram_figure(rows, _: Callable[..., str]) -> dict:
    errors = [row.check_error("heading") for row in rows if row.attempts]
    return {
        "data": [
            {
                "type": "histogram",
                "x": [e for e in errors if e is not None],
                "name": _("review.heading_error"),
                "marker": {"color": PALETTE[0]},
            }
        ],
        "layout": {
            **LAYOUT,
            "title": titled(_("review.histogram_title")),
            "bargap": 0.05,
            "xaxis": {"title": {"text": _("review.heading_error")}, "automargin": True},
            # whole students: integer ticks, never 0.5
            "yaxis": {
                "title": {"text": _("review.students")},
                "dtick": max(1, math.ceil(len(errors) / 8)),
                "tickformat": "d",
            },
        },
    }
