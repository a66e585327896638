"""A real LTI 1.3 platform on loopback for the tests, built on ``lti1p3platform`` (the
platform side from the package registry): it signs id_tokens with its own RSA key, issues
service tokens only for a client assertion that verifies against GyroLab's published
JWKS, and checks deep-linking responses against the same keys.  Around it, what an LMS
keeps: its users, one course, the resource links deep linking made, line items and the
scores received, plus dials the tests turn to make it misbehave (tamper with a claim, sign
with a forged key, fail score posts).

Served by uvicorn in a thread (``running_platform``); a test plays the browser with an
httpx client (``Browser``), following redirects and submitting the auto-posting forms.
"""

from __future__ import annotations

import asyncio
import functools
import html
import json
import re
import socket
import threading
import time
import urllib.request
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from http.cookiejar import CookieJar, DefaultCookiePolicy
from urllib.parse import urlencode

import httpx
import jwt
import uvicorn
from cryptography.hazmat.primitives import serialization
from cryptography.hazmat.primitives.asymmetric import rsa
from fastapi import FastAPI, Request
from fastapi.responses import HTMLResponse, JSONResponse, RedirectResponse, Response
from lti1p3platform.ltiplatform import LTI1P3PlatformConfAbstract
from lti1p3platform.message_launch import LTIAdvantageMessageLaunchAbstract
from lti1p3platform.oidc_login import OIDCLoginAbstract
from lti1p3platform.registration import Registration

from tests.loopback import TLS

CLIENT_ID = "gyrolab-client"
DEPLOYMENT_ID = "deployment-1"
CONTEXT_ID = "physics-201"
LIS = "http://purl.imsglobal.org/vocab/lis/v2/membership#"
NRPS_SCOPE = "https://purl.imsglobal.org/spec/lti-nrps/scope/contextmembership.readonly"
SCORE_SCOPE = "https://purl.imsglobal.org/spec/lti-ags/scope/score"
LINEITEM_SCOPES = [
    "https://purl.imsglobal.org/spec/lti-ags/scope/lineitem",
    "https://purl.imsglobal.org/spec/lti-ags/scope/lineitem.readonly",
]
USERS = {
    "teacher-1": {
        "name": "Prof. Wang 王教授",
        "email": "wang@uni.example",
        "roles": [LIS + "Instructor"],
    },
    "student-1": {"name": "Li Wei 李伟", "email": "liwei@uni.example", "roles": [LIS + "Learner"]},
    "student-2": {"name": "Zhao Min", "email": "zhao@uni.example", "roles": [LIS + "Learner"]},
    "student-3": {"name": "Sun Li", "email": "sun@uni.example", "roles": [LIS + "Learner"]},
    "observer-1": {"name": "A Parent", "email": "parent@example", "roles": [LIS + "Mentor"]},
}


def new_private_key() -> str:
    key = rsa.generate_private_key(public_exponent=65537, key_size=2048)
    return key.private_bytes(
        serialization.Encoding.PEM,
        serialization.PrivateFormat.PKCS8,
        serialization.NoEncryption(),
    ).decode()


@functools.cache
def platform_key() -> str:
    """The platform's own key, one per test process (a 2048-bit key costs ~70 ms to make
    and as much again each time a library loads it; ``forge`` still signs with a new one)."""
    return new_private_key()


@functools.cache
def loaded_key(private_pem: str) -> rsa.RSAPrivateKey:
    """A private key loaded once (loading checks the key: ~30 ms for 2048 bits)."""
    return serialization.load_pem_private_key(private_pem.encode(), None)


@functools.cache
def public_of(private_pem: str) -> str:
    return (
        loaded_key(private_pem)
        .public_key()
        .public_bytes(serialization.Encoding.PEM, serialization.PublicFormat.SubjectPublicKeyInfo)
        .decode()
    )


@functools.cache
def _jwk_of(pem: str) -> tuple:
    return tuple(Registration.get_jwk(pem).items())


