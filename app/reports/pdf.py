"""A :class:`~app.reports.content.Report` laid out as HTML and printed to PDF by WeasyPrint
(no browser): tagged PDF, figures as vector SVG, fonts from the machine's fontconfig, the
samples attached as CSV when the record is too long to print."""

from __future__ import annotations

import base64
from dataclasses import dataclass

from app import __version__
from app.lab.chart_texts import fit_summary, readings_summary
from app.lab.exports import Selection, readings_csv
from app.lab.pages import error_text
from app.lab.store import PARTS
from app.lab.truth import heading_error
from app.paths import TEMPLATES_DIR
from app.reports.content import Report
from app.reports.figures import fit_svg, has_readings_figure, readings_svg
from app.web.i18n import format_datetime, translator
from app.web.local_time import zone
from app.web.render import templates

CSS = (TEMPLATES_DIR / "reports" / "lab_report.css").read_text(encoding="utf-8")


@dataclass
class Figure:
    data_url: str
    summary: str


def _figures(report: Report, _, draw: bool) -> list[Figure]:
    """Per part: the readings, then the fit; each captioned with the page chart's summary.
    Not ``draw``: the same figures and captions with empty images (what the PDF cache
    keys on, with the figures' inputs: matplotlib's drawing is most of a cached report's
    cost)."""
    out = []
    for part in PARTS:
        outcome = report.results[part]
        part_name = _(f"lab.part_short_{part}")
        if has_readings_figure(outcome):
            caption = f"{part_name}, {_('chart.readings_title')}: {readings_summary(outcome, _)}"
            out.append(Figure(_data_url(readings_svg(outcome, _)) if draw else "", caption))
        if outcome.result is not None:
            caption = f"{part_name}, {_('chart.fit_title')}: {fit_summary(outcome, _)}"
            out.append(Figure(_data_url(fit_svg(outcome, _)) if draw else "", caption))
    return out


def _data_url(svg: str) -> str:
    return "data:image/svg+xml;base64," + base64.b64encode(svg.encode("utf-8")).decode("ascii")


def attachment_name(report: Report) -> str:
    suffix = f"attempt-{report.attempt.number}" if report.attempt else "current"
    return f"gyrolab-session-{report.session.id}-{suffix}-readings.csv"


def report_html(report: Report, language: str, draw_figures: bool = True) -> str:
    """The report as one self-contained HTML document in ``language`` (its figures' images
    left empty unless ``draw_figures``)."""
    _ = translator(language)
    shown_zone = zone(report.course.timezone if report.course else None)
    template = templates.env.get_template("reports/lab_report.html")
    return template.render(
        r=report,
        _=_,
        lang=language,
        css=CSS,
        parts=PARTS,
        version=__version__,
        figures=_figures(report, _, draw_figures),
        attachment_name=attachment_name(report),
        source_names=", ".join(_("source." + source) for source in report.sources),
        heading_error=heading_error,
        error_text=lambda error: error_text(error, _),
        when=lambda value: format_datetime(value, language, "yMMMd", "Hm", shown_zone),
    )


def report_pdf(report: Report, language: str) -> bytes:
    """The PDF bytes of ``report`` in ``language``.  Only ``data:`` URLs are fetched (the
    figures): nothing a student typed can make the renderer reach a file or the network."""
    from weasyprint import HTML, Attachment
    from weasyprint.urls import URLFetcher

    fetcher = URLFetcher(allowed_protocols={"data"})
    attachments = []
    if report.readings_attached:
        selection = Selection(report.session.id, report.attempt.id if report.attempt else None)
        attachments.append(
            Attachment(
                string="".join(readings_csv(selection)),
                name=attachment_name(report),
                description=translator(language)("report.attachment_description"),
                url_fetcher=fetcher,
            )
        )
    document = HTML(string=report_html(report, language), url_fetcher=fetcher, base_url=None)
    return document.write_pdf(pdf_tags=True, attachments=attachments or None)
