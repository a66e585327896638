"""Every public function of the science core documents itself the numpydoc way."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

CORE = Path(__file__).resolve().parents[1] / "app" / "core"
PUBLIC = [
    (path.name, node)
    for path in sorted(CORE.glob("*.py"))
    for node in ast.parse(path.read_text()).body
    if isinstance(node, ast.FunctionDef) and not node.name.startswith("_")
]


@pytest.mark.parametrize(("module", "function"), PUBLIC, ids=lambda v: getattr(v, "name", v))
def test_public_core_functions_have_numpydoc_sections(module, function):
    doc = ast.get_docstring(function) or ""
    for section in ("Parameters\n----------", "Returns\n-------"):
        assert section in doc, f"{module}:{function.name} lacks {section.splitlines()[0]}"
    documented = {
        line.split(" : ")[0].strip()
        for line in doc.split("Parameters\n----------")[1].split("\n\n")[0].splitlines()
        if line and not line.startswith(" ")
    }
    names = {a.arg for a in function.args.args + function.args.kwonlyargs}
    listed = {name.strip() for entry in documented for name in entry.split(",")}
    assert names <= listed, f"{module}:{function.name}: {sorted(names - listed)} undocumented"