class PlatformRegistration(Registration):
    """lti1p3platform's registration, signing with the platform's key loaded once: the
    library loads the PEM again for every token it signs and for every key id it names."""

    def get_jwks(self) -> list[dict]:
        public_key = self.get_platform_public_key()
        return [dict(_jwk_of(public_key))] if public_key else []

    def get_kid(self) -> str | None:
        private_key = self.get_platform_private_key()
        return dict(_jwk_of(private_key)).get("kid") if private_key else None

    def platform_encode_and_sign(self, payload: dict, expiration: int | None = None) -> str:
        if expiration:
            payload.update({"iat": int(time.time()), "exp": int(time.time()) + expiration})
        key = loaded_key(self.get_platform_private_key())
        return jwt.encode(payload, key, algorithm="RS256", headers={"kid": self.get_kid()})


@dataclass
class PlatformState:
    """What the LMS holds and the tests' dials."""

    url: str
    tool_url: str
    private_key: str = field(default_factory=platform_key)
    links: dict[str, dict] = field(default_factory=dict)  # resource link id → content item
    lineitems: dict[str, dict] = field(default_factory=dict)
    scores: list[dict] = field(default_factory=list)
    members_inactive: tuple[str, ...] = ("gone-1",)
    tamper: Callable[[dict], dict] | None = None  # edits the claims before signing
    forge: bool = False  # sign with a key that is not the platform's, under its kid
    expires_in: int = 300
    fail_scores: int = 0  # answer this many score posts with 503
    last_id_token: str | None = None
    tokens_issued: int = 0
    refusals: list[str] = field(default_factory=list)  # why token requests were refused
    registration_token: str = "registration-token-1"  # what the LMS admin's page hands out
    registered: dict | None = None  # the tool configuration GyroLab sent (dynamic registration)
    storage_target: str | None = None  # offer platform storage (LTI Client Side OIDC Launch)

    @property
    def registration(self) -> Registration:
        return (
            PlatformRegistration()
            .set_iss(self.url)
            .set_client_id(CLIENT_ID)
            .set_deployment_id(DEPLOYMENT_ID)
            .set_launch_url(f"{self.tool_url}/lti/launch")
            .set_deeplink_launch_url(f"{self.tool_url}/lti/launch")
            .set_oidc_login_url(f"{self.tool_url}/lti/login")
            .set_tool_key_set_url(f"{self.tool_url}/lti/jwks.json")
            .set_platform_public_key(public_of(self.private_key))
            .set_platform_private_key(self.private_key)
        )

    def platform_fields(self) -> dict:
        """What a GyroLab administrator types in to register this platform."""
        return {
            "name": "Test LMS",
            "issuer": self.url,
            "client_id": CLIENT_ID,
            "auth_login_url": f"{self.url}/authorize",
            "auth_token_url": f"{self.url}/token",
            "key_set_url": f"{self.url}/jwks",
            "deployment_ids": DEPLOYMENT_ID,
        }


def register_with_cli(server, platform: PlatformState) -> None:
    """Register ``platform`` with a running GyroLab (``tests.e2e.conftest.LiveServer``)
    the way an administrator does: ``gyrolab lti add-platform``."""
    fields = platform.platform_fields()
    server.gyrolab(
        "lti", "add-platform",
        "--name", fields["name"],
        "--issuer", fields["issuer"],
        "--client-id", fields["client_id"],
        "--login-url", fields["auth_login_url"],
        "--token-url", fields["auth_token_url"],
        "--jwks-url", fields["key_set_url"],
        "--deployment", fields["deployment_ids"],
    )  # fmt: skip


class PlatformConf(LTI1P3PlatformConfAbstract):
    def init_platform_config(self, state: PlatformState) -> None:
        self._registration = state.registration

    def get_registration_by_params(self, **kwargs) -> Registration:
        return self._registration


