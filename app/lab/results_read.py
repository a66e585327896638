"""The hot read path: a device or script polling ``GET /api/v1/sessions/{id}/results``
with a bearer token, answered from the result cache in two selects on one snapshot.

1. One select finds the live token, its owner, the session, whether the owner may read it
   (owner or lab partner) and every column the result depends on (the session's and its
   assignment's) -- the token is checked on every request, so a revoked token or a
   changed password (which revokes them) is refused at once;
2. one select reads the current takes' key columns; their digest with (1) is the result
   cache's key (``lab.result_cache``), and a hit is the REST body, serialised once;
3. the token's per-minute rate is admitted from its in-memory lease (an ``UPDATE``
   once per lease, ``accounts.rate_leases``).

The statements are compiled once (bound parameters) and run on a pooled driver connection
(``app.prepared``), so no SQL expression is built, compiled or cache-keyed per request,
and no ORM object is loaded.  Anything else -- a cookie caller, a bad or rate-limited
token, someone else's session, a result not yet solved -- returns None, and the caller
takes the general path, which answers it (with the right error).
"""

from __future__ import annotations

from sqlalchemy import and_, bindparam, exists, or_, select

from app.accounts.rate_leases import LEASES, lease_parameters, lease_update
from app.db import get_engine
from app.lab.result_cache import CACHE, KEY_COLUMNS, NOT_IN_RESULTS, CachedResults, digest_rows
from app.models import ApiToken, Assignment, LabSession, SessionMember, Take, User, utcnow
from app.prepared import Prepared, driver_transaction
from app.web.signing import token_digest

READ_SCOPE = "read"


def _result_columns(model) -> list:
    return [c for c in model.__table__.columns if c.name not in NOT_IN_RESULTS]


SESSION_COLUMNS = _result_columns(LabSession)
ASSIGNMENT_COLUMNS = _result_columns(Assignment)
_member = exists().where(
    SessionMember.session_id == LabSession.id, SessionMember.user_id == User.id
)
CALLER = (
    ApiToken.id.label("token_id"),
    ApiToken.scopes,
    User.must_change_password,
    or_(LabSession.owner_id == User.id, _member).label("member"),
    Assignment.id.label("assignment_present"),
)
SESSION_AT = len(CALLER)  # a row: the caller's columns, the session's, the assignment's
ASSIGNMENT_AT = SESSION_AT + len(SESSION_COLUMNS)
CALLER_AND_SESSION = Prepared(
    select(
        *CALLER,
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
TAKE_KEYS = Prepared(
    select(*KEY_COLUMNS)
    .where(and_(Take.session_id == bindparam("session_id"), Take.superseded_at.is_(None)))
    .order_by(Take.part, Take.position)
)
LEASE_AND_TOUCH = Prepared(lease_update(ApiToken).values(last_used_at=bindparam("now")))


def _token_leaser(token_id: int):
    """Lease requests of the token's window in a short statement of its own (the same
    write ``accounts.tokens.check_token`` makes)."""

    def lease(size: int, now):
        counted = LEASE_AND_TOUCH.first(get_engine(), **lease_parameters(token_id, size, now))
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
    with driver_transaction(get_engine(), snapshot=True) as transaction:
        row = transaction.first(
            CALLER_AND_SESSION, digest=digest, session_id=session_id, now=utcnow()
        )
        if (
            row is None
            or row.must_change_password
            or not row.member
            or READ_SCOPE not in row.scopes.split(",")
        ):
            return None
        takes = transaction.rows(TAKE_KEYS, session_id=session_id)
    session_row = row[SESSION_AT:ASSIGNMENT_AT]
    assignment_row = row[ASSIGNMENT_AT:] if row.assignment_present is not None else ()
    entry = CACHE.get(digest_rows(takes, session_row, assignment_row))
    if entry is None:
        return None
    if not LEASES.admit(digest, rate_per_minute, _token_leaser(row.token_id)).admitted:
        return None  # the general path admits again and answers 429 with its wait
    return entry
