"""The student lab: sessions, recording positions (by hand, CSV), results, submit, export."""

from __future__ import annotations

import json
import math

from fastapi import APIRouter, Request
from jinja2.utils import htmlsafe_json_dumps
from markupsafe import Markup
from sqlalchemy.exc import OperationalError
from sqlmodel import Session

from app.accounts.deps import CurrentUser
from app.core.column_names import RATE_UNITS
from app.core.exceptions import UserError
from app.core.long_headers import ROLE_NAMES
from app.core.part_names import PART_LETTERS, PART_WORDS
from app.core.presets import PRESETS
from app.core.table_headers import SUMMARY_LABELS
from app.core.units import UNIT_SYMBOLS, UNITS
from app.courses import deadlines
from app.lab.attempts import (
    amendments_of,
    attempts_of,
    comments_of,
    mark_seen,
    released_grade,
    shown_to_student,
)
from app.lab.chart_texts import (
    allan_text,
    compass_summary,
    compass_table,
    fit_summary,
    fit_table,
    readings_summary,
    readings_table,
)
from app.lab.charts import allan_figure, compass_figure, fit_figure, readings_figure
from app.lab.deps import OwnedSession
from app.lab.grid import GRID_LIMIT
from app.lab.partner_pages import partner_view
from app.lab.planner import plan_view, session_plan
from app.lab.result_cache import CACHE, cached_results
from app.lab.results import with_samples
from app.lab.service import allowed_methods
from app.lab.sim import (
    FIRST_PASS,
    nominal_angle,
    north_dial_deg,
    position_count,
    warm_up_state,
)
from app.lab.store import PARTS, current_takes, is_editable, take_history
from app.lab.truth import auto_check, session_truth, truth_visible
from app.models import (
    Assignment,
    Course,
    LabSession,
)
from app.web.deps import SessionDep
from app.web.i18n import client_messages, translator
from app.web.render import (
    csrf_token_for,
    render,
    request_language,
    templates,
)

SHOWN_SUMMARY_LABELS = sorted(SUMMARY_LABELS)  # for the grid's script, once
LONG_ROLES = {role: list(ROLE_NAMES[role]) for role in ("position", "angle_deg", "value")}

router = APIRouter(prefix="/lab", tags=["pages: lab"], include_in_schema=False)


def _figures(results, _) -> tuple[dict[str, dict], dict[str, dict]]:
    """The plotly figures, and for each its text alternative: ``{"summary": sentence,
    "table": {"columns", "rows"}}`` shown under the chart."""
    figures, texts = {}, {}
    for part, outcome in results.items():
        if outcome.positions:
            figures[f"{part}-readings"] = readings_figure(outcome, _)
            texts[f"{part}-readings"] = {
                "summary": readings_summary(outcome, _),
                "table": readings_table(outcome, _),
            }
        fit = fit_figure(outcome, _)
        if fit:
            figures[f"{part}-fit"] = fit
            texts[f"{part}-fit"] = {
                "summary": fit_summary(outcome, _),
                "table": fit_table(outcome, _),
            }
        allan = allan_figure(outcome, _)
        if allan:
            figures[f"{part}-allan"] = allan
            summary, table = allan_text(allan, _)
            texts[f"{part}-allan"] = {"summary": summary, "table": table}
    heading = results["heading"]
    if heading.result is not None:
        angles = [heading.positions[k].take.angle_deg for k in sorted(heading.positions)]
        figures["heading-compass"] = compass_figure(heading.result, angles, _)
        texts["heading-compass"] = {
            "summary": compass_summary(heading.result, _),
            "table": compass_table(heading.result, angles, _),
        }
    return figures, texts


def _cached_figures(db: Session, session: LabSession, entry, solved: dict, _):
    """The figures of a cached result in the page's language, with their text
    alternatives: drawn (from the samples) once per data version and language, then
    embedded as they are."""
    language = _.language
    cached = entry.figures.get(language)
    if cached is None:
        figures, texts = _figures(solved or with_samples(db, session, entry.parts), _)
        cached = (texts, Markup(htmlsafe_json_dumps(figures)))
        CACHE.add_figures(entry, language, cached)
    return cached