class StartLogin(OIDCLoginAbstract):
    storage_target: str | None = None

    def set_lti_message_hint(self, **kwargs) -> None:
        self._lti_message_hint = json.dumps(kwargs)

    def get_redirect(self, url: str) -> RedirectResponse:
        if self.storage_target:
            url += "&" + urlencode({"lti_storage_target": self.storage_target})
        return RedirectResponse(url, status_code=302)


class PlatformLaunch(LTIAdvantageMessageLaunchAbstract):
    """The launch the platform sends back to the tool's redirect URI."""

    def __init__(self, request_params: dict, conf: PlatformConf, state: PlatformState):
        super().__init__(None, conf)
        self.params, self.state = request_params, state

    def get_preflight_response(self) -> dict:
        return self.params

    def generate_launch_request(self):
        launch = super().generate_launch_request()
        if self.state.tamper or self.state.forge:  # edit the signed claims, sign again
            claims = jwt.decode(launch["id_token"], options={"verify_signature": False})
            kid = jwt.get_unverified_header(launch["id_token"])["kid"]
            if self.state.tamper:
                claims = self.state.tamper(claims)
            key = new_private_key() if self.state.forge else loaded_key(self.state.private_key)
            launch["id_token"] = jwt.encode(claims, key, algorithm="RS256", headers={"kid": kid})
        self.state.last_id_token = launch["id_token"]
        return launch

    def render_launch_form(self, launch_data: dict, **kwargs) -> HTMLResponse:
        fields = {"id_token": launch_data["id_token"], "state": launch_data["state"]}
        if self.state.storage_target:
            fields["lti_storage_target"] = self.state.storage_target
        return HTMLResponse(auto_post_form(launch_data["launch_url"], fields))


PLATFORM_STORAGE_SCRIPT = """
const stored = {};
window.platformStorageCalls = [];
window.addEventListener("message", (event) => {
  const data = event.data || {};
  window.platformStorageCalls.push(data.subject);
  const mine = (stored[event.origin] = stored[event.origin] || {});
  const reply = { subject: data.subject + ".response", message_id: data.message_id, key: data.key };
  if (data.subject === "lti.put_data") { mine[data.key] = data.value; reply.value = data.value; }
  else if (data.subject === "lti.get_data") {
    if (data.key in mine) { reply.value = mine[data.key]; }
    else { reply.error = { code: "bad_request", message: "no value for this key" }; }
  } else { return; }
  event.source.postMessage(reply, event.origin);
});
"""


def auto_post_form(url: str, fields: dict[str, str]) -> str:
    inputs = "".join(
        f'<input type="hidden" name="{html.escape(k)}" value="{html.escape(v)}">'
        for k, v in fields.items()
    )
    return (
        f'<!doctype html><html><body><form id="post" method="post" action="{html.escape(url)}">'
        f'{inputs}<button type="submit">Continue</button></form>'
        '<script>document.getElementById("post").submit()</script></body></html>'
    )


def bearer_ok(request: Request, conf: PlatformConf, scopes: list[str]) -> bool:
    header = request.headers.get("authorization", "")
    if not header.lower().startswith("bearer "):
        return False
    try:
        return conf.validate_token(header.split(" ", 1)[1], allowed_scopes=scopes)
    except Exception:  # noqa: BLE001 -- any bad token is a 401
        return False


