"""The test suite's own rules: fixtures every test gets (tests/conftest.py), helpers written once
(tests/protocols.py, tests/browser_support.py), no test module importing another."""

import ast
import time
from pathlib import Path

import pytest

from mt_widgets.study import parse_protocol
from mt_widgets.widgets import animation
from protocols import TEXTS, phase, protocol_toml

TESTS = Path(__file__).resolve().parent


@pytest.mark.parametrize("run", [1, 2])
def test_each_test_starts_with_the_canvas_queue_free(run):
    # The second run fails if the first one's ten minutes of queued playback leaked into it.
    assert animation._Queue.drained_in() == 0.0
    assert animation._Queue.add(600.0) >= time.monotonic() + 599.0


def test_no_test_module_imports_another():
    # A test module's helpers go in a support module (helpers.py, scripted.py, browser_support.py, ...):
    # importing a test module runs its tests' module-level set-up twice and hides where a helper lives.
    offenders = []
    for path in TESTS.rglob("*.py"):
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            names = ([alias.name for alias in node.names] if isinstance(node, ast.Import)
                     else [node.module or ""] if isinstance(node, ast.ImportFrom) else [])
            if any(part.startswith("test_") for name in names for part in name.split(".")):
                offenders.append(f"{path.relative_to(TESTS)}:{node.lineno}")
    assert not offenders, offenders


def test_the_protocol_factory_writes_a_protocol_the_study_reads():
    text = protocol_toml("lab", [phase("A", "sim-point", 2, guidance=["target"]), phase("B", "uarm-line")],
                         seed=9, texts={"welcome": "Hello."}, practice_s=3, top={"withdrawal": "exclude"})
    protocol = parse_protocol(text, "lab.toml")
    assert protocol.name == "lab" and protocol.data["seed"] == 9 and protocol.lam == 0.01
    assert [(p.id, p.skill, p.episodes, list(p.guidance)) for p in protocol.phases] == [
        ("A", "sim-point", 2, ["target"]), ("B", "uarm-line", 1, [])]
    assert protocol.data["texts"] == {**TEXTS, "welcome": "Hello."}
    assert protocol.data["practice"] == {"skill": "sim-point", "duration_s": 3, "text": "Practice."}
    assert protocol.data["withdrawal"] == "exclude"
