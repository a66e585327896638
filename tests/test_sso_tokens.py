"""Issue 31, item 1: single sign-on refuses every bad ID token with a page that says why,
logs nobody in, and never takes an identity from outside a verified ID token of the
discovered issuer (tests/oidc_forger.py crafts the tokens)."""

from __future__ import annotations

from collections.abc import Iterator
from urllib.parse import urlsplit

import httpx
import pytest
from fastapi.testclient import TestClient
from sqlmodel import select

from app.accounts import sso
from app.config import get_settings
from app.db import read_session
from app.models import ExternalIdentity
from tests.loopback import TLS
from tests.oidc_forger import CLIENT_ID, CLIENT_SECRET, VARIANTS, running_forger

# refused before any write; the good one is one insert
# slow: a real OpenID provider served on loopback
pytestmark = [pytest.mark.one_backend, pytest.mark.slow]


@pytest.fixture(scope="module")
def forger() -> Iterator:
    with running_forger() as running:
        yield running


@pytest.fixture
def client(app, forger, monkeypatch) -> TestClient:
    settings = get_settings()
    monkeypatch.setattr(
        settings, "oidc_discovery_url", f"{forger.url}/.well-known/openid-configuration"
    )
    monkeypatch.setattr(settings, "oidc_client_id", CLIENT_ID)
    monkeypatch.setattr(settings, "oidc_client_secret", CLIENT_SECRET)
    monkeypatch.setattr(settings, "oidc_name", "Forger ID")
    sso.provider_client.cache_clear()
    return TestClient(app, follow_redirects=False)


def round_trip(client: TestClient, forger, variant: str, language: str = "en"):
    forger.next_variant = variant
    headers = {"Accept-Language": language}
    start = client.get("/login/sso", headers=headers)
    assert start.status_code == 302
    back = httpx.get(start.headers["location"], verify=TLS).headers["location"]
    parts = urlsplit(back)
    return client.get(f"{parts.path}?{parts.query}", headers=headers)


def logged_in(client: TestClient) -> bool:
    return "gyrolab_session" in client.cookies or client.get("/lab").status_code == 200


def test_a_good_token_logs_in(client, forger):
    forger.subject = "good-person"
    reply = round_trip(client, forger, "good")
    assert reply.status_code in (302, 303) and logged_in(client)


@pytest.mark.parametrize("variant", VARIANTS)
def test_every_bad_id_token_is_refused_with_a_page_that_says_why(client, forger, variant):
    forger.subject = f"victim-{variant}"
    reply = round_trip(client, forger, variant)
    assert reply.status_code == 400, reply.text[:500]
    assert "Sign-in with Forger ID did not work (the ID token" in reply.text
    assert "Traceback" not in reply.text
    assert not logged_in(client)
    with read_session() as db:
        assert db.exec(select(ExternalIdentity).where(
            ExternalIdentity.subject == f"victim-{variant}")).first() is None  # fmt: skip


def test_an_identity_outside_an_id_token_is_never_taken(client, forger):
    """The token response carries no ID token but a `userinfo` naming an LTI platform's
    teacher: refused, nobody logged in (before: logged in as that teacher)."""
    reply = round_trip(client, forger, "no_id_token")
    assert reply.status_code == 400 and "no ID token" in reply.text
    assert not logged_in(client)


def test_the_refusal_speaks_the_users_language(client, forger):
    reply = round_trip(client, forger, "expired", language="zh-CN")
    assert reply.status_code == 400 and '<html lang="zh-CN">' in reply.text


def test_an_lti_platforms_issuer_cannot_log_in_through_single_sign_on(client, forger):
    """Identities of OIDC and LTI share one table: a provider whose issuer is a registered
    LTI platform's would speak for that platform's people (its teachers).  Refused."""
    from app.db import write_session
    from app.models import LtiPlatform

    with write_session() as db:
        db.add(LtiPlatform(name="Same issuer", issuer=forger.url, client_id="c",
                           auth_login_url="https://x/auth", auth_token_url="https://x/token",
                           key_set_url="https://x/jwks"))  # fmt: skip
    forger.subject = "teacher-on-the-platform"
    reply = round_trip(client, forger, "good")
    assert reply.status_code == 400 and "registered for LTI" in reply.text
    assert not logged_in(client)