def create_platform_app(state: PlatformState) -> FastAPI:
    app = FastAPI()

    def conf() -> PlatformConf:
        return PlatformConf(state=state)

    @app.get("/start")
    def start(user: str, kind: str = "link", link: str = "link-1"):
        """A user of the LMS clicks GyroLab: a resource link, or "add activity" (deep)."""
        login = StartLogin(None, conf())
        login.storage_target = state.storage_target
        login.set_lti_message_hint(user=user, kind=kind, link=link)
        if kind == "deep":
            login.set_deeplinking_launch_url()
        return login.initiate_login(user)

    @app.get("/course")
    def course_page(user: str, kind: str = "link", link: str = "link-1"):
        """The LMS's course page: GyroLab in a frame, and (with ``storage_target``) the
        platform storage of the LTI Client Side OIDC Launch -- values kept per origin."""
        start = f"/start?{urlencode({'user': user, 'kind': kind, 'link': link})}"
        script = PLATFORM_STORAGE_SCRIPT if state.storage_target else ""
        return HTMLResponse(
            "<!doctype html><html><head><title>Physics 201 · LMS</title></head><body>"
            f"<h1>Physics 201</h1><iframe id='tool' name='tool' src='{html.escape(start)}' "
            "style='width:900px;height:600px' title='GyroLab'></iframe>"
            f"<script>{script}</script></body></html>"
        )

    @app.get("/authorize")
    def authorize(request: Request):
        params = dict(request.query_params)
        if params.get("redirect_uri") != f"{state.tool_url}/lti/launch":
            return JSONResponse({"error": "invalid redirect_uri"}, 400)
        hint = json.loads(params.get("lti_message_hint") or "{}")
        user = hint.get("user") or params.get("login_hint")
        profile = USERS[user]
        launch = PlatformLaunch(params, conf(), state)
        launch.set_id_token_expiration(state.expires_in)
        launch.set_user_data(user, profile["roles"], profile["name"], profile["email"])
        launch.set_launch_context_claim(
            CONTEXT_ID,
            [LIS.replace("membership#", "course#") + "CourseOffering"],
            "Physics 201 物理实验",
            "PHYS201",
        )
        launch.set_nrps(f"{state.url}/nrps/{CONTEXT_ID}")
        if hint.get("kind") == "deep":
            launch.set_dl(f"{state.url}/deep-link-return", title="GyroLab")
        else:
            item = state.links.get(hint["link"], {})
            launch.set_resource_link_claim(hint["link"], title=item.get("title"))
            launch.set_custom_parameters_claim(item.get("custom", {}))
            launch.set_ags(
                f"{state.url}/ags/{CONTEXT_ID}/lineitems",
                item.get("lineitem"),
            )
        return launch.lti_launch()

    @app.get("/.well-known/openid-configuration")
    def openid_configuration():
        """The platform's configuration for LTI Dynamic Registration."""
        return {
            "issuer": state.url,
            "authorization_endpoint": f"{state.url}/authorize",
            "token_endpoint": f"{state.url}/token",
            "jwks_uri": f"{state.url}/jwks",
            "registration_endpoint": f"{state.url}/register",
            "https://purl.imsglobal.org/spec/lti-platform-configuration": {
                "product_family_code": "lti1p3platform-test",
                "version": "0.1.8",
                "messages_supported": [{"type": "LtiResourceLinkRequest"}],
            },
        }

    @app.post("/register")
    async def register(request: Request):
        if request.headers.get("authorization") != f"Bearer {state.registration_token}":
            return JSONResponse({"error": "invalid registration token"}, 401)
        body = json.loads(await request.body())
        tool = body.get("https://purl.imsglobal.org/spec/lti-tool-configuration") or {}
        if body.get("initiate_login_uri") != f"{state.tool_url}/lti/login" or not tool:
            return JSONResponse({"error": "invalid tool configuration"}, 400)
        state.registered = body
        answer = {**body, "client_id": "dyn-client"}
        answer["https://purl.imsglobal.org/spec/lti-tool-configuration"] = {
            **tool,
            "deployment_id": "dyn-deployment",
        }
        return answer

    @app.get("/jwks")
    def jwks():
        return {"keys": state.registration.get_jwks()}

    @app.post("/token")
    async def token(request: Request):
        form = {k: str(v) for k, v in (await request.form()).items()}
        platform = conf()
        try:
            answer = platform.get_access_token(form)
        except Exception as error:  # noqa: BLE001 -- refused assertion
            state.refusals.append(f"{type(error).__name__}: {error}")
            return JSONResponse({"error": "invalid_client", "detail": str(error)}, 400)
        state.tokens_issued += 1
        return answer

    @app.post("/deep-link-return")
    async def deep_link_return(request: Request):
        form = {k: str(v) for k, v in (await request.form()).items()}
        try:
            items = conf().validate_deeplinking_resp(form)
        except Exception as error:  # noqa: BLE001
            return HTMLResponse(f"refused: {html.escape(str(error))}", 400)
        for item in items:
            link_id = f"link-{len(state.links) + 1}"
            entry = {"title": item.get("title"), "custom": item.get("custom", {})}
            if "lineItem" in item:
                entry["lineitem"] = new_lineitem(
                    state, {**item["lineItem"], "resourceLinkId": link_id}
                )
            state.links[link_id] = entry
        return HTMLResponse(f"added {len(items)}: {html.escape(json.dumps(list(state.links)))}")

    @app.get("/nrps/{context_id}")
    def memberships(request: Request, context_id: str):
        if not bearer_ok(request, conf(), [NRPS_SCOPE]):
            return JSONResponse({"error": "unauthorized"}, 401)
        members = [
            {
                "user_id": uid,
                "name": u["name"],
                "email": u["email"],
                "status": "Active",
                "roles": u["roles"],
            }
            for uid, u in USERS.items()
        ] + [
            {"user_id": uid, "status": "Inactive", "roles": [LIS + "Learner"]}
            for uid in state.members_inactive
        ]
        body = {"id": str(request.url), "context": {"id": context_id}, "members": members}
        return JSONResponse(
            body, media_type="application/vnd.ims.lti-nrps.v2.membershipcontainer+json"
        )

    @app.get("/ags/{context_id}/lineitems")
    def lineitems(request: Request, context_id: str):
        if not bearer_ok(request, conf(), LINEITEM_SCOPES):
            return JSONResponse({"error": "unauthorized"}, 401)
        return JSONResponse(list(state.lineitems.values()))

    @app.post("/ags/{context_id}/lineitems")
    async def create_lineitem(request: Request, context_id: str):
        if not bearer_ok(request, conf(), LINEITEM_SCOPES):
            return JSONResponse({"error": "unauthorized"}, 401)
        url = new_lineitem(state, json.loads(await request.body()))
        return JSONResponse(state.lineitems[url], 201)

    @app.post("/ags/{context_id}/lineitems/{item}/scores")
    async def score(request: Request, context_id: str, item: str):
        if not bearer_ok(request, conf(), [SCORE_SCOPE]):
            return JSONResponse({"error": "unauthorized"}, 401)
        if state.fail_scores > 0:
            state.fail_scores -= 1
            return Response("busy", 503)
        lineitem_url = f"{state.url}/ags/{context_id}/lineitems/{item}"
        if lineitem_url not in state.lineitems:
            return JSONResponse({"error": "no such line item"}, 404)
        state.scores.append({"lineitem": lineitem_url, **json.loads(await request.body())})
        return Response(status_code=204)

    return app


