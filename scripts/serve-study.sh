#!/usr/bin/env bash
# Serves the study page (notebooks/study_sim.ipynb) with Voila and the configuration in
# deploy/voila/voila.py (the demo's: kernels end with their page, a preheated kernel waits for
# the next participant). Logs go to $MT_WIDGETS_STUDY_LOGS, else ~/mt-widgets-studies/<protocol>.
# Open http://localhost:8866/ . Extra arguments go to Voila, e.g. --port=8000.
set -euo pipefail
REPO="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
source "$REPO/scripts/setup.sh"
cd "$REPO"
exec "$VENV/bin/voila" --no-browser --Voila.config_file_paths="$REPO/deploy/voila" "$@" notebooks/study_sim.ipynb
