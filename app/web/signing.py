"""Signed cookie values and token digests: what every layer above uses to hand out and
check a secret without storing it in the clear."""

from __future__ import annotations

import hashlib
import hmac

from itsdangerous import BadSignature, URLSafeSerializer


def token_digest(token: str) -> str:
    return hashlib.sha256(token.encode()).hexdigest()


def tokens_match(expected: str | None, given: str | None) -> bool:
    return bool(expected) and bool(given) and hmac.compare_digest(expected, given)


def signer(secret: str, purpose: str) -> URLSafeSerializer:
    """Signs small JSON values for cookies (itsdangerous); ``purpose`` is the salt, so a
    value signed for one cookie is never accepted by another."""
    return URLSafeSerializer(secret, salt=f"gyrolab-{purpose}")


def signed(value: object, secret: str, purpose: str) -> str:
    return signer(secret, purpose).dumps(value)


def unsigned(cookie: str | None, secret: str, purpose: str) -> object | None:
    """The signed value, or None when the cookie is missing, altered or for another use."""
    if not cookie:
        return None
    try:
        return signer(secret, purpose).loads(cookie)
    except BadSignature:
        return None
