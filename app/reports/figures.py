"""The lab report's figures: matplotlib drawings saved as SVG (vector, text kept as text so
the PDF renderer sets it in the report's own fonts, Chinese included).

The same quantities as the page's charts (``app.lab.charts``): each position's readings,
and the position means with their 1σ and the fitted curve.  Colours are the Okabe–Ito
palette, told apart by colour-blind readers, and every series also has its own marker.
"""

from __future__ import annotations

import io
from collections.abc import Callable
from functools import cache

import numpy as np

from app.lab.charts import PALETTE, downsample

MARKERS = ["o", "s", "^", "D", "v", "P", "X", "*"]
STYLE = {
    "svg.fonttype": "none",  # text stays text: selectable, and set by the PDF's fonts
    "font.size": 9,
    "axes.spines.top": False,
    "axes.spines.right": False,
    "axes.grid": True,
    "grid.color": "#dddddd",
    "grid.linewidth": 0.6,
    "svg.hashsalt": "gyrolab",  # the same drawing gives the same bytes
}


CJK_FAMILIES = ("WenQuanYi Zen Hei", "Noto Sans CJK SC", "Source Han Sans SC")


@cache
def _families() -> list[str]:
    """DejaVu Sans, then the CJK fonts this machine has: matplotlib falls back glyph by
    glyph, so Chinese labels are measured with a CJK font."""
    from matplotlib import font_manager

    installed = {font.name for font in font_manager.fontManager.ttflist}
    return ["DejaVu Sans", *(name for name in CJK_FAMILIES if name in installed)]


def _svg(draw: Callable) -> str:
    """Run ``draw(axes)`` on a fresh 16 × 7.5 cm figure and return it as SVG text."""
    import matplotlib
    from matplotlib.backends.backend_svg import FigureCanvasSVG
    from matplotlib.figure import Figure

    with matplotlib.rc_context({**STYLE, "font.family": _families()}):
        figure = Figure(figsize=(6.3, 2.95), layout="constrained")
        FigureCanvasSVG(figure)
        draw(figure.add_subplot())
        buffer = io.StringIO()
        figure.savefig(buffer, format="svg", metadata={"Date": None})
    text = buffer.getvalue()
    return text[text.index("<svg") :]  # no XML prologue: the SVG goes inside an <img> data URL


def has_readings_figure(part_result) -> bool:
    """Whether :func:`readings_svg` draws the part: it has positions, each with readings."""
    positions = part_result.positions.values()
    return bool(positions) and all(item.values is not None for item in positions)


def figure_inputs(part_result) -> bytes:
    """Everything the part's two figures are drawn from besides the language: each
    position's readings and times, the part, and the fit's angles, means, 1σ and
    coefficients.  Equal inputs draw equal figures (:data:`STYLE` fixes the SVG's ids),
    so a digest of these stands for the drawings without drawing them."""
    pieces = [part_result.part.encode()]

    def add(label: str, numbers) -> None:  # each run of numbers with its length: no aliasing
        if numbers is None:
            pieces.append(f"|{label}:-|".encode())
            return
        array = np.asarray(numbers, dtype=float).ravel()
        pieces.append(f"|{label}:{array.size}|".encode() + array.tobytes())

    for position, item in sorted(part_result.positions.items()):
        add(f"values {position}", item.values)
        add(f"times {position}", item.times)
    if (result := part_result.result) is not None:
        fit = result.fit
        add("angles", fit.angles_deg)
        add("means", fit.means)
        add("sigmas", fit.position_sigmas)
        add("coefficients", [fit.a, fit.b, fit.c])
    return b"".join(pieces)


def readings_svg(part_result, _: Callable[..., str]) -> str | None:
    """Each position's used readings against time (or reading number when untimed); a
    long record drawn from each bucket's lowest and highest reading, as the page's chart
    (:func:`app.lab.charts.downsample`): 2000 points are more than the figure's width has
    printed dots, and a logger's million readings per position made a 29 MB PDF in 25 s."""
    if not has_readings_figure(part_result):
        return None
    positions = sorted(part_result.positions.items())
    timed = all(item.times is not None for _k, item in positions)

    def draw(axes):
        for position, item in positions:
            x = item.times if timed else np.arange(1, item.values.size + 1)
            x, y = downsample(x, item.values)
            style = PALETTE[(position - 1) % len(PALETTE)]
            few = item.values.size <= 60
            axes.plot(
                x,
                y,
                color=style,
                linewidth=0.8,
                marker=MARKERS[(position - 1) % len(MARKERS)] if few else None,
                markersize=3,
                label=_("chart.position", n=position),
            )
        axes.set_xlabel(_("chart.time_s") if timed else _("chart.reading_number"))
        axes.set_ylabel(_("chart.rate_deg_h"))
        axes.legend(loc="best", fontsize=7, ncols=min(4, len(positions)))

    return _svg(draw)


def fit_svg(part_result, _: Callable[..., str]) -> str | None:
    """The position means with their 1σ and the fitted ``a·cos α + c·sin α + b``."""
    result = part_result.result
    if result is None:
        return None
    fit = result.fit
    angles = np.asarray(fit.angles_deg, dtype=float)
    sigmas = fit.position_sigmas or [0.0] * len(fit.means)
    span = np.ptp(angles)
    grid = (
        np.linspace(angles.min() - 20, angles.max() + 20, 241)
        if span < 360
        else np.linspace(angles.min(), angles.max(), 241)
    )
    curve = fit.a * np.cos(np.radians(grid)) + fit.c * np.sin(np.radians(grid)) + fit.b

    def draw(axes):
        axes.plot(grid, curve, color=PALETTE[1], linestyle=":", linewidth=1.4, label=_("chart.fit"))
        axes.errorbar(
            angles,
            fit.means,
            yerr=sigmas,
            fmt="o",
            color=PALETTE[0],
            markersize=5,
            capsize=3,
            label=_("chart.means"),
        )
        axis = "chart.angle_heading" if part_result.part == "heading" else "chart.angle_latitude"
        axes.set_xlabel(_(axis))
        axes.set_ylabel(_("chart.rate_deg_h"))
        axes.legend(loc="best", fontsize=7)

    return _svg(draw)
