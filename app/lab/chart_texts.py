"""Text alternatives for the charts: a sentence of each chart's numbers (its caption, also
the lab report's figure caption) and a data table ``{"columns", "rows"}`` behind a toggle."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np


def readings_summary(part_result, _: Callable[..., str]) -> str:
    """E.g. "Readings of 4 positions, 10–12 each; means from −9.87 to 10.74 °/h"."""
    items = [part_result.positions[k] for k in sorted(part_result.positions)]
    counts = [item.n for item in items]
    means = [item.mean for item in items if item.n]
    if not means:
        return _("chart.summary_no_readings")
    return _(
        "chart.summary_readings",
        positions=len(items),
        n=f"{min(counts)}" if min(counts) == max(counts) else f"{min(counts)}–{max(counts)}",
        low=f"{min(means):.3f}",
        high=f"{max(means):.3f}",
    )


def fit_summary(part_result, _: Callable[..., str]) -> str:
    """E.g. "4 position means with the fitted sinusoid: amplitude H 10.000 °/h, bias
    0.020 °/h, start azimuth 10.75°" (the latitude part: latitude and Earth rate)."""
    result = part_result.result
    fit = result.fit
    common = {"positions": len(fit.means), "bias": f"{fit.b:.3f}"}
    if part_result.part == "heading":
        return _(
            "chart.summary_fit_heading",
            amplitude=f"{result.amplitude_deg_h:.3f}",
            azimuth=f"{result.azimuth_deg:.2f}",
            **common,
        )
    return _(
        "chart.summary_fit_latitude",
        latitude=f"{result.latitude_deg:.2f}",
        rate=f"{result.earth_rate_deg_h:.3f}",
        **common,
    )


def readings_table(part_result, _: Callable[..., str]) -> dict:
    """The readings chart's numbers: each position's n, mean and standard deviation."""
    return {
        "columns": [_("results.position"), "n", _("results.mean"), _("results.std")],
        "rows": [
            [
                k,
                item.n,
                f"{item.mean:.3f}" if item.n else "—",
                f"{item.std:.3f}" if item.std is not None else "—",
            ]
            for k, item in sorted(part_result.positions.items())
        ],
    }


def fit_table(part_result, _: Callable[..., str]) -> dict:
    """The fit chart's numbers: angle, mean, 1σ and the fitted value at each position."""
    fit = part_result.result.fit
    sigmas = fit.position_sigmas or [None] * len(fit.means)
    angles = np.asarray(fit.angles_deg, dtype=float)
    fitted = fit.a * np.cos(np.radians(angles)) + fit.c * np.sin(np.radians(angles)) + fit.b
    return {
        "columns": [
            _("results.angle"),
            _("results.mean"),
            "1σ",
            _("chart.fit"),
        ],
        "rows": [
            [f"{angle:g}°", f"{mean:.3f}", "—" if s is None else f"{s:.4f}", f"{value:.3f}"]
            for angle, mean, s, value in zip(
                angles.tolist(), list(fit.means), sigmas, fitted.tolist(), strict=True
            )
        ],
    }


def compass_summary(heading_result, _: Callable[..., str]) -> str:
    return _("chart.summary_compass", azimuth=f"{heading_result.azimuth_deg:.2f}")


def compass_table(heading_result, angles, _: Callable[..., str]) -> dict:
    """Each position's direction, clockwise from north."""
    first = float(angles[0]) if len(angles) else 0.0
    return {
        "columns": [_("results.position"), _("chart.direction")],
        "rows": [
            [index, f"{(heading_result.azimuth_deg + float(angle) - first) % 360:.2f}°"]
            for index, angle in enumerate(angles, start=1)
        ],
    }


def allan_text(figure: dict, _: Callable[..., str]) -> tuple[str, dict]:
    """The Allan chart's sentence and table, read off the figure itself."""
    trace = figure["data"][0]
    taus, adevs = trace["x"], trace["y"]
    best = int(np.argmin(adevs))
    summary = _(
        "chart.summary_allan",
        points=len(taus),
        floor=f"{adevs[best]:.4f}",
        tau=f"{taus[best]:.3g}",
    )
    model = figure["data"][1]["y"] if len(figure["data"]) > 1 else [None] * len(taus)
    table = {
        "columns": ["τ (s)", _("chart.adev"), _("chart.allan_model")],
        "rows": [
            [f"{t:.3g}", f"{a:.4f}", "—" if m is None else f"{m:.4f}"]
            for t, a, m in zip(taus, adevs, model, strict=True)
        ],
    }
    return summary, table


def class_text(rows, _: Callable[..., str]) -> tuple[str, dict]:
    """The class charts' sentence and table: each submitted student's errors."""
    table_rows = []
    heading_errors, latitude_errors = [], []
    for row in rows:
        if not row.attempts:
            continue
        heading, latitude = row.check_error("heading"), row.check_error("latitude")
        if heading is not None:
            heading_errors.append(heading)
        if latitude is not None:
            latitude_errors.append(latitude)
        table_rows.append(
            [
                row.student.display_name,
                "—" if heading is None else f"{heading:+.2f}",
                "—" if latitude is None else f"{latitude:.2f}",
            ]
        )
    if not heading_errors:
        summary = _("chart.summary_class_empty", n=len(table_rows))
    else:
        summary = _(
            "chart.summary_class",
            n=len(table_rows),
            low=f"{min(heading_errors):+.2f}",
            high=f"{max(heading_errors):+.2f}",
            median=f"{float(np.median(heading_errors)):+.2f}",
            worst=f"{max(latitude_errors):.2f}" if latitude_errors else "—",
        )
    table = {
        "columns": [_("review.student"), _("review.heading_error"), _("review.latitude_error")],
        "rows": table_rows,
    }
    return summary, table
