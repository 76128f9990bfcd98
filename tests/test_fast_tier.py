"""The fast tier's marks (tests/conftest.py) keep naming tests that exist: a renamed slow test
would otherwise quietly join the fast tier, a moved browser folder leave it."""

import ast
from pathlib import Path

from conftest import SLOW_TESTS

ROOT = Path(__file__).resolve().parents[1]


def test_every_listed_slow_test_exists():
    for prefix in SLOW_TESTS:
        path, _, name = prefix.partition("::")
        file = ROOT / path
        assert file.is_file(), f"SLOW_TESTS names {path}, which does not exist"
        if name:
            tests = {node.name for node in ast.walk(ast.parse(file.read_text(encoding="utf-8")))
                     if isinstance(node, ast.FunctionDef) and node.name.startswith("test_")}
            assert any(test.startswith(name) for test in tests), f"no test in {path} starts with {name!r}"


def test_the_browser_folders_exist():
    for folder in ("browser", "browser_study"):
        assert (ROOT / "tests" / folder).is_dir()
