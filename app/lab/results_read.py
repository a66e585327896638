"""The hot read path: a device or script polling ``GET /api/v1/sessions/{id}/results``
with a bearer token, answered from the result cache in two small Core queries.

1. One query finds the live token, its owner, the session, whether the owner may read it
   (owner or lab partner) and every column the result depends on (the session's and its
   assignment's) -- the token is checked on every request, so a revoked token or a
   changed password (which revokes them) is refused at once;
2. the token's per-minute rate is admitted from its in-memory lease (a database write
   once per lease, ``accounts.rate_leases``);
3. one query reads the current takes' key columns; their digest with (1) is the result
   cache's key (``lab.result_cache``), and a hit is the REST body, serialised once.

The statements are built once (bound parameters), so no SQL expression is built or
compiled per request, and no ORM object is loaded.  Anything else -- a cookie caller, a
bad or rate-limited token, someone else's session, a result not yet solved -- returns
None, and the caller takes the general path, which answers it (with the right error).
"""

from __future__ import annotations

from sqlalchemy import and_, bindparam, exists, or_, select

from app.accounts.rate_leases import LEASES, lease_statement
from app.db import get_engine, reader, statement_session
from app.lab.result_cache import CACHE, KEY_COLUMNS, NOT_IN_RESULTS, CachedResults, digest_rows
from app.models import ApiToken, Assignment, LabSession, SessionMember, Take, User, utcnow
from app.web.signing import token_digest

READ_SCOPE = "read"


def _result_columns(model) -> list:
    return [c for c in model.__table__.columns if c.name not in NOT_IN_RESULTS]


SESSION_COLUMNS = _result_columns(LabSession)
ASSIGNMENT_COLUMNS = _result_columns(Assignment)
_member = exists().where(
    SessionMember.session_id == LabSession.id, SessionMember.user_id == User.id
)
CALLER_AND_SESSION = (
    select(
        ApiToken.id.label("token_id"),
        ApiToken.scopes,
        User.must_change_password,
        or_(LabSession.owner_id == User.id, _member).label("member"),
        Assignment.id.label("assignment_present"),
        *[c.label(f"s_{c.name}") for c in SESSION_COLUMNS],
        *[c.label(f"a_{c.name}") for c in ASSIGNMENT_COLUMNS],
    )
    .select_from(ApiToken)
    .join(User, User.id == ApiToken.user_id)
    .join(LabSession, LabSession.id == bindparam("session_id"))
    .outerjoin(Assignment, Assignment.id == LabSession.assignment_id)
    .where(
        ApiToken.token_hash == bindparam("digest"),
        ApiToken.revoked_at.is_(None),
        or_(ApiToken.expires_at.is_(None), ApiToken.expires_at > bindparam("now")),
    )
)
TAKE_KEYS = (
    select(*KEY_COLUMNS)
    .where(and_(Take.session_id == bindparam("session_id"), Take.superseded_at.is_(None)))
    .order_by(Take.part, Take.position)
)


def _token_leaser(token_id: int):
    """Lease requests of the token's window in a short statement of its own (the same
    write ``accounts.tokens.check_token`` makes)."""

    def lease(size: int, now):
        with statement_session() as db:
            statement = lease_statement(ApiToken, token_id, size, now).values(last_used_at=now)
            counted = db.execute(statement).first()
            db.commit()
        return None if counted is None else (counted.window_start, counted.window_count)

    return lease


def cached_results_for_token(
    authorization: str, session_id: int, rate_per_minute: int
) -> CachedResults | None:
    """The cached results of ``session_id`` for a bearer token allowed to read it, or
    None when this path cannot answer (see the module's docstring)."""
    if authorization[:7].lower() != "bearer ":
        return None
    digest = token_digest(authorization[7:].strip())
    with reader(get_engine()).connect() as connection:
        row = connection.execute(
            CALLER_AND_SESSION, {"digest": digest, "session_id": session_id, "now": utcnow()}
        ).first()
        if (
            row is None
            or row.must_change_password
            or not row.member
            or READ_SCOPE not in row.scopes.split(",")
        ):
            return None
        takes = connection.execute(TAKE_KEYS, {"session_id": session_id}).all()
    session_row = tuple(getattr(row, f"s_{c.name}") for c in SESSION_COLUMNS)
    assignment_row = (
        tuple(getattr(row, f"a_{c.name}") for c in ASSIGNMENT_COLUMNS)
        if row.assignment_present is not None
        else ()
    )
    entry = CACHE.get(digest_rows(takes, session_row, assignment_row))
    if entry is None:
        return None
    if not LEASES.admit(digest, rate_per_minute, _token_leaser(row.token_id)).admitted:
        return None  # the general path admits again and answers 429 with its wait
    return entry
