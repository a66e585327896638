"""The grading desk's pages: one submission (with next/previous student), saving a review,
returning or releasing it, bulk release from the class dashboard, per-student extensions."""

from __future__ import annotations

import json
from datetime import datetime

from fastapi import APIRouter, BackgroundTasks, Request
from jinja2.utils import htmlsafe_json_dumps
from markupsafe import Markup
from sqlmodel import select

from app.accounts.deps import CsrfProtected, TeacherUser
from app.core.exceptions import UserError
from app.courses import deadlines
from app.lab import partners
from app.lab.attempts import (
    amendments_of,
    comments_of,
    grade_text,
    latest_attempt,
    rubric_of,
    rubric_scores_of,
)
from app.lab.pages import UNIT_NAMES, session_view
from app.lab.results import current_data
from app.lab.truth import auto_check, session_truth
from app.models import Attempt, SessionStatus, User
from app.review import evidence, grading, lms_outbox
from app.review.deps import ReviewableSession, TeacherAssignment
from app.review.evidence import finding_text
from app.review.evidence_charts import evidence_figures
from app.review.service import session_row
from app.web.deps import FormDep, SessionDep
from app.web.i18n import translator
from app.web.local_time import local_input_to_utc, utc_to_local_input
from app.web.render import flash, redirect, render, request_language

router = APIRouter(tags=["pages: review"], include_in_schema=False)


@router.get("/review/sessions/{session_id}")
def submission_page(request: Request, target: ReviewableSession, db: SessionDep):
    return render(request, "review/submission.html", desk_view(request, target, db))


def desk_view(request: Request, target, db) -> dict:
    """Everything the grading desk's page shows of one submission."""
    session, assignment, course = target.session, target.assignment, target.course
    _ = translator(request_language(request))
    attempts = db.exec(
        select(Attempt).where(Attempt.session_id == session.id).order_by(Attempt.number)
    ).all()
    view = session_view(db, session, assignment, attempts, _, reviewer=True)
    # the teacher always sees the truth, the auto-check and the unreleased review
    truth = session_truth(db, session, assignment)
    latest = attempts[-1] if attempts else None
    check = auto_check(json.loads(latest.results_json), truth, assignment) if latest else None
    due = deadlines.due_for(db, assignment, session.owner_id)
    evidence_row = session_row(db, assignment, session)
    charts = {}
    if evidence_row is not None and evidence_row.evidence:
        data = current_data(db, session)
        charts = evidence_figures(assignment, session, data, evidence_row.evidence, _)
    view.update(
        {
            "truth": truth,
            "check": check,
            "latest": latest,
            "feedback": latest.feedback if latest else "",
            "position_feedback": comments_of(latest),
            "rubric": rubric_of(assignment),
            "rubric_scores": rubric_scores_of(latest),
            "grade": grade_text(latest, assignment),
            "amendments": amendments_of(db, latest),
            "student": db.get(User, session.owner_id),
            "members": partners.members_of(db, session),
            "course": course,
            "timezone": course.timezone,
            "neighbours": grading.neighbours(db, session),
            "due": due,
            "extension_value": utc_to_local_input(due, course.timezone),
            "extended": due is not None and due != assignment.due_at,
            "editable": False,
            "reviewer": True,
            "history": [],
            "methods": [],
            "units": [],
            "unit_names": UNIT_NAMES,
            "plotly_url": request.app.state.plotly_url,
            "interrupted": None,
            "typed": None,
            "problem": None,
            "evidence_row": evidence_row,
            "evidence_text": lambda finding: finding_text(finding, _),
            "evidence_figures": {key: text for key, (_figure, text) in charts.items()},
            "evidence_figures_json": Markup(
                htmlsafe_json_dumps({key: figure for key, (figure, _text) in charts.items()})
            ),
        }
    )
    return view


def typed_review(form, rubric: list[dict], problem: UserError) -> dict:
    """What the teacher typed into the review form, as typed, and which field was refused
    (shown again with the message: nothing typed is lost when one value is wrong)."""
    fields = {key: str(value) for key, value in form.items()}
    field = str(problem.params.get("field", ""))
    names = [str(criterion["name"]) for criterion in rubric]
    invalid = "points" if field == "points" and not rubric else ""
    if field in names:
        invalid = f"rubric-{names.index(field)}"
    elif field == "reason":
        invalid = "reason"
    elif problem.key == "review.points_required":  # released with no points: the first gap
        empty = [i for i in range(len(rubric)) if not fields.get(f"rubric-{i}", "").strip()]
        invalid = f"rubric-{empty[0]}" if empty else "" if rubric else "points"
    return {
        "feedback": fields.get("feedback", "")[: grading.MAX_FEEDBACK],
        "comments": {
            key.removeprefix("comment-"): value[: grading.MAX_COMMENT]
            for key, value in fields.items()
            if grading.COMMENT_KEY.fullmatch(key)
        },
        "rubric": {str(i): fields.get(f"rubric-{i}", "")[:32] for i in range(len(rubric))},
        "points": fields.get("points", "")[:32],
        "letter": fields.get("letter", "")[:32],
        "reason": fields.get("reason", "")[: grading.MAX_REASON],
        "invalid": invalid,
    }


