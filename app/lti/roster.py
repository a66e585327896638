"""Names and Role Provisioning Services: a linked course's roster from the LMS.

On a teacher's launch (after the response) and on demand ("Sync roster" on the course
page, ``gyrolab lti sync-roster``).  Active learners get accounts without passwords (or
keep theirs, found by ``iss``/``sub``) and are enrolled; active instructors get teacher
accounts.  Members the LMS lists as inactive or deleted are not enrolled; an enrolment
made earlier stays (with its work), for the teacher to remove.  The network round trips
happen before the one write transaction.
"""

from __future__ import annotations

from dataclasses import dataclass

import requests
from pylti1p3.exception import LtiException
from pylti1p3.names_roles import NamesRolesProvisioningService

from app.core.exceptions import UserError
from app.db import read_session, write_session
from app.lti.handshake import service_connector
from app.lti.keys import ensure_key
from app.lti.platforms import registration_of
from app.lti.provisioning import enrol, person, role_of
from app.models import Course, LtiContext, LtiPlatform, Role, utcnow

NRPS_VERSIONS = ["2.0"]
MAX_MEMBERS = 5000


@dataclass
class RosterSync:
    students: int = 0  # active learners now enrolled
    newly_enrolled: int = 0
    teachers: int = 0
    skipped: int = 0  # inactive, deleted or of another role
    problem: str | None = None


def fetch_members(platform_id: int, memberships_url: str) -> list[dict]:
    ensure_key()
    with read_session() as db:
        registration = registration_of(db, db.get(LtiPlatform, platform_id))
    service = NamesRolesProvisioningService(
        service_connector(registration),
        {"context_memberships_url": memberships_url, "service_versions": NRPS_VERSIONS},
    )
    return list(service.get_members())[:MAX_MEMBERS]


def sync_roster(context_row_id: int) -> RosterSync:
    """Fetch the roster and apply it; a failure is recorded on the link and returned."""
    with read_session() as db:
        context = db.get(LtiContext, context_row_id)
        if context is None:
            raise UserError("error.not_found", status=404)
        platform_id, url = context.platform_id, context.memberships_url
    if not url:
        return _record(context_row_id, RosterSync(problem="no NRPS endpoint in the launches"))
    try:
        members = fetch_members(platform_id, url)
    except (LtiException, requests.RequestException, ValueError, KeyError) as error:
        return _record(context_row_id, RosterSync(problem=str(error)[:300] or type(error).__name__))
    outcome = RosterSync()
    with write_session() as db:
        context = db.get(LtiContext, context_row_id)
        platform = db.get(LtiPlatform, context.platform_id)
        course = db.get(Course, context.course_id)
        for member in members:
            role = role_of(member.get("roles") or [])
            if str(member.get("status", "Active")) != "Active" or role is None:
                outcome.skipped += 1
                continue
            try:
                user = person(db, platform, member, role)
            except UserError:  # no user id, or an account of another role
                outcome.skipped += 1
                continue
            if role == Role.teacher or user.role == Role.teacher:
                outcome.teachers += 1
                continue
            outcome.students += 1
            outcome.newly_enrolled += enrol(db, course, user)
        context.roster_synced_at, context.roster_problem = utcnow(), None
        db.add(context)
    return outcome


def _record(context_row_id: int, outcome: RosterSync) -> RosterSync:
    with write_session() as db:
        context = db.get(LtiContext, context_row_id)
        if context is not None:
            context.roster_problem = outcome.problem
            db.add(context)
    return outcome
