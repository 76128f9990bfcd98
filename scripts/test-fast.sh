#!/usr/bin/env bash
# The fast tier for the edit loop: every test but the real-browser ones, the notebooks (nbval)
# and the slow ones (marked in tests/conftest.py), in about a minute on a 2-core machine.
# ./scripts/run-tests.sh still runs everything. Extra arguments go to pytest (a folder, -k ...).
set -euo pipefail
REPO="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
source "$REPO/scripts/setup.sh"
cd "$REPO"
# The one switch that shortens long work under test (see mt_widgets/core/fast_mode.py).
export MT_WIDGETS_FAST=1
exec "$VENV/bin/python" -m pytest -m "not browser and not slow" --timeout=600 "$@"
