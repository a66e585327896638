"""The teacher's uploaded readings of earlier years (``app/review/archives.py``)."""

from __future__ import annotations

from typing import Annotated

from fastapi import APIRouter, File, Request, UploadFile

from app.accounts.deps import CsrfProtected, TeacherUser
from app.core.exceptions import UserError
from app.review import archives
from app.web.deps import ObjectId, SessionDep
from app.web.render import flash, redirect, render

router = APIRouter(tags=["pages: review"], include_in_schema=False)
PAGE = "/review/archives"


@router.get(PAGE)
def archives_page(request: Request, teacher: TeacherUser, db: SessionDep):
    listed = archives.teacher_archives(db, teacher.id)
    return render(request, "review/archives.html", {"archives": listed})


@router.post(PAGE, dependencies=[CsrfProtected])
def upload_archive(
    request: Request,
    teacher: TeacherUser,
    db: SessionDep,
    readings: Annotated[UploadFile | None, File()] = None,
):
    """A class zip or readings CSV of an earlier year → its copy keys, kept."""
    response = redirect(PAGE)
    try:
        stored = archives.upload_archive(db, teacher.id, readings)
    except UserError as error:  # the page again, the refusal beside the file field
        listed = archives.teacher_archives(db, teacher.id)
        view = {"archives": listed, "problems": {"readings": error}}
        return render(request, "review/archives.html", view, 400)
    db.commit()
    flash(response, request, "archive.stored", "success", name=stored.name, n=stored.groups)
    return response


@router.post(PAGE + "/{archive_id}/delete", dependencies=[CsrfProtected])
def delete_archive(request: Request, archive_id: ObjectId, teacher: TeacherUser, db: SessionDep):
    archives.delete_archive(db, teacher.id, archive_id)
    db.commit()
    response = redirect(PAGE)
    flash(response, request, "archive.deleted", "success")
    return response
