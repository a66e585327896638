"""Students join a course with its code or join link: their consent to enrolment."""

from __future__ import annotations

from typing import Annotated

from fastapi import APIRouter, Form, Request

from app.accounts.deps import CsrfProtected, StudentUser
from app.accounts.service import course_by_code, join_course
from app.core.exceptions import UserError
from app.web.deps import SessionDep
from app.web.render import flash, redirect, render

router = APIRouter(tags=["pages: join"], include_in_schema=False)


@router.get("/join")
def join_page(request: Request, student: StudentUser, db: SessionDep, code: str = ""):
    """The join form; a join link (``/join?code=…``) shows the course to confirm."""
    course = course_by_code(db, code[:64]) if code else None
    context = {"code": code[:16], "course": course}
    if code and course is None:
        context["error"] = "join.bad_code"
    return render(request, "join.html", context)


@router.post("/join", dependencies=[CsrfProtected])
def join(
    request: Request,
    student: StudentUser,
    db: SessionDep,
    code: Annotated[str, Form(max_length=64)] = "",
):
    try:
        course = join_course(db, student, code)
    except UserError as error:
        db.rollback()
        return render(request, "join.html", {"code": code[:16], "error": error.key}, 400)
    db.commit()
    response = redirect("/")
    flash(response, request, "join.joined", "success", name=course.name)
    return response
