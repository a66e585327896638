"""The error-analysis explorer pages: heading error against azimuth, and dwell time."""

from __future__ import annotations

import csv
import io
import math
from typing import Annotated, Literal

from fastapi import APIRouter, Query, Request
from fastapi.responses import Response

from app.accounts.deps import CurrentUser
from app.core.exceptions import UserError
from app.core.presets import PRESETS
from app.explore.scenarios import (
    SCENARIOS,
    drift_order_curves,
    dwell_curve,
    heading_error_curves,
)
from app.explore.schemas import ExplorerQuery
from app.web.i18n import client_messages, translator
from app.web.render import render, request_language

router = APIRouter(prefix="/explore", tags=["pages: explorer"], include_in_schema=False)


QueryDep = Annotated[ExplorerQuery, Query()]


@router.get("")
def explorer_page(request: Request, user: CurrentUser):
    _ = translator(request_language(request))
    return render(
        request,
        "explore/index.html",
        {
            "scenarios": SCENARIOS,
            "presets": sorted(PRESETS),
            "defaults": ExplorerQuery().model_dump(),
            "plotly_url": request.app.state.plotly_url,
            "messages": client_messages(JS_MESSAGES, _.language),
            "scenario_texts": {key: _(f"scenario_text.{key}") for key in SCENARIOS},
        },
    )


JS_MESSAGES = (
    "explore.axis_azimuth",
    "explore.axis_error",
    "explore.formula",
    "explore.monte_carlo",
    "explore.method_two",
    "explore.method_four",
    "explore.method_seeker",
    "explore.runs_used",
    "explore.dwell_axis",
    "explore.sigma_axis",
    "explore.floor",
    "explore.white_only",
    "explore.expected",
    "explore.chart_title",
    "explore.dwell_title",
    "explore.knee",
    "explore.orders_title",
    "explore.order_1234",
    "explore.order_1324",
    "explore.order_12344321",
    "explore.summary_heading",
    "explore.summary_dwell",
    "explore.summary_orders",
)


@router.get("/data")
def explorer_data(request: Request, user: CurrentUser, query: QueryDep):
    curves, info = heading_error_curves(query.explorer_input())
    _ = translator(request_language(request))
    return {
        "curves": [c.__dict__ for c in curves],
        "info": info,
        "dwell": dwell_curve(query.preset, query.latitude_deg, _),
        "orders": drift_order_curves(
            query.latitude_deg, query.dwell_s, query.bias_drift_deg_h_per_h
        ),
    }


@router.get("/data.csv")
def explorer_csv(
    request: Request,
    user: CurrentUser,
    query: QueryDep,
    chart: Literal["heading", "dwell", "orders"] = "heading",
):
    """The data behind either chart, as CSV with labelled units."""
    _ = translator(request_language(request))
    buffer = io.StringIO()
    writer = csv.writer(buffer)
    if chart == "orders":
        data = drift_order_curves(query.latitude_deg, query.dwell_s, query.bias_drift_deg_h_per_h)
        writer.writerow(
            ["true_azimuth_deg", *[f"heading_error_deg_order_{k}" for k in data["orders"]]]
        )
        for index, azimuth in enumerate(data["azimuth_deg"]):
            writer.writerow(
                [f"{azimuth:g}", *[f"{errors[index]:.6f}" for errors in data["orders"].values()]]
            )
    elif chart == "dwell":
        data = dwell_curve(query.preset, query.latitude_deg, _)
        writer.writerow(["dwell_s", "heading_sigma_deg", "white_noise_only_deg", "floor_deg"])
        for row in zip(data["dwell_s"], data["sigma_deg"], data["white_only_deg"], strict=True):
            writer.writerow(
                [f"{row[0]:.3f}", f"{row[1]:.6f}", f"{row[2]:.6f}", f"{data['floor_deg']:.6f}"]
            )
    else:
        curves, info = heading_error_curves(query.explorer_input())
        writer.writerow(
            [
                "method",
                "kind",
                "true_azimuth_deg",
                "heading_error_deg",
                "monte_carlo_std_deg",
                "runs",
            ]
        )
        for curve in curves:
            for azimuth, value in zip(curve.azimuths_deg, curve.formula_deg, strict=True):
                writer.writerow([curve.method, "first_order", azimuth, _num(value), "", ""])
            for azimuth, mean, std in zip(
                curve.mc_azimuths_deg, curve.mc_mean_deg, curve.mc_std_deg, strict=True
            ):
                writer.writerow(
                    [curve.method, "monte_carlo", azimuth, _num(mean), _num(std), info["runs"]]
                )
    if not buffer.getvalue():
        raise UserError("error.bad_request")
    return Response(
        "\ufeff" + buffer.getvalue(),
        media_type="text/csv; charset=utf-8",
        headers={"Content-Disposition": f'attachment; filename="gyrolab-explorer-{chart}.csv"'},
    )


def _num(value) -> str:
    return "" if value is None or not math.isfinite(value) else f"{value:.6f}"
