"""The fast tier's marks (tests/conftest.py) keep naming tests that exist: a renamed slow test
would otherwise quietly join the fast tier, a moved browser folder leave it."""

import ast
from pathlib import Path

from tiers import SLOW_TESTS

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


def test_the_browser_test_folders_are_named_as_the_marking_expects():
    # tests/conftest.py marks every test in a folder named browser* as a browser test.
    folders = {path.name for path in (ROOT / "tests").glob("browser*") if path.is_dir()}
    assert {"browser", "browser_study"} <= folders