def new_lineitem(state: PlatformState, fields: dict) -> str:
    url = f"{state.url}/ags/{CONTEXT_ID}/lineitems/{len(state.lineitems) + 1}"
    state.lineitems[url] = {**fields, "id": url}
    return url


class _PromptServer(uvicorn.Server):
    """uvicorn that notices ``should_exit`` within 5 ms (uvicorn's own loop ticks every
    0.1 s, and two servers stopped one after the other cost each LTI test 0.4 s)."""

    async def main_loop(self) -> None:
        while not self.should_exit:
            await asyncio.sleep(0.005)


def bound_socket() -> socket.socket:
    """A loopback socket bound to a port of the kernel's choosing, held until served.

    Two ``free_port()`` calls in a row once returned the same port, and the second server
    failed with ``[Errno 98] Address already in use``; a port held from the moment it is
    chosen cannot be taken by anyone else."""
    sock = socket.socket()
    sock.bind(("127.0.0.1", 0))
    return sock


def url_of(sock: socket.socket) -> str:
    return f"http://127.0.0.1:{sock.getsockname()[1]}"


@contextmanager
def serving(*apps_and_sockets) -> Iterator[None]:
    """ASGI apps served by uvicorn, each in a thread on its bound socket, stopped together:
    ``serving(app, sock)`` or ``serving(app_a, sock_a, app_b, sock_b)``."""
    pairs = list(zip(apps_and_sockets[::2], apps_and_sockets[1::2], strict=True))
    running: list[tuple[uvicorn.Server, threading.Thread]] = []
    try:
        for app, sock in pairs:
            server = _PromptServer(uvicorn.Config(app, log_level="warning"))
            thread = threading.Thread(target=server.run, kwargs={"sockets": [sock]}, daemon=True)
            thread.start()
            running.append((server, thread))
        deadline = time.monotonic() + 20
        for server, thread in running:
            while not server.started:
                if time.monotonic() > deadline or not thread.is_alive():
                    raise RuntimeError("server did not start")
                time.sleep(0.005)
        yield
    finally:
        for server, _thread in running:
            server.should_exit = True
        for _server, thread in running:
            thread.join(10)
        for _app, sock in pairs:
            sock.close()


