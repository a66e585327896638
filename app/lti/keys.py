"""GyroLab's signing keys for LTI: RS256 key pairs in the database, published at
``/lti/jwks.json``.

The newest unretired key signs (deep-linking responses, service-token requests).
``rotate()`` makes a new key and retires the old ones; a retired key stays in the JWKS
for ``KEEP_RETIRED`` so a platform that cached the old set, or a message signed just
before the rotation, still verifies; after that it is dropped.
"""

from __future__ import annotations

import json
from datetime import timedelta

from jwcrypto.jwk import JWK
from sqlmodel import Session, col, select

from app.models import LtiKey, utcnow

KEY_BITS = 2048
KEEP_RETIRED = timedelta(days=7)


def new_key() -> LtiKey:
    """A fresh RSA key pair; its ``kid`` is the RFC 7638 thumbprint of the public key."""
    pair = JWK.generate(kty="RSA", size=KEY_BITS)
    kid = pair.thumbprint()
    public = json.loads(pair.export_public())
    public.update({"kid": kid, "alg": "RS256", "use": "sig"})
    private_pem = pair.export_to_pem(private_key=True, password=None).decode()
    return LtiKey(kid=kid, private_pem=private_pem, public_jwk=json.dumps(public))


def signing_key(db: Session) -> LtiKey:
    """The key that signs now (``ensure_key`` makes the first)."""
    key = db.exec(
        select(LtiKey).where(col(LtiKey.retired_at).is_(None)).order_by(col(LtiKey.id).desc())
    ).first()
    if key is None:
        raise LookupError("GyroLab has no LTI signing key yet")
    return key


def ensure_key() -> None:
    """Make the first signing key if there is none (its own transaction)."""
    from app.db import read_session, write_session

    with read_session() as db:
        if db.exec(select(LtiKey.id).where(col(LtiKey.retired_at).is_(None))).first():
            return
    with write_session() as db:
        if not db.exec(select(LtiKey.id).where(col(LtiKey.retired_at).is_(None))).first():
            db.add(new_key())


def public_pem(key: LtiKey) -> str:
    return JWK.from_json(key.public_jwk).export_to_pem().decode()


def rotate(db: Session) -> LtiKey:
    """A new signing key; the old ones retired (kept in the JWKS for ``KEEP_RETIRED``)."""
    now = utcnow()
    for old in db.exec(select(LtiKey).where(col(LtiKey.retired_at).is_(None))):
        old.retired_at = now
        db.add(old)
    key = new_key()
    db.add(key)
    cutoff = now - KEEP_RETIRED
    for stale in db.exec(select(LtiKey).where(col(LtiKey.retired_at) < cutoff)):
        db.delete(stale)
    db.flush()
    return key


def jwks(db: Session) -> dict:
    """The public keys a platform may see signatures of: the current and recently retired."""
    cutoff = utcnow() - KEEP_RETIRED
    rows = db.exec(
        select(LtiKey)
        .where(col(LtiKey.retired_at).is_(None) | (col(LtiKey.retired_at) >= cutoff))
        .order_by(col(LtiKey.id).desc())
    ).all()
    return {"keys": [json.loads(row.public_jwk) for row in rows]}
