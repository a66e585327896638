"""Settings page for personal access tokens (for scripts and the serial bridge)."""

from __future__ import annotations

from typing import Annotated

from fastapi import APIRouter, Form, Request

from app.accounts.deps import CsrfProtected, CurrentUser
from app.accounts.tokens import new_token, user_tokens
from app.core.exceptions import UserError
from app.models import ApiToken, utcnow
from app.web.deps import ObjectId, SessionDep
from app.web.render import flash, redirect, render

router = APIRouter(prefix="/account/tokens", tags=["pages: tokens"], include_in_schema=False)


@router.get("")
def tokens_page(request: Request, user: CurrentUser, db: SessionDep):
    return render(request, "auth/tokens.html", {"tokens": user_tokens(db, user)})


@router.post("", dependencies=[CsrfProtected])
def create_token(
    request: Request,
    user: CurrentUser,
    db: SessionDep,
    name: Annotated[str, Form(max_length=100)] = "",
    scopes: Annotated[list[str] | None, Form()] = None,
):
    chosen = tuple(s for s in (scopes or []) if s in ("read", "upload"))
    problems = {}
    if not name.strip():
        problems["name"] = UserError("tokens.name_required")
    if "read" not in chosen:
        problems["scopes"] = UserError("tokens.read_required")
    if problems:  # the form again as typed (name and scopes), each problem beside its field
        context = {
            "tokens": user_tokens(db, user),
            "problems": problems,
            "typed": {"name": name, "scopes": chosen},
        }
        return render(request, "auth/tokens.html", context, 400)
    raw, record = new_token(db, user, kind="personal", name=name.strip(), scopes=chosen)
    db.commit()
    return render(
        request,
        "auth/tokens.html",
        {"tokens": user_tokens(db, user), "new_token": raw, "new_record": record},
    )


@router.post("/{token_id}/revoke", dependencies=[CsrfProtected])
def revoke_token(request: Request, token_id: ObjectId, user: CurrentUser, db: SessionDep):
    record = db.get(ApiToken, token_id)
    if record is None or record.user_id != user.id or record.kind != "personal":
        raise UserError("error.not_found", status=404)
    record.revoked_at = record.revoked_at or utcnow()
    db.add(record)
    db.commit()
    response = redirect("/account/tokens")
    flash(response, request, "tokens.revoked", "success", name=record.name)
    return response
