"""LTI 1.3: platforms, the tool's keys, launches, contexts, resource links and grade posts.
Every change here needs an Alembic migration (tests check it)."""

from __future__ import annotations

from datetime import datetime

from sqlalchemy import UniqueConstraint
from sqlmodel import Field, SQLModel

from app.models.clock import utcnow


class LtiPlatform(SQLModel, table=True):
    """An LMS registered with GyroLab (by an administrator or by dynamic registration):
    its issuer, the client id it gave GyroLab, its endpoints and its deployments."""

    __tablename__ = "lti_platform"
    __table_args__ = (UniqueConstraint("issuer", "client_id"),)
    id: int | None = Field(default=None, primary_key=True)
    name: str = Field(max_length=200)
    issuer: str = Field(max_length=500, index=True)
    client_id: str = Field(max_length=255)
    auth_login_url: str = Field(max_length=1000)  # the platform's OIDC authorization endpoint
    auth_token_url: str = Field(max_length=1000)  # OAuth 2 token endpoint (services)
    auth_audience: str | None = Field(default=None, max_length=1000)
    key_set_url: str = Field(max_length=1000)  # the platform's JWKS
    deployment_ids: str = Field(default="", max_length=4000)  # one per line
    registered_by: str = Field(default="admin", max_length=16)  # admin | dynamic
    created_at: datetime = Field(default_factory=utcnow)


class LtiKey(SQLModel, table=True):
    """GyroLab's signing keys (RS256): the newest unretired one signs; retired ones stay in
    the JWKS for a while so messages signed just before a rotation still verify."""

    __tablename__ = "lti_key"
    id: int | None = Field(default=None, primary_key=True)
    kid: str = Field(max_length=64, unique=True)
    private_pem: str = Field(max_length=8000)
    public_jwk: str = Field(max_length=4000)
    created_at: datetime = Field(default_factory=utcnow)
    retired_at: datetime | None = None


class LtiLaunchValue(SQLModel, table=True):
    """Short-lived values of the LTI handshake: nonces (used once), state parameters, a
    deep-linking launch's claims while the teacher picks an assignment."""

    __tablename__ = "lti_launch_value"
    key: str = Field(primary_key=True, max_length=200)
    value: str = Field(max_length=200_000)
    expires_at: datetime = Field(index=True)


class LtiContext(SQLModel, table=True):
    """An LMS course (an LTI context) and the GyroLab course it is linked to."""

    __tablename__ = "lti_context"
    __table_args__ = (UniqueConstraint("platform_id", "context_id"),)
    id: int | None = Field(default=None, primary_key=True)
    platform_id: int = Field(foreign_key="lti_platform.id", index=True, ondelete="CASCADE")
    context_id: str = Field(max_length=255)
    course_id: int = Field(foreign_key="course.id", index=True, ondelete="CASCADE")
    title: str = Field(default="", max_length=255)
    memberships_url: str | None = Field(default=None, max_length=1000)  # NRPS
    lineitems_url: str | None = Field(default=None, max_length=1000)  # AGS
    ags_scopes: str = Field(default="", max_length=1000)  # the AGS scopes the LMS granted
    roster_synced_at: datetime | None = None
    roster_problem: str | None = Field(default=None, max_length=500)


class LtiResourceLink(SQLModel, table=True):
    """An activity placed in the LMS (a resource link) and the assignment it opens, with
    the AGS line item its grades go to."""

    __tablename__ = "lti_resource_link"
    __table_args__ = (UniqueConstraint("platform_id", "resource_link_id"),)
    id: int | None = Field(default=None, primary_key=True)
    platform_id: int = Field(foreign_key="lti_platform.id", index=True, ondelete="CASCADE")
    resource_link_id: str = Field(max_length=255)
    context_row_id: int = Field(foreign_key="lti_context.id", index=True, ondelete="CASCADE")
    assignment_id: int | None = Field(
        default=None, foreign_key="assignment.id", index=True, ondelete="CASCADE"
    )
    lineitem_url: str | None = Field(default=None, max_length=1000)
    created_at: datetime = Field(default_factory=utcnow)


class LtiGradePost(SQLModel, table=True):
    """A released grade on its way to the LMS (AGS score): kept until the platform
    acknowledges it, retried with growing pauses, every failure visible to the teacher."""

    __tablename__ = "lti_grade_post"
    id: int | None = Field(default=None, primary_key=True)
    attempt_id: int = Field(foreign_key="attempt.id", index=True, ondelete="CASCADE")
    student_id: int = Field(foreign_key="user.id", index=True, ondelete="CASCADE")
    link_id: int = Field(foreign_key="lti_resource_link.id", index=True, ondelete="CASCADE")
    score: float
    maximum: float
    comment: str = Field(default="", max_length=20_000)
    status: str = Field(default="pending", max_length=8)  # pending | sent
    tries: int = 0
    last_error: str | None = Field(default=None, max_length=500)
    next_try_at: datetime = Field(default_factory=utcnow, index=True)
    created_at: datetime = Field(default_factory=utcnow)
    sent_at: datetime | None = None
