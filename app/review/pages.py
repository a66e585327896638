"""Teacher review: the class dashboard of an assignment, a submission, feedback, grades, export."""

from __future__ import annotations

import io
import math
import zlib
from typing import Annotated

from fastapi import APIRouter, File, Form, Request, UploadFile

from app.accounts.deps import CsrfProtected, CurrentUser
from app.core.allan_summary import dwell_lines, note_lines, term_rows
from app.core.exceptions import FieldProblems, UserError
from app.core.numpy_files import is_npz
from app.core.presets import PRESETS
from app.core.typed_numbers import parse_typed_number
from app.core.workbook_sheets import is_workbook
from app.core.workbook_text import workbook_text
from app.courses import characterisation
from app.courses.assignment_form import form_context, form_values, parse_assignment_form
from app.lab.chart_texts import class_text
from app.lab.charts import class_error_figure, class_histogram_figure
from app.lab.planner import assignment_plan, plan_view
from app.review.accuracy import accuracy_rows, class_accuracy
from app.review.dashboard_cells import class_cells
from app.review.deps import TeacherAssignment
from app.review.evidence import badge_text, finding_text, once_per_finding
from app.review.exports import (
    class_table_response,
    class_table_xlsx_response,
    class_zip_response,
)
from app.review.lms_outbox import passback_state
from app.review.service import class_rows, status_counts
from app.web.deps import FormDep, SessionDep
from app.web.i18n import translator
from app.web.render import flash, redirect, render, request_language, time_formatter
from app.web.work_slots import pool

router = APIRouter(tags=["pages: review"], include_in_schema=False)


@router.get("/courses/{course_id}/assignments/{assignment_id}")
def assignment_dashboard(
    request: Request,
    target: TeacherAssignment,
    db: SessionDep,
    status: str = "",
):
    return render(request, "review/dashboard.html", dashboard_context(request, target, db, status))


def dashboard_context(request: Request, target, db, status: str = "", **extra) -> dict:
    """What the assignment's dashboard shows (``extra``: the settings form as typed and
    its refused fields, after a refused change)."""
    course, assignment = target.course, target.assignment
    language = request_language(request)
    _ = translator(language)
    rows = class_rows(db, assignment)
    figures = {
        "class-errors": class_error_figure(rows, _),
        "class-histogram": class_histogram_figure(rows, _),
    }
    summary, table = class_text(rows, _)
    accuracy = accuracy_rows(class_accuracy(assignment, rows))
    figure_texts = dict.fromkeys(figures, {"summary": summary, "table": table})
    stored = characterisation.summary_of(assignment, with_time=True)
    words = None
    if stored is not None and "terms" in stored:
        words = {
            "terms": term_rows(stored["terms"], _),
            "dwell": dwell_lines(stored["dwell"], _),
            "notes": note_lines(stored.get("notes", []), _),
        }
    return {
        "course": course,
        "assignment": assignment,
        "rows": rows,
        "cells": class_cells(rows, time_formatter(language, course.timezone)),
        "counts": status_counts(rows),
        "figures": figures,
        "figure_texts": figure_texts,
        "status_filter": status,
        "timezone": course.timezone,
        "form": form_values(assignment, course.timezone),
        "characterisation": stored,
        "characterisation_words": words,
        "characterisation_typed": {"rate_hz": "", "unit": "", "column": ""},
        "characterisation_problems": {},
        "characterisation_choices": [],
        "presets": sorted(PRESETS),
        "plotly_url": request.app.state.plotly_url,
        "passback": passback_state(db, assignment.id),
        "accuracy": accuracy,
        "evidence_text": once_per_finding(lambda finding: finding_text(finding, _)),
        "evidence_badge": once_per_finding(lambda finding: badge_text(finding, _)),
        "plan": plan_view(assignment_plan(assignment)),
        **form_context(),
        **extra,
    }


@router.post(
    "/courses/{course_id}/assignments/{assignment_id}/settings", dependencies=[CsrfProtected]
)
def update_settings(
    request: Request,
    target: TeacherAssignment,
    db: SessionDep,
    form: FormDep,
):
    course, assignment = target.course, target.assignment
    values = {key: form.get(key, "") for key in form if key != "methods"}
    values["methods"] = form.getlist("methods")
    try:
        updated = parse_assignment_form(values, course.timezone)
    except FieldProblems as refused:  # the form again, as typed, every refused field marked
        context = dashboard_context(
            request,
            target,
            db,
            form={**form_values(assignment, course.timezone), **values},
            **form_context(refused.problems),
        )
        return render(request, "review/dashboard.html", context, 400)
    kept = {"id", "course_id", "created_at", "gyro_characterisation"}  # not on this form
    for name, value in updated.model_dump(exclude=kept).items():
        setattr(assignment, name, value)
    db.add(assignment)
    db.commit()
    response = redirect(f"/courses/{course.id}/assignments/{assignment.id}")
    flash(response, request, "assignment.updated", "success")
    return response