class Browser:
    """A person's browser, played by httpx: cookies, redirects, auto-posting forms."""

    FORM = re.compile(r'<form[^>]*method="post"[^>]*action="([^"]+)"', re.I)
    FIELD = re.compile(r'<input type="hidden" name="([^"]+)" value="([^"]*)"', re.I)

    def __init__(self, headers: dict | None = None):
        # like a browser, count loopback as a secure context: Secure cookies go over http
        # (httpx copies its jar into one with the default policy for each request, so the
        # Cookie header is made here, from this jar, with this policy)
        self.jar = CookieJar(DefaultCookiePolicy(secure_protocols=("https", "wss", "http")))
        self.client = httpx.Client(
            follow_redirects=True,
            timeout=20,
            verify=TLS,
            headers=headers or {},
            cookies=self.jar,
            event_hooks={"request": [self._cookie_header]},
        )

    def _cookie_header(self, request: httpx.Request) -> None:
        compatible = urllib.request.Request(str(request.url), method=request.method)
        self.jar.add_cookie_header(compatible)
        header = compatible.get_header("Cookie")
        if header:
            request.headers["Cookie"] = header

    def get(self, url: str) -> httpx.Response:
        return self.client.get(url)

    def submit_auto_form(self, page: httpx.Response, extra: dict | None = None) -> httpx.Response:
        """Post the page's first form with its hidden fields (what its script would do)."""
        actions = [a for a in self.FORM.findall(page.text) if a not in ("/lang", "/logout")]
        action = html.unescape(actions[0])
        fields = {k: html.unescape(v) for k, v in self.FIELD.findall(page.text)}
        return self.client.post(
            httpx.URL(str(page.url)).join(action), data={**fields, **(extra or {})}
        )

    @staticmethod
    def data(page: httpx.Response, name: str) -> str | None:
        found = re.search(rf'data-{name}="([^"]*)"', page.text)
        return html.unescape(found.group(1)) if found else None

    def framed_login(self, page: httpx.Response) -> httpx.Response:
        """GyroLab's login page inside a frame, as its script goes on where no platform
        storage is offered: ask whether the state cookie arrived, then go to the
        platform's authorization URL (or stay on the page that offers a new window)."""
        if 'id="lti-frame"' not in page.text or self.data(page, "mode") != "login":
            return page
        state = self.data(page, "state")
        check = self.get(str(httpx.URL(str(page.url)).join(f"/lti/state-check?state={state}")))
        if not check.json()["cookie"]:
            return page
        return self.get(self.data(page, "auth-url"))

    def launch(self, platform_url: str, **params) -> httpx.Response:
        """Click GyroLab in the LMS: login initiation, authorization, the form post."""
        page = self.get(f"{platform_url}/start?{urlencode(params)}")
        assert page.status_code == 200, page.text[:500]
        page = self.framed_login(page)
        if "/lti/launch" not in page.text:
            return page  # the tool refused the login initiation
        return self.submit_auto_form(page)
