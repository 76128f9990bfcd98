"""The test helpers themselves: every name they import is used (no import kept only for a side
effect behind a lint waiver)."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

TESTS = Path(__file__).resolve().parent.parent


def unused_imports(path: Path) -> list[str]:
    tree = ast.parse(path.read_text())
    imported = {}
    for node in tree.body:
        if isinstance(node, ast.Import):
            for alias in node.names:
                imported[alias.asname or alias.name.split(".")[0]] = alias.name
        elif isinstance(node, ast.ImportFrom) and node.module != "__future__":
            for alias in node.names:
                imported[alias.asname or alias.name] = f"{node.module}.{alias.name}"
    used = {n.id for n in ast.walk(tree) if isinstance(n, ast.Name)}
    return sorted(full for name, full in imported.items() if name not in used)


@pytest.mark.parametrize("helpers", ["hardware/helpers.py", "uarm_app/helpers.py"])
def test_every_import_of_the_test_helpers_is_used(helpers):
    assert unused_imports(TESTS / helpers) == []


def test_the_checker_finds_an_unused_import(tmp_path):
    module = tmp_path / "m.py"
    module.write_text("import os\nimport mt_widgets.hardware  # noqa: F401\nfrom re import match\nmatch('a', 'a')\n")
    assert unused_imports(module) == ["mt_widgets.hardware", "os"]
