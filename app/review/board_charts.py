"""The class board's charts, drawn large for a projector: each group a point with its 1σ,
the true value a line, the class's pooled value a band (app/review/board.py)."""

from __future__ import annotations

import math
from collections.abc import Callable

from app.lab.charts import PALETTE, titled

BIG = {
    "margin": {"l": 90, "r": 30, "t": 70, "b": 70},
    "height": 420,
    "font": {"family": "system-ui, 'PingFang SC', 'Noto Sans CJK SC', sans-serif", "size": 18},
    "showlegend": False,
}


def group_axis(board: dict, _: Callable[..., str]) -> list[str]:
    return [point["label"] or _("board.group", n=point["number"]) for point in board["groups"]]


def per_group_figure(
    board: dict,
    value: str,
    sigma: str,
    truth: float | None,
    pool: dict | None,
    title: str,
    axis: str,
    _: Callable[..., str],
) -> dict:
    """One quantity per group with its 1σ, the true value and the pooled band."""
    x = group_axis(board, _)
    groups = board["groups"]
    shapes = []
    if truth is not None:
        shapes.append(_line(truth, "#000000", "dash"))
    if pool is not None:
        low = pool["value"] - pool["standard_error"]
        high = pool["value"] + pool["standard_error"]
        shapes.append(
            {
                "type": "rect",
                "xref": "paper",
                "x0": 0,
                "x1": 1,
                "y0": low,
                "y1": high,
                "fillcolor": PALETTE[2],
                "opacity": 0.2,
                "line": {"width": 0},
            }
        )
    # the truth and the band are shapes, which plotly's autorange ignores: an unseen point
    # at each keeps them in view
    anchors = [truth] if truth is not None else []
    if pool is not None:
        anchors += [pool["value"] - pool["standard_error"], pool["value"] + pool["standard_error"]]
    return {
        "data": [
            {
                "type": "scatter",
                "mode": "markers",
                "x": [x[0]] * len(anchors) if x else [],
                "y": anchors,
                "marker": {"opacity": 0},
                "hoverinfo": "skip",
            },
            {
                "type": "scatter",
                "mode": "markers",
                "x": x,
                "y": [p.get(value) for p in groups],
                "error_y": {
                    "type": "data",
                    "array": [p.get(sigma) for p in groups],
                    "visible": True,
                    "thickness": 2,
                },
                "marker": {
                    "size": 16,
                    "color": [PALETTE[1] if p["outlier"] else PALETTE[0] for p in groups],
                    "symbol": ["diamond" if p["outlier"] else "circle" for p in groups],
                },
            },
        ],
        "layout": {
            **BIG,
            "title": {**titled(title), "font": {"size": 22}},
            "xaxis": {"automargin": True, "tickangle": -30 if len(x) > 8 else 0},
            "yaxis": {"title": {"text": axis}, "automargin": True},
            "shapes": shapes,
        },
    }


def cos_latitude_figure(board: dict, _: Callable[..., str]) -> dict:
    """The measured horizontal component H against cos φ of each group's station, with
    H = Ω·cos φ for the true Ω: several sites on one line."""
    groups = [p for p in board["groups"] if p.get("amplitude_deg_h") is not None]
    cos_phi = [math.cos(math.radians(p["true_latitude_deg"])) for p in groups]
    omega = board["true_earth_rate_deg_h"]
    line = [min(cos_phi, default=0.0), max(cos_phi, default=1.0)]
    return {
        "data": [
            {
                "type": "scatter",
                "mode": "markers",
                "x": cos_phi,
                "y": [p["amplitude_deg_h"] for p in groups],
                "error_y": {
                    "type": "data",
                    "array": [p.get("amplitude_sigma_deg_h") for p in groups],
                    "visible": True,
                },
                "marker": {"size": 14, "color": PALETTE[0]},
                "name": _("board.measured"),
            },
            {
                "type": "scatter",
                "mode": "lines",
                "x": line,
                "y": [omega * c for c in line],
                "line": {"color": "#000000", "dash": "dash"},
                "name": _("board.expected_line"),
            },
        ],
        "layout": {
            **BIG,
            "title": {**titled(_("board.cos_title")), "font": {"size": 22}},
            "xaxis": {"title": {"text": "cos φ"}, "automargin": True},
            "yaxis": {"title": {"text": _("board.amplitude_axis")}, "automargin": True},
        },
    }


def board_figures(board: dict, _: Callable[..., str]) -> dict:
    figures = {
        "board-rate": per_group_figure(
            board,
            "earth_rate_deg_h",
            "earth_rate_sigma_deg_h",
            board["true_earth_rate_deg_h"],
            board["earth_rate"],
            _("board.rate_title"),
            _("board.rate_axis"),
            _,
        ),
        "board-latitude": per_group_figure(
            board,
            "latitude_deg",
            "latitude_sigma_deg",
            board["true_latitude_deg"],
            board["latitude"],
            _("board.latitude_title"),
            _("board.latitude_axis"),
            _,
        ),
        "board-heading": per_group_figure(
            board,
            "heading_error_deg",
            "heading_sigma_deg",
            0.0,
            None,
            _("board.heading_title"),
            _("board.heading_axis"),
            _,
        ),
    }
    if board["several_stations"]:
        figures["board-cos"] = cos_latitude_figure(board, _)
    return figures


def _line(y: float, color: str, dash: str) -> dict:
    return {
        "type": "line",
        "xref": "paper",
        "x0": 0,
        "x1": 1,
        "y0": y,
        "y1": y,
        "line": {"color": color, "dash": dash, "width": 2},
    }
