"""The documentation's sources, without building them (fast): the README stays a newcomer's page
whose links lead into the docs, what moved out of it is in the docs, and the benchmarks' tables are
drawn from their data."""

from __future__ import annotations

import json
import re
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
README = ROOT / "README.md"
sys.path.insert(0, str(ROOT / "docs" / "_ext"))

import benchmark_figures  # noqa: E402


def test_the_readme_is_a_newcomers_page():
    text = README.read_text()
    assert len(text.splitlines()) <= 200
    for command in ("./scripts/run-tests.sh", "./scripts/open-lab.sh", "./scripts/build-docs.sh"):
        assert command in text
    assert "![" in text and (ROOT / "docs" / "_static" / "screenshots" / "demo-guidance.png").is_file()


def test_the_readmes_links_lead_to_files_that_exist():
    links = re.findall(r"\]\(([^)#]+)(?:#[^)]*)?\)", README.read_text())
    local = [link for link in links if "://" not in link]
    assert len(local) >= 15
    for link in local:
        assert (ROOT / link).exists(), f"README.md links {link}, which does not exist"


def test_the_docs_pages_keep_what_moved_out_of_the_readme():
    # A sample of what a user needs, each in the page it moved to.
    expected = {
        "docs/testing.md": ["tests/tiers.py", "NOTEBOOK_PARAMETERS", "./scripts/test-fast.sh"],
        "docs/user/study.md": ["MT_WIDGETS_EXPERIMENTER_CODE", "PROLIFIC_PID", "export_bids", "[[sessions]]"],
        "docs/user/analysis.md": ["analyse_study", "sample_size_per_group(0.9)", "| uArm (cm) | P2→P5 | control |"],
        "docs/user/course.md": ["nbgrader generate_assignment", "class_admin.py", "MT_WIDGETS_CLASS_NAMES"],
        "docs/user/deploy.md": ["proxy_set_header Upgrade", "cull_idle_timeout = 600", "preheat_kernel"],
        "docs/user/uarm.md": ["SafetyEnvelope", "MT_WIDGETS_SCREEN", "UNCERTAIN"],
        "docs/user/widgets.md": ["EpisodeWidget", "SkillRegistry", "ipycanvas issue #322"],
        "docs/tutorials.md": ["10_protocol_capstone", "appendix_b_uarm_firmware"],
        "docs/architecture.md": ["mt_widgets/core/", "tests/test_architecture.py"],
        "docs/benchmarks.md": ["bench_kiosk.py", "tests/test_benchmarks.py", "results.json"],
    }
    for page, needles in expected.items():
        text = (ROOT / page).read_text()
        for needle in needles:
            assert needle in text, f"{page} lost {needle!r}"


def test_every_tutorial_is_in_the_tutorials_toctree():
    text = (ROOT / "docs" / "tutorials.md").read_text()
    for notebook in sorted((ROOT / "tutorials").glob("*.ipynb")):
        assert f"tutorials/{notebook.stem}\n" in text, f"docs/tutorials.md does not list {notebook.name}"


def test_the_benchmark_tables_come_from_the_data():
    results = json.loads((ROOT / "docs" / "benchmarks" / "results.json").read_text())
    tables = benchmark_figures.tables(results)
    assert "41.6x (target 4x)" in tables["core"] and "43.8x (target 10x)" in tables["core"]
    changed = json.loads(json.dumps(results))
    changed["kiosk"]["runs"][0]["shipped_p50"] = 9.87
    assert "9.87 s" in benchmark_figures.tables(changed)["kiosk_runs"]
    assert "9.87 s" not in tables["kiosk_runs"]
    # Every kiosk run is a row of its table, in order.
    rows = tables["kiosk_runs"].splitlines()[2:]
    assert len(rows) == len(results["kiosk"]["runs"])
    assert [row.split(" | ")[3] for row in rows] == [f"{run['shipped_p50']:.2f} s" for run in results["kiosk"]["runs"]]
    # Which way each run was timed is said on its row; the summary is the newest run timed in the page.
    assert [row.split(" | ")[2] for row in rows] == [run.get("timed", "polled") for run in results["kiosk"]["runs"]]
    newest = [run for run in results["kiosk"]["runs"] if run.get("timed") == "in the page" and "memory_mb" in run][-1]
    assert f"{newest['shipped_p50']:.2f} s / {newest['shipped_p95']:.2f} s" in tables["kiosk"]


