"""Browser code reaches the page only as a widget front end (an anywidget ES module shipped with the
package), never through markup: no ``onerror=`` handler (an image that fails to load runs it) and no
``<script>`` in the files that make pages, nor in any widget a page holds."""

import fnmatch
import re
from pathlib import Path

import pytest

try:
    import tomllib
except ModuleNotFoundError:  # Python 3.10: the same parser as the tomli package (the test extra has it there)
    import tomli as tomllib

from ipywidgets.widgets.widget import _instances as live_widgets

REPO = Path(__file__).resolve().parents[1]
#: What makes the pages: the package, the deployment (Voila's and the hub's settings, templates), and the
#: notebooks the pages and the lab open.
PAGE_SOURCES = ("mt_widgets", "deploy", "notebooks", "tutorials")
SUFFIXES = {".py", ".ipynb", ".js", ".html", ".j2", ".jinja", ".jinja2", ".tpl", ".template", ".css", ".json"}
#: An inline event handler in markup (``onerror="..."``, ``onload='...'``) or a script element.
INJECTED = re.compile(r"""\bon[a-z]+\s*=\s*(\\?["']|&quot;)|<\s*script\b""", re.IGNORECASE)


def page_files():
    for folder in PAGE_SOURCES:
        for path in sorted((REPO / folder).rglob("*")):
            if path.is_file() and path.suffix in SUFFIXES and "__pycache__" not in path.parts:
                yield path


def test_the_pattern_finds_what_it_is_for():
    for injected in ("<img src='data:,' onerror=\"go()\">", '<img onerror=&quot;x&quot;>', "<script>go()</script>",
                     "HTML(f\"<img onload='{code}'>\")", "< SCRIPT src=x>",
                     "<video onended=\\\"go()\\\">"):
        assert INJECTED.search(injected), injected
    for fine in ("canvas.on_mouse_down(self._on_mouse_down)", "onerror = None", "a description of scripts"):
        assert not INJECTED.search(fine), fine


def test_no_file_that_makes_a_page_injects_a_script():
    files = list(page_files())
    assert any(path.name == "canvas_access.js" for path in files)  # the walk sees the front ends
    found = [f"{path.relative_to(REPO)}:{text.count(chr(10), 0, match.start()) + 1}: {match.group(0)}"
             for path in files
             for text in [path.read_text(errors="replace")]
             for match in INJECTED.finditer(text)]
    assert not found, found


def test_the_front_ends_are_package_data():
    globs = tomllib.loads((REPO / "pyproject.toml").read_text())["tool"]["setuptools"]["package-data"]["mt_widgets"]
    front_ends = [path.relative_to(REPO / "mt_widgets").as_posix()
                  for path in (REPO / "mt_widgets").rglob("*") if path.suffix in (".js", ".css")]
    assert "widgets/canvas_access.js" in front_ends and "apps/study/navigation.js" in front_ends
    for name in front_ends:
        # setuptools' "**/" also matches no folder at all.
        assert any(fnmatch.fnmatch(name, glob) or fnmatch.fnmatch(name, glob.removeprefix("**/"))
                   for glob in globs), name


@pytest.fixture
def pages(tmp_path):
    """Every widget alive after building the demo page with an arrow drawn, and an online study page
    whose participant declined (its goodbye holds the navigation widget: the pilot given the pool's
    completion links, which the shipped pilot leaves out)."""
    from mt_widgets.apps.study import OnlineStudyPage
    from mt_widgets.apps.study.navigation import PageAddress
    from mt_widgets.widgets import DemoPage
    from tests.study_pages.support import buttons_in, pilot_with_completion_urls, prolific

    before = set(live_widgets)
    demo = DemoPage(skill="sim-point")
    demo.episode.demonstrate([1.0, 0.5])
    online = OnlineStudyPage(pilot_with_completion_urls(tmp_path), tmp_path / "logs", prolific("D1"),
                             redirect_delay_s=0)
    while not online.session.finished:
        assert online.session.current_step().kind != "demonstration", "the consent step comes first"
        declines = [b for b in buttons_in(online.view.body) if b.description == "I do not agree"]
        (declines[0] if declines else buttons_in(online.view.body)[0]).click()
    widgets = [w for key, w in live_widgets.items() if key not in before]
    assert any(isinstance(w, PageAddress) and w.action == "go" for w in widgets)
    return widgets


def test_no_widget_of_a_page_carries_a_script(pages):
    texts = [value for widget in pages for name in ("value", "description", "tooltip", "placeholder")
             for value in [getattr(widget, name, None)] if isinstance(value, str)]
    assert texts and any("Teaching effort" in text for text in texts)
    found = [text[:200] for text in texts if INJECTED.search(text)]
    assert not found, found


def test_the_front_ends_name_no_study_word():
    # A participant's browser receives every front end's source (the widgets' state): like the page's
    # words, it names no group (tests/study/test_app.py checks the words).
    words = re.compile(r"\b(target|control|group|groups|condition)\b", re.IGNORECASE)
    sources = [path for path in (REPO / "mt_widgets").rglob("*") if path.suffix in (".js", ".css")]
    assert len(sources) >= 4
    found = {path.name: words.findall(path.read_text()) for path in sources if words.search(path.read_text())}
    assert not found, found
