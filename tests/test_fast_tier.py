"""The tiers (tests/tiers.py) and their marks (tests/conftest.py): every test lands in exactly one
tier, the files the marks name exist, and the scripts run the tiers tiers.py lists."""

import itertools
import re
import subprocess
import sys
from pathlib import Path

import pytest
from _pytest.mark.expression import Expression

from tiers import (
    DOCS_TESTS,
    HUB_TESTS,
    INSTALL_TESTS,
    LINT_TESTS,
    MARKS,
    OTHER_PYTHONS,
    TIERS,
    tier_expression,
    tier_paths,
)

ROOT = Path(__file__).resolve().parents[1]


@pytest.mark.parametrize("marks", [set(combination) for size in range(len(MARKS) + 1)
                                   for combination in itertools.combinations(MARKS, size)],
                         ids=lambda marks: "+".join(sorted(marks)) or "unmarked")
def test_every_combination_of_marks_is_in_exactly_one_tier(marks):
    chosen = [name for name, expression in TIERS if Expression.compile(expression).evaluate(lambda mark: mark in marks)]
    assert len(chosen) == 1, f"a test marked {sorted(marks)} runs in the tiers {chosen}"


def test_the_cheap_tiers_run_first():
    assert [name for name, _ in TIERS][:2] == ["lint", "fast"]
    assert tier_expression("fast") == TIERS[1][1]
    with pytest.raises(ValueError, match="name: expected one of"):
        tier_expression("quick")


def test_the_files_the_marks_name_exist_and_the_marks_are_declared():
    for path in LINT_TESTS + HUB_TESTS + DOCS_TESTS + INSTALL_TESTS:
        assert (ROOT / path).is_file(), f"tests/tiers.py names {path}, which does not exist"
    declared = {line.split(":")[0].strip().strip('"') for line in
                (ROOT / "pyproject.toml").read_text().split("markers = [", 1)[1].split("]", 1)[0].splitlines()
                if line.strip()}
    assert set(MARKS) <= declared


def test_the_browser_test_folders_are_named_as_the_marking_expects():
    # tests/conftest.py marks every test in a folder named browser* as a browser test.
    folders = {path.name for path in (ROOT / "tests").glob("browser*") if path.is_dir()}
    assert {"browser", "browser_study"} <= folders


def test_the_lint_mark_lands_on_the_lint_tests_only():
    # Collect a few known tests and read the marks conftest.py gave them.
    result = subprocess.run(
        [sys.executable, "-m", "pytest", "--collect-only", "-q", "-p", "no:cacheprovider",
         "-m", tier_expression("lint"), "tests/test_lint.py", "tests/test_fast_tier.py"],
        cwd=ROOT, capture_output=True, text=True, timeout=300)
    collected = [line for line in result.stdout.splitlines() if "::" in line]
    assert collected and all(line.startswith("tests/test_lint.py::") for line in collected), result.stdout


def test_the_script_lists_the_tiers_for_run_tests():
    listed = subprocess.run([sys.executable, str(ROOT / "tests" / "tiers.py")], capture_output=True, text=True,
                            check=True, timeout=60).stdout
    others = [(name, tier_expression("fast")) for name, _ in OTHER_PYTHONS]
    expected = [(name, expression, *tier_paths(name)) for name, expression in TIERS]
    assert [tuple(line.split("\t")) for line in listed.splitlines()] == expected[:2] + others + expected[2:]
    assert tier_paths("lint") == LINT_TESTS and tier_paths("hub") == HUB_TESTS and tier_paths("fast") == ()
    assert tier_paths("docs") == DOCS_TESTS
    assert tier_paths("install") == INSTALL_TESTS
    assert "tests/tiers.py" in (ROOT / "scripts" / "run-tests.sh").read_text()


def test_the_other_pythons_are_the_oldest_and_the_newest_pyproject_lists():
    text = (ROOT / "pyproject.toml").read_text()
    listed = sorted(int(minor) for minor in re.findall(r'"Programming Language :: Python :: 3\.(\d+)"', text))
    assert [version for _, version in OTHER_PYTHONS] == [f"3.{listed[0]}", f"3.{listed[-1]}"]
    assert 11 in listed, "the shared venv's Python is one of them"
    assert f'requires-python = ">=3.{listed[0]}"' in text


def _stub_checkout(root: Path, other_status: int) -> Path:
    """A checkout whose run-tests.sh is the real one and whose Pythons, venvs and tiers are stubs: each
    "pytest" run writes when it started and ended into runs.txt, and the other Pythons' exit with
    ``other_status``."""
    (root / "scripts").mkdir(parents=True)
    (root / "scripts" / "run-tests.sh").write_text((ROOT / "scripts" / "run-tests.sh").read_text())
    (root / "scripts" / "setup.sh").write_text('VENV="$REPO/.venv"\n')
    runs = root / "runs.txt"
    for venv, status in ((".venv", 0), ("other", other_status)):
        (root / venv / "bin").mkdir(parents=True)
        python = root / venv / "bin" / "python"
        python.write_text(
            "#!/bin/bash\n"
            'if [ "$1" = tests/tiers.py ]; then\n'
            "    printf 'lint\\tlint\\tt.py\\nfast\\tnot slow\\n"
            "fast-py3.10\\tnot slow\\nfast-py3.13\\tnot slow\\n'; exit\n"
            "fi\n"
            f'echo "{venv} start $(date +%s.%N)" >> {runs}\n'
            "sleep 1\n"
            f'echo "{venv} end $(date +%s.%N)" >> {runs}\n'
            f"exit {status}\n")
        python.chmod(0o755)
    venv_script = root / "scripts" / "python-venv.sh"
    venv_script.write_text(f'#!/bin/bash\necho {root / "other"}\n')
    venv_script.chmod(0o755)
    return runs


@pytest.mark.slow
def test_run_tests_runs_the_other_pythons_fast_tiers_at_the_same_time_after_the_fast_tier(tmp_path):
    runs = _stub_checkout(tmp_path, other_status=0)
    result = subprocess.run(["bash", str(tmp_path / "scripts" / "run-tests.sh")], capture_output=True, text=True,
                            timeout=120)
    assert result.returncode == 0, result.stdout + result.stderr
    times = [line.split() for line in runs.read_text().splitlines()]
    own = [float(t) for name, _, t in times if name == ".venv"]       # lint then fast: start, end, start, end
    starts = [float(t) for name, what, t in times if name == "other" and what == "start"]
    ends = [float(t) for name, what, t in times if name == "other" and what == "end"]
    other = list(zip(sorted(starts), sorted(ends)))
    assert len(own) == 4 and len(other) == 2
    (first_start, first_end), (second_start, second_end) = sorted(other)
    assert first_start >= own[3], "after the fast tier"
    assert second_start < first_end, "at the same time, not one after the other"
    summary = result.stdout[result.stdout.index("== the tiers' times:"):]
    assert [line.split()[0] for line in summary.splitlines()[1:5]] == ["lint", "fast", "fast-py3.10", "fast-py3.13"]
    assert summary.count("passed") == 5, summary   # four tiers and "all tiers passed"


@pytest.mark.slow
def test_run_tests_stops_at_a_failing_other_python_and_exits_with_its_status(tmp_path):
    _stub_checkout(tmp_path, other_status=3)
    result = subprocess.run(["bash", str(tmp_path / "scripts" / "run-tests.sh")], capture_output=True, text=True,
                            timeout=120)
    assert result.returncode == 3
    assert "fast-py3.10    " in result.stdout and "FAILED (3)" in result.stdout
    assert "stopped at the tier 'fast-py3.10'" in result.stderr
