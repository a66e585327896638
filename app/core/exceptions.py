"""The one user-facing error type of GyroLab."""

from __future__ import annotations


class UserError(ValueError):
    """Something the user sent or asked for that cannot be done, in words they can act on.

    Raised by the science core (bad or insufficient readings) and by every service and
    dependency of the app; rendered once by ``app.web.errors``: JSON ``{"detail": ...}``
    under ``/api`` and for ``fetch()`` calls, else the error page.

    Parameters
    ----------
    key
        The message's key in the catalogue; the message is translated into the reader's
        language with ``params`` filled in.
    message
        The same message as an English sentence, for the command line and logs (optional:
        ``str(error)`` is then the English catalogue text, or the key).
    status
        The HTTP status it answers with: 400 bad input, 403 not allowed, 404 no such object
        (or not yours), 409 conflicts with the current state, 413 too large, 429 too many
        requests, 503 busy.
    headers
        Extra response headers, e.g. ``Retry-After`` or ``WWW-Authenticate``.
    **params
        Values for the message's ``{placeholders}``.
    """

    def __init__(
        self,
        key: str,
        message: str = "",
        /,
        *,
        status: int = 400,
        headers: dict[str, str] | None = None,
        **params: object,
    ) -> None:
        super().__init__(message or key)
        self.key = key
        self.status = status
        self.headers = headers or {}
        self.params = params
