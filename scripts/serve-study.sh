#!/usr/bin/env bash
# Serves the study pages with Voila: `mt-widgets study serve`, with the configuration in
# deploy/voila/voila.py (--Voila.config_file_paths=deploy/voila; the demo's: kernels end with their
# page, a preheated kernel waits for the next participant).
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
online=()
if [ "${1:-}" = "--online" ]; then
    shift
    online=(--online)
fi
exec "$VENV/bin/python" -m mt_widgets.cli study serve "${online[@]}" -- "$@"
