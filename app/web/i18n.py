"""Translations: every user-facing string exists in English and Simplified Chinese.

The catalogues are gettext ``.po`` files, ``locales/<locale>/LC_MESSAGES/messages.po``,
whose msgids are message keys (``"lab.submitted"``) and msgstrs the text with ``{name}``
placeholders; they are compiled (Babel) at first use, or at a served worker's start-up.
Code and templates call ``_(key, **params)``; a key with plural forms takes its count
from ``n``.  Dates and numbers are formatted by Babel for the reader's locale
(:func:`format_datetime`).
The language is the user's saved choice, else the ``lang`` cookie, else Accept-Language.
"""

from __future__ import annotations

from collections.abc import Callable
from datetime import UTC, datetime, tzinfo
from functools import lru_cache
from io import BytesIO

from babel import Locale
from babel.dates import format_datetime as babel_format_datetime
from babel.dates import get_timezone_name, match_skeleton
from babel.messages.mofile import write_mo
from babel.messages.pofile import read_po
from babel.numbers import format_decimal
from babel.support import Translations

from app.core.text_files import BIDI_CONTROLS
from app.paths import LOCALES_DIR

LANGUAGES = ("en", "zh-CN")
DEFAULT_LANGUAGE = "en"
LANGUAGE_NAMES = {"en": "English", "zh-CN": "中文"}
LOCALES = {"en": "en", "zh-CN": "zh_CN"}  # language tag → gettext locale


@lru_cache
def catalogue(language: str):
    """The language's ``.po`` file as read by Babel."""
    path = LOCALES_DIR / LOCALES[language] / "LC_MESSAGES" / "messages.po"
    with path.open("rb") as handle:
        return read_po(handle, locale=LOCALES[language])


@lru_cache
def translations(language: str) -> Translations:
    """The language's catalogue compiled to gettext's binary form (in memory)."""
    compiled = BytesIO()
    write_mo(compiled, catalogue(language))
    compiled.seek(0)
    return Translations(compiled)


def load_languages(zone: tzinfo) -> None:
    """Compile every language's catalogue and read its locale's data now (a served
    worker's start-up): left to first use, the first page in each language paid ≈ 40 ms
    for them -- the ``.po`` parsed and compiled, CLDR's time-zone names and number
    formats read -- inside a student's request in the class's first seconds."""
    sample = datetime(2026, 1, 1, 12, tzinfo=UTC)
    for language in LANGUAGES:
        translations(language)
        format_datetime(sample, language, zone=zone)  # with the zone's name
        format_number(1.5, language)


def messages() -> dict[str, dict[str, str]]:
    """Every key with its text in each language (plural keys: their first form)."""
    out: dict[str, dict[str, str]] = {}
    for language in LANGUAGES:
        for message in catalogue(language):
            if not message.id:
                continue
            key = message.id[0] if isinstance(message.id, tuple) else message.id
            text = message.string[0] if isinstance(message.string, tuple) else message.string
            out.setdefault(key, {})[language] = text
    return out


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
    return key in catalogue(DEFAULT_LANGUAGE)


def translate(key: str, language: str, **params: object) -> str:
    """The message ``key`` in ``language`` (English when missing there; the key itself
    when unknown), its placeholders filled from ``params`` -- a value quoted from a file or
    a form without bidirectional controls, which would reorder the message after it
    ("'\u202e°/s' is not a number")."""
    text, plural_language = _message(key, language)
    if plural_language is not None:
        count = params.get("n", 1)
        text = translations(plural_language).ngettext(key, key, int(count) if count else 0)
    if not params:
        return text
    shown = {
        name: BIDI_CONTROLS.sub("", value) if isinstance(value, str) else value
        for name, value in params.items()
    }
    return text.format(**shown)


@lru_cache(maxsize=64)
def client_messages(keys: tuple[str, ...], language: str) -> dict[str, str | dict[str, str]]:
    """A page script's messages, placeholders left in; a plural message as
    ``{"one", "other"}`` (the script picks the form by its ``n``)."""
    out: dict[str, str | dict[str, str]] = {}
    for key in keys:
        text, plural_language = _message(key, language)
        if plural_language is None:
            out[key] = text
        else:
            catalogue_ = translations(plural_language)
            out[key] = {
                "one": catalogue_.ngettext(key, key, 1),
                "other": catalogue_.ngettext(key, key, 2),
            }
    return out


@lru_cache(maxsize=8192)
def _message(key: str, language: str) -> tuple[str, str | None]:
    """The catalogue's text of ``key`` (a page asks for ~250 of them; the catalogues never
    change while serving), and the language to pick a plural form in, if it has them."""
    if language not in LANGUAGES:
        language = DEFAULT_LANGUAGE
    entry = catalogue(language).get(key)
    if entry is None or not entry.string:
        language = DEFAULT_LANGUAGE
        entry = catalogue(language).get(key)
    if entry is None:
        return key, None
    if entry.pluralizable:
        return key, language
    return translations(language).gettext(key), None


def format_datetime(
    value: datetime | None,
    language: str,
    date: str | None = "yMMMd",
    time: str | None = "Hm",
    zone: tzinfo | None = None,
    with_zone: bool = True,
) -> str:
    """A date and time the way the reader's locale writes them, from CLDR skeletons
    (Babel): "Nov 22, 2026 20:05" / "2026年11月22日 20:05"; "" for None.  Stored times
    are UTC; ``zone`` (the course's) gives the wall clock shown."""
    if value is None:
        return ""
    return _formatted(value, language, date, time, zone, with_zone)


@lru_cache(maxsize=8192)
def _formatted(value: datetime, language: str, date, time, zone, with_zone: bool = True) -> str:
    """format_datetime's work, remembered: a page of a class formats the same submission
    times on every refresh, and Babel's formatting is the slow part of it."""
    if zone is not None:
        value = (value if value.tzinfo else value.replace(tzinfo=UTC)).astimezone(zone)
    locale = _locale(language)
    parts = [
        babel_format_datetime(value, _skeleton_pattern(language, skeleton), locale=locale)
        for skeleton in (date, time)
        if skeleton
    ]
    if time and zone is not None and with_zone:  # which wall clock: "20:05 China Time"
        parts.append(zone_label(zone, language))
    return " ".join(parts)


@lru_cache(maxsize=256)
def zone_label(zone: tzinfo, language: str) -> str:
    """A time zone as the reader's locale names it (CLDR, via Babel): "China Time" /
    "中国时间", "Central European Time" / "中欧时间"; "UTC" for UTC itself."""
    key = getattr(zone, "key", "")
    if zone is UTC or key in ("UTC", "Etc/UTC", "Etc/GMT", "GMT"):
        return "UTC"
    return get_timezone_name(zone, width="long", locale=_locale(language), uncommon=False)


@lru_cache
def _locale(language: str) -> Locale:
    return Locale.parse(LOCALES[language])


@lru_cache
def _skeleton_pattern(language: str, skeleton: str):
    """The locale's pattern for a CLDR skeleton (what ``format_skeleton`` looks up on
    every call; a class dashboard formats hundreds of dates)."""
    patterns = _locale(language).datetime_skeletons
    return patterns[skeleton if skeleton in patterns else match_skeleton(skeleton, patterns)]


def format_number(value: float, language: str, digits: int = 3) -> str:
    """A number with the locale's separators (Babel), at most ``digits`` decimals."""
    return format_decimal(round(value, digits), locale=_locale(language))


def translator(language: str) -> Callable[..., str]:
    def _(key: str, **params: object) -> str:
        return translate(key, language, **params)

    _.language = language  # what a cache of translated output is keyed by
    return _
