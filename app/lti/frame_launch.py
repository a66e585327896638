"""A launch inside an LMS frame, where the browser keeps no third-party cookies.

The OIDC state ties a launch to the browser that started it.  Outside a frame the state
cookie does that; inside one, today's browsers drop or partition GyroLab's cookies.  Three
ways are tried, in order, by ``static/js/lti_frame.js`` on the pages built here:

1. **Platform storage** (1EdTech *LTI Client Side OIDC Launch*): when the LMS sends
   ``lti_storage_target``, the login page stores ``state_<state>`` and ``nonce_<nonce>`` in
   the LMS's window with ``lti.put_data`` (postMessage to the LMS's authorization origin,
   answers accepted only from it); the launch page reads them back with ``lti.get_data``
   and posts the launch again with ``lti_platform_state``, which the server accepts only
   for a state whose login it started and whose nonce is still unused.
2. **A partitioned state cookie** (CHIPS, ``Partitioned; SameSite=None; Secure``): kept
   per top-level site, so it reaches GyroLab's frame inside this LMS and nowhere else.
   The login page asks ``/lti/state-check`` whether it arrived.
3. **A new window**: neither works (no platform storage, cookies refused): the login page
   offers to start the same login in a window of its own, where cookies are first-party.

After the launch, GyroLab's own pages open in a new window through a one-time link
(``/lti/continue``); the deep-linking picker works in the frame, its launch id being its
credential.
"""

from __future__ import annotations

from urllib.parse import parse_qs, urlencode, urlsplit

import jwt

from app.lti.framing import origin

STORAGE_TARGET = "lti_storage_target"
PLATFORM_STATE = "lti_platform_state"
STATE_COOKIE = "lti1p3-{state}"  # pylti1p3's name for the state cookie
LOOPBACK = {"localhost", "127.0.0.1", "::1"}
MAX_TARGET = 200


def secure_context(public_base: str) -> bool:
    """Whether browsers treat GyroLab's address as a secure context (HTTPS, or loopback):
    only there may a cookie be ``Secure``, hence ``SameSite=None`` and ``Partitioned``."""
    parts = urlsplit(public_base)
    return parts.scheme == "https" or (parts.hostname or "") in LOOPBACK


def storage_target(params: dict[str, str]) -> str:
    """The LMS's frame for platform storage (``_parent`` or a frame's name), or ''."""
    target = str(params.get(STORAGE_TARGET) or "")
    return target if 0 < len(target) <= MAX_TARGET else ""


def state_cookie_matches(cookies: dict[str, str], state: str) -> bool:
    return bool(state) and cookies.get(STATE_COOKIE.format(state=state)) == state


def login_page(location: str, params: dict[str, str]) -> dict:
    """What the login page needs: the platform's authorization URL (``location``, with the
    state and nonce the login made), where to store them, and the new-window fallback."""
    query = parse_qs(urlsplit(location).query)
    again = {k: v for k, v in params.items() if k != STORAGE_TARGET}
    return {
        "mode": "login",
        "auth_url": location,
        "state": (query.get("state") or [""])[0],
        "nonce": (query.get("nonce") or [""])[0],
        "platform_origin": origin(location) or "",
        "target": storage_target(params),
        "new_window_url": "/lti/login?" + urlencode(again),
    }


def unverified_claims(id_token: str) -> dict:
    """The id_token's claims before any check -- only to find which platform to ask and
    which keys to read; the launch is checked in full once the state is confirmed."""
    try:
        claims = jwt.decode(id_token, options={"verify_signature": False})
    except jwt.PyJWTError:
        return {}
    return claims if isinstance(claims, dict) else {}


def check_page(params: dict[str, str], platform_origin: str) -> dict:
    """What the launch page needs to confirm the state from platform storage and post the
    launch again."""
    claims = unverified_claims(params.get("id_token", ""))
    return {
        "mode": "check",
        "state": params.get("state", ""),
        "nonce": str(claims.get("nonce") or ""),
        "platform_origin": platform_origin,
        "target": storage_target(params),
        "fields": {
            "id_token": params.get("id_token", ""),
            "state": params.get("state", ""),
            STORAGE_TARGET: storage_target(params),
        },
    }
