"""Teacher review: the class dashboard of an assignment, a submission, feedback, grades, export."""

from __future__ import annotations

import math
from typing import Annotated

from fastapi import APIRouter, File, Form, Request, UploadFile

from app.core.exceptions import UserError
from app.core.presets import PRESETS
from app.core.readings import parse_decimal
from app.core.text_files import decode_text
from app.courses import characterisation
from app.courses.assignment_form import form_values, parse_assignment_form
from app.lab.chart_texts import class_text
from app.lab.charts import class_error_figure, class_histogram_figure
from app.lti.grades import passback_state
from app.review.deps import TeacherAssignment
from app.review.exports import class_table_response, class_zip_response
from app.review.service import class_rows, status_counts
from app.web.deps import CsrfProtected, FormDep, SessionDep
from app.web.i18n import translator
from app.web.render import flash, redirect, render, request_language

router = APIRouter(tags=["pages: review"], include_in_schema=False)


@router.get("/courses/{course_id}/assignments/{assignment_id}")
def assignment_dashboard(
    request: Request,
    target: TeacherAssignment,
    db: SessionDep,
    status: str = "",
):
    course, assignment = target.course, target.assignment
    _ = translator(request_language(request))
    rows = class_rows(db, assignment)
    figures = {
        "class-errors": class_error_figure(rows, _),
        "class-histogram": class_histogram_figure(rows, _),
    }
    summary, table = class_text(rows, _)
    figure_texts = dict.fromkeys(figures, {"summary": summary, "table": table})
    return render(
        request,
        "review/dashboard.html",
        {
            "course": course,
            "assignment": assignment,
            "rows": rows,
            "counts": status_counts(rows),
            "figures": figures,
            "figure_texts": figure_texts,
            "status_filter": status,
            "timezone": course.timezone,
            "form": form_values(assignment, course.timezone),
            "characterisation": characterisation.summary_of(assignment, with_time=True),
            "presets": sorted(PRESETS),
            "plotly_url": request.app.state.plotly_url,
            "passback": passback_state(db, assignment.id),
        },
    )


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
    except UserError as problem:
        response = redirect(f"/courses/{course.id}/assignments/{assignment.id}#settings")
        flash(response, request, problem.key, "error", **problem.params)
        return response
    kept = {"id", "course_id", "created_at", "gyro_characterisation"}  # not on this form
    for name, value in updated.model_dump(exclude=kept).items():
        setattr(assignment, name, value)
    db.add(assignment)
    db.commit()
    response = redirect(f"/courses/{course.id}/assignments/{assignment.id}")
    flash(response, request, "assignment.updated", "success")
    return response


MAX_RECORD_BYTES = 20_000_000  # about a million readings as text


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
    unit: Annotated[str, Form(max_length=16)] = "deg/h",
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
        data = record.file.read(MAX_RECORD_BYTES + 1) if record else b""
        if not data:
            raise UserError("characterisation.no_file", "Choose the record's CSV file.")
        if len(data) > MAX_RECORD_BYTES:
            raise UserError("characterisation.too_large", "The file is larger than 20 MB.")
        text = decode_text(data)
        try:
            rate = parse_decimal(rate_hz.strip())
        except ValueError:
            rate = math.nan
        summary = characterisation.characterise(text, rate, unit)
    except UserError as error:
        flash(response, request, error.key, "error", **error.params)
        return response
    characterisation.store(assignment, summary)
    db.add(assignment)
    db.commit()
    flash(
        response,
        request,
        "characterisation.stored",
        "success",
        arw=f"{summary['arw_deg_rt_h']:.4g}",
        bias=f"{summary['bias_instability_deg_h']:.3g}",
    )
    return response


@router.get("/courses/{course_id}/assignments/{assignment_id}/export.csv")
def export_assignment_csv(request: Request, target: TeacherAssignment, db: SessionDep):
    _ = translator(request_language(request))
    return class_table_response(db, target.assignment, target.course, _)


@router.get("/courses/{course_id}/assignments/{assignment_id}/export.zip")
def export_assignment_zip(request: Request, target: TeacherAssignment, db: SessionDep):
    """The class table plus every submitted attempt's own data."""
    _ = translator(request_language(request))
    return class_zip_response(db, target.assignment, target.course, _)
