"""The page templates' compiled code kept on disk between starts (app/web/template_cache.py)."""

from __future__ import annotations

import os
import tempfile

import pytest
from jinja2 import Environment, FileSystemLoader

from app.paths import TEMPLATES_DIR
from app.web.template_cache import TemplateCodeCache, environment_key, use_code_cache

PAGE = "lab/session.html"  # with its includes and macros


def fresh_environment(**options) -> Environment:
    """An environment like the app's (its loader and extension), as a new worker has."""
    return Environment(
        loader=FileSystemLoader(str(TEMPLATES_DIR)), extensions=["jinja2.ext.i18n"], **options
    )


def compiled_by(environment: Environment) -> list[str]:
    """The names the environment compiles from source from now on."""
    names: list[str] = []
    compile_source = environment.compile

    def counting(source, name=None, filename=None, raw=False, defer_init=False):
        names.append(name)
        return compile_source(source, name, filename, raw, defer_init)

    environment.compile = counting
    return names


def small_pages(tmp_path) -> FileSystemLoader:
    pages = tmp_path / "pages"
    pages.mkdir(exist_ok=True)
    (pages / "p.html").write_text("<p>{{ _('hello') }} {{ x }}</p>")
    return FileSystemLoader(str(pages))


def render(environment: Environment) -> str:
    return environment.get_template("p.html").render(_=lambda key: key, x=1)


def test_a_start_after_the_first_loads_each_templates_compiled_code(tmp_path):
    first = fresh_environment()
    assert use_code_cache(first, "1.0", str(tmp_path))
    first_compiled = compiled_by(first)
    first.get_template(PAGE)
    assert PAGE in first_compiled and list(tmp_path.glob("__gyrolab_*.cache"))

    second = fresh_environment()
    use_code_cache(second, "1.0", str(tmp_path))
    second_compiled = compiled_by(second)
    second.get_template(PAGE)
    assert second_compiled == []  # loaded, not compiled
    # the cached code is the compiled code: the same module as a compile from source
    uncached = fresh_environment()
    assert second.get_template(PAGE).blocks.keys() == uncached.get_template(PAGE).blocks.keys()


def test_a_changed_environment_or_version_compiles_again(tmp_path):
    assert environment_key(fresh_environment(), "1.0") == environment_key(
        fresh_environment(), "1.0"
    )
    warmed = fresh_environment()
    use_code_cache(warmed, "1.0", str(tmp_path))
    warmed.get_template(PAGE)
    for changed, version in ((fresh_environment(trim_blocks=True), "1.0"),
                             (fresh_environment(), "1.1")):  # fmt: skip
        use_code_cache(changed, version, str(tmp_path))
        compiled = compiled_by(changed)
        changed.get_template(PAGE)
        assert PAGE in compiled


def test_a_changed_template_is_compiled_again(tmp_path):
    pages = tmp_path / "pages"
    pages.mkdir()
    (pages / "p.html").write_text("one {{ x }}")
    cache = tmp_path / "cache"
    cache.mkdir()

    def environment() -> Environment:
        made = Environment(loader=FileSystemLoader(str(pages)))
        use_code_cache(made, "1.0", str(cache))
        return made

    assert environment().get_template("p.html").render(x=1) == "one 1"
    (pages / "p.html").write_text("two {{ x }}")
    assert environment().get_template("p.html").render(x=1) == "two 1"


def test_a_cache_file_that_cannot_be_written_fails_no_page(tmp_path, caplog):
    environment = Environment(loader=small_pages(tmp_path), extensions=["jinja2.ext.i18n"])
    assert use_code_cache(environment, "1.0", str(tmp_path / "gone"))  # never made
    assert render(environment) == "<p>hello 1</p>"
    assert "template code not cached" in caplog.text


def test_an_unsafe_cache_directory_leaves_the_templates_uncached(tmp_path, monkeypatch):
    """Jinja's own directory must be the user's own directory, mode 0700: here another
    file holds its name (as another user's link or file could)."""
    (tmp_path / f"_jinja2-cache-{os.getuid()}").write_text("not a directory")
    monkeypatch.setattr(tempfile, "gettempdir", lambda: str(tmp_path))  # Jinja's base for it
    environment = Environment(loader=small_pages(tmp_path), extensions=["jinja2.ext.i18n"])
    assert not use_code_cache(environment, "1.0")
    assert environment.bytecode_cache is None
    assert render(environment) == "<p>hello 1</p>"


def test_the_apps_templates_use_the_cache():
    from app.web.render import templates

    assert isinstance(templates.env.bytecode_cache, TemplateCodeCache)


@pytest.mark.parametrize("version", ["1.0", "2.0"])
def test_the_key_names_the_version(version):
    assert environment_key(fresh_environment(), version) != environment_key(
        fresh_environment(), version + ".1"
    )
