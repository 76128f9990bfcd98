"""The documentation site builds with the documented command, warnings as errors, and holds what it
promises: an API page for every public name, every tutorial, the benchmarks' plots drawn from their
data, and every guide page. One build (about a minute) serves every test here: the ``docs`` tier."""

from __future__ import annotations

import json
import os
import re
import subprocess
import sys
import time
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
HTML = ROOT / "docs" / "_build" / "html"
sys.path.insert(0, str(ROOT / "docs" / "_ext"))

import api_names  # noqa: E402


@pytest.fixture(scope="module")
def build():
    """``./scripts/build-docs.sh -E`` (every page read again) with this run's Python: its output."""
    environment = {**os.environ, "PYTHON": sys.executable, "PYTHONPATH": str(ROOT)}
    started = time.monotonic()
    result = subprocess.run([str(ROOT / "scripts" / "build-docs.sh"), "-E"], cwd=ROOT, env=environment,
                            capture_output=True, text=True, timeout=900)
    print(f"docs build: {time.monotonic() - started:.1f} s")
    return result


def test_the_site_builds_without_a_warning(build):
    output = build.stdout + build.stderr
    assert build.returncode == 0, output[-6000:]
    assert "build succeeded" in output, output[-3000:]
    warnings = [line for line in output.splitlines() if re.search(r"\b(WARNING|ERROR|CRITICAL)\b:", line)]
    assert not warnings, "\n".join(warnings[:40])
    assert (HTML / "index.html").is_file()


def test_every_public_name_has_an_api_page(build):
    names = api_names.public_names()
    assert len(names) >= 200, len(names)   # today's __all__s hold 214 names
    for name in names:
        page = HTML / "api" / "generated" / f"{name.documented_as}.html"
        assert page.is_file(), f"{name.full_name}: no API page {page.relative_to(ROOT)}"
        assert f'id="{name.documented_as}"' in page.read_text(), f"{page.name} does not document {name.documented_as}"
        # docs/conf.py escapes a literal followed by a letter (````Phase``s``); a stray escape
        # would show as a backslash inside the literal.
        assert '<span class="pre">\\</span>' not in page.read_text(), f"{page.name} shows an escape's backslash"
        package_page = (HTML / "api" / f"{name.package}.html").read_text()
        assert f"generated/{name.documented_as}.html" in package_page, \
            f"api/{name.package}.html does not link {name.full_name}'s page"
        assert '<span class="pre">\\</span>' not in package_page, f"api/{name.package}.html shows a backslash"


def test_the_api_index_links_every_package(build):
    index = (HTML / "api" / "index.html").read_text()
    for package in api_names.packages():
        assert f'href="{package}.html"' in index, f"api/index.html does not link {package}"


def test_every_tutorial_is_rendered_with_its_text(build):
    tutorials = sorted((ROOT / "tutorials").glob("*.ipynb"))
    assert len(tutorials) >= 15
    for notebook in tutorials:
        page = HTML / "tutorials" / f"{notebook.stem}.html"
        assert page.is_file(), f"{notebook.name} is not rendered"
        cells = json.loads(notebook.read_text())["cells"]
        heading = next(line for cell in cells if cell["cell_type"] == "markdown"
                       for line in "".join(cell["source"]).splitlines() if line.startswith("# "))
        title = re.sub(r"[`*$\\]", "", heading[2:]).strip()
        text = re.sub(r"<[^>]+>", "", page.read_text())
        assert title.split()[0] in text, f"{notebook.name}: its title {title!r} is not on its page"


def test_the_tutorials_are_rendered_with_their_executed_outputs(build):
    # The build executes them (docs/conf.py): printed numbers and figures come out of today's code.
    with_outputs = [page.stem for page in (HTML / "tutorials").glob("*.html") if "cell_output" in page.read_text()]
    assert len(with_outputs) >= 14, sorted(with_outputs)
    ridge = (HTML / "tutorials" / "02_ridge_regression.html").read_text()
    assert re.search(r'<img [^>]*src="\.\./_images/[0-9a-f]{64}\.png"', ridge), "tutorial 02's figure is not shown"
    assert "cell_output" in (HTML / "notebooks" / "analysis.html").read_text()


def test_the_benchmarks_page_draws_every_figure_from_the_data(build):
    page = (HTML / "benchmarks.html").read_text()
    results = json.loads((ROOT / "docs" / "benchmarks" / "results.json").read_text())
    for figure in ("core", "targets", "kiosk", "online", "hub"):
        assert f"{figure}.png" in page, f"the benchmarks page shows no {figure}.png"
        assert list((HTML / "_images").glob(f"{figure}*.png")), f"{figure}.png was not copied into the site"
    for run in results["kiosk"]["runs"]:
        assert f"{run['shipped_p50']:.2f} s" in page and f"{run['stock_p50']:.2f} s" in page
    for row in results["core"]["speed"]:
        assert f"{row['ratio']:.1f}x" in page
    for run in results["hub"]["runs"]:
        assert f"{run['pss_mib']} ({run['pss_server_mib']} + {run['pss_kernel_mib']})" in page


def test_the_guide_lists_every_guide_page(build):
    page = (HTML / "guide.html").read_text()
    guides = sorted((ROOT / "docs" / "guide").glob("*.md"))
    for guide in guides:
        assert (HTML / "guide" / f"{guide.stem}.html").is_file(), f"docs/guide/{guide.name} is not built"
        assert f'href="guide/{guide.stem}.html"' in page, f"guide.html does not link {guide.name}"
    if not guides:
        assert "No guide pages have been written yet." in page


def test_the_maths_is_typeset_by_the_sites_own_mathjax(build):
    # Offline (a classroom without internet): MathJax and its fonts come from the site, not a CDN.
    science = (HTML / "science.html").read_text()
    assert '<span class="math' in science or "\\(" in science, "docs/science.md shows no maths"
    assert 'src="_static/mathjax/tex-chtml.js' in science, "science.html does not load the site's MathJax"
    assert (HTML / "_static" / "mathjax" / "tex-chtml.js").is_file()
    assert list((HTML / "_static" / "mathjax" / "output" / "chtml" / "fonts" / "woff-v2").glob("*.woff"))
    cdn = [page.relative_to(HTML).as_posix() for page in HTML.rglob("*.html")
           if re.search(r"https?://[^\"']*mathjax", page.read_text(errors="replace"), flags=re.I)]
    assert not cdn, f"pages asking a CDN for MathJax: {cdn[:10]}"
