#!/usr/bin/env bash
# Serves the study pages with Voila and the configuration in deploy/voila/voila.py (the demo's:
# kernels end with their page, a preheated kernel waits for the next participant).
#
#   ./scripts/serve-study.sh [VOILA OPTIONS]           the lab page, notebooks/study_sim.ipynb, at /
#   ./scripts/serve-study.sh --online [VOILA OPTIONS]  the online participant page at
#       /voila/render/study_online.ipynb?PROLIFIC_PID=...&STUDY_ID=...&SESSION_ID=... and the
#       experimenter's page at /voila/render/study_sim.ipynb (nothing else of the repository)
#
# The experimenter's panel opens with $MT_WIDGETS_EXPERIMENTER_CODE; when it is not set, a code
# is made up and printed here. Logs go to $MT_WIDGETS_STUDY_LOGS, else ~/mt-widgets-studies/<protocol>;
# the online page's protocol is $MT_WIDGETS_STUDY_PROTOCOL (a file with an [online] table; default:
# the pilot, notebooks/study_online_pilot.toml). At capacity a new arrival gets a page saying the study is
# busy and when to come back: $MT_WIDGETS_STUDY_MAX_PARTICIPANTS (taking part at once) and
# $MT_WIDGETS_STUDY_MIN_FREE_MIB (memory kept free); unset, no limit (mt_widgets/apps/study/capacity.py).
# Open http://localhost:8866/ . Extra arguments go to Voila, e.g. --port=8000.
# Serving on the internet: docs/user/deploy.md, "Serving the online study on the internet".
set -euo pipefail
REPO="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
source "$REPO/scripts/setup.sh"
cd "$REPO"
if [ -z "${MT_WIDGETS_EXPERIMENTER_CODE:-}" ]; then
    MT_WIDGETS_EXPERIMENTER_CODE="$("$VENV/bin/python" -c 'import secrets; print(secrets.token_urlsafe(9))')"
    export MT_WIDGETS_EXPERIMENTER_CODE
    echo "Experimenter code for this server: $MT_WIDGETS_EXPERIMENTER_CODE"
fi
if [ "${1:-}" = "--online" ]; then
    shift
    # Only the two pages (and the pilot protocol they read) are in the served folder.
    PAGES="$(mktemp -d "${TMPDIR:-/tmp}/mt-widgets-study-pages.XXXXXX")"
    trap 'rm -rf "$PAGES"' EXIT
    for name in study_sim.ipynb study_online.ipynb study_online_pilot.toml; do
        ln -s "$REPO/notebooks/$name" "$PAGES/$name"
    done
    "$VENV/bin/voila" --no-browser --Voila.config_file_paths="$REPO/deploy/voila" "$@" "$PAGES"
else
    exec "$VENV/bin/voila" --no-browser --Voila.config_file_paths="$REPO/deploy/voila" "$@" notebooks/study_sim.ipynb
fi
