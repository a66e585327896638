"""``gyrolab --help`` and argparse's refusals in the user's language: every command's and
option's help from the catalogues, argparse's own words ("usage:", "options", the ``-h``
line, "invalid choice") translated, English exactly as argparse words it."""

from __future__ import annotations

import argparse
import re

import pytest

from app.cli.localised_parser import refusal_words, wanted_language
from app.cli.main import build_parser, main

CHINESE = re.compile(r"[\u4e00-\u9fff]")


def parsers(parser: argparse.ArgumentParser):
    """The parser and every subcommand's, depth first."""
    yield parser
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for child in action.choices.values():
                yield from parsers(child)


def helps(parser: argparse.ArgumentParser) -> list[str]:
    """Every help line the parser shows: its description, each option's, each command's."""
    lines = [parser.description] if parser.description else []
    for action in parser._actions:
        if action.help and action.help is not argparse.SUPPRESS:
            lines.append(action.help)
        if isinstance(action, argparse._SubParsersAction):
            lines += [choice.help for choice in action._choices_actions if choice.help]
    return lines


def test_every_help_line_is_in_both_languages():
    english, chinese = (list(parsers(build_parser(language))) for language in ("en", "zh-CN"))
    assert [p.prog for p in english] == [p.prog for p in chinese]
    assert len(english) >= 19  # gyrolab, its commands, lti's
    count = 0
    for en, zh in zip(english, chinese, strict=True):
        en_lines, zh_lines = helps(en), helps(zh)
        assert len(en_lines) == len(zh_lines), en.prog
        for en_line, zh_line in zip(en_lines, zh_lines, strict=True):
            assert "clihelp." not in en_line and "clihelp." not in zh_line, en.prog
            assert not CHINESE.search(en_line), (en.prog, en_line)
            assert CHINESE.search(zh_line), (en.prog, zh_line)
            count += 1
    assert count > 100


def test_help_in_the_language_lang_names_or_the_one_asked_for(capsys, monkeypatch):
    monkeypatch.setenv("LANG", "zh_CN.UTF-8")
    with pytest.raises(SystemExit) as shown:
        main(["--help"])
    assert shown.value.code == 0
    out = capsys.readouterr().out
    assert out.startswith("用法：gyrolab")
    assert "显示此帮助信息并退出" in out and "由 CSV 计算航向" in out and "选项" in out
    monkeypatch.setenv("LANG", "C.UTF-8")
    with pytest.raises(SystemExit):
        main(["solve", "--help", "--language", "zh-CN"])
    out = capsys.readouterr().out
    assert "真实纬度 φ0（用于百分比误差）" in out and "位置参数" in out
    with pytest.raises(SystemExit):
        main(["solve", "--help"])
    out = capsys.readouterr().out
    assert out.startswith("usage: gyrolab solve") and "show this help message and exit" in out
    assert "true latitude φ0 (for percent errors)" in out and "positional arguments" in out


def plain_refusal(capsys, build, argv) -> str:
    """What a plain argparse parser says to ``argv``: its last line."""
    parser = argparse.ArgumentParser(prog="gyrolab solve")
    build(parser)
    with pytest.raises(SystemExit):
        parser.parse_args(argv)
    return capsys.readouterr().err.strip().splitlines()[-1]


REFUSED = [
    # (the arguments, how a plain parser is built for the same refusal, the Chinese words)
    (
        ["solve", "heading", "x.csv", "--rotation", "up"],
        lambda p: p.add_argument("--rotation", choices=["ccw", "cw"]),
        ["--rotation", "up"],
        "参数 --rotation：无效的选项 'up'（可选：'ccw', 'cw'）",
    ),
    (
        ["solve"],
        lambda p: (p.add_argument("part"), p.add_argument("file")),
        [],
        "缺少以下参数：part, file",
    ),
    (
        ["solve", "heading", "x.csv", "--step", "ninety"],
        lambda p: p.add_argument("--step", type=float),
        ["--step", "ninety"],
        "参数 --step：'ninety' 不是有效的数",
    ),
    (
        ["solve", "heading", "x.csv", "--step"],
        lambda p: p.add_argument("--step", type=float),
        ["--step"],
        "参数 --step：需要一个值",
    ),
]


@pytest.mark.parametrize(("argv", "build", "plain_argv", "chinese"), REFUSED)
def test_argparses_refusals_in_both_languages(
    capsys, monkeypatch, argv, build, plain_argv, chinese
):
    plain = plain_refusal(capsys, build, plain_argv)
    monkeypatch.setenv("LANG", "C.UTF-8")
    with pytest.raises(SystemExit) as refused:
        main(argv)
    assert refused.value.code == 2
    err = capsys.readouterr().err
    assert err.startswith("usage: gyrolab solve")
    assert err.strip().splitlines()[-1] == plain  # English exactly as argparse words it
    monkeypatch.setenv("LANG", "zh_CN.UTF-8")
    with pytest.raises(SystemExit) as refused:
        main(argv)
    assert refused.value.code == 2
    err = capsys.readouterr().err
    assert err.startswith("用法：gyrolab solve")
    assert err.strip().splitlines()[-1] == f"gyrolab solve：错误：{chinese}"


def test_a_bridge_source_given_twice_and_an_unknown_option(capsys, monkeypatch):
    monkeypatch.setenv("LANG", "zh_CN.UTF-8")
    with pytest.raises(SystemExit):
        main(["bridge", "--serial", "COM3", "--file", "log.bin"])
    assert "参数 --file 不能与参数 --serial 同时使用" in capsys.readouterr().err
    with pytest.raises(SystemExit):
        main(["solve", "heading", "x.csv", "--bogus"])
    assert "无法识别的参数：--bogus" in capsys.readouterr().err


def test_the_language_asked_for_is_read_before_parsing(monkeypatch):
    monkeypatch.setenv("LANG", "zh_CN.UTF-8")
    assert wanted_language(["solve", "--language", "en"]) == "en"
    assert wanted_language(["solve", "--language=en"]) == "en"
    assert wanted_language(["solve", "--language", "fr"]) == "zh-CN"  # then refused as a choice
    assert wanted_language(["solve", "--language"]) == "zh-CN"
    monkeypatch.setenv("LANG", "C")
    assert wanted_language([]) == "en"


def test_a_refusal_argparse_words_otherwise_is_shown_as_it_is():
    assert refusal_words("something new happened", lambda key, **_: key) == "something new happened"
