#!/usr/bin/env bash
# The edit loop: the tiers lint and fast of tests/tiers.py (every test but the slow, real-browser,
# notebook and hub ones), in about a minute on a 2-core machine, without Chromium.
# ./scripts/run-tests.sh runs every tier. Extra arguments go to pytest (a folder, -k ...).
set -euo pipefail
REPO="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
source "$REPO/scripts/setup.sh"
cd "$REPO"
exec "$VENV/bin/python" -m pytest -m "lint or ($("$VENV/bin/python" tests/tiers.py fast))" --timeout=600 "$@"