@router.get("/sessions/{session_id}")
def session_page(request: Request, session: OwnedSession, user: CurrentUser, db: SessionDep):
    _ = translator(request_language(request))
    attempts = attempts_of(db, session.id)
    assignment = db.get(Assignment, session.assignment_id) if session.assignment_id else None
    group = partner_view(db, session, assignment, user)
    config = {
        "sessionId": session.id,
        "csrf": csrf_token_for(request),
        "minReadings": session.min_readings,
        "gridLimit": GRID_LIMIT,  # a longer paste is held and saved as pasted, not shown
        "summaryLabels": SHOWN_SUMMARY_LABELS,  # a pasted row of means is no reading
        "longRoles": LONG_ROLES,  # a pasted table of one reading per row beside its position
        "partWords": PART_WORDS,  # both parts' tables pasted, each under its title
        "partLetters": PART_LETTERS,
        "angles": {  # each position's angle: a pasted header of angles the other way is said
            part: [nominal_angle(session, part, k) for k in range(1, position_count(session) + 1)]
            for part in ("heading", "latitude")
        },
        "rateUnits": RATE_UNITS,  # a pasted header's "(°/s)" against the grid's unit
        "table": {"heading": session.sim_table_heading, "latitude": session.sim_table_latitude},
        "plane": session.sim_plane_dial_deg,
        "messages": client_messages(JS_MESSAGES, _.language),
        "version": session.updated_at.isoformat(),
        "shared": len(group["members"]) > 1,
    }
    editable = is_editable(session)
    if mark_seen(db, attempts):  # the dashboard's notice has been read
        try:
            db.commit()
        except OperationalError:  # a read-only database: the notice simply stays
            db.rollback()
    course = db.get(Course, assignment.course_id) if assignment else None
    history, recordings = take_history(db, session.id)
    if recordings > len(history):  # some current takes may be older than those shown
        current = current_takes(db, session.id)
    else:
        current = [take for take in history if take.superseded_at is None]
    return render(
        request,
        "lab/session.html",
        {
            **session_view(db, session, assignment, attempts, _, editable=editable, takes=current),
            "due": deadlines.due_for(db, assignment, session.owner_id),
            "timezone": course.timezone if course else None,
            **group,
            "history": history,
            "recordings": recordings,
            "methods": allowed_methods(db, session),
            "units": UNITS,
            "unit_names": UNIT_NAMES,
            "plotly_url": request.app.state.plotly_url,
            "interrupted": session.stream_part,
            "config": config,
            "editable": editable,
            "reviewer": False,
        },
    )


def _cached_blocks(entry, figure_texts: dict, language: str, editable: bool, _) -> dict:
    """Each part's results half (``lab/_part_results.html``), rendered once per result
    key, language and ``editable`` and kept with the cached result: it depends on
    nothing else, and it is most of the page's rendering."""
    blocks = entry.blocks.get((language, editable))
    if blocks is None:
        template = templates.get_template("lab/_part_results.html")
        blocks = {
            part: Markup(
                template.render(
                    part=part,
                    outcome=entry.parts[part],
                    figures=figure_texts,
                    editable=editable,
                    lang=language,
                    _=_,
                    error_text=lambda error: error_text(error, _),
                )
            )
            for part in PARTS
        }
        CACHE.add_blocks(entry, language, editable, blocks)
    return blocks


