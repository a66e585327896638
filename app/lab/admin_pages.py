"""The administrator's storage page action: superseded re-recordings pruned (the accounts
page offers it; ``app.lab.prune`` does it)."""

from __future__ import annotations

from typing import Annotated

from fastapi import APIRouter, Form, Request

from app.accounts.deps import AdminUser, CsrfProtected
from app.lab.prune import prune_takes
from app.web.deps import SessionDep
from app.web.render import flash, redirect

router = APIRouter(prefix="/admin", tags=["pages: admin"], include_in_schema=False)


@router.post("/prune", dependencies=[CsrfProtected])
def prune_old_takes(
    request: Request,
    admin: AdminUser,
    db: SessionDep,
    days: Annotated[int, Form(ge=1, le=3650)] = 30,
):
    """Remove re-recordings superseded more than ``days`` ago that no attempt refers to."""
    pruned = prune_takes(db, days)
    db.commit()
    response = redirect("/admin/accounts")
    flash(
        response,
        request,
        "admin.pruned",
        "success",
        n=pruned.takes,
        mb=f"{pruned.bytes / 1e6:.1f}",
        days=days,
    )
    return response
