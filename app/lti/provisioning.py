"""A verified launch → a GyroLab account, course, enrolment, resource link and the page to
open.  Nothing here talks to the network; the caller commits.

* The person is the platform's ``iss`` and ``sub`` (``ExternalIdentity``): the first
  launch makes an account with no password, named from the LMS; later launches find it.
* Roles: an instructor, teaching assistant, content developer or administrator of the
  LMS course is a teacher; a learner is a student; a mentor (an observer of another
  person: a parent, an advisor) is refused.  No role, or only roles GyroLab does not know,
  gives a learner's rights -- the least there are.
  An existing account keeps its role: a student account launched as an instructor is
  refused rather than promoted.
* The LMS course (context) is linked to one GyroLab course, made by the first teacher who
  launches from it; students are enrolled on their launch (and by roster sync).  A launch
  with no context (a link placed outside any course) stands for its deployment: one
  GyroLab course per deployment, named after the platform.
* A resource link opens the assignment deep linking put into it (custom parameter
  ``gyrolab_assignment``, accepted only for an assignment of the linked course).
"""

from __future__ import annotations

import hashlib
from dataclasses import dataclass

from sqlmodel import Session, select

from app.accounts.sso import account_for
from app.core.exceptions import UserError
from app.core.text_files import shown_name
from app.lab import sessions as labsessions
from app.models import (
    Assignment,
    Course,
    Enrollment,
    LtiContext,
    LtiPlatform,
    LtiResourceLink,
    Role,
    User,
)

CLAIM = "https://purl.imsglobal.org/spec/lti/claim/"
AGS_CLAIM = "https://purl.imsglobal.org/spec/lti-ags/claim/endpoint"
NRPS_CLAIM = "https://purl.imsglobal.org/spec/lti-nrps/claim/namesroleservice"
DEEP_LINKING = "LtiDeepLinkingRequest"
TEACHING_ROLES = {"Instructor", "TeachingAssistant", "ContentDeveloper", "Administrator"}
OBSERVER_ROLES = {"Mentor"}
ASSIGNMENT_PARAMETER = "gyrolab_assignment"


@dataclass
class Landing:
    """Where a launch takes the person (``url``: a session, a dashboard, the page that
    gives a resource link its assignment, or the deep-linking picker)."""

    user: User
    course: Course
    url: str
    context_row_id: int
    teacher: bool


def role_names(roles) -> set[str]:
    """The short names of LIS role URIs (``…/membership#Instructor`` → ``Instructor``)."""
    if not isinstance(roles, list):
        return set()
    return {str(role).rsplit("#", 1)[-1].rsplit("/", 1)[-1] for role in roles}


def role_of(roles: list) -> Role | None:
    """LIS role URIs (or NRPS short names) → teacher, student or None.

    ``http://purl.imsglobal.org/vocab/lis/v2/membership#Instructor`` and
    ``…membership/Instructor#TeachingAssistant`` are teachers, ``…#Learner`` a student.
    """
    names = role_names(roles)
    if names & TEACHING_ROLES:
        return Role.teacher
    if "Learner" in names:
        return Role.student
    return None


def launch_role(roles) -> Role | None:
    """The role a launch gets: ``role_of``, else None for an observer (refused), else a
    student -- a launch with no role or only unknown ones has a learner's rights."""
    role = role_of(roles)
    if role is not None:
        return role
    return None if role_names(roles) & OBSERVER_ROLES else Role.student


def person_claims(platform: LtiPlatform, body: dict) -> dict:
    """The identity claims of a launch (or an NRPS member) in OpenID Connect's names."""
    extension = body.get(CLAIM + "ext") if isinstance(body.get(CLAIM + "ext"), dict) else {}
    given = " ".join(str(body.get(k) or "") for k in ("given_name", "family_name")).strip()
    subject = str(body.get("sub") or body.get("user_id") or "")
    email = body.get("email") if isinstance(body.get("email"), str) else None
    username = extension.get("user_username") or body.get("preferred_username")
    name = body.get("name") or given
    if not name:  # no name: the e-mail's local part, else the platform and a short tag
        local = email.split("@", 1)[0] if email else ""
        tag = hashlib.sha256(subject.encode()).hexdigest()[:6]
        name = username or local or f"{platform.name} · {tag}"
    return {
        "iss": platform.issuer,
        "sub": subject,
        "name": name,
        "email": email,
        "preferred_username": username,
    }


def person(db: Session, platform: LtiPlatform, body: dict, role: Role) -> User:
    claims = person_claims(platform, body)
    if not claims["sub"]:
        raise UserError("lti.no_user", status=400)
    user = account_for(db, claims, role)
    if user.role == Role.admin or (role == Role.teacher and user.role != Role.teacher):
        raise UserError("lti.role_mismatch", status=403)
    return user


def context_of(platform: LtiPlatform, body: dict) -> tuple[str, str]:
    """The LMS course's id and title; with no context claim (a link placed outside any
    course), ``deployment:<id>`` and the platform's name."""
    context = body.get(CLAIM + "context")
    if isinstance(context, dict) and context.get("id"):
        title = shown_name(str(context.get("title") or context.get("label") or ""))[:200]
        return str(context["id"])[:255], title
    deployment = body.get(CLAIM + "deployment_id")
    return f"deployment:{deployment}"[:255], f"{platform.name} · GyroLab"[:200]


