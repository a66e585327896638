"""Teacher pages: courses and their rosters."""

from __future__ import annotations

from typing import Annotated

from fastapi import APIRouter, File, Form, Request, UploadFile
from sqlmodel import Session, select

from app.accounts.deps import CsrfProtected, TeacherUser
from app.accounts.roster_csv import MAX_ROSTER_BYTES, parse_roster, person_problems
from app.accounts.service import (
    NewCredential,
    add_student,
    check_roster_against_accounts,
    import_roster,
    may_reset_password,
    reset_password,
    rotate_join_code,
)
from app.core.exceptions import UserError
from app.core.presets import PRESETS
from app.core.text_files import shown_name
from app.courses.assignment_form import form_context, form_values
from app.courses.deps import TeacherCourse
from app.courses.listing import teacher_dashboard
from app.models import Assignment, Course, Enrollment, LtiContext, LtiPlatform, User
from app.web.deps import ObjectId, SessionDep
from app.web.exports import credential_downloads
from app.web.i18n import translator
from app.web.local_time import valid_zone_name, zone_choices
from app.web.render import flash, redirect, render, request_language

router = APIRouter(prefix="/courses", tags=["pages: courses"], include_in_schema=False)

NameField = Annotated[str, Form(max_length=200)]


def lms_links(db: Session, course: Course) -> list[dict]:
    """The LMS courses linked to ``course``, for its page."""
    rows = db.exec(select(LtiContext).where(LtiContext.course_id == course.id)).all()
    return [{"context": row, "platform": db.get(LtiPlatform, row.platform_id)} for row in rows]


def enrolled_student(db: Session, course: Course, student_id: int) -> User:
    enrollment = db.exec(
        select(Enrollment).where(
            Enrollment.course_id == course.id, Enrollment.student_id == student_id
        )
    ).first()
    if enrollment is None:
        raise UserError("course.no_such_student", status=404)
    return db.get(User, student_id)


def roster(db: Session, course: Course) -> list[User]:
    """The course's students, each with ``may_reset`` (may this course's teacher give them a
    one-time password?)."""
    students = list(
        db.exec(
            select(User)
            .join(Enrollment, Enrollment.student_id == User.id)
            .where(Enrollment.course_id == course.id)
            .order_by(User.username)
        ).all()
    )
    teacher = db.get(User, course.teacher_id)
    return [(student, may_reset_password(db, teacher, student)) for student in students]


@router.get("")
def course_list(teacher: TeacherUser):
    return redirect("/")


@router.post("", dependencies=[CsrfProtected])
def create_course(request: Request, teacher: TeacherUser, db: SessionDep, name: NameField = ""):
    if not shown_name(name):  # the dashboard again, the name as typed and its message beside it
        context = teacher_dashboard(db, teacher)
        context.update(course_name=name, course_problems=_name_problem())
        return render(request, "dashboard/teacher.html", context, 400)
    course = Course(name=shown_name(name), teacher_id=teacher.id)
    db.add(course)
    db.commit()
    response = redirect(f"/courses/{course.id}")
    flash(response, request, "course.created", "success", name=course.name)
    return response


def _name_problem() -> dict[str, UserError]:
    return {"name": UserError("course.name_required")}


def course_context(db: Session, course: Course, **extra) -> dict:
    """What the course page shows: roster, assignments, and any form errors in ``extra``."""
    assignments = db.exec(
        select(Assignment)
        .where(Assignment.course_id == course.id)
        .order_by(Assignment.created_at.desc())
    ).all()
    return {
        "course": course,
        "students": roster(db, course),
        "assignments": assignments,
        "presets": sorted(PRESETS),
        "assignment_form": form_values(),
        "timezone": course.timezone,
        "zones": zone_choices(),
        "lms": lms_links(db, course),
        **form_context(),
        **extra,
    }


@router.get("/{course_id}")
def course_page(request: Request, course: TeacherCourse, teacher: TeacherUser, db: SessionDep):
    return render(request, "courses/detail.html", course_context(db, course))


@router.post("/{course_id}/rename", dependencies=[CsrfProtected])
def rename_course(
    request: Request,
    course: TeacherCourse,
    teacher: TeacherUser,
    db: SessionDep,
    name: NameField = "",
):
    if not shown_name(name):
        context = course_context(db, course, settings_typed={"name": name})
        context["settings_problems"] = _name_problem()
        return render(request, "courses/detail.html", context, 400)
    response = redirect(f"/courses/{course.id}")
    course.name = shown_name(name)
    db.add(course)
    db.commit()
    flash(response, request, "course.renamed", "success", name=course.name)
    return response


@router.post("/{course_id}/timezone", dependencies=[CsrfProtected])
def set_course_timezone(
    request: Request,
    course: TeacherCourse,
    teacher: TeacherUser,
    db: SessionDep,
    timezone: Annotated[str, Form(max_length=64)] = "",
):
    """The zone due dates are typed and shown in (stored times stay UTC)."""
    try:
        course.timezone = valid_zone_name(timezone)
    except UserError as problem:
        db.rollback()
        context = course_context(db, course, settings_problems={"timezone": problem})
        return render(request, "courses/detail.html", context, 400)
    response = redirect(f"/courses/{course.id}")
    db.add(course)
    db.commit()
    flash(response, request, "course.timezone_saved", "success", zone=course.timezone)
    return response


