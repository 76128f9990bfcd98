"""Every module of the package, the tests and the benchmarks uses what it imports
(there is no linter in the test environment; an unused import hides a missing use or a stale one)."""

import ast
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
CHECKED = sorted({*ROOT.glob("mt_widgets/**/*.py"), *ROOT.glob("tests/**/*.py"), *ROOT.glob("benchmarks/*.py")})


def _words(tree) -> set[str]:
    """Names read in ``tree``, plus the words of its strings (``__all__``, string annotations)."""
    words = {n.id for n in ast.walk(tree) if isinstance(n, ast.Name)}
    for node in ast.walk(tree):
        if isinstance(node, ast.Constant) and isinstance(node.value, str):
            words.update(node.value.replace("[", " ").replace("]", " ").replace(".", " ").replace(",", " ").split())
    return words


def unused_imports(source: str) -> list[str]:
    """Imported names never read in the scope that imports them (the module, or a function)."""
    tree = ast.parse(source)
    lines = source.splitlines()
    scopes = [tree] + [n for n in ast.walk(tree) if isinstance(n, (ast.FunctionDef, ast.AsyncFunctionDef))]
    unused = []
    for scope in scopes:
        words = _words(scope)
        body = scope.body
        pending = list(body)
        while pending:  # the scope's own statements (if/try/with blocks), not nested functions
            node = pending.pop()
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
                continue
            if isinstance(node, (ast.Import, ast.ImportFrom)):
                if getattr(node, "module", None) == "__future__" or "noqa" in lines[node.lineno - 1]:
                    continue
                unused += [f"{name} (line {node.lineno})" for alias in node.names
                           if (name := (alias.asname or alias.name).split(".")[0]) not in words]
                continue
            pending += [child for child in ast.iter_child_nodes(node) if isinstance(child, ast.stmt)]
    return sorted(unused)


def test_the_checker_finds_an_unused_import():
    assert unused_imports("import os\nfrom x import a, b as c\nprint(c)\n") == ["a (line 2)", "os (line 1)"]
    # Per scope: an import in one function is not used by another function's.
    assert unused_imports("def f():\n    from x import a\ndef g():\n    from x import a\n    a()\n") == \
        ["a (line 2)"]


@pytest.mark.parametrize("path", [p for p in CHECKED if p.name != "__init__.py"], ids=lambda p: str(p.relative_to(ROOT)))
def test_no_unused_imports(path):
    assert unused_imports(path.read_text(encoding="utf-8")) == []
