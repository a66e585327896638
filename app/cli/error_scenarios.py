"""``gyrolab errors``: every error-explorer scenario as a command.

``gyrolab errors --list`` names the scenarios; ``gyrolab errors --scenario NAME`` prints the
scenario's parameters and, at each Monte Carlo azimuth, the first-order and simulated
heading errors (°) of each method -- the numbers behind the explorer's chart.
"""

from __future__ import annotations

import argparse
from dataclasses import asdict, replace

from app.core.error_analysis import METHODS
from app.core.exceptions import UserError
from app.explore.scenarios import SCENARIOS, heading_error_curves, scenario_input
from app.web.i18n import translate


def scenario_report(
    name: str, method: str | None = None, seed: int = 1, language: str = "en"
) -> dict:
    """The scenario's parameters and its heading errors at the Monte Carlo azimuths."""
    params = scenario_input(name)
    if method:
        params = replace(params, method=method)
    curves, info = heading_error_curves(params, seed, formula_at_mc_points=True)
    return {
        "scenario": name,
        "title": translate(f"scenario.{name}", language),
        "parameters": asdict(params),
        "runs_per_azimuth": info["runs"],
        "methods": [
            {
                "method": curve.method,
                "azimuth_deg": curve.mc_azimuths_deg,
                "first_order_error_deg": curve.formula_deg,
                "monte_carlo_mean_error_deg": curve.mc_mean_deg,
                "monte_carlo_std_error_deg": curve.mc_std_deg,
            }
            for curve in curves
        ],
    }


def _text(value: float | None) -> str:
    return "—" if value is None else f"{value:+.5f}"


def print_report(report: dict, language: str = "en") -> None:
    def say(key: str, **params) -> str:
        return translate(key, language, **params)

    print(f"{report['scenario']}: {report['title']}")
    for key, value in report["parameters"].items():
        print(f"  {key} = {value}")
    columns = [say(f"cli.errors_{name}") for name in ("azimuth", "first_order", "simulated")]
    columns.append(say("cli.errors_spread"))
    for method in report["methods"]:
        runs = report["runs_per_azimuth"]
        print("\n" + say("cli.errors_method", method=method["method"], runs=runs))
        widths = (10, 14, 12, 10)
        print(" ".join(f"{text:>{width}}" for text, width in zip(columns, widths, strict=True)))
        rows = zip(
            method["azimuth_deg"],
            method["first_order_error_deg"],
            method["monte_carlo_mean_error_deg"],
            method["monte_carlo_std_error_deg"],
            strict=True,
        )
        for azimuth, formula, mean, std in rows:
            print(f"{azimuth:10.1f} {_text(formula):>14} {_text(mean):>12} {_text(std):>10}")


def add_errors_command(commands, guarded, to_json_text, say) -> None:
    errors = commands.add_parser("errors", help=say("clihelp.errors"))
    errors.add_argument("--list", action="store_true", help=say("clihelp.errors.list"))
    errors.add_argument("--scenario", choices=sorted(SCENARIOS), metavar="NAME")
    errors.add_argument("--method", choices=METHODS, help=say("clihelp.errors.method"))
    errors.add_argument("--json", action="store_true")
    errors.add_argument("--language", choices=["en", "zh-CN"], help=say("clihelp.language"))

    def run(args: argparse.Namespace) -> int:
        if args.list:
            for name in SCENARIOS:
                print(f"{name:30} {translate(f'scenario.{name}', args.language)}")
            return 0
        if not args.scenario:
            raise UserError("cli.name_a_scenario")
        report = scenario_report(args.scenario, args.method, language=args.language)
        if args.json:
            print(to_json_text(report))
        else:
            print_report(report, args.language)
        return 0

    errors.set_defaults(handler=guarded(run))
