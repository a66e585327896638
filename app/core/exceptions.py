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
        The message's key in the catalogue (``locales/*/LC_MESSAGES/messages.po``), the
        one source of its words: the renderers translate it into the reader's language
        (English on the command line) with ``params`` filled in.  ``str(error)`` is the key
        and its parameters, for logs.
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
        /,
        *,
        status: int = 400,
        headers: dict[str, str] | None = None,
        **params: object,
    ) -> None:
        super().__init__(key)
        self.key = key
        self.status = status
        self.headers = headers or {}
        self.params = params

    def __str__(self) -> str:
        if not self.params:
            return self.key
        return f"{self.key} ({', '.join(f'{k}={v!r}' for k, v in self.params.items())})"


class FieldProblems(UserError):
    """Every refused field of one form at once, so a page can show each message beside its
    field (and keep everything typed): ``problems`` maps a field's name to its
    :class:`UserError`, in the form's order.  Anything that renders a plain UserError
    (the API, the command line) shows the first."""

    def __init__(self, problems: dict[str, UserError]) -> None:
        if not problems:
            raise ValueError("FieldProblems needs at least one problem")
        first = next(iter(problems.values()))
        super().__init__(first.key, status=first.status, **first.params)
        self.problems = problems
