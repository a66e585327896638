"""Administrators and LTI: the platforms GyroLab trusts (add by hand, or make a one-time
dynamic-registration link), GyroLab's key (rotate), and the addresses an LMS needs."""

from __future__ import annotations

from fastapi import APIRouter, Request
from sqlmodel import select

from app.accounts.deps import AdminUser, CsrfProtected
from app.core.exceptions import UserError
from app.lti import keys
from app.lti.platforms import PlatformFields, add_platform, deployments_of
from app.lti.registration import new_registration_link
from app.models import LtiContext, LtiKey, LtiPlatform
from app.web.deps import FormDep, ObjectId, SessionDep
from app.web.render import flash, redirect, render

router = APIRouter(prefix="/admin/lti", tags=["pages: admin"], include_in_schema=False)
FIELDS = ("name", "issuer", "client_id", "auth_login_url", "auth_token_url", "key_set_url")


def tool_urls(request: Request) -> dict[str, str]:
    from app.lti.pages import public_base

    base = public_base(request)
    return {
        "login": f"{base}/lti/login",
        "launch": f"{base}/lti/launch",
        "jwks": f"{base}/lti/jwks.json",
        "register": f"{base}/lti/register",
    }


def lti_context(request: Request, db, **extra) -> dict:
    platforms = db.exec(select(LtiPlatform).order_by(LtiPlatform.name)).all()
    courses = {
        platform.id: len(
            db.exec(select(LtiContext.id).where(LtiContext.platform_id == platform.id)).all()
        )
        for platform in platforms
    }
    key = db.exec(select(LtiKey).order_by(LtiKey.id.desc())).first()
    return {
        "platforms": [
            {"row": p, "deployments": deployments_of(p), "courses": courses[p.id]}
            for p in platforms
        ],
        "urls": tool_urls(request),
        "key": key,
        "form": {},
        **extra,
    }


@router.get("")
def lti_page(request: Request, admin: AdminUser, db: SessionDep):
    return render(request, "admin/lti.html", lti_context(request, db))


@router.post("/platforms", dependencies=[CsrfProtected])
def add_platform_page(request: Request, admin: AdminUser, db: SessionDep, form: FormDep):
    values = {name: str(form.get(name, ""))[:1000] for name in (*FIELDS, "deployment_ids")}
    fields = PlatformFields(
        **{name: values[name] for name in FIELDS},
        deployment_ids=values["deployment_ids"].replace(",", "\n").splitlines(),
    )
    try:
        platform = add_platform(db, fields)
    except UserError as problem:
        db.rollback()
        context = lti_context(request, db, form=values, problem=problem)
        return render(request, "admin/lti.html", context, problem.status)
    db.commit()
    response = redirect("/admin/lti")
    flash(response, request, "lti.platform_saved", "success", name=platform.name)
    return response


@router.post("/platforms/{platform_id}/remove", dependencies=[CsrfProtected])
def remove_platform(request: Request, platform_id: ObjectId, admin: AdminUser, db: SessionDep):
    platform = db.get(LtiPlatform, platform_id)
    if platform is None:
        raise UserError("error.not_found", status=404)
    name = platform.name
    db.delete(platform)
    db.commit()
    response = redirect("/admin/lti")
    flash(response, request, "lti.platform_removed", "success", name=name)
    return response


@router.post("/registration-link", dependencies=[CsrfProtected])
def make_registration_link(request: Request, admin: AdminUser, db: SessionDep):
    token = new_registration_link(db)
    db.commit()
    link = f"{tool_urls(request)['register']}?token={token}"
    return render(request, "admin/lti.html", lti_context(request, db, registration_link=link))


@router.post("/rotate-key", dependencies=[CsrfProtected])
def rotate_key(request: Request, admin: AdminUser, db: SessionDep):
    key = keys.rotate(db)
    db.commit()
    response = redirect("/admin/lti")
    flash(response, request, "lti.key_rotated", "success", kid=key.kid[:12])
    return response
