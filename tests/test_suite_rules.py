"""Rules the test suite keeps about itself."""

from __future__ import annotations

import ast
from pathlib import Path

TESTS = Path(__file__).resolve().parent


def marks_on_helpers(source: str) -> list[str]:
    """Functions that carry a ``pytest.mark`` but are not tests: pytest ignores such a mark
    silently, so the test it was meant for runs without it."""
    found = []
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef) and not node.name.startswith(
            "test"
        ):
            for decorator in node.decorator_list:
                text = ast.unparse(decorator)
                if text.startswith("pytest.mark."):
                    found.append(f"{node.name} ({text})")
    return found


def test_a_mark_meant_for_a_test_is_on_the_test():
    """A helper written between a test's marks and the test once took its ``slow`` and
    ``one_backend`` marks: the suite ran it on both databases in every quick run."""
    misplaced = {
        str(path.relative_to(TESTS)): marks_on_helpers(path.read_text(encoding="utf-8"))
        for path in sorted(TESTS.rglob("*.py"))
    }
    assert {path: found for path, found in misplaced.items() if found} == {}


def test_the_rule_sees_a_mark_on_a_helper():
    source = (
        "import pytest\n"
        "@pytest.mark.slow\n"
        "def readable(data):\n    return data\n"
        "@pytest.mark.parametrize('x', [1])\n"
        "def test_x(x):\n    pass\n"
    )
    assert marks_on_helpers(source) == ["readable (pytest.mark.slow)"]
