"""The CSP of LTI pages an LMS may show in a frame (the deep-linking picker, "open in a new
window", the end of dynamic registration): the site's policy with ``frame-ancestors``
naming the platform's origins and, for a deep-linking response, ``form-action`` allowing
the platform's return URL."""

from __future__ import annotations

from urllib.parse import urlsplit

from app.web.headers import CSP


def origin(url: str | None) -> str | None:
    parts = urlsplit(url or "")
    if parts.scheme not in ("http", "https") or not parts.netloc:
        return None
    return f"{parts.scheme}://{parts.netloc}"


def framed_csp(frame_urls: list[str | None], form_urls: list[str | None] = ()) -> str:
    ancestors = sorted({o for o in map(origin, frame_urls) if o})
    targets = sorted({o for o in map(origin, form_urls) if o})
    policy = CSP.replace(
        "frame-ancestors 'none'", "frame-ancestors " + (" ".join(ancestors) or "'none'")
    )
    if targets:
        policy = policy.replace("form-action 'self'", "form-action 'self' " + " ".join(targets))
    return policy
