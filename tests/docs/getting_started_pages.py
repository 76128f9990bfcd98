"""The getting-started pages as tests read them: their code blocks, the skip marker, and a runner.

Every fenced ``bash`` and ``python`` block of docs/getting-started/*.md runs in order, in a fresh
folder with a fresh home (``run_page``): the shell blocks through bash (``set -e``), the Python
blocks in one namespace per page, as in one Python session, all in one process of the Python under
test (tests/docs/page_driver.py, which imports nothing from the repository). A block that cannot run
here (a server that runs until it is stopped, a clone's scripts, an install, a real arm) is preceded
by the marker ``<!-- not run by tests/docs/test_getting_started.py: REASON -->``, and says why.

Two tests run the pages: tests/docs/test_getting_started.py with this checkout (slow tier), and
tests/install/test_getting_started_from_wheel.py with the built wheel in a fresh venv, without the
repository on the path (install tier), as a newcomer without a clone runs them.
"""

from __future__ import annotations

import json
import re
import shutil
import subprocess
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
PAGES = sorted((ROOT / "docs" / "getting-started").glob("*.md"))
#: The marker before a block the tests leave out, and why (the reason is required).
SKIP = re.compile(r"^<!-- not run by tests/docs/test_getting_started\.py: (?P<reason>.*\S.*) -->$")
LANGUAGES = ("bash", "python")
#: Blocks that show a file's content rather than something to type, left as they are.
CONTENT = ("toml", "text", "json")
DRIVER = Path(__file__).resolve().parent / "page_driver.py"


@dataclass(frozen=True)
class Block:
    language: str
    code: str
    line: int
    skipped_because: str | None


def blocks(page: Path) -> list[Block]:
    """The page's fenced code blocks (those inside list items too), with the skip marker before each."""
    lines = page.read_text(encoding="utf-8").splitlines()
    found, i = [], 0
    while i < len(lines):
        opening = re.match(r"^(\s*)```(\S*)\s*$", lines[i])
        if not opening:
            i += 1
            continue
        indent, language = len(opening.group(1)), opening.group(2)
        end = next(j for j in range(i + 1, len(lines)) if re.match(r"^\s*```\s*$", lines[j]))
        before = next((lines[j].strip() for j in range(i - 1, -1, -1) if lines[j].strip()), "")
        marker = SKIP.match(before)
        code = "\n".join(line[indent:] for line in lines[i + 1:end]) + "\n"
        if not language.startswith("{"):   # a MyST directive (```{toctree}), not code
            found.append(Block(language, code, i + 1, marker.group("reason") if marker else None))
        i = end + 1
    return found


def runnable(page: Path) -> list[Block]:
    """The blocks of ``page`` a test runs: code, not content, and not marked as left out."""
    return [block for block in blocks(page) if block.skipped_because is None and block.language in LANGUAGES]


def run_page(page: Path, python: Path, environment: dict, folder: Path) -> subprocess.CompletedProcess:
    """Runs ``page``'s blocks top to bottom with ``python``, in ``folder``/work with ``folder``/home as HOME.

    ``environment`` is the rest of the environment (its PATH decides which ``mt-widgets`` the shell
    blocks run). The driver is copied into ``folder`` so that the only folder it puts on the path is
    this empty one. Returns the finished run; its last line of output says where mt_widgets came from."""
    home, work = folder / "home", folder / "work"
    home.mkdir()
    work.mkdir()
    driver = folder / DRIVER.name
    shutil.copyfile(DRIVER, driver)
    listed = folder / "blocks.json"
    listed.write_text(json.dumps([{"language": block.language, "code": block.code,
                                   "where": f"{page.relative_to(ROOT)}:{block.line}"}
                                  for block in runnable(page)]), encoding="utf-8")
    return subprocess.run([str(python), str(driver), str(listed)], cwd=work, env={**environment, "HOME": str(home)},
                          capture_output=True, text=True, timeout=1200)
