"""The Python examples of the README and of the documentation's user pages run as written (keeping
them true). The README keeps a few; most moved with their text into docs/ (docs/user/*.md,
docs/getting-started/*.md), where they run the same way."""

import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
README = ROOT / "README.md"
PAGES = [README, *sorted((ROOT / "docs" / "user").glob("*.md")),
         *sorted((ROOT / "docs" / "getting-started").glob("*.md"))]
BLOCKS = [(page.relative_to(ROOT).as_posix(), index, block) for page in PAGES
          for index, block in enumerate(re.findall(r"```python\n(.*?)```", page.read_text(), flags=re.S))]


def test_the_readme_and_the_docs_have_examples():
    assert sum(page == "README.md" for page, _, _ in BLOCKS) >= 4
    assert sum(page != "README.md" for page, _, _ in BLOCKS) >= 6


@pytest.mark.slow
@pytest.mark.parametrize(("page", "index", "block"), BLOCKS, ids=[f"{page}-{index}" for page, index, _ in BLOCKS])
def test_example_runs(page, index, block, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)  # examples that write files write them here
    exec(compile(block, f"{page} python block {index}", "exec"), {"__name__": "__readme__"})
