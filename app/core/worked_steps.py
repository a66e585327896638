"""A worked solution's pieces: a step's words (message keys with their numbers, so each
language's catalogue holds the words) and its lines of mathematics, how numbers are written
into the formulas, and the steps as plain text (:mod:`app.core.explain` writes the steps).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field


@dataclass(frozen=True)
class Words:
    """A message key of the catalogues and the values of its ``{placeholders}``."""

    key: str
    params: dict[str, str] = field(default_factory=dict)


@dataclass(frozen=True)
class Step:
    title: Words
    lines: tuple[str | Words, ...]  # mathematics; a line with words in it as Words
    sentence: Words | None = None  # a conclusion in words
    legend: Words | None = None  # what the symbols of the lines mean


AZIMUTH_LEGEND = Words("steps.legend_azimuth")
FIT_LEGEND = Words("steps.legend_fit")
AMPLITUDE_LEGEND = Words("steps.legend_amplitude")
ELEVATION_LEGEND = Words("steps.legend_elevation")


def fixed(value: float, digits: int = 3) -> str:
    """A number to a fixed count of decimals, as the worked steps write it.

    Parameters
    ----------
    value : float
        The number.
    digits : int
        Decimals.

    Returns
    -------
    str
        ``value`` with ``digits`` decimals ("-0.940").
    """
    return f"{value:.{digits}f}"


def in_formula(value: float, digits: int = 3) -> str:
    """A number substituted into a formula: negatives in parentheses, so that
    "10.706 − (-8.951)" reads as the handout writes it.

    Parameters
    ----------
    value : float
        The number.
    digits : int
        Decimals.

    Returns
    -------
    str
        ``value`` with ``digits`` decimals, in parentheses when negative.
    """
    text = fixed(value, digits)
    return f"({text})" if value < 0 else text


MODEL_NOTES = {
    "white": Words("steps.model_white"),
    "closure": Words("steps.model_closure"),
    "allan": Words("steps.model_allan"),
}


def render_text(steps: list[Step], translate: Callable[..., str]) -> str:
    """The steps as plain text (the command line's ``--explain``).

    Parameters
    ----------
    steps : list of Step
        From :func:`app.core.explain.explain_heading` or ``explain_latitude``.
    translate : callable
        ``translate(key, **params)``: a message of the catalogues in the reader's language
        (``app.web.i18n.translator(language)``).

    Returns
    -------
    str
        One line per step.
    """

    def say(words: Words) -> str:
        return translate(words.key, **words.params)

    out = []
    for number, step in enumerate(steps, start=1):
        out.append(f"{number}. {say(step.title)}")
        out.extend(f"   {line if isinstance(line, str) else say(line)}" for line in step.lines)
        if step.legend:
            out.append(f"   {say(step.legend)}")
        if step.sentence:
            out.append(f"   {say(step.sentence)}")
    return "\n".join(out)
