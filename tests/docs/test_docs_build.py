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


#: Pages the offline look opens: maths in the prose and the code's outputs, and widgets with their
#: saved state (ipywidgets' controls, ipycanvas' canvases, anywidget's accessibility layer).
OFFLINE_PAGES = ("tutorials/02_ridge_regression.html", "tutorials/06_drawing_a_demonstration.html")


def test_offline_the_site_shows_its_maths_and_the_tutorials_widgets(build, tmp_path):
    # Chromium with the network blocked: every request not to the site's own server is refused and
    # recorded. The maths must be typeset (MathJax's output elements) and the executed tutorials'
    # widgets drawn from their saved state, by the site's own widget manager and modules
    # (docs/conf.py: nb_ipywidgets_js). Chromium drives this in the docs tier, not the browser tier,
    # so that it looks at this tier's one build (about 15 s) instead of building the site again.
    import functools
    import http.server
    import threading

    from playwright.sync_api import sync_playwright

    from browser_support import CHROMIUM, CHROMIUM_ARGS

    assert build.returncode == 0, (build.stdout + build.stderr)[-3000:]
    class Quiet(http.server.SimpleHTTPRequestHandler):
        def log_message(self, *args):   # a line per request would bury the test's own output
            pass

    server = http.server.ThreadingHTTPServer(("127.0.0.1", 0), functools.partial(Quiet, directory=str(HTML)))
    threading.Thread(target=server.serve_forever, daemon=True).start()
    site = f"http://127.0.0.1:{server.server_address[1]}"
    outside, failed = [], []
    try:
        with sync_playwright() as playwright:
            browser = playwright.chromium.launch(executable_path=CHROMIUM, args=CHROMIUM_ARGS)
            context = browser.new_context(viewport={"width": 1280, "height": 1000})

            def only_the_site(route):
                if route.request.url.startswith((site, "data:", "blob:")):
                    route.continue_()
                else:
                    outside.append(route.request.url)
                    route.abort()

            context.route("**/*", only_the_site)
            page = context.new_page()
            page.on("response", lambda response: failed.append(response.url) if response.status >= 400 else None)
            seen = {}
            for path in OFFLINE_PAGES:
                page.goto(f"{site}/{path}", wait_until="load", timeout=60_000)
                page.wait_for_selector("mjx-container", state="attached", timeout=60_000)
                page.wait_for_selector(".widget-subarea .jupyter-widgets", state="attached", timeout=60_000)
                page.wait_for_load_state("networkidle", timeout=60_000)
                seen[path] = page.evaluate("""() => ({
                    maths: document.querySelectorAll('mjx-container[jax="CHTML"]').length,
                    raw_tex: [...document.querySelectorAll('.math')].filter(m => !m.querySelector('mjx-container')
                                                                           && /\\\\|\\$/.test(m.textContent)).length,
                    views: document.querySelectorAll('script[type="application/vnd.jupyter.widget-view+json"]').length,
                    drawn: document.querySelectorAll('.widget-subarea > .jupyter-widgets').length,
                    buttons: [...document.querySelectorAll('.widget-subarea button')].map(b => b.textContent.trim())
                             .filter(t => t),
                    canvases: document.querySelectorAll('.widget-subarea canvas').length,
                    errors: [...document.querySelectorAll('.widget-subarea')].filter(s => /Error|Failed/.test(
                             s.textContent) && !s.querySelector('.jupyter-widgets')).length})""")
                page.locator(".widget-subarea").first.scroll_into_view_if_needed()
                page.screenshot(path=str(ROOT / "test-artifacts" / f"docs-offline-{Path(path).stem}.png"))
            browser.close()
    finally:
        server.shutdown()
    assert outside == [], f"the pages asked outside the site: {outside[:10]}"
    assert failed == [], f"the site lacked: {failed[:10]}"
    for path, found in seen.items():
        assert found["maths"] > 0 and found["raw_tex"] == 0, (path, found)
        # Every saved widget view is drawn (none left as its script tag or an error message).
        assert found["views"] > 0 and found["drawn"] == found["views"] and found["errors"] == 0, (path, found)
    drawing = seen["tutorials/06_drawing_a_demonstration.html"]
    assert "Confirm" in " ".join(drawing["buttons"]) and drawing["canvases"] > 0, drawing