def linked_course(
    db: Session, platform: LtiPlatform, body: dict, user: User, role: Role
) -> tuple[Course, LtiContext]:
    context_id, title = context_of(platform, body)
    row = db.exec(
        select(LtiContext).where(
            LtiContext.platform_id == platform.id, LtiContext.context_id == context_id
        )
    ).first()
    if row is None:
        if role != Role.teacher:
            raise UserError("lti.course_not_ready", status=409)
        course = Course(name=title or context_id, teacher_id=user.id)
        db.add(course)
        db.flush()
        row = LtiContext(platform_id=platform.id, context_id=context_id, course_id=course.id)
    course = db.get(Course, row.course_id)
    if role == Role.teacher and user.role == Role.teacher and course.teacher_id != user.id:
        owner = db.get(User, course.teacher_id)
        raise UserError("lti.other_teacher", status=403, owner=owner.display_name)
    row.title = title or row.title
    services = body.get(NRPS_CLAIM) if isinstance(body.get(NRPS_CLAIM), dict) else {}
    grades = body.get(AGS_CLAIM) if isinstance(body.get(AGS_CLAIM), dict) else {}
    if services.get("context_memberships_url"):
        row.memberships_url = str(services["context_memberships_url"])[:1000]
    if grades.get("lineitems"):
        row.lineitems_url = str(grades["lineitems"])[:1000]
    if isinstance(grades.get("scope"), list):
        row.ags_scopes = " ".join(str(scope) for scope in grades["scope"])[:1000]
    db.add(row)
    db.flush()
    return course, row


def enrol(db: Session, course: Course, student: User) -> bool:
    """Enrol ``student`` in ``course``; whether they were not enrolled before."""
    found = db.exec(
        select(Enrollment.id).where(
            Enrollment.course_id == course.id, Enrollment.student_id == student.id
        )
    ).first()
    if found is None:
        db.add(Enrollment(course_id=course.id, student_id=student.id))
    return found is None


def resource_link(
    db: Session, platform: LtiPlatform, context: LtiContext, course: Course, body: dict
) -> LtiResourceLink:
    link_claim = body.get(CLAIM + "resource_link") or {}
    link_id = str(link_claim.get("id") or "")[:255]
    link = db.exec(
        select(LtiResourceLink).where(
            LtiResourceLink.platform_id == platform.id,
            LtiResourceLink.resource_link_id == link_id,
        )
    ).first()
    if link is not None and link.context_row_id != context.id:
        # a link belongs to the LMS course it was placed in: another course's link id
        # would land this person in that course's assignment, outside both rosters
        raise UserError("lti.link_other_context", status=409)
    link = link or LtiResourceLink(
        platform_id=platform.id, resource_link_id=link_id, context_row_id=context.id
    )
    if link.assignment_id is None:
        custom = body.get(CLAIM + "custom") if isinstance(body.get(CLAIM + "custom"), dict) else {}
        link.assignment_id = assignment_in(db, course, custom.get(ASSIGNMENT_PARAMETER))
    grades = body.get(AGS_CLAIM) if isinstance(body.get(AGS_CLAIM), dict) else {}
    if grades.get("lineitem"):
        link.lineitem_url = str(grades["lineitem"])[:1000]
    db.add(link)
    db.flush()
    return link


def assignment_in(db: Session, course: Course, value) -> int | None:
    """The id of an assignment of ``course`` named by ``value``; None for anything else."""
    try:
        assignment = db.get(Assignment, int(str(value)))
    except (TypeError, ValueError, OverflowError):
        return None
    return assignment.id if assignment is not None and assignment.course_id == course.id else None


def land(
    db: Session, platform: LtiPlatform, body: dict, launch_id: str, default_title: str
) -> Landing:
    """Everything a verified launch sets up, and the page it opens."""
    role = launch_role(body.get(CLAIM + "roles"))
    if role is None:
        raise UserError("lti.role_unknown", status=403)
    user = person(db, platform, body, role)
    if user.role == Role.teacher:  # a teacher previewing as a learner still owns the course
        role = Role.teacher
    course, context = linked_course(db, platform, body, user, role)
    if role == Role.student:
        if course.archived:
            raise UserError("lti.course_not_ready", status=409)
        enrol(db, course, user)
    if body.get(CLAIM + "message_type") == DEEP_LINKING:
        if role != Role.teacher:
            raise UserError("lti.teachers_only", status=403)
        return Landing(user, course, f"/lti/deep-link/{launch_id}", context.id, True)
    link = resource_link(db, platform, context, course, body)
    if link.assignment_id is None:
        if role != Role.teacher:
            raise UserError("lti.no_assignment_yet", status=409)
        return Landing(user, course, f"/lti/links/{link.id}", context.id, True)
    if role == Role.teacher:
        url = f"/courses/{course.id}/assignments/{link.assignment_id}"
        return Landing(user, course, url, context.id, True)
    assignment = db.get(Assignment, link.assignment_id)
    session, _created = labsessions.start_session(
        db, user, labsessions.SessionSettings(), assignment, default_title
    )
    db.flush()
    return Landing(user, course, f"/lab/sessions/{session.id}", context.id, False)