@router.post("/{course_id}/archive", dependencies=[CsrfProtected])
def archive_course(
    request: Request,
    course: TeacherCourse,
    teacher: TeacherUser,
    db: SessionDep,
    archived: Annotated[bool, Form()] = True,
):
    course.archived = archived
    db.add(course)
    db.commit()
    response = redirect(f"/courses/{course.id}")
    flash(response, request, "course.archived" if archived else "course.unarchived", "success")
    return response


@router.post("/{course_id}/students", dependencies=[CsrfProtected])
def add_student_by_hand(
    request: Request,
    course: TeacherCourse,
    teacher: TeacherUser,
    db: SessionDep,
    username: Annotated[str, Form(max_length=64)] = "",
    display_name: NameField = "",
    email: Annotated[str, Form(max_length=254)] = "",
):
    typed = {"username": username, "display_name": display_name, "email": email}
    problems = person_problems(username.strip(), display_name.strip(), email.strip())
    if not problems:
        try:
            credential = add_student(
                db, course, username.strip(), display_name.strip(), email.strip() or None
            )
        except UserError as error:  # the account named cannot join (a teacher's, consent)
            db.rollback()
            problems = {"username": error}
    if problems:  # the page again: everything typed, each refused field marked
        context = course_context(db, course, form=typed, add_problems=problems)
        return render(request, "courses/detail.html", context, 400)
    db.commit()
    if credential is None:
        response = redirect(f"/courses/{course.id}")
        flash(response, request, "roster.enrolled_existing", "success", username=username)
        return response
    return render(
        request,
        "courses/credentials.html",
        {
            "course": course,
            "credentials": [credential],
            "enrolled": [],
            **credential_downloads(
                [credential],
                [course.name, credential.username],
                translator(request_language(request)),
            ),
        },
    )


@router.post("/{course_id}/import", dependencies=[CsrfProtected])
def import_students(
    request: Request,
    course: TeacherCourse,
    teacher: TeacherUser,
    db: SessionDep,
    roster_file: Annotated[UploadFile | None, File()] = None,
):
    data = roster_file.file.read(MAX_ROSTER_BYTES + 1) if roster_file else b""
    parsed = parse_roster(data)
    problems = parsed.problems or check_roster_against_accounts(db, parsed.rows)
    if problems or not parsed.rows:
        return render(
            request,
            "courses/detail.html",
            course_context(db, course, import_problems=problems),
            400,
        )
    outcome = import_roster(db, course, parsed.rows)
    db.commit()
    return render(
        request,
        "courses/credentials.html",
        {
            "course": course,
            "credentials": outcome.created,
            "enrolled": outcome.enrolled,
            "needs_code": outcome.needs_code,
            **credential_downloads(
                outcome.created, [course.name], translator(request_language(request))
            ),
        },
    )


@router.post("/{course_id}/students/{student_id}/reset-password", dependencies=[CsrfProtected])
def reset_student_password(
    request: Request,
    course: TeacherCourse,
    student_id: ObjectId,
    teacher: TeacherUser,
    db: SessionDep,
):
    student = enrolled_student(db, course, student_id)
    if not may_reset_password(db, teacher, student):
        response = redirect(f"/courses/{course.id}")
        flash(response, request, "roster.reset_needs_admin", "error", username=student.username)
        return response
    password = reset_password(db, student)
    db.commit()
    credential = NewCredential(student.username, student.display_name, password)
    return render(
        request,
        "courses/credentials.html",
        {
            "course": course,
            "credentials": [credential],
            "enrolled": [],
            "reset": True,
            **credential_downloads(
                [credential],
                [course.name, credential.username],
                translator(request_language(request)),
            ),
        },
    )


@router.post("/{course_id}/join-code", dependencies=[CsrfProtected])
def new_join_code(request: Request, course: TeacherCourse, teacher: TeacherUser, db: SessionDep):
    """Replace the course's join code (the old code and links stop working)."""
    rotate_join_code(db, course)
    db.commit()
    response = redirect(f"/courses/{course.id}#join")
    flash(response, request, "join.code_rotated", "success", code=course.join_code)
    return response


@router.post("/{course_id}/students/{student_id}/remove", dependencies=[CsrfProtected])
def remove_student(
    request: Request,
    course: TeacherCourse,
    student_id: ObjectId,
    teacher: TeacherUser,
    db: SessionDep,
):
    """Take a student off the roster; their account and all their work stay."""
    student = enrolled_student(db, course, student_id)
    enrollment = db.exec(
        select(Enrollment).where(
            Enrollment.course_id == course.id, Enrollment.student_id == student.id
        )
    ).one()
    db.delete(enrollment)
    db.commit()
    response = redirect(f"/courses/{course.id}")
    flash(response, request, "roster.removed", "success", username=student.username)
    return response
