"""Translations: every user-facing string exists in English and Simplified Chinese.

Strings are looked up by key in :data:`app.web.messages.MESSAGES`; templates call
``_(key, **params)``.
The language is the user's saved choice, else the ``lang`` cookie, else Accept-Language.
"""

from __future__ import annotations

from collections.abc import Callable

from app.web.messages import MESSAGES

LANGUAGES = ("en", "zh-CN")
DEFAULT_LANGUAGE = "en"
LANGUAGE_NAMES = {"en": "English", "zh-CN": "中文"}


def normalise(code: str | None) -> str | None:
    """Map 'zh', 'zh-cn', 'zh-Hans-CN', 'en-GB'... onto a supported language, else None."""
    if not code:
        return None
    code = code.strip().lower()
    if code.startswith("zh"):
        return "zh-CN"
    if code.startswith("en"):
        return "en"
    return None


def negotiate(accept_language: str | None) -> str:
    """Best supported language for an Accept-Language header (q-values honoured)."""
    if not accept_language:
        return DEFAULT_LANGUAGE
    choices: list[tuple[float, int, str]] = []
    for index, part in enumerate(accept_language.split(",")):
        tag, _, params = part.strip().partition(";")
        quality = 1.0
        if params.strip().startswith("q="):
            try:
                quality = float(params.strip()[2:])
            except ValueError:
                quality = 0.0
        language = normalise(tag)
        if language and quality > 0:
            choices.append((-quality, index, language))
    return min(choices)[2] if choices else DEFAULT_LANGUAGE


def is_known(key: str) -> bool:
    return key in MESSAGES


def translate(key: str, language: str, **params: object) -> str:
    entry = MESSAGES.get(key)
    text = key if entry is None else entry.get(language) or entry["en"]
    return text.format(**params) if params else text


def translator(language: str) -> Callable[..., str]:
    def _(key: str, **params: object) -> str:
        return translate(key, language, **params)

    return _