def _record_source(record: UploadFile):
    """The uploaded record as a binary file, read in blocks (spooled to disk by the server):
    gzip-compressed CSV (``.gz``, or the gzip magic bytes) is decompressed as it is read;
    an Excel workbook's sheet of readings is read as its text
    (:func:`app.core.workbook_text.workbook_text`, bounded)."""
    import gzip

    handle = record.file
    handle.seek(0)
    magic = handle.read(8)
    handle.seek(0)
    if not magic:
        raise UserError("characterisation.no_file")
    if magic[:2] == b"\x1f\x8b":
        return gzip.GzipFile(fileobj=handle, mode="rb")
    if is_workbook(magic):
        data = handle.read()
        if is_npz(data):  # a zip too: NumPy's archive, read as such by the characterisation
            return io.BytesIO(data)
        return io.BytesIO(workbook_text(data).encode())
    return handle  # text, or a MATLAB data file (read as such by the characterisation)


# a refused characterisation upload: the field its problem is about (else the file)
CHARACTERISATION_FIELDS = {
    "characterisation.bad_rate": "characterisation-rate",
    "allan.bad_rate": "characterisation-rate",
    "allan.no_rate": "characterisation-rate",
    "characterisation.unit_doubt": "characterisation-unit",
    "allan.unit_conflict": "characterisation-unit",
    "allan.angle_not_rate": "characterisation-unit",
    "allan.no_value_column": "characterisation-column",
    "allan.no_rate_column": "characterisation-column",
    "allan.no_such_column": "characterisation-column",
    "allan.choose_column": "characterisation-column",
    "matlab.choose_vector": "characterisation-column",
}


@router.post(
    "/courses/{course_id}/assignments/{assignment_id}/characterisation",
    dependencies=[CsrfProtected],
)
def upload_characterisation(
    request: Request,
    target: TeacherAssignment,
    db: SessionDep,
    record: Annotated[UploadFile | None, File()] = None,
    rate_hz: Annotated[str, Form(max_length=40)] = "",
    unit: Annotated[str, Form(max_length=16)] = "",
    column: Annotated[str, Form(max_length=100)] = "",
    remove: Annotated[str, Form(max_length=8)] = "",
):
    """The bench gyro's static record → its noise model for this assignment's real data."""
    course, assignment = target.course, target.assignment
    response = redirect(f"/courses/{course.id}/assignments/{assignment.id}#characterisation")
    if remove:
        characterisation.store(assignment, None)
        db.add(assignment)
        db.commit()
        flash(response, request, "characterisation.removed", "success")
        return response
    try:
        if record is None:
            raise UserError("characterisation.no_file")
        rate = None
        if rate_hz.strip():
            try:
                rate = parse_typed_number(rate_hz)
            except ValueError:
                rate = math.nan
        try:
            with pool("analysis").slot(course.teacher_id):
                summary = characterisation.characterise(
                    _record_source(record),
                    rate,
                    unit.strip() or None,
                    column.strip() or None,
                )
        # a truncated gzip stream (EOFError), a damaged header or check (BadGzipFile, an
        # OSError), damaged compressed data (zlib.error: was a 500)
        except (OSError, EOFError, zlib.error):
            raise UserError("characterisation.bad_gzip") from None
    except UserError as error:  # the section again: what was typed, the refusal beside its field
        typed = {"rate_hz": rate_hz.strip(), "unit": unit.strip(), "column": column.strip()}
        problems = {CHARACTERISATION_FIELDS.get(error.key, "characterisation-record"): error}
        context = dashboard_context(
            request,
            target,
            db,
            characterisation_typed=typed,
            characterisation_problems=problems,
            characterisation_choices=getattr(error, "choices", []),  # the columns to choose
        )
        return render(request, "review/dashboard.html", context, error.status)
    characterisation.store(assignment, summary)
    db.add(assignment)
    db.commit()
    flash(response, request, "characterisation.stored", "success")
    return response


@router.get("/courses/{course_id}/assignments/{assignment_id}/export.csv")
def export_assignment_csv(request: Request, target: TeacherAssignment, db: SessionDep):
    _ = translator(request_language(request))
    return class_table_response(db, target.assignment, target.course, _)


@router.get("/courses/{course_id}/assignments/{assignment_id}/export.xlsx")
def export_assignment_xlsx(request: Request, target: TeacherAssignment, db: SessionDep):
    """The class table as an Excel workbook, in the teacher's language."""
    _ = translator(request_language(request))
    return class_table_xlsx_response(db, target.assignment, target.course, _)


@router.get("/courses/{course_id}/assignments/{assignment_id}/export.zip")
def export_assignment_zip(
    request: Request, target: TeacherAssignment, user: CurrentUser, db: SessionDep
):
    """The class table plus every submitted attempt's own data."""
    _ = translator(request_language(request))
    return class_zip_response(db, target.assignment, target.course, _, user.id)
