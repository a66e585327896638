"""The class board for the projector (app/review/board.py): live, with its snapshots."""

from __future__ import annotations

import json

from fastapi import APIRouter, Request
from fastapi.responses import JSONResponse
from sqlmodel import select

from app.accounts.deps import CsrfProtected, TeacherUser
from app.core.exceptions import UserError
from app.core.jsonsafe import json_safe
from app.models import BoardSnapshot
from app.review.board import board_data
from app.review.board_charts import board_figures
from app.review.deps import TeacherAssignment
from app.review.service import class_rows
from app.web.deps import ObjectId, SessionDep
from app.web.i18n import translator
from app.web.render import flash, redirect, render, request_language

router = APIRouter(tags=["pages: review"], include_in_schema=False)
BASE = "/courses/{course_id}/assignments/{assignment_id}/board"


def board_view(request: Request, target, board: dict, snapshot=None) -> dict:
    _ = translator(request_language(request))
    return {
        "course": target.course,
        "assignment": target.assignment,
        "board": board,
        "figures": board_figures(board, _),
        "snapshot": snapshot,
        "plotly_url": request.app.state.plotly_url,
        "base": BASE.format(course_id=target.course.id, assignment_id=target.assignment.id),
    }


def live_board(db, target, names: bool) -> dict:
    return json_safe(board_data(db, target.assignment, class_rows(db, target.assignment), names))


@router.get(BASE)
def class_board(request: Request, target: TeacherAssignment, db: SessionDep, names: bool = False):
    view = board_view(request, target, live_board(db, target, names))
    view["snapshots"] = db.exec(
        select(BoardSnapshot.id, BoardSnapshot.created_at)
        .where(BoardSnapshot.assignment_id == target.assignment.id)
        .order_by(BoardSnapshot.created_at.desc())
    ).all()
    return render(request, "review/board.html", view)


@router.get(BASE + ".json")
def class_board_json(
    request: Request, target: TeacherAssignment, db: SessionDep, names: bool = False
):
    """What the live board redraws from every 10 s: the board and its figures."""
    _ = translator(request_language(request))
    board = live_board(db, target, names)
    return JSONResponse({"board": board, "figures": json_safe(board_figures(board, _))})


@router.post(BASE + "/snapshots", dependencies=[CsrfProtected])
def keep_snapshot(
    request: Request, target: TeacherAssignment, teacher: TeacherUser, db: SessionDep
):
    """Keep the board as it stands (names hidden) with the assignment."""
    board = live_board(db, target, names=False)
    snapshot = BoardSnapshot(
        assignment_id=target.assignment.id, teacher_id=teacher.id, data=json.dumps(board)
    )
    db.add(snapshot)
    db.commit()
    base = BASE.format(course_id=target.course.id, assignment_id=target.assignment.id)
    response = redirect(f"{base}/snapshots/{snapshot.id}")
    flash(response, request, "board.snapshot_saved", "success")
    return response


@router.get(BASE + "/snapshots/{snapshot_id}")
def board_snapshot(
    request: Request, target: TeacherAssignment, db: SessionDep, snapshot_id: ObjectId
):
    snapshot = db.get(BoardSnapshot, snapshot_id)
    if snapshot is None or snapshot.assignment_id != target.assignment.id:
        raise UserError("error.not_found", status=404)
    view = board_view(request, target, json.loads(snapshot.data), snapshot)
    view["snapshots"] = []
    return render(request, "review/board.html", view)
