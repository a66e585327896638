"""An Allan analysis in words: each term, the dwell advice and what was done to the record,
in the reader's language (the caller passes its translator ``_``; the words live in the
gettext catalogues).  The CLI, the teacher's characterisation and the JSON share it, so the
same record reads the same everywhere."""

from __future__ import annotations

from collections.abc import Callable

from app.core.allan import UNITS, AllanResult
from app.core.allan_fit import BUMPS, TERM_ORDER

Translate = Callable[..., str]


def _number(value: float) -> str:
    return f"{value:.4g}"


def _seconds(value: float) -> str:
    """τ as people write it: 0.1, 12.8, 1638 (never 1.64e+03)."""
    return f"{value:.0f}" if value >= 100 else f"{value:.3g}"


def term_rows(terms: dict[str, dict], _: Translate) -> list[dict]:
    """One row per IEEE 952 term: its name, and its value with interval and τ region, or
    "not resolved" with the bound the curve allows.

    Parameters
    ----------
    terms : dict
        :meth:`TermEstimate.to_json` by term name, as stored.
    _ : callable
        The reader's translator.

    Returns
    -------
    list of dict
        ``name``, ``label``, ``resolved`` and ``text`` of each term.
    """
    rows = []
    for name in (*TERM_ORDER, *BUMPS):
        term = terms.get(name) or {"resolved": False}
        unit = UNITS[name]
        if term["resolved"]:
            low, high = term.get("interval") or (term["value"], term["value"])
            region = term.get("tau_region_s") or (0.0, 0.0)
            tau_low, tau_high = _seconds(region[0]), _seconds(region[1])
            text = _(
                "allan.resolved" if tau_low != tau_high else "allan.resolved_at",
                value=_number(term["value"]),
                unit=unit,
                low=_number(low),
                high=_number(high),
                tau_low=tau_low,
                tau_high=tau_high,
            )
            if term.get("corr_time_s"):
                text += " " + _("allan.markov_time", time=_seconds(term["corr_time_s"]))
            if term.get("period_s"):
                text += " " + _("allan.sine_period", period=_seconds(term["period_s"]))
        elif name == "markov":
            text = _("allan.no_bump")
        elif name == "sinusoid":
            text = _("allan.no_swing")
        else:
            text = _("allan.not_resolved", bound=_number(term.get("upper_bound") or 0.0), unit=unit)
        rows.append(
            {
                "name": name,
                "label": _(f"allan.term.{name}"),
                "resolved": term["resolved"],
                "text": text,
            }
        )
    return rows


def dwell_lines(dwell: dict, _: Translate) -> list[str]:
    """The dwell advice in words: the best dwell, or the lower bound and why, the
    shortest dwell within 10 % of the best σ, and, with a periodic bias, that whole periods
    of it average it out.

    Parameters
    ----------
    dwell : dict
        :meth:`DwellAdvice.to_json`.
    _ : callable
        The reader's translator.

    Returns
    -------
    list of str
        One sentence each.
    """
    best = f"{dwell['recommended_s']:.0f}"
    if dwell["lower_bound"] and dwell["limit"] == "record" and dwell.get("levels_off"):
        lines = [_("allan.dwell_floor_record", dwell=best)]
    elif dwell["lower_bound"]:
        key = "allan.dwell_lower_record" if dwell["limit"] == "record" else "allan.dwell_lower_lab"
        lines = [_(key, dwell=best)]
    else:
        lines = [_("allan.dwell_best", dwell=best)]
    if dwell["near_best_s"] < dwell["recommended_s"]:
        lines.append(_("allan.dwell_near", dwell=f"{dwell['near_best_s']:.0f}"))
    if dwell.get("swing_period_s"):
        period = dwell["swing_period_s"]
        lines.append(
            _("allan.dwell_whole_periods", period=f"{period:.0f}", twice=f"{2 * period:.0f}")
        )
    if dwell.get("source") == "curve":
        lines.append(_("allan.dwell_curve"))
    elif dwell.get("source") == "fit":
        lines.append(_("allan.dwell_fitted"))
    return lines


def note_lines(notes: list[dict], _: Translate) -> list[str]:
    """What was done to the record (gaps, spikes, warm-up, few stretches).

    Parameters
    ----------
    notes : list of dict
        The analysis's notes (key and parameters).
    _ : callable
        The reader's translator.

    Returns
    -------
    list of str
        One sentence each.
    """
    return [_(note["key"], **note["params"]) for note in notes]


def summary_lines(result: AllanResult, _: Translate) -> list[str]:
    """Everything above as plain lines (the CLI's report).

    Parameters
    ----------
    result : AllanResult
        The analysis.
    _ : callable
        The reader's translator.

    Returns
    -------
    list of str
        Notes, one line per term, the minimum, the model's fit and the dwell advice.
    """
    lines = note_lines(result.notes, _)
    rows = term_rows({n: t.to_json() for n, t in result.terms.items()}, _)
    width = max(len(row["label"]) for row in rows)
    for row in rows:
        lines.append(f"{row['label']:<{width}}  {row['text']}")
    lines.append(
        _(
            "allan.minimum_model" if result.dwell.source in ("model", "fit") else "allan.minimum",
            adev=_number(result.adev_min_deg_h),
            tau=_seconds(result.tau_min_s),
        )
    )
    if not result.model_fits:
        lines.append(_("allan.misfit"))
    lines.extend(dwell_lines(result.dwell.to_json(), _))
    return lines
