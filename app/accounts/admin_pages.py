"""Administrators: every account, new accounts, and password resets teachers may not do."""

from __future__ import annotations

from typing import Annotated

from fastapi import APIRouter, Form, Request
from sqlalchemy import func, or_
from sqlmodel import select

from app.accounts.deps import AdminUser, CsrfProtected
from app.accounts.roster_csv import person_problems
from app.accounts.security import generate_password, normalise_username
from app.accounts.service import NewCredential, create_user, may_reset_password
from app.accounts.service import reset_password as give_new_password
from app.core.exceptions import UserError
from app.models import Course, Enrollment, Role, User
from app.web.deps import ObjectId, SessionDep
from app.web.exports import credential_downloads
from app.web.i18n import translator
from app.web.render import render, request_language

router = APIRouter(prefix="/admin", tags=["pages: admin"], include_in_schema=False)
PAGE_SIZE = 200


def accounts_context(db, query: str, **extra) -> dict:
    """Accounts matching ``query`` (username or name), with who created them and how many
    courses hold them."""
    statement = select(User).order_by(User.role, User.username).limit(PAGE_SIZE)
    if query:
        login = f"%{normalise_username(query)}%"  # a student number typed in full width too
        name = f"%{query.strip().lower()}%"
        statement = statement.where(
            or_(func.lower(User.username).like(login), func.lower(User.display_name).like(name))
        )
    users = db.exec(statement).all()
    names = {u.id: u.username for u in db.exec(select(User).where(User.role == Role.teacher))}
    courses = dict(
        db.exec(
            select(Enrollment.student_id, func.count(Enrollment.id)).group_by(Enrollment.student_id)
        ).all()
    )
    taught = dict(
        db.exec(select(Course.teacher_id, func.count(Course.id)).group_by(Course.teacher_id)).all()
    )
    rows = [
        {
            "user": user,
            "created_by": names.get(user.created_by_id, ""),
            "courses": courses.get(user.id, 0) + taught.get(user.id, 0),
        }
        for user in users
    ]
    return {"rows": rows, "query": query, "page_size": PAGE_SIZE, "roles": list(Role), **extra}


@router.get("/accounts")
def accounts_page(request: Request, admin: AdminUser, db: SessionDep, q: str = ""):
    return render(request, "admin/accounts.html", accounts_context(db, q.strip()[:64]))


@router.post("/accounts", dependencies=[CsrfProtected])
def create_account(
    request: Request,
    admin: AdminUser,
    db: SessionDep,
    username: Annotated[str, Form(max_length=64)] = "",
    display_name: Annotated[str, Form(max_length=128)] = "",
    role: Annotated[str, Form(max_length=16)] = "student",
):
    form = {"username": username, "display_name": display_name, "role": role}
    problems = person_problems(username.strip(), display_name.strip())
    if role not in set(Role):
        problems["role"] = UserError("admin.bad_role")
    if not problems:
        password = generate_password()
        try:
            user = create_user(
                db,
                username=username.strip(),
                display_name=display_name.strip(),
                role=Role(role),
                password=password,
                must_change_password=True,
            )
        except UserError as failure:  # the username is taken
            db.rollback()
            problems["username"] = failure
    if problems:  # the form again as typed, each refused field marked
        context = accounts_context(db, "", form=form, create_problems=problems)
        return render(request, "admin/accounts.html", context, 400)
    db.commit()
    credential = NewCredential(user.username, user.display_name, password)
    return credentials_page(request, credential, reset=False)


@router.post("/accounts/{user_id}/reset-password", dependencies=[CsrfProtected])
def reset_account_password(request: Request, user_id: ObjectId, admin: AdminUser, db: SessionDep):
    user = db.get(User, user_id)
    if user is None:
        raise UserError("error.not_found", status=404)
    if not may_reset_password(db, admin, user):
        context = accounts_context(db, "", error="admin.reset_refused", error_params={})
        return render(request, "admin/accounts.html", context, 403)
    password = give_new_password(db, user)
    db.commit()
    credential = NewCredential(user.username, user.display_name, password)
    return credentials_page(request, credential, reset=True)


def credentials_page(request: Request, credential: NewCredential, *, reset: bool):
    context = {
        "credentials": [credential],
        "reset": reset,
        **credential_downloads(
            [credential], [credential.username], translator(request_language(request))
        ),
    }
    return render(request, "admin/credentials.html", context)
