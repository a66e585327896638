"""An OpenID provider on loopback that hands out the ID token a test asks for -- good, or
broken in one of the ways an attacker or a misconfigured provider would break it.

It speaks just enough of OpenID Connect for GyroLab's authorization-code flow: discovery,
JWKS, an authorization endpoint that sends the browser straight back with a code naming
the variant, and a token endpoint that answers with the crafted token.  Tokens are made
with joserfc (RS256 with the provider's key, or what the variant says)."""

from __future__ import annotations

import base64
import json
import threading
import time
from contextlib import contextmanager
from urllib.parse import urlencode

import uvicorn
from joserfc import jwt
from joserfc.jwk import OctKey, RSAKey
from starlette.applications import Starlette
from starlette.requests import Request
from starlette.responses import JSONResponse, RedirectResponse
from starlette.routing import Route

CLIENT_ID = "gyrolab"
CLIENT_SECRET = "gyrolab-secret"
KEY = RSAKey.generate_key(2048, parameters={"kid": "good", "use": "sig"})
OTHER_KEY = RSAKey.generate_key(2048, parameters={"kid": "good", "use": "sig"})

VARIANTS = (
    "alg_none",
    "wrong_key",
    "hs256_client_secret",
    "wrong_iss",
    "wrong_aud",
    "two_aud_no_azp",
    "expired",
    "no_exp",
    "wrong_nonce",
    "no_nonce",
)


def _b64(data: dict) -> str:
    return base64.urlsafe_b64encode(json.dumps(data).encode()).rstrip(b"=").decode()


def make_token(variant: str, issuer: str, nonce: str, subject: str) -> str:
    now = int(time.time())
    claims = {
        "iss": issuer,
        "sub": subject,
        "aud": CLIENT_ID,
        "iat": now,
        "exp": now + 600,
        "nonce": nonce,
        "name": "Forged Person",
    }
    header = {"alg": "RS256", "kid": "good"}
    key = KEY
    if variant == "wrong_iss":
        claims["iss"] = "https://lms.example"  # an LTI platform's issuer, say
    elif variant == "wrong_aud":
        claims["aud"] = "someone-else"
    elif variant == "two_aud_no_azp":
        claims["aud"] = [CLIENT_ID, "someone-else"]
    elif variant == "expired":
        claims["iat"], claims["exp"] = now - 7200, now - 3600
    elif variant == "no_exp":
        del claims["exp"]
    elif variant == "wrong_nonce":
        claims["nonce"] = "not-the-one-sent"
    elif variant == "no_nonce":
        del claims["nonce"]
    elif variant == "wrong_key":
        key = OTHER_KEY
    elif variant == "alg_none":
        return f"{_b64({'alg': 'none', 'typ': 'JWT'})}.{_b64(claims)}."
    elif variant == "hs256_client_secret":
        header = {"alg": "HS256"}
        key = OctKey.import_key(CLIENT_SECRET.encode())
        return jwt.encode(header, claims, key, algorithms=["HS256"])
    return jwt.encode(header, claims, key)


class Forger:
    """The provider's state: the variant of the next token and the nonce it was sent."""

    def __init__(self) -> None:
        self.url = ""
        self.nonces: dict[str, str] = {}
        self.subject = "forged-1"

    def app(self) -> Starlette:
        async def discovery(request: Request):
            return JSONResponse(
                {
                    "issuer": self.url,
                    "authorization_endpoint": f"{self.url}/authorize",
                    "token_endpoint": f"{self.url}/token",
                    "jwks_uri": f"{self.url}/jwks",
                    "response_types_supported": ["code"],
                    "subject_types_supported": ["public"],
                    "id_token_signing_alg_values_supported": ["RS256"],
                }
            )

        async def jwks(request: Request):
            return JSONResponse({"keys": [KEY.as_dict(private=False)]})

        async def authorize(request: Request):
            query = request.query_params
            variant = query.get("login_hint") or self.next_variant
            self.nonces[variant] = query.get("nonce", "")
            back = {"code": variant, "state": query["state"]}
            return RedirectResponse(f"{query['redirect_uri']}?{urlencode(back)}", 302)

        async def token(request: Request):
            form = await request.form()
            variant = str(form["code"])
            answer = {"access_token": "at-" + variant, "token_type": "Bearer", "expires_in": 60}
            if variant == "no_id_token":  # an identity asserted outside any signed token
                answer["userinfo"] = {"iss": "https://lms.example", "sub": "teacher-7"}
            else:
                answer["id_token"] = make_token(
                    variant, self.url, self.nonces.get(variant, ""), self.subject
                )
            return JSONResponse(answer)

        return Starlette(
            routes=[
                Route("/.well-known/openid-configuration", discovery),
                Route("/jwks", jwks),
                Route("/authorize", authorize),
                Route("/token", token, methods=["POST"]),
            ]
        )

    next_variant = "good"


@contextmanager
def running_forger():
    forger = Forger()
    config = uvicorn.Config(forger.app(), host="127.0.0.1", port=0, log_level="error")
    server = uvicorn.Server(config)
    thread = threading.Thread(target=server.run, daemon=True)
    thread.start()
    deadline = time.monotonic() + 20
    while not server.started:
        if time.monotonic() > deadline or not thread.is_alive():
            raise RuntimeError("the forged OpenID provider did not start")
        time.sleep(0.02)
    port = server.servers[0].sockets[0].getsockname()[1]
    forger.url = f"http://127.0.0.1:{port}"
    try:
        yield forger
    finally:
        server.should_exit = True
        thread.join(5)
