#!/usr/bin/env bash
# Sets up .venv with mt-widgets and every extra (lab, test, bench, course, hub). Idempotent: it re-installs
# only when pyproject.toml changed since the last run. Sourced by open-lab.sh and run-tests.sh.
set -euo pipefail
REPO="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
VENV="$REPO/.venv"
PYTHON="${PYTHON:-python3}"

if ! "$PYTHON" -c 'import sys; sys.exit(sys.version_info < (3, 10))' 2>/dev/null; then
    echo "mt-widgets needs Python >= 3.10; '$PYTHON' is $("$PYTHON" --version 2>&1 || echo missing)." >&2
    exit 1
fi
if [ ! -x "$VENV/bin/python" ]; then
    echo "== creating $VENV"
    "$PYTHON" -m venv "$VENV"
fi
stamp="$VENV/.mt-widgets-installed"
wanted="$(sha256sum "$REPO/pyproject.toml" | cut -d' ' -f1)"
if [ "$(cat "$stamp" 2>/dev/null || true)" != "$wanted" ]; then
    echo "== installing mt-widgets[lab,test,bench,course,hub,docs] into $VENV"
    "$VENV/bin/python" -m pip install --quiet --upgrade pip
    "$VENV/bin/python" -m pip install --quiet -e "$REPO[lab,test,bench,course,hub,docs]"
    echo "$wanted" > "$stamp"
fi
