"""The Python examples of the README and of the documentation's user pages run as written (keeping
them true). The README keeps a few; most moved with their text into docs/user/*.md, where they run
the same way (the getting-started pages run top to bottom: tests/docs/test_getting_started.py)."""

import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
README = ROOT / "README.md"
# The getting-started pages run page by page, top to bottom (tests/docs/test_getting_started.py).
PAGES = [README, *sorted((ROOT / "docs" / "user").glob("*.md"))]
BLOCKS = [(page.relative_to(ROOT).as_posix(), index, block) for page in PAGES
          for index, block in enumerate(re.findall(r"```python\n(.*?)```", page.read_text(), flags=re.S))]


#: Whether mt-widgets is on the package index (PyPI). Until the first upload (docs/release.md, its
#: last step), no page may tell a user to ``pip install mt-widgets`` by name from the index.
PUBLISHED_ON_PYPI = False
#: The pages a user installs from.
INSTALL_PAGES = [README, ROOT / "docs" / "getting-started" / "index.md", ROOT / "docs" / "guide" / "install.md",
                 ROOT / "docs" / "guide" / "command.md", *sorted((ROOT / "docs" / "getting-started").glob("*.md"))]


def test_no_page_promises_an_install_from_the_package_index_before_a_release_is_there():
    # `pip install mt-widgets`, `pip install "mt-widgets[lab]"` (by name, from the index); not
    # `pip install "mt-widgets[lab] @ git+..."`, a wheel's file, or `pip install -e ".[lab]"`.
    by_name = re.compile(r"""pip install (?:-U |--upgrade )?(["']?)mt-widgets(?:\[[a-z,]+\])?(?:[=<>~!][^"'\s`]*)?\1"""
                         r"(?![^\s`]|\s+@)")
    promised = [(page.relative_to(ROOT).as_posix(), match.group(0)) for page in INSTALL_PAGES
                for match in by_name.finditer(page.read_text(encoding="utf-8"))]
    if PUBLISHED_ON_PYPI:
        assert promised
    else:
        assert not promised, f"mt-widgets is not on PyPI yet (docs/release.md): {promised}"


def test_the_wheel_the_install_pages_name_is_this_versions():
    version = re.search(r'^version = "([^"]+)"', (ROOT / "pyproject.toml").read_text(), flags=re.M).group(1)
    for page in (README, ROOT / "docs" / "getting-started" / "index.md", ROOT / "docs" / "guide" / "install.md"):
        wheels = re.findall(r"mt_widgets-([0-9][^-\s]*)-py3-none-any\.whl", page.read_text(encoding="utf-8"))
        assert wheels and set(wheels) == {version}, (page.name, wheels, version)


def test_the_readme_and_the_docs_have_examples():
    assert sum(page == "README.md" for page, _, _ in BLOCKS) >= 4
    assert sum(page != "README.md" for page, _, _ in BLOCKS) >= 6


@pytest.mark.slow
@pytest.mark.parametrize(("page", "index", "block"), BLOCKS, ids=[f"{page}-{index}" for page, index, _ in BLOCKS])
def test_example_runs(page, index, block, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)  # examples that write files write them here
    exec(compile(block, f"{page} python block {index}", "exec"), {"__name__": "__readme__"})
