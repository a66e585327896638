"""A teacher's LMS controls: the course's roster sync, an assignment's grade posts, and
choosing the assignment of an activity placed in the LMS without deep linking.

The network calls (NRPS, AGS) run after the request's transaction is committed, so no
database lock is held while the LMS answers."""

from __future__ import annotations

from fastapi import APIRouter, Request
from sqlmodel import Session, select

from app.accounts.deps import CsrfProtected, TeacherUser
from app.core.exceptions import UserError
from app.courses.pages import lms_links
from app.lti import grades, roster
from app.lti.provisioning import assignment_in
from app.models import Assignment, Course, LtiContext, LtiResourceLink
from app.review.deps import TeacherAssignment
from app.web.deps import FormDep, ObjectId, SessionDep
from app.web.render import flash, redirect, render

router = APIRouter(tags=["pages: lti"], include_in_schema=False)


@router.post("/courses/{course_id}/lti/sync", dependencies=[CsrfProtected])
def sync_course_roster(request: Request, course_id: ObjectId, teacher: TeacherUser, db: SessionDep):
    course = db.get(Course, course_id)
    if course is None or course.teacher_id != teacher.id:
        raise UserError("error.not_found", status=404)
    contexts = [row["context"].id for row in lms_links(db, course)]
    db.commit()  # no lock held while the LMS answers
    response = redirect(f"/courses/{course.id}#lms")
    for context_id in contexts:
        outcome = roster.sync_roster(context_id)
        if outcome.problem:
            flash(response, request, "lti.sync_failed", "error", reason=outcome.problem)
        else:
            flash(
                response,
                request,
                "lti.synced",
                "success",
                students=outcome.students,
                new=outcome.newly_enrolled,
                skipped=outcome.skipped,
            )
    return response


@router.post(
    "/courses/{course_id}/assignments/{assignment_id}/lti/send", dependencies=[CsrfProtected]
)
def send_grades_now(request: Request, target: TeacherAssignment, db: SessionDep):
    course, assignment = target.course, target.assignment
    db.commit()  # no lock held while the LMS answers
    counts = grades.send_now(assignment.id)
    response = redirect(f"/courses/{course.id}/assignments/{assignment.id}#lms")
    kind = "error" if counts["failed"] else "success"
    flash(response, request, "lti.sent_now", kind, sent=counts["sent"], failed=counts["failed"])
    return response


def _own_link(db: Session, link_id: int, teacher) -> tuple[LtiResourceLink, Course]:
    link = db.get(LtiResourceLink, link_id)
    context = db.get(LtiContext, link.context_row_id) if link else None
    course = db.get(Course, context.course_id) if context else None
    if course is None or course.teacher_id != teacher.id:
        raise UserError("error.not_found", status=404)
    return link, course


@router.get("/lti/links/{link_id}")
def link_page(request: Request, link_id: ObjectId, teacher: TeacherUser, db: SessionDep):
    """An activity placed without deep linking: the teacher picks its assignment once."""
    link, course = _own_link(db, link_id, teacher)
    assignments = db.exec(
        select(Assignment).where(Assignment.course_id == course.id).order_by(Assignment.id)
    ).all()
    context = {"link": link, "course": course, "assignments": assignments}
    return render(request, "lti/link.html", context)


@router.post("/lti/links/{link_id}", dependencies=[CsrfProtected])
def choose_link_assignment(
    request: Request, link_id: ObjectId, teacher: TeacherUser, db: SessionDep, form: FormDep
):
    link, course = _own_link(db, link_id, teacher)
    chosen = assignment_in(db, course, form.get("assignment_id"))
    if chosen is None:
        raise UserError("lti.choose_assignment", status=400)
    link.assignment_id = chosen
    db.add(link)
    db.commit()
    response = redirect(f"/courses/{course.id}/assignments/{chosen}")
    flash(response, request, "lti.link_saved", "success")
    return response
