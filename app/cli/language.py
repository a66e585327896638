"""The language a command speaks: ``--language`` where the command has it, else the one
``LANG`` names (``zh_CN.UTF-8`` → zh-CN), else English; and its words from the catalogue."""

from __future__ import annotations

import argparse
import os
from collections.abc import Callable


def command_language(args: argparse.Namespace | None = None) -> str:
    from app.web.i18n import normalise

    language = getattr(args, "language", None)
    return language or normalise(os.environ.get("LANG", "").split(".")[0]) or "en"


def speaker(args: argparse.Namespace | None = None) -> Callable[..., str]:
    """``say(key, **params)``: the catalogue's words in the command's language."""
    from app.web.i18n import translate

    language = command_language(args)
    return lambda key, **params: translate(key, language, **params)
