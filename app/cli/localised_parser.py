"""The command line's parser in its user's language: every command's help from the
catalogue (``clihelp.*``), and argparse's own words -- "usage:", its section titles, the
``-h`` line and its refusals ("the following arguments are required", "invalid choice")
-- in the same language.

The language is read before the parser is built (a ``--help`` is printed while the
arguments are parsed): ``--language`` among the arguments, else the one ``LANG`` names
(:func:`app.cli.language.command_language`).
"""

from __future__ import annotations

import argparse
import re
import sys
from collections.abc import Callable, Sequence

from app.cli.language import command_language

Say = Callable[..., str]

# argparse's refusals (Python 3.11-3.13), each with the catalogue's key for its words;
# quoting differs between versions, so the quoted parts are taken as they are
REFUSALS: tuple[tuple[re.Pattern[str], str], ...] = tuple(
    (re.compile(pattern, re.DOTALL), key)
    for pattern, key in (
        (r"the following arguments are required: (?P<names>.+)", "cli.args_required"),
        (r"unrecognized arguments: (?P<arguments>.+)", "cli.args_unrecognised"),
        (r"one of the arguments (?P<names>.+) is required", "cli.args_one_required"),
        (r"ambiguous option: (?P<option>\S+) could match (?P<matches>.+)", "cli.args_ambiguous"),
        (
            r"argument (?P<argument>\S+): invalid choice: (?P<value>.+?) "
            r"\(choose from (?P<choices>.+)\)",
            "cli.args_invalid_choice",
        ),
        (
            r"argument (?P<argument>\S+): invalid (?P<kind>\w+) value: (?P<value>.+)",
            "cli.args_invalid_value",
        ),
        (r"argument (?P<argument>\S+): expected one argument", "cli.args_expected_one"),
        (
            r"argument (?P<argument>\S+): not allowed with argument (?P<other>\S+)",
            "cli.args_not_allowed_with",
        ),
    )
)
KINDS = {"int": "cli.kind_int", "float": "cli.kind_float"}


def wanted_language(argv: Sequence[str]) -> str:
    """The language the arguments ask for (``--language zh-CN``, ``--language=en``), else
    ``LANG``'s, else English."""
    asked = None
    for index, argument in enumerate(argv):
        if argument == "--language" and index + 1 < len(argv):
            asked = argv[index + 1]
        elif argument.startswith("--language="):
            asked = argument.split("=", 1)[1]
    if asked in ("en", "zh-CN"):
        return asked
    return command_language()


def help_speaker(language: str) -> Say:
    """``say(key, **params)`` for help text: the catalogue's words with ``%`` doubled, as
    argparse formats a help string with ``%(default)s`` and the like."""
    from app.web.i18n import translate

    return lambda key, **params: translate(key, language, **params).replace("%", "%%")


def parser_class(language: str) -> type[argparse.ArgumentParser]:
    """An ``ArgumentParser`` speaking ``language``; subcommands' parsers are of the same
    class (argparse makes them with ``type(parent)``)."""
    from app.web.i18n import translate

    def say(key: str, **params) -> str:
        return translate(key, language, **params)

    class Formatter(argparse.HelpFormatter):
        def add_usage(self, usage, actions, groups, prefix=None):
            if prefix is None:
                prefix = say("cli.usage")
            super().add_usage(usage, actions, groups, prefix)

    class LocalisedParser(argparse.ArgumentParser):
        def __init__(self, *args, add_help: bool = True, **kwargs):
            kwargs.setdefault("formatter_class", Formatter)
            super().__init__(*args, add_help=False, **kwargs)
            self._positionals.title = say("cli.positionals")
            self._optionals.title = say("cli.options")
            if add_help:
                self.add_argument(
                    "-h",
                    "--help",
                    action="help",
                    default=argparse.SUPPRESS,
                    help=say("cli.help_option").replace("%", "%%"),
                )

        def error(self, message: str):
            self.print_usage(sys.stderr)
            refusal = refusal_words(message, say)
            self.exit(2, say("cli.parse_error", prog=self.prog, message=refusal) + "\n")

    return LocalisedParser


def refusal_words(message: str, say: Say) -> str:
    """argparse's refusal in the catalogue's words; one it does not know, as it is."""
    for pattern, key in REFUSALS:
        found = pattern.fullmatch(message)
        if found:
            params = found.groupdict()
            if "kind" in params:
                params["kind"] = (
                    say(KINDS[params["kind"]]) if params["kind"] in KINDS else params["kind"]
                )
            return say(key, **params)
    return message
