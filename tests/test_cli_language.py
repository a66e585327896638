"""The operator's commands (create-user, migrate, prune, backup, restore, lti) speak the
language ``LANG`` names, as the science commands and the bridge do: every line they print,
refusals included.  A password's refusal once printed its message key."""

from __future__ import annotations

import pytest

from app.cli.main import main

SAID = {
    "create-user --username tina --password abc": (
        "error: unacceptable password: The new password needs at least 8 characters.",
        "错误：密码不可用：新密码至少需要 8 个字符。",
    ),
    "create-user --username tina --password a-good-password": (
        "created teacher tina",
        "已创建教师 tina",
    ),
    "migrate": ("database is at the newest schema", "数据库已是最新结构"),
    "prune": (
        "removed 0 re-recording(s) superseded more than 30 days ago (0.0 MB); submitted data "
        "is never removed",
        "已删除 0 个被取代超过 30 天的重新记录（0.0 MB）；已提交的数据从不删除",
    ),
    "restore {copy}": (
        "gyrolab restore: this replaces the whole database; stop the server and repeat with --yes",
        "gyrolab restore: 此操作会替换整个数据库；请先停止服务器，再加 --yes 重试",
    ),
    "restore {missing} --yes": (
        "gyrolab restore: {missing} does not exist",
        "gyrolab restore: {missing} 不存在",
    ),
    "backup {copy}": (
        "gyrolab backup: {copy} exists already; choose a new file name",
        "gyrolab backup: {copy} 已存在；请换一个新文件名",
    ),
    "lti registration-link": (
        "gyrolab lti registration-link: give --base-url or set GYROLAB_PUBLIC_URL",
        "gyrolab lti registration-link: 请给出 --base-url，或设置 GYROLAB_PUBLIC_URL",
    ),
    "lti sync-roster --course 9": (
        "gyrolab lti sync-roster: course 9 is not linked to an LMS",
        "gyrolab lti sync-roster: 课程 9 未关联到 LMS",
    ),
    "lti send-grades": ("sent 0, failed 0", "已发送 0，失败 0"),
}


@pytest.mark.sqlite_only  # the words do not depend on the database
@pytest.mark.parametrize("language", ["en", "zh-CN"])
def test_the_operators_commands_speak_the_language_lang_names(
    app, tmp_path, capsys, monkeypatch, language
):
    monkeypatch.setenv("LANG", "zh_CN.UTF-8" if language == "zh-CN" else "en_GB.UTF-8")
    monkeypatch.delenv("GYROLAB_PUBLIC_URL", raising=False)
    names = {"copy": str(tmp_path / "copy.db"), "missing": str(tmp_path / "missing.db")}
    main(["backup", names["copy"]])
    capsys.readouterr()
    for command, (english, chinese) in SAID.items():
        main(command.format(**names).split())
        out, err = capsys.readouterr()
        expected = (english if language == "en" else chinese).format(**names)
        assert (out + err).strip() == expected, command


@pytest.mark.sqlite_only  # a database file the server has never started on
def test_the_lti_commands_bring_a_new_database_to_its_schema_first(tmp_path, capsys, monkeypatch):
    """An administrator registers the LMS before the server's first start: the lti
    commands met SQLAlchemy's "no such table" traceback; now they migrate first, as
    create-user does."""
    from app.config import get_settings
    from app.db import engine_for

    monkeypatch.setenv("GYROLAB_VAR_DIR", str(tmp_path / "new-var"))
    monkeypatch.setenv("LANG", "en_GB.UTF-8")
    get_settings.cache_clear()
    engine_for.cache_clear()
    try:
        assert main(["lti", "list"]) == 0
        out, err = capsys.readouterr()  # no rows, and a word where a person reads it
        assert out == "" and "No LTI platform is registered yet" in err
        assert main(["lti", "send-grades"]) == 0
        assert main(["lti", "rotate-key"]) == 0
        out, err = capsys.readouterr()
        assert "sent 0, failed 0" in out and "new signing key" in out and err == ""
        monkeypatch.setenv("LANG", "zh_CN.UTF-8")
        assert main(["lti", "list"]) == 0
        assert "尚未登记任何 LTI 平台" in capsys.readouterr().err
        lms = "https://lms.example.edu"
        assert main([
            "lti", "add-platform", "--issuer", lms, "--client-id", "c1",
            "--login-url", f"{lms}/auth", "--token-url", f"{lms}/token",
            "--jwks-url", f"{lms}/jwks", "--name", "Moodle",
        ]) == 0  # fmt: skip
        capsys.readouterr()
        assert main(["lti", "list"]) == 0
        out, err = capsys.readouterr()
        assert out.split("\t")[1:4] == ["Moodle", lms, "c1"] and err == ""
    finally:
        get_settings.cache_clear()
        engine_for.cache_clear()
