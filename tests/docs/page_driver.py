"""Runs one getting-started page's blocks in order, as a newcomer types them: a standalone script.

Run as ``python page_driver.py BLOCKS.json`` with the Python under test (the repository's venv, or a
fresh venv holding only the built wheel): it imports nothing from the repository, so what the
blocks import comes from that Python alone. BLOCKS.json is a list of ``{"language", "code",
"where"}``; the ``bash`` blocks run through ``bash -euo pipefail`` with this process's environment
(its PATH says which ``mt-widgets`` runs), the ``python`` blocks in one namespace, as in one Python
session. A failing block prints where it is and what it said, and the driver exits with 1; at the
end it prints one line, ``mt_widgets from PATH``, where the package the blocks used was imported
from (``none`` when no block imported it).
"""

from __future__ import annotations

import json
import subprocess
import sys
import traceback


def main(blocks_file: str) -> int:
    with open(blocks_file, encoding="utf-8") as handle:
        blocks = json.load(handle)
    namespace: dict = {"__name__": "__getting_started__"}
    for block in blocks:
        where, code = block["where"], block["code"]
        if block["language"] == "bash":
            run = subprocess.run(["bash", "-euo", "pipefail", "-c", code], capture_output=True, text=True,
                                 timeout=600)
            if run.returncode != 0:
                print(f"{where}: exit {run.returncode}\n{code}\n{run.stdout}\n{run.stderr}", file=sys.stderr)
                return 1
        else:
            try:
                exec(compile(code, where, "exec"), namespace)
            except BaseException:   # the page's own error, with its traceback, is the test's message
                print(f"{where}:\n{code}\n{traceback.format_exc()}", file=sys.stderr)
                return 1
    package = sys.modules.get("mt_widgets")
    print(f"mt_widgets from {package.__file__ if package else 'none'}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1]))