def session_view(
    db: Session,
    session: LabSession,
    assignment,
    attempts,
    _,
    *,
    reviewer: bool = False,
    editable: bool = False,
    takes: list | None = None,
) -> dict:
    """What both the student's page and the teacher's review show of a session.

    A review belongs to its attempt: the student sees the latest attempt's review once the
    teacher returned or released it -- also while re-recording, until the next submission
    -- and earlier attempts' reviews with those attempts.  ``takes``: the session's
    current takes where the caller has them (one query fewer)."""
    solved: dict = {}
    entry = cached_results(db, session, assignment, on_miss=solved.update, takes=takes)
    results = entry.parts
    figure_texts, figures_json = _cached_figures(db, session, entry, solved, _)
    nominal = {
        part: [nominal_angle(session, part, k) for k in range(1, position_count(session) + 1)]
        for part in PARTS
    }
    latest = attempts[-1] if attempts else None
    given = latest is not None and (reviewer or shown_to_student(latest))
    visible = truth_visible(session, assignment, len(attempts))
    truth = session_truth(db, session, assignment, takes) if visible else None
    check = None
    if truth is not None and assignment is not None and attempts:
        check = auto_check(json.loads(attempts[-1].results_json), truth, assignment)
    heading = results["heading"]
    north = None
    if heading.result is not None:
        first = heading.positions[min(heading.positions)].take.angle_deg
        north = north_dial_deg(session, heading.result.azimuth_deg, first)
    return {
        "session": session,
        "north_dial": north,
        "results": results,
        "figures": figure_texts,
        "figures_json": figures_json,
        "result_blocks": _cached_blocks(entry, figure_texts, _.language, editable, _),
        "attempts": attempts,
        "assignment": assignment,
        "nominal": nominal,
        "drawing": drawing_coordinates(session),
        "positions": range(1, position_count(session) + 1),
        "preset": PRESETS.get(session.simulator_preset),
        "plan": plan_view(session_plan(db, session)),
        "warm_up": warm_up_state(session) if session.simulator_preset in PRESETS else None,
        "error_text": lambda error: error_text(error, _),
        "truth": truth,
        "check": check,
        "feedback": latest.feedback if given else "",
        "feedback_attempt": latest if given else None,
        "position_feedback": comments_of(latest) if given else {},
        "grade": released_grade(session, attempts, assignment) or None,
        "amendments": amendments_of(db, latest) if given and latest.released_at else [],
        "attempt_results": [(a, json.loads(a.results_json)) for a in attempts],
        "attempt_reviews": {
            a.number: {"feedback": a.feedback, "comments": comments_of(a)}
            for a in attempts
            if (reviewer or shown_to_student(a)) and (a.feedback or a.feedback_positions)
        },
    }


UNIT_NAMES = UNIT_SYMBOLS
JS_MESSAGES = (
    "js.not_a_number",
    "js.not_finite",
    "js.grid_ok",
    "js.grid_empty",
    "js.saving",
    "js.saved",
    "js.failed",
    "js.preview_title",
    "js.choose_file",
    "js.recording",
    "js.done",
    "js.connection_lost",
    "js.turned",
    "js.plane_set",
    "js.turn_needed",
    "js.position",
    "js.samples",
    "js.mean",
    "js.angle",
    "js.too_large",
    "chart.time_s",
    "chart.rate_deg_h",
    "js.pasted",
    "js.header_skipped",
    "js.row_numbers_skipped",
    "js.long_block",
    "js.leading_columns_skipped",
    "js.summary_rows_skipped",
    "js.means_row_skipped",
    "js.header_angles_other_way",
    "js.long_angles_other_way",
    "js.unit_named_other",
    "js.unit_unread",
    "js.spreadsheet_error",
    "js.lines_above_skipped",
    "js.own_table_taken",
    "js.turned_table",
    "js.summary_column_skipped",
    "js.time_column_skipped",
    "js.record_of_axes",
    "js.second_table_skipped",
    "js.record_position",
    "js.record_column",
    "js.workbook_sheet",
    "js.position_problem",
    "js.long_paste_held",
    "js.long_paste_bad",
    "js.cells_dropped",
    "js.trim_shown",
    "js.done_trim",
    "js.projector",
    "js.projector_exit",
    "js.partner_recording",
    "js.part_heading",
    "js.part_latitude",
    "js.grid_loaded",
    "js.grid_not_loaded",
    "js.grid_unchanged",
    "source.simulator",
)


def error_text(error: UserError, _) -> str:
    """A core error in the page's language."""
    return _(error.key, **error.params)


def drawing_coordinates(session: LabSession) -> dict[str, dict[int, tuple]]:
    """Where each position's axis and label go on the 200×200 drawings."""
    out: dict[str, dict[int, tuple]] = {"heading": {}, "latitude": {}}
    for k in range(1, FIRST_PASS + 1):  # the return pass 5–8 revisits these
        relative = math.radians(nominal_angle(session, "heading", k) - session.heading_start_deg)
        sx, sy = math.sin(relative), -math.cos(relative)  # position 1 drawn pointing up
        out["heading"][k] = (
            round(100 + 70 * sx, 2),
            round(100 + 70 * sy, 2),
            round(100 + 90 * sx, 2),
            round(100 + 90 * sy, 2),
        )
        elevation = math.radians(nominal_angle(session, "latitude", k))
        cx, cy = math.cos(elevation), -math.sin(elevation)  # north to the right, zenith up
        out["latitude"][k] = (
            round(100 + 70 * cx, 2),
            round(100 + 70 * cy, 2),
            round(100 + 90 * cx, 2),
            round(100 + 90 * cy, 2),
        )
    return out