def test_the_benchmark_figures_are_drawn(tmp_path):
    results = json.loads((ROOT / "docs" / "benchmarks" / "results.json").read_text())
    written = benchmark_figures.figures(results, tmp_path)
    assert sorted(path.name for path in written) == ["core.png", "hub.png", "kiosk.png", "online.png", "targets.png"]
    for path in written:
        assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and path.stat().st_size > 5000


def _requirement_names(requirements: list[str]) -> set[str]:
    return {re.split(r"[\[<>=!~;\s]", requirement, maxsplit=1)[0].lower().replace("_", "-")
            for requirement in requirements}


def test_what_docs_conf_imports_from_the_repository_runs_with_the_docs_extra_alone():
    # `pip install -e ".[docs]"` then ./scripts/build-docs.sh: the modules of this repository that
    # docs/conf.py imports (its _ext/ helpers, the notebooks' shortening) are imported, and the
    # shortening applied, in a Python where every package only the test extra brings is missing.
    import ast
    import subprocess
    from importlib.metadata import packages_distributions

    try:
        import tomllib
    except ModuleNotFoundError:   # Python 3.10
        import tomli as tomllib
    extras = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["optional-dependencies"]
    docs = _requirement_names(extras["docs"])
    for extra in ("lab", "widgets", "analysis", "uarm"):
        docs |= _requirement_names(extras[extra])
    test_only = _requirement_names(extras["test"]) - docs
    blocked = sorted(module for module, dists in packages_distributions().items()
                     if {d.lower().replace("_", "-") for d in dists} & test_only)
    assert "pytest" in blocked and "nbval" in blocked

    tree = ast.parse((ROOT / "docs" / "conf.py").read_text())
    local = {path.stem for path in (ROOT / "docs" / "_ext").glob("*.py")} | {"tests"}
    imported = sorted({node.module if isinstance(node, ast.ImportFrom) else alias.name
                       for node in ast.walk(tree) if isinstance(node, (ast.Import, ast.ImportFrom))
                       for alias in node.names
                       if ((node.module if isinstance(node, ast.ImportFrom) else alias.name) or "").split(".")[0]
                       in local})
    assert "tests.notebook_parameters" in imported, imported
    script = f"""
import importlib, importlib.abc, sys
from pathlib import Path
BLOCKED = {blocked!r}
class Missing(importlib.abc.MetaPathFinder):
    def find_spec(self, name, path=None, target=None):
        if name.split(".")[0] in BLOCKED:
            raise ModuleNotFoundError(f"No module named {{name!r}} (not in the docs extra)")
sys.meta_path.insert(0, Missing())
sys.path[:0] = [{str(ROOT)!r}, {str(ROOT / "docs" / "_ext")!r}]
for name in {imported!r}:
    importlib.import_module(name)
parameters = importlib.import_module("tests.notebook_parameters")
source = parameters.injected_source("N = 300\\n", {{"N": 3}}, Path("/tmp"), "a.ipynb")
assert source.rstrip().endswith("N = 3"), source
try:
    parameters.injected_source("N = 300\\n", {{"M": 3}}, Path("/tmp"), "a.ipynb")
except parameters.ParametersError:
    pass
else:
    raise AssertionError("a parameter the cell does not assign was accepted")
"""
    run = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, cwd=ROOT)
    assert run.returncode == 0, run.stderr
