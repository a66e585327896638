"""Teacher review: the class dashboard of an assignment, a submission, feedback, grades, export."""

from __future__ import annotations

import json
import math
from typing import Annotated

from fastapi import APIRouter, File, Form, Request, UploadFile
from sqlmodel import select

from app.core.exceptions import UserError
from app.core.presets import PRESETS
from app.core.readings import parse_decimal
from app.courses import characterisation
from app.courses.assignment_form import form_values, parse_assignment_form
from app.lab.charts import class_error_figure, class_histogram_figure
from app.lab.pages import UNIT_NAMES, session_view
from app.models import Attempt, User
from app.review.deps import ReviewableSession, TeacherAssignment
from app.review.exports import class_table_response, class_zip_response
from app.review.service import (
    auto_check,
    class_rows,
    grade_and_release,
    return_for_revision,
    session_truth,
    status_counts,
)
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
    return render(
        request,
        "review/dashboard.html",
        {
            "course": course,
            "assignment": assignment,
            "rows": rows,
            "counts": status_counts(rows),
            "figures": figures,
            "status_filter": status,
            "form": form_values(assignment),
            "characterisation": characterisation.summary_of(assignment),
            "presets": sorted(PRESETS),
            "plotly_url": request.app.state.plotly_url,
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
        updated = parse_assignment_form(values)
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
        try:
            text = data.decode("utf-8-sig")
        except UnicodeDecodeError:
            raise UserError("characterisation.encoding", "The file is not UTF-8 text.") from None
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
def export_assignment_csv(target: TeacherAssignment, db: SessionDep):
    return class_table_response(db, target.assignment)


@router.get("/courses/{course_id}/assignments/{assignment_id}/export.zip")
def export_assignment_zip(target: TeacherAssignment, db: SessionDep):
    """The class table plus every submitted attempt's own data."""
    return class_zip_response(db, target.assignment)


@router.get("/review/sessions/{session_id}")
def submission_page(request: Request, target: ReviewableSession, db: SessionDep):
    session, assignment, course = target.session, target.assignment, target.course
    _ = translator(request_language(request))
    attempts = db.exec(
        select(Attempt).where(Attempt.session_id == session.id).order_by(Attempt.number)
    ).all()
    view = session_view(db, session, assignment, attempts, _)
    # the teacher always sees the truth, the auto-check and the unreleased feedback
    truth = session_truth(db, session, assignment)
    check = (
        auto_check(json.loads(attempts[-1].results_json), truth, assignment) if attempts else None
    )
    student = db.get(User, session.owner_id)
    view.update(
        {
            "truth": truth,
            "check": check,
            "feedback": session.feedback,
            "position_feedback": json.loads(session.feedback_positions or "{}"),
            "grade": session.grade,
            "student": student,
            "course": course,
            "editable": False,
            "reviewer": True,
            "history": [],
            "methods": [],
            "units": [],
            "unit_names": UNIT_NAMES,
            "plotly_url": request.app.state.plotly_url,
            "interrupted": None,
        }
    )
    return render(request, "review/submission.html", view)


@router.post("/review/sessions/{session_id}/feedback", dependencies=[CsrfProtected])
def save_feedback(request: Request, target: ReviewableSession, db: SessionDep, form: FormDep):
    """Comments (overall and per position) and the grade; 'action' may return or release."""
    session = target.session
    session.feedback = str(form.get("feedback", ""))[:20_000]
    comments = {
        key.removeprefix("comment-"): str(value)[:2000]
        for key, value in form.items()
        if key.startswith("comment-") and str(value).strip()
    }
    session.feedback_positions = json.dumps(comments, ensure_ascii=False)
    grade = str(form.get("grade", "")).strip()[:32]
    action = form.get("action", "save")
    has_attempt = db.exec(select(Attempt).where(Attempt.session_id == session.id)).first()
    response = redirect(f"/review/sessions/{session.id}")
    if action in ("return", "release") and has_attempt is None:
        flash(response, request, "review.nothing_submitted", "error")
        return response
    if action == "release" and not grade:
        flash(response, request, "review.grade_required", "error")
        return response
    session.grade = grade or session.grade
    if action == "return":
        return_for_revision(session)
        key = "review.returned"
    elif action == "release":
        grade_and_release(session, grade)
        key = "review.released"
    else:
        key = "review.saved"
    db.add(session)
    db.commit()
    flash(response, request, key, "success")
    return response