@router.post("/review/sessions/{session_id}/feedback", dependencies=[CsrfProtected])
def save_review(
    request: Request,
    target: ReviewableSession,
    teacher: TeacherUser,
    db: SessionDep,
    form: FormDep,
    background: BackgroundTasks,
):
    """The review of the latest attempt (feedback, comments, points, rubric, letter);
    ``action`` = save | return | release, or amend (a released grade, with a ``reason``);
    ``go`` = next | previous after saving."""
    session, assignment = target.session, target.assignment
    response = redirect(f"/review/sessions/{session.id}")
    attempt = latest_attempt(db, session.id)
    action = str(form.get("action", "save"))
    graded = session.status == SessionStatus.graded
    try:
        if attempt is None:
            raise UserError("review.nothing_submitted", status=409)
        if graded and action != "amend":
            raise UserError("review.already_released", status=409)
        review = grading.parse_review({k: str(v) for k, v in form.items()}, assignment)
        if action == "amend":
            queued = grading.amend(
                db, session, attempt, review, str(form.get("reason", "")), teacher.id
            )
            if queued:
                background.add_task(lms_outbox.wake_sender)
        else:
            grading.store_review(attempt, review)
        if action == "return":
            grading.return_for_revision(db, session, attempt)
        elif action == "release":
            queued = grading.release(db, session, attempt)
            if queued:
                background.add_task(lms_outbox.wake_sender)
    except UserError as problem:
        db.rollback()
        if attempt is None or (graded and action != "amend"):  # no form to fill
            flash(response, request, problem.key, "error", **problem.params)
            return response
        # the page again, with everything typed and the refused field marked (a redirect
        # would show the stored review and lose what was typed)
        view = desk_view(request, target, db)
        view["typed"] = typed_review(form, view["rubric"], problem)
        params = dict(problem.params)
        if params.get("field") == "points":  # the form's own word, not the field's name
            params["field"] = translator(request_language(request))("review.points")
        view["problem"] = {"key": problem.key, "params": params}
        return render(request, "review/submission.html", view, problem.status)
    db.add(attempt)
    db.add(session)
    db.commit()
    key = {
        "return": "review.returned",
        "release": "review.released",
        "amend": "review.amended",
    }.get(action, "review.saved")
    step = grading.neighbours(db, session)
    go = str(form.get("go", ""))
    target_id = None
    if go == "next" and step.next:
        target_id = step.next[0]
    elif go == "previous" and step.previous:
        target_id = step.previous[0]
    if target_id is not None:
        response = redirect(f"/review/sessions/{target_id}")
    flash(response, request, key, "success")
    return response


@router.post("/review/sessions/{session_id}/evidence", dependencies=[CsrfProtected])
def mark_evidence_seen(
    request: Request,
    target: ReviewableSession,
    teacher: TeacherUser,
    db: SessionDep,
    form: FormDep,
):
    """Mark one data-evidence finding as seen, with a note (the finding itself stays)."""
    session = target.session
    response = redirect(f"/review/sessions/{session.id}#data-evidence")
    try:
        row = session_row(db, target.assignment, session)
        evidence.mark_seen(
            db,
            session,
            row.evidence if row is not None else [],
            teacher.id,
            str(form.get("check", ""))[:32],
            str(form.get("part", ""))[:32],
            str(form.get("note", "")),
        )
    except UserError as problem:
        db.rollback()
        flash(response, request, problem.key, "error", **problem.params)
        return response
    db.commit()
    flash(response, request, "evidence.marked", "success")
    return response


@router.post("/review/sessions/{session_id}/extension", dependencies=[CsrfProtected])
def save_extension(request: Request, target: ReviewableSession, db: SessionDep, form: FormDep):
    """A later due date for this student, typed in the course's time zone (blank removes)."""
    session, assignment, course = target.session, target.assignment, target.course
    response = redirect(f"/review/sessions/{session.id}#extension")
    text = str(form.get("due_at", "")).strip()
    due = None
    if text and not form.get("remove"):
        try:
            due = local_input_to_utc(datetime.fromisoformat(text[:32]), course.timezone)
        except ValueError:  # the desk again: the date as typed, its message beside it
            view = desk_view(request, target, db)
            view["extension_typed"] = text[:64]
            view["extension_problems"] = {"due_at": UserError("assignment.bad_due")}
            return render(request, "review/submission.html", view, 400)
    deadlines.set_extension(db, assignment, session.owner_id, due)
    db.commit()
    flash(
        response,
        request,
        "review.extension_saved" if due else "review.extension_removed",
        "success",
    )
    return response


@router.post(
    "/courses/{course_id}/assignments/{assignment_id}/release", dependencies=[CsrfProtected]
)
def release_selected(
    request: Request,
    target: TeacherAssignment,
    db: SessionDep,
    form: FormDep,
    background: BackgroundTasks,
):
    """Bulk release: every ticked submission that has points (and their LMS grade posts)."""
    course, assignment = target.course, target.assignment
    chosen = []
    for value in form.getlist("session"):
        try:
            chosen.append(int(str(value)))
        except ValueError:
            continue
    released, skipped = grading.bulk_release(db, assignment, chosen[:10_000])
    db.commit()
    if released and lms_outbox.anything_queued():
        background.add_task(lms_outbox.wake_sender)
    response = redirect(f"/courses/{course.id}/assignments/{assignment.id}")
    kind = "success" if released and not skipped else ("warning" if released else "error")
    flash(response, request, "review.bulk_released", kind, released=released, skipped=skipped)
    return response
