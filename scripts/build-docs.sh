#!/usr/bin/env bash
# Builds the documentation site into docs/_build/html with Sphinx (myst-nb, the pydata theme),
# every warning an error. Needs the `docs` extra (pip install -e ".[docs]"); uses .venv/ when it
# exists (scripts/setup.sh makes it), else the python on PATH. Extra arguments go to sphinx-build
# (e.g. -E to reread every page). The tutorials and the apps' notebooks are executed during the build
# (shortened as under test); MT_WIDGETS_DOCS_EXECUTE=0 renders them as committed, without outputs.
set -euo pipefail
REPO="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
PYTHON="${PYTHON:-$([ -x "$REPO/.venv/bin/python" ] && echo "$REPO/.venv/bin/python" || command -v python3)}"
cd "$REPO"
exec "$PYTHON" -m sphinx -W --keep-going -b html "$@" docs docs/_build/html
